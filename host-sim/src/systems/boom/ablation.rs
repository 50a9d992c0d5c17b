//! The paper's method taken apart: each of its steps replaced in turn by what it stands for
//! (the rate without the AR filter, the root's true angle for the lagged inclinometer, the first
//! mode's own ratio of tip deflection to tip slope for the fixed `α`, no moving average), and
//! the peak error of each, so that each step's cost is a number.

use super::beam::assemble;
use super::config::BoomConfig;
use super::modal::first_mode;
use super::peaks::{peak_errors, PeakErrors};
use super::simulate::BoomRecording;
use anyhow::{anyhow, Result};
use edgekf::systems::boom::{Ar2, PaperEstimator, PaperSettings};
use std::collections::BTreeMap;

/// What a variant changes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Ideal {
    /// The gyro less its bias, not through the AR filter.
    pub no_ar_filter: bool,
    /// The root's true angle in place of the inclinometer.
    pub true_root: bool,
    /// `α` of the first mode at the current length.
    pub mode_alpha: bool,
    /// No moving average.
    pub no_smoothing: bool,
}

/// The variants reported, in order: the method, each step replaced alone, all replaced.
pub const VARIANTS: [(&str, Ideal); 6] = [
    ("the paper's method", Ideal { no_ar_filter: false, true_root: false, mode_alpha: false, no_smoothing: false }),
    ("without the AR filter", Ideal { no_ar_filter: true, true_root: false, mode_alpha: false, no_smoothing: false }),
    (
        "the true root angle for the inclinometer",
        Ideal { no_ar_filter: false, true_root: true, mode_alpha: false, no_smoothing: false },
    ),
    (
        "α of the first mode for 2/3",
        Ideal { no_ar_filter: false, true_root: false, mode_alpha: true, no_smoothing: false },
    ),
    (
        "without the moving average",
        Ideal { no_ar_filter: false, true_root: false, mode_alpha: false, no_smoothing: true },
    ),
    ("all four", Ideal { no_ar_filter: true, true_root: true, mode_alpha: true, no_smoothing: true }),
];

/// The first mode's `w(L) / (L w'(L))` at `length` (the angle of the run's start).
fn mode_alpha(config: &BoomConfig, length: f64) -> Result<f64> {
    let b = assemble(config, length);
    let (_, shape) = first_mode(&b, config.boom.gravity, config.runs.start_angle)?;
    Ok(shape[b.tip()] / (length * shape[b.tip() + 1]))
}

/// The paper's method on `rec` with `ideal`'s replacements.
pub fn run_variant(config: &BoomConfig, rec: &BoomRecording, ar: Ar2, ideal: Ideal) -> Result<Vec<f64>> {
    let col = |n: &str| rec.column(n).ok_or_else(|| anyhow!("the recording has no `{n}`"));
    let (gyro, length) = (col("gyro_rate")?, col("boom_length")?);
    let root = if ideal.true_root { col("truth_root_angle")? } else { col("incl_angle")? };
    // The true root has no lag to take out.
    let lag = if ideal.true_root { 0.0 } else { config.inclinometer.lag };
    let mut settings = PaperSettings::new(1.0 / config.gyro.sample_rate, ar, config.gyro.scale, lag);
    settings.ar_filter = !ideal.no_ar_filter;
    if ideal.no_smoothing {
        settings.smoothing = 1;
    }
    let mut est = PaperEstimator::<f64>::new(&settings);
    let mut alphas = BTreeMap::new();
    let mut out = Vec::with_capacity(rec.t.len());
    for k in 0..rec.t.len() {
        let alpha = if ideal.mode_alpha {
            let key = (length[k] * 10.0).round() as i64;
            match alphas.get(&key) {
                Some(a) => *a,
                None => {
                    let a = mode_alpha(config, key as f64 / 10.0)?;
                    alphas.insert(key, a);
                    a
                }
            }
        } else {
            settings.alpha
        };
        out.push(est.step_with(gyro[k], root[k], length[k], alpha).vibration);
    }
    Ok(out)
}

/// Every variant of [`VARIANTS`] on `rec`, with its peak errors.
pub fn ablation(config: &BoomConfig, rec: &BoomRecording, ar: Ar2) -> Result<Vec<(&'static str, PeakErrors)>> {
    let truth = rec.column("truth_tip_vibration").ok_or_else(|| anyhow!("the recording has no truth"))?;
    let rate = rec.column("truth_root_rate").ok_or_else(|| anyhow!("the recording has no truth"))?;
    VARIANTS
        .iter()
        .map(|(name, ideal)| Ok((*name, peak_errors(&rec.t, &run_variant(config, rec, ar, *ideal)?, truth, rate))))
        .collect()
}
