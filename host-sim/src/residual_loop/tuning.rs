//! The process noise set from the data before the search.
//!
//! A filter whose process noise is larger than what the data need is over-cautious (NIS below
//! its bounds), and on such a filter any parameter that makes the model more damped or stiffer
//! also shrinks the predicted spread and raises the likelihood whatever the data say: a damping
//! factor's likelihood then rises to the edge of its range on healthy and changed runs alike.
//! So a system may offer one scale on the noise its model's dynamics carry
//! ([`LoopSystem::scale_noise`]); the engine fits it by maximum likelihood on the base model,
//! keeps it only if it pays for its parameter like an effect does, and writes it into the
//! configuration's keys. It is a tuning, not an effect: a healthy record may need it too. It
//! only lowers the noise (see `SPAN`).

use super::correction::EffectCorrection;
use super::filter::Run;
use super::optimize::maximise;
use super::options::LoopOptions;
pub use super::report::Tuning;
use super::system::LoopSystem;
pub use super::system::TunableNoise;
use anyhow::Result;

/// The smallest the scale may go, a factor on the configuration's. It never goes above 1:
/// more noise than declared is what an effect the model lacks looks like, and naming that
/// effect is the search's work (a fault the noise had swallowed would be found late, or not).
const SPAN: f64 = 1000.0;
/// Grid points over `ln` of the scale before Brent's method.
const GRID: usize = 5;
/// Tolerance of the fit in `ln` of the scale (5 %).
const TOLERANCE: f64 = 0.05;

/// A scale kept: the tuning, its correction, and the base model and run it gives.
pub struct Tuned<M> {
    /// What was kept.
    pub tuning: Tuning,
    /// How it enters the configuration.
    pub correction: EffectCorrection,
    /// The base model with the scale.
    pub model: M,
    /// Its run.
    pub run: Run,
}

/// Fits the scale on `sys`'s base model if it offers one (or takes a baseline's,
/// [`LoopOptions::noise_scale`]), leaves it set on `sys` if it pays (else set back to 1) and
/// returns it with its correction and the base run it gives.
pub fn tune<S: LoopSystem>(sys: &mut S, base: &Run, options: &LoopOptions) -> Result<Option<Tuned<S::Model>>> {
    let Some(noise) = sys.scale_noise(1.0) else { return Ok(None) };
    if options.progress {
        eprintln!("loop: fitting the process noise of {} to the data", noise.what);
    }
    let base_ll = base.log_likelihood();
    let n = base.measurements().max(2) as f64;
    let penalty = 0.5 * n.ln() + options.gain_floor * n;
    if let Some(scale) = options.noise_scale {
        // A healthy baseline's level, not refitted on a record that may carry the change.
        sys.scale_noise(scale);
        let (model, run) = sys.run(&[])?;
        let tuning = Tuning { what: noise.what, scale, delta_log_likelihood: run.log_likelihood() - base_ll, penalty };
        let correction = tuning.correction(&noise.keys);
        return Ok(Some(Tuned { tuning, correction, model, run }));
    }
    let mut eval = |x: f64| {
        sys.scale_noise(x.exp());
        sys.run(&[]).ok().map(|(_, r)| r.log_likelihood())
    };
    let best = maximise(&mut eval, -SPAN.ln(), 0.0, GRID, TOLERANCE);
    let kept = best.filter(|m| m.value - base_ll > penalty);
    let Some(m) = kept else {
        sys.scale_noise(1.0);
        return Ok(None);
    };
    sys.scale_noise(m.x.exp());
    let (model, run) = sys.run(&[])?;
    let tuning = Tuning { what: noise.what, scale: m.x.exp(), delta_log_likelihood: m.value - base_ll, penalty };
    let correction = tuning.correction(&noise.keys);
    Ok(Some(Tuned { tuning, correction, model, run }))
}
