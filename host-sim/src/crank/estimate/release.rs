//! Second stage of the fast estimator: the clearance from the release transient.
//!
//! The mechanism is released at rest with every journal centred in its bearing, so the journal
//! of the clearance joint first flies freely across the clearance: the first impact comes after
//! `t₁ ≈ √(2c / a)`, `a` the relative acceleration of journal and bearing at release (g at A
//! from 30°: 0.25 mm gives 7.1 ms, 0.1 mm 4.5 ms). That flight happens before any impact, so
//! it is not chaotic: any simulator of the mechanism, or the mechanism itself, gives the same
//! `t₁` for the same clearance and release, whatever impact sequence follows. `a` depends on
//! the release angle, which the crank acceleration before the first impact gives (−79, −27 and
//! +12 rad/s² at 20°, 30° and 40° with a clearance at A).
//!
//! Features ([`release_features`], on the first 0.1 s only, ~5 operations per sample): the
//! sample of the first jump of `|Δα|` above 12 × its median over the first 0.1 s (the impact),
//! the gap to the next one (the rebound's flight), and the mean α before the first. The model
//! ([`ReleaseModel`]) is, per joint, a least-squares fit of `ln c` on
//! `1, l, l², u, u², l·u, g` with `l = ln(t₁ / 5 ms)`, `u = α₀ / 100 rad/s²`,
//! `g = ln(gap / 5 ms)`; it refines the first stage's estimate of the named joint when the
//! two agree within [`ReleaseModel::max_step`] (in `ln c`), and leaves it alone otherwise.
//! The timing is read to one sample (0.1 ms at 10 kHz), which bounds what it can give: ±2 %
//! of `c` at 0.25 mm and ±2.2 % at 0.1 mm from the first impact alone.
//!
//! The recording must start at release (as the paper's experiment and the UKF assume).
//!
//! Status: experimental, off in the built-in model (`edgekf crank train --release-stage` fits
//! it). On the 264 training runs, `2c / t₁²` is 9–11 m/s² at A for most runs (free fall, as
//! expected), but the detector sometimes takes a later impact for the first (a soft first
//! contact, or at C, whose impacts barely show in the crank's acceleration), and the second
//! gap is already irregular; with this stage the training-set error rose from RMS 7.3 % to
//! 8.3 % (worst 36 %). A detector that finds the first contact reliably (e.g. a matched
//! filter on the pre-impact level) is what it needs.

use super::train::Run;
use crate::crank::Joint;
use serde::{Deserialize, Serialize};

/// Number of regressors of [`ReleaseModel`].
pub const RELEASE_TERMS: usize = 7;

/// Length of the transient examined, s.
pub const RELEASE_SPAN: f64 = 0.1;

/// What the release transient shows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReleaseFeatures {
    /// Time of the first impact after release, s.
    pub first_impact: f64,
    /// Time from the first impact to the next, s.
    pub second_gap: f64,
    /// Mean crank acceleration before the first impact, rad/s².
    pub release_alpha: f64,
}

/// The release features of `x` (sampled at `rate` Hz from the release on); `None` if the
/// first 0.1 s hold fewer than two impacts.
pub fn release_features(x: &[f64], rate: f64) -> Option<ReleaseFeatures> {
    let n = ((RELEASE_SPAN * rate).round() as usize).min(x.len());
    if n < 16 {
        return None;
    }
    let mut d: Vec<f64> = x[..n].windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    let mid = d.len() / 2;
    let median = *d.select_nth_unstable_by(mid, f64::total_cmp).1;
    let thr = 12.0 * median.max(1e-9);
    // Onsets: |Δα| above the threshold after at least 3 samples below it.
    let mut onsets = Vec::with_capacity(2);
    let mut quiet = 3usize;
    for k in 1..n {
        if (x[k] - x[k - 1]).abs() > thr {
            if quiet >= 3 {
                onsets.push(k);
                if onsets.len() == 2 {
                    break;
                }
            }
            quiet = 0;
        } else {
            quiet += 1;
        }
    }
    let (k1, k2) = (*onsets.first()?, *onsets.get(1)?);
    let release_alpha = x[..k1].iter().sum::<f64>() / k1 as f64;
    Some(ReleaseFeatures { first_impact: (k1 as f64 - 0.5) / rate, second_gap: (k2 - k1) as f64 / rate, release_alpha })
}

/// Regressors `1, l, l², u, u², l·u, g` of [`ReleaseModel`].
pub fn release_regressor(f: &ReleaseFeatures) -> [f64; RELEASE_TERMS] {
    let l = (f.first_impact / 5e-3).ln();
    let u = f.release_alpha / 100.0;
    let g = (f.second_gap / 5e-3).ln();
    [1.0, l, l * l, u, u * u, l * u, g]
}

/// The second stage: per joint, `ln c` from the release features.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReleaseModel {
    /// Largest `|ln c₂ − ln c₁|` between the first stage's estimate and this one for which this
    /// one is used.
    pub max_step: f64,
    /// Per joint A, B, C: weights on [`release_regressor`].
    pub weights: Vec<Vec<f64>>,
}

impl ReleaseModel {
    /// Checks the numbers.
    pub fn validate(&self) -> Result<(), String> {
        if self.weights.len() != 3 || self.weights.iter().any(|w| w.len() != RELEASE_TERMS) {
            return Err(format!("release.weights needs 3 rows of {RELEASE_TERMS}"));
        }
        if !(self.max_step.is_finite() && self.max_step > 0.0) || self.weights.iter().flatten().any(|v| !v.is_finite())
        {
            return Err("release: every number must be finite, max_step positive".into());
        }
        Ok(())
    }

    /// `ln c` of `joint` from the release features.
    pub fn ln_clearance(&self, joint: Joint, f: &ReleaseFeatures) -> f64 {
        let r = release_regressor(f);
        self.weights[joint.index()].iter().zip(r).map(|(w, r)| w * r).sum()
    }

    /// The refined clearance of `joint` given the first stage's `first` (m), or `None` when the
    /// two disagree by more than [`ReleaseModel::max_step`].
    pub fn refine(&self, joint: Joint, first: f64, f: &ReleaseFeatures) -> Option<f64> {
        let l = self.ln_clearance(joint, f);
        (l.is_finite() && (l - first.ln()).abs() <= self.max_step).then(|| l.exp())
    }

    /// Least-squares fit per joint on the runs with release features (runs are labelled by
    /// their joint); `max_step` as given.
    pub fn fit(runs: &[Run], feats: &[Option<ReleaseFeatures>], max_step: f64) -> Self {
        use nalgebra::{DMatrix, DVector};
        let weights = Joint::ALL
            .iter()
            .map(|&j| {
                let rows: Vec<(Vec<f64>, f64)> = runs
                    .iter()
                    .zip(feats)
                    .filter(|(r, f)| r.joint == j && f.is_some())
                    .map(|(r, f)| (release_regressor(f.as_ref().expect("filtered")).to_vec(), r.clearance.ln()))
                    .collect();
                if rows.len() < RELEASE_TERMS {
                    return vec![0.0; RELEASE_TERMS];
                }
                let x = DMatrix::from_fn(rows.len(), RELEASE_TERMS, |i, c| rows[i].0[c]);
                let y = DVector::from_iterator(rows.len(), rows.iter().map(|r| r.1));
                let mut a = x.transpose() * &x;
                for i in 1..RELEASE_TERMS {
                    a[(i, i)] += 1e-9 * rows.len() as f64;
                }
                let w = a.lu().solve(&(x.transpose() * y)).unwrap_or_else(|| DVector::zeros(RELEASE_TERMS));
                w.iter().copied().collect()
            })
            .collect();
        Self { max_step, weights }
    }

    /// The model as a TOML table `[release]`.
    pub fn to_toml(&self) -> String {
        let list = |v: &[f64]| format!("[{}]", v.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", "));
        let rows = self.weights.iter().map(|w| format!("    {},\n", list(w))).collect::<String>();
        format!(
            "\n# Second stage (release transient): rows A, B, C, weights on 1, l, l², u, u², l·u, g\n[release]\nmax_step = {:?}\nweights = [\n{rows}]\n",
            self.max_step
        )
    }
}
