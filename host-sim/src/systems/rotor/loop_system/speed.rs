//! The running speed read from the data, for recordings whose speed is known only nominally
//! (an induction motor slips a few per cent under load; a bearing line at a non-integer order
//! is named only if the speed is right to a fraction of a spectral bin).
//!
//! Two stages: the strongest line of the channels' spectrum within a band around the nominal
//! speed (a Hann-windowed DFT of the whole record scanned in steps of a twentieth of its
//! resolution), then the speed at which the base model's innovations are most likely (the 1×
//! phasor of the filter only stays locked to the data at the right speed), refined by Brent's
//! method within a resolution cell of the spectral estimate; the spectral estimate stands if
//! the likelihood has no maximum inside that cell.

use super::{RotorLoopOptions, RotorSystem};
use crate::io::data::DataFile;
use crate::residual_loop::optimize::maximise;
use crate::residual_loop::LoopOptions;
use crate::systems::rotor::RotorModel;
use anyhow::{bail, Result};
use serde::Serialize;
use std::f64::consts::TAU;

/// Where the running speed came from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RunningSpeed {
    /// The speed the loop used, Hz.
    pub hz: f64,
    /// The configuration's (nominal) speed, Hz.
    pub declared_hz: f64,
    /// `"config"` or `"estimated"`.
    pub source: &'static str,
    /// The spectral estimate the likelihood search started from, Hz (estimated speeds only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spectral_hz: Option<f64>,
}

impl RunningSpeed {
    /// `30.000 Hz (1800.0 rpm), from the configuration` or `29.412 Hz (…), estimated from the
    /// data (−1.96 % from the configured 30.000 Hz)`.
    pub fn describe(&self) -> String {
        let base = format!("{:.3} Hz ({:.1} rpm)", self.hz, self.hz * 60.0);
        if self.source == "config" {
            format!("{base}, from the configuration")
        } else {
            format!(
                "{base}, estimated from the data ({:+.2} % from the configured {:.3} Hz)",
                (self.hz / self.declared_hz - 1.0) * 100.0,
                self.declared_hz
            )
        }
    }
}

/// The frequency (Hz) of the strongest line in `[low, high]` Hz of the summed power of
/// `columns` sampled at `rate`, from a Hann-windowed DFT of the whole record scanned in steps
/// of `1/(20 T)` and refined by a parabola through the three highest points. `None` if the
/// band is empty or the record has no finite samples.
///
/// ```
/// use edgekf_sim::systems::rotor::loop_system::speed::strongest_line;
/// let rate = 1000.0;
/// let x: Vec<f64> = (0..2000).map(|k| (std::f64::consts::TAU * 29.37 * k as f64 / rate).sin()).collect();
/// let f = strongest_line(&[x], rate, 27.0, 33.0).unwrap();
/// assert!((f - 29.37).abs() < 0.01, "{f}");
/// ```
pub fn strongest_line(columns: &[Vec<f64>], rate: f64, low: f64, high: f64) -> Option<f64> {
    let n = columns.iter().map(Vec::len).min()?;
    if n < 8 || !(low > 0.0 && high > low && rate > 0.0) {
        return None;
    }
    let span = n as f64 / rate;
    let step = 1.0 / (20.0 * span);
    // Each channel without its mean, Hann-windowed, missing samples as 0: computed once, not
    // per frequency.
    let weighted: Vec<Vec<f64>> = columns
        .iter()
        .map(|col| {
            let finite = col[..n].iter().filter(|v| v.is_finite());
            let mean = finite.clone().sum::<f64>() / finite.count().max(1) as f64;
            (0..n)
                .map(|k| {
                    let w = 0.5 - 0.5 * (TAU * k as f64 / (n - 1) as f64).cos();
                    if col[k].is_finite() {
                        (col[k] - mean) * w
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    let power = |f: f64| -> f64 {
        let (c, s) = ((TAU * f / rate).cos(), (TAU * f / rate).sin());
        weighted
            .iter()
            .map(|x| {
                let (mut re, mut im, mut cr, mut ci) = (0.0, 0.0, 1.0f64, 0.0f64);
                for v in x {
                    re += v * cr;
                    im -= v * ci;
                    (cr, ci) = (cr * c - ci * s, ci * c + cr * s);
                }
                re * re + im * im
            })
            .sum()
    };
    let count = ((high - low) / step).floor() as usize + 1;
    let p: Vec<f64> = (0..count).map(|i| power(low + i as f64 * step)).collect();
    let (i, _) = p.iter().enumerate().filter(|(_, v)| v.is_finite()).max_by(|a, b| a.1.total_cmp(b.1))?;
    let f = low + i as f64 * step;
    if i == 0 || i + 1 == p.len() {
        return Some(f);
    }
    let (a, b, c) = (p[i - 1], p[i], p[i + 1]);
    let denom = a - 2.0 * b + c;
    let shift = if denom < 0.0 { 0.5 * (a - c) / denom } else { 0.0 };
    Some(f + shift.clamp(-0.5, 0.5) * step)
}

/// Estimates the running speed of `data` within `± band` (a fraction) of the configured
/// speed of `model`: the strongest line in that band, then the maximum-likelihood speed of the
/// base model within one spectral resolution cell of it (or the line itself if the
/// likelihood still rises at the cell's edge).
pub fn estimate_speed(
    model: &RotorModel,
    data: &DataFile,
    options: &LoopOptions,
    rotor: &RotorLoopOptions,
    band: f64,
) -> Result<RunningSpeed> {
    let declared = model.config().operation.speed;
    if !(declared > 0.0 && declared.is_finite()) {
        bail!(
            "estimating the speed needs the nominal speed in operation.speed (it searches around it), not {declared}"
        );
    }
    if !(band > 0.0 && band < 0.5) {
        bail!("the speed band must be a fraction in (0, 0.5), not {band}");
    }
    let rate = model.config().operation.sample_rate;
    let nominal_hz = declared / TAU;
    let base = RotorSystem::new(model, data, options, rotor)?;
    let spectral = strongest_line(base.columns(), rate, nominal_hz * (1.0 - band), nominal_hz * (1.0 + band))
        .ok_or_else(|| anyhow::anyhow!("no spectrum to read the speed from (too few samples?)"))?;
    let span = data.t.len() as f64 / rate;
    let cell = 1.0 / span;
    let log_likelihood = |hz: f64| {
        let at = RunningSpeed { hz, declared_hz: nominal_hz, source: "estimated", spectral_hz: None };
        RotorSystem::at_speed(model, data, options, rotor, at).and_then(|s| s.base_log_likelihood()).ok()
    };
    let best = maximise(log_likelihood, spectral - cell, spectral + cell, 4, 1e-5 * nominal_hz)
        .ok_or_else(|| anyhow::anyhow!("no speed near {spectral:.3} Hz gives a usable filter"))?;
    // A likelihood still rising at the edge of the cell is not locked to the 1× line (on a
    // real record the base model's innovations are dominated by what it lacks): the spectral
    // line, resolved to a twentieth of the cell, is the better estimate then.
    let hz = if (best.x - spectral).abs() < 0.9 * cell { best.x } else { spectral };
    Ok(RunningSpeed { hz, declared_hz: nominal_hz, source: "estimated", spectral_hz: Some(spectral) })
}
