//! Second stage of the fast estimator, on the host: fitting the release-transient laws of
//! [`edgekf::systems::crank::ReleaseModel`] (the detector, the laws and their use are the chip's
//! code, in `edgekf::systems::crank`, whose module text explains the physics).
//!
//! Training labels each run with the hypothesis that is true for it: how many contacts the
//! sampled recording missed before the one detected. The simulator knows: the journal's
//! eccentricity rises monotonically from the centre until the first contact, and every contact
//! turns it back. So the number of rise-to-fall turns of the sampled eccentricity before the
//! detected sample is the number of contacts missed ([`missed_contacts`]).
//!
//! The laws need only the first [`RELEASE_SPAN`] of a run, so they are trained on their own
//! grid of short runs ([`super::train::release_grid`]), many more than the window features' 10 s
//! runs: 1 080 runs of 0.1 s cost less than one 10 s run per joint and clearance.

use super::runs::Run;
use crate::systems::crank::Joint;
use edgekf::systems::crank::{release_regressors, ReleaseModel, RELEASE_HYPOTHESES, RELEASE_TERMS};
use serde::{Deserialize, Serialize};

pub use edgekf::systems::crank::{ReleaseFeatures, RELEASE_SPAN};

/// Contacts missed before the detected one (sample `detected`), from the journal's sampled
/// eccentricity `e` (m) at the clearance joint of clearance `c`: the rise-to-fall turns of `e`
/// before that sample (a fall by more than 0.1 % of `c` counts; the rise from the centre has
/// none).
///
/// ```
/// use edgekf_sim::systems::crank::estimate::release::missed_contacts;
/// let rise = [0.0, 1e-5, 4e-5, 9e-5, 1.6e-4];
/// assert_eq!(missed_contacts(&rise, 2e-4, 4), 0);
/// let bounced = [0.0, 4e-5, 1.6e-4, 1.9e-4, 1.7e-4, 1.8e-4, 2e-4];
/// assert_eq!(missed_contacts(&bounced, 2e-4, 6), 1);
/// ```
pub fn missed_contacts(e: &[f64], c: f64, detected: usize) -> usize {
    let tol = 1e-3 * c;
    // Rising: `extreme` is the peak so far; falling: the trough so far.
    let (mut turns, mut rising, mut extreme) = (0, true, f64::NEG_INFINITY);
    for &v in e.iter().take(detected) {
        if rising && v < extreme - tol {
            turns += 1;
            rising = false;
        } else if !rising && v > extreme + tol {
            rising = true;
        }
        extreme = if rising { extreme.max(v) } else { extreme.min(v) };
    }
    turns
}

/// Margin on the training runs' range of pre-contact levels, rad/s²: about 4 standard
/// deviations of the level's noise at 5 rad/s² over the ~40 samples before the first contact.
pub const LEVEL_MARGIN: f64 = 4.0;

/// The fit of one release law ([`ReleaseStage::residuals`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawFit {
    /// Its joint.
    pub joint: Joint,
    /// Its hypothesis (contacts missed before the one seen).
    pub hypothesis: usize,
    /// Runs it was fitted to.
    pub runs: usize,
    /// RMS residual of `ln c`.
    pub rms: f64,
    /// Largest absolute residual of `ln c`.
    pub largest: f64,
}

/// The second stage as stored in a model file: [`ReleaseModel`] in `f64`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReleaseStage {
    /// Largest `|ln c₂ − ln c₁|` between the window features' estimate and a release law's for
    /// which the law is taken.
    pub max_step: f64,
    /// Standard deviation of the window features' `ln c` (the training set's RMS error).
    pub spread: f64,
    /// Windows of the training recordings `spread` was measured on (fewer windows widen it).
    pub windows: f64,
    /// Per joint A, B, C: the centre of the pre-contact level, rad/s².
    pub centre: Vec<f64>,
    /// Per joint A, B, C: the range of pre-contact levels the laws hold for, rad/s² (the
    /// training runs' range widened by [`LEVEL_MARGIN`]).
    pub level: Vec<[f64; 2]>,
    /// Per joint A, B, C, per hypothesis: the natural logarithm of its prior probability (its
    /// share of the training runs, with one run added to every hypothesis).
    pub prior: Vec<Vec<f64>>,
    /// Per joint A, B, C, per hypothesis (first contact seen, second, third, fourth): weights on
    /// `1, l, u, u², u³, l·u`.
    pub weights: Vec<Vec<Vec<f64>>>,
}

impl ReleaseStage {
    /// Checks the shapes and numbers.
    pub fn validate(&self) -> Result<(), String> {
        let shape = self.centre.len() == 3
            && self.level.len() == 3
            && self.level.iter().all(|[lo, hi]| lo <= hi)
            && self.prior.len() == 3
            && self.prior.iter().all(|p| p.len() == RELEASE_HYPOTHESES)
            && self.weights.len() == 3
            && self.weights.iter().all(|j| j.len() == RELEASE_HYPOTHESES && j.iter().all(|w| w.len() == RELEASE_TERMS));
        if !shape {
            return Err(format!(
                "release: centre needs 3 values, level 3 ranges [low, high], prior 3 rows of {RELEASE_HYPOTHESES}, weights 3 × {RELEASE_HYPOTHESES} rows of {RELEASE_TERMS}"
            ));
        }
        let all = self
            .weights
            .iter()
            .flatten()
            .flatten()
            .chain(&self.centre)
            .chain(self.prior.iter().flatten())
            .chain(self.level.iter().flatten());
        let ok = self.max_step.is_finite()
            && self.max_step >= 0.0
            && self.spread.is_finite()
            && self.spread > 0.0
            && self.windows.is_finite()
            && self.windows >= 1.0
            && all.clone().all(|v| v.is_finite());
        if !ok {
            return Err("release: every number must be finite, max_step not negative, spread positive".into());
        }
        Ok(())
    }

    /// The chip's form.
    pub fn to_shared(&self) -> ReleaseModel<f64> {
        let mut m = ReleaseModel::off();
        m.max_step = self.max_step;
        m.spread = self.spread;
        m.windows = self.windows;
        for j in 0..3 {
            m.centre[j] = self.centre[j];
            m.level[j] = self.level[j];
            for h in 0..RELEASE_HYPOTHESES {
                m.prior[j][h] = self.prior[j][h];
                for (w, v) in m.weights[j][h].iter_mut().zip(&self.weights[j][h]) {
                    *w = *v;
                }
            }
        }
        m
    }

    /// Least squares per joint and hypothesis on labelled runs (`labels[i]`: contacts missed
    /// before the detected one, [`missed_contacts`]); runs without release features or with
    /// a label beyond the hypotheses are left out. A law with fewer than `2 × RELEASE_TERMS`
    /// runs is all zeros and never taken (its `ln c` of 0 is 1 m, outside every step).
    /// `spread`: the window features' error in `ln c` on recordings of `windows` windows.
    pub fn fit(
        runs: &[Run],
        feats: &[Option<ReleaseFeatures<f64>>],
        labels: &[usize],
        max_step: f64,
        (spread, windows): (f64, f64),
    ) -> Self {
        use nalgebra::{DMatrix, DVector};
        let mut centre = vec![0.0; 3];
        let mut level = vec![[0.0; 2]; 3];
        let mut weights = vec![vec![vec![0.0; RELEASE_TERMS]; RELEASE_HYPOTHESES]; 3];
        let mut prior = vec![vec![0.0; RELEASE_HYPOTHESES]; 3];
        for joint in Joint::ALL {
            let j = joint.index();
            let of_joint: Vec<usize> =
                runs.iter().zip(labels).filter(|(r, _)| r.joint == joint).map(|(_, &l)| l).collect();
            for (h, p) in prior[j].iter_mut().enumerate() {
                let n = of_joint.iter().filter(|&&l| l == h).count();
                *p = ((n + 1) as f64 / (of_joint.len() + RELEASE_HYPOTHESES) as f64).ln();
            }
            let levels: Vec<f64> = runs
                .iter()
                .zip(feats)
                .filter(|(r, _)| r.joint == joint)
                .filter_map(|(_, f)| f.map(|f| f.release_alpha))
                .collect();
            centre[j] = levels.iter().sum::<f64>() / levels.len().max(1) as f64;
            let (lo, hi) = levels.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
            level[j] = if lo <= hi { [lo - LEVEL_MARGIN, hi + LEVEL_MARGIN] } else { [0.0, 0.0] };
            for (h, law) in weights[j].iter_mut().enumerate() {
                let rows: Vec<([f64; RELEASE_TERMS], f64)> = runs
                    .iter()
                    .zip(feats)
                    .zip(labels)
                    .filter(|((r, _), &l)| r.joint == joint && l == h)
                    .filter_map(|((r, f), _)| f.map(|f| (release_regressors(&f, centre[j]), r.clearance.ln())))
                    .collect();
                if rows.len() < 2 * RELEASE_TERMS {
                    continue;
                }
                let x = DMatrix::from_fn(rows.len(), RELEASE_TERMS, |i, c| rows[i].0[c]);
                let y = DVector::from_iterator(rows.len(), rows.iter().map(|r| r.1));
                if let Some(w) = (x.transpose() * &x).lu().solve(&(x.transpose() * y)) {
                    *law = w.iter().copied().collect();
                }
            }
        }
        Self { max_step, spread, windows, centre, level, prior, weights }
    }

    /// How well each law fits the runs it was fitted to (labelled as for [`ReleaseStage::fit`]).
    pub fn residuals(&self, runs: &[Run], feats: &[Option<ReleaseFeatures<f64>>], labels: &[usize]) -> Vec<LawFit> {
        let model = self.to_shared();
        let mut out = Vec::new();
        for joint in Joint::ALL {
            for hypothesis in 0..RELEASE_HYPOTHESES {
                if self.weights[joint.index()][hypothesis].iter().all(|w| *w == 0.0) {
                    continue;
                }
                let r: Vec<f64> = runs
                    .iter()
                    .zip(feats)
                    .zip(labels)
                    .filter(|((r, _), &l)| r.joint == joint && l == hypothesis)
                    .filter_map(|((r, f), _)| {
                        f.map(|f| model.ln_clearances(joint.index(), &f)[hypothesis] - r.clearance.ln())
                    })
                    .collect();
                let rms = (r.iter().map(|e| e * e).sum::<f64>() / r.len().max(1) as f64).sqrt();
                let largest = r.iter().fold(0.0_f64, |m, e| m.max(e.abs()));
                out.push(LawFit { joint, hypothesis, runs: r.len(), rms, largest });
            }
        }
        out
    }

    /// The stage as a TOML table `[release]`.
    pub fn to_toml(&self) -> String {
        let list = |v: &[f64]| format!("[{}]", v.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", "));
        let joints = self
            .weights
            .iter()
            .map(|j| format!("    [{}],\n", j.iter().map(|w| list(w)).collect::<Vec<_>>().join(", ")))
            .collect::<String>();
        let level = format!("[{}]", self.level.iter().map(|r| list(r)).collect::<Vec<_>>().join(", "));
        format!(
            "\n# Second stage (release transient): per joint A, B, C the pre-contact level's centre\n# and, per hypothesis (first contact seen, second, third, fourth), ln prior and weights on\n# 1, l, u, u², u³, l·u\n[release]\nmax_step = {:?}\nspread = {:?}\nwindows = {:?}\ncentre = {}\nlevel = {}\nprior = [\n{}]\nweights = [\n{joints}]\n",
            self.max_step,
            self.spread,
            self.windows,
            list(&self.centre),
            level,
            self.prior.iter().map(|p| format!("    {},\n", list(p))).collect::<String>()
        )
    }
}
