//! A score test of the declared settings. The search looks for effects while the innovations
//! fail a generic test (whiteness, bias, NIS); a declared setting can be off by several times
//! what the data can tell and still leave innovations that pass every generic test (a worn
//! part shifts the response within the noise's own spectrum). So once the innovations look
//! consistent, each declared setting is moved by one tolerance (one run): the change of the
//! innovations is their sensitivity, which gives the log-likelihood's slope and the setting's
//! Fisher information (Gauss–Newton), and so the gain a fit could make. A setting that
//! promises more than its cost is fitted in full like any candidate, and the same acceptance
//! rule decides.

use super::filter::Run;
use super::fit::Engine;
use super::system::Described;
use super::vocabulary::Applied;
use super::LoopSystem;
use rayon::prelude::*;

impl<S: LoopSystem> Engine<'_, S> {
    /// The declared settings with a scalar, not yet in the model (`effects`), whose fit
    /// promises more than its cost on `base` (the current model's run): the peak of
    /// `g θ − I θ² / 2` within the range the setting may take, from the slope
    /// `g = −Σ ν ∂ν/∂θ / s` and information `I = Σ (∂ν/∂θ)² / s` over every channel and sample
    /// (`s` the innovation's variance, `∂ν/∂θ` from one run a tolerance away).
    pub(super) fn declared_worth_fitting(&self, effects: &[Applied<S::Effect>], base: &Run) -> Vec<S::Effect> {
        let fresh: Vec<S::Effect> =
            self.sys.declared().into_iter().filter(|e| !effects.iter().any(|x| x.effect == *e)).collect();
        let promising: Vec<bool> = fresh
            .par_iter()
            .map(|e| {
                let Some((range, _)) = self.sys.fitting(e).scalar else { return false };
                let h = range.tolerance.max(1e-9);
                let step = if range.neutral + h <= range.high { h } else { -h };
                if range.neutral + step < range.low {
                    return false;
                }
                let mut with = effects.to_vec();
                with.push(Applied::new(*e, range.neutral + step));
                let Ok((_, moved)) = self.sys.run(&with) else { return false };
                let (slope, information) = slope_and_information(base, &moved, step);
                // The quadratic's peak, or its value at the end of the range it may take.
                let best = (slope / information).clamp(range.low - range.neutral, range.high - range.neutral);
                information > 0.0 && slope * best - 0.5 * information * best * best > self.penalty(e, false)
            })
            .collect();
        fresh.into_iter().zip(promising).filter(|(_, p)| *p).map(|(e, _)| e).collect()
    }
}

/// The log-likelihood's slope `g` and the Fisher information `I` of one scalar at `base`, from
/// `moved` (the same model with the scalar moved by `step`), by Gauss–Newton on the
/// innovations: near the declared value the log-likelihood is `g θ − I θ² / 2`.
fn slope_and_information(base: &Run, moved: &Run, step: f64) -> (f64, f64) {
    let (mut slope, mut information) = (0.0, 0.0);
    for ((v0, v1), s) in base.innovation.iter().zip(&moved.innovation).zip(&base.variance) {
        for ((a, b), s) in v0.iter().zip(v1).zip(s) {
            if a.is_finite() && b.is_finite() && s.is_finite() && *s > 0.0 {
                let d = (b - a) / step;
                slope -= a * d / s;
                information += d * d / s;
            }
        }
    }
    (slope, information)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Innovations `ν(θ) = ν₀ − θ d` with unit variance: the log-likelihood is
    /// `−½ Σ (ν₀ − θ d)²`, whose slope at 0 is `Σ ν₀ d` and curvature `Σ d²`.
    #[test]
    fn the_slope_and_information_are_those_of_linear_innovations() {
        let d = [0.5, -1.0, 2.0, 0.25];
        let nu0 = [1.0, 0.3, -0.2, 0.8];
        let run = |theta: f64| Run {
            innovation: vec![nu0.iter().zip(&d).map(|(n, d)| n - theta * d).collect()],
            variance: vec![vec![1.0; 4]],
            ..Run::default()
        };
        let (g, i) = slope_and_information(&run(0.0), &run(0.01), 0.01);
        let want_g: f64 = nu0.iter().zip(&d).map(|(n, d)| n * d).sum();
        let want_i: f64 = d.iter().map(|d| d * d).sum();
        assert!((g - want_g).abs() < 1e-12 && (i - want_i).abs() < 1e-12, "{g} {i}");
    }
}
