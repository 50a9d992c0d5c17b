//! The multi-feature fast estimator: which joint has the clearance, and how large it is, from
//! ten features of the crank angular acceleration, with no simulation at run time.
//!
//! * [`feature_vector`]: per 0.25 s window, cheap time-domain statistics (levels of α, of its
//!   first and second differences and of a high-pass residual, kurtoses, impact rate, impact
//!   peak and width), averaged over the windows and taken in logarithms;
//! * [`FastModel`]: standardised features → a linear discriminant per joint (the largest names
//!   the joint) and a ridge regression per joint for `ln c`, refined by the release stage
//!   ([`super::release`]: the first contact after release, `c ∝ t₁²`). Learned by [`super::train`]
//!   (`edgekf crank train --out model.toml`); the built-in model ([`FastModel::builtin`]) is
//!   `fast_model.toml` next to this file, written by that command with its defaults
//!   (`edgekf crank train --out host-sim/src/systems/crank/estimate/fast_model.toml`: 264 runs of 10 s,
//!   about 3 minutes on two cores in release).

use super::release::{ReleaseFeatures, ReleaseStage};
use super::trained_for::TrainedFor;
use super::{EstimateRow, Recording};
use crate::systems::crank::Joint;
use edgekf::systems::crank::{ReleaseDetector, MIN_FIT, RELEASE_HYPOTHESES, RELEASE_TERMS};
use serde::{Deserialize, Serialize};

pub use edgekf::systems::crank::{FEATURES, FEATURE_NAMES};

/// Arithmetic operations per sample counted for [`feature_vector`], before the median: about
/// 4 for the differences, 3 for the 8-sample box filter, 3 + 3 + 3 + 3 for the four sums of
/// squares, 2 + 2 for the two fourth powers, 3 for the impact detector.
pub const OPS_PER_SAMPLE: u64 = 29;

/// The feature vector of a recording.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeatureVector {
    /// The features ([`FEATURE_NAMES`]).
    pub values: [f64; FEATURES],
    /// Windows averaged.
    pub windows: usize,
    /// Arithmetic operations spent (per sample [`OPS_PER_SAMPLE`] plus the median of `|Δα|`
    /// by quickselect, ~3 comparisons per sample; plus [`RELEASE_OPS_PER_SAMPLE`] per sample
    /// of the release detector until the contact).
    pub operations: u64,
    /// The release transient's features ([`super::release`]), if a contact was seen.
    pub release: Option<ReleaseFeatures<f64>>,
    /// Training truth, not a feature: contacts the sampled recording missed before the one
    /// the release detector saw ([`super::release::missed_contacts`]); `None` when unknown.
    pub missed: Option<usize>,
}

/// Latest first sample, s after release, that [`FastModel::estimate`] corrects the release
/// stage's contact time for.
pub const MAX_FIRST_SAMPLE: f64 = 0.002;

/// Moves the contact time by the file's first `t` if that is a little after release
/// (`0 < t₀ <` [`MAX_FIRST_SAMPLE`]): the detector counts samples from the first one.
fn shift_to_release(release: &mut Option<ReleaseFeatures<f64>>, rec: &Recording) {
    let t0 = rec.t.first().copied().unwrap_or(0.0);
    if let Some(r) = release.as_mut().filter(|_| t0 > 0.0 && t0 < MAX_FIRST_SAMPLE) {
        r.contact += t0;
    }
}

/// Arithmetic operations per sample of the release detector while it looks for the contact:
/// 12 for the sums, 30 for the 3 × 3 solve, residual and threshold.
pub const RELEASE_OPS_PER_SAMPLE: u64 = 42;

/// Features of `x` sampled at `rate` Hz, from windows of `window_s` (a trailing partial window
/// is dropped). `windows == 0` if `x` is shorter than one window.
///
/// The computation is the chip's ([`edgekf::systems::crank::CrankFeatures`], streaming, one sample
/// at a time) in `f64`: one implementation for the host, the training and the firmware. A
/// missing sample (NaN) is skipped by the window statistics (a window closes after `n` usable
/// samples) and its time is counted by the release detector, as on the node.
pub fn feature_vector(x: &[f64], rate: f64, window_s: f64) -> FeatureVector {
    let n = edgekf::systems::crank::window_samples(window_s, rate);
    let Ok(mut f) = edgekf::systems::crank::CrankFeatures::new(vec![0.0; n.saturating_sub(1)], n, rate) else {
        return FeatureVector {
            values: [1e-12f64.ln(); FEATURES],
            windows: 0,
            operations: 0,
            release: None,
            missed: None,
        };
    };
    let mut detector = ReleaseDetector::<f64>::new(rate);
    for &v in x {
        f.push(v);
        detector.push(v);
    }
    let windows = f.windows() as usize;
    let release = detector.features();
    let release_ops = RELEASE_OPS_PER_SAMPLE * (detector.examined() as u64).saturating_sub(MIN_FIT as u64);
    FeatureVector {
        values: f.features(),
        windows,
        operations: (OPS_PER_SAMPLE + 3) * (windows * n) as u64 + release_ops,
        release,
        missed: None,
    }
}

/// Regressor `c` of standardised features `z`: 1, then `z₁ … z_F`, then `z₁² … z_F²`.
pub fn regressor(z: &[f64], c: usize) -> f64 {
    match c {
        0 => 1.0,
        c if c <= FEATURES => z[c - 1],
        c => z[c - 1 - FEATURES].powi(2),
    }
}

/// The learned map: standardisation, one linear discriminant and one regression per joint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FastModel {
    /// What it was trained on (free text).
    pub trained_on: String,
    /// Window length of the features, s.
    pub window: f64,
    /// Feature names, must equal [`FEATURE_NAMES`].
    pub features: Vec<String>,
    /// Feature means of the training set (standardisation).
    pub mean: Vec<f64>,
    /// Feature standard deviations of the training set.
    pub scale: Vec<f64>,
    /// Per joint A, B, C: `[bias, w₁ … w_F]` of the discriminant score on standardised
    /// features; the largest score names the joint.
    pub discriminant: Vec<Vec<f64>>,
    /// Per joint A, B, C: `[bias, w₁ … w_F]` of `ln(clearance / m)` on standardised features,
    /// optionally followed by `F` weights on their squares ([`regressor`]).
    pub regression: Vec<Vec<f64>>,
    /// Second stage from the release transient ([`super::release`]); absent in older files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub release: Option<ReleaseStage>,
    /// The mechanism and sensor it was trained for ([`super::trained_for`]); absent in older
    /// files, which are then not checked.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trained_for: Option<TrainedFor>,
}

/// Result of [`FastModel::estimate`].
#[derive(Debug, Clone, PartialEq)]
pub struct ModelEstimate {
    /// The joint judged to have the clearance.
    pub joint: Joint,
    /// Clearances A, B, C, m: the estimate at `joint`, 0 at the others.
    pub clearance: [f64; 3],
    /// Discriminant scores of A, B, C.
    pub scores: [f64; 3],
    /// The clearance each joint's regression gives (m), whichever joint is named.
    pub per_joint: [f64; 3],
    /// The features.
    pub features: FeatureVector,
    /// The release law's hypothesis that gave the clearance (0: the first contact was seen,
    /// 1: the second, 2: the third), or `None` where the window features gave it.
    pub release: Option<usize>,
    /// Arithmetic operations: features plus the model (at most `12 (F + 1)` and 3 exp of ~20).
    pub operations: u64,
}

impl ModelEstimate {
    /// The last row of the estimate file: the whole recording.
    pub fn row(&self, rec: &Recording) -> EstimateRow {
        EstimateRow { t: rec.t.last().copied().unwrap_or(0.0), clearance: self.clearance }
    }
}

/// The built-in model, written by `edgekf crank train --out host-sim/src/systems/crank/estimate/fast_model.toml`.
pub const BUILTIN_MODEL: &str = include_str!("fast_model.toml");

impl FastModel {
    /// The built-in model ([`BUILTIN_MODEL`]).
    pub fn builtin() -> Self {
        Self::from_toml_str(BUILTIN_MODEL).expect("the built-in fast model is valid")
    }

    /// Parses and checks a model.
    pub fn from_toml_str(text: &str) -> anyhow::Result<Self> {
        let m: Self = crate::io::config::parse_toml(text)?;
        m.validate().map_err(|e| anyhow::anyhow!(e))?;
        Ok(m)
    }

    /// Reads a model file.
    pub fn load(path: &std::path::Path) -> anyhow::Result<Self> {
        let text =
            std::fs::read_to_string(path).map_err(|e| anyhow::anyhow!("{}: cannot read: {e}", path.display()))?;
        Self::from_toml_str(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
    }

    /// The model as TOML.
    pub fn to_toml(&self) -> String {
        // Written by hand (the crate's toml has no serialiser); `{:?}` of an f64 is its shortest
        // round-trip form, valid TOML.
        let list = |v: &[f64]| format!("[{}]", v.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", "));
        let rows =
            |r: &[Vec<f64>]| format!("[\n{}]", r.iter().map(|w| format!("    {},\n", list(w))).collect::<String>());
        let names = self.features.iter().map(|n| format!("{n:?}")).collect::<Vec<_>>().join(", ");
        format!(
            "# edgekf crank fast model: written by `edgekf crank train`.\ntrained_on = {:?}\nwindow = {:?}\nfeatures = [{names}]\nmean = {}\nscale = {}\n# rows A, B, C: [bias, weights on the standardised features]\ndiscriminant = {}\nregression = {}\n",
            self.trained_on,
            self.window,
            list(&self.mean),
            list(&self.scale),
            rows(&self.discriminant),
            rows(&self.regression)
        ) + &self.release.as_ref().map_or(String::new(), ReleaseStage::to_toml)
            + &self.trained_for.as_ref().map_or(String::new(), TrainedFor::to_toml)
    }

    fn validate(&self) -> Result<(), String> {
        if self.features.len() != FEATURES || self.features.iter().zip(FEATURE_NAMES).any(|(a, b)| a != b) {
            return Err(format!("features must be {FEATURE_NAMES:?}"));
        }
        let rows_ok = |r: &Vec<Vec<f64>>, squares: bool| {
            r.len() == 3 && r.iter().all(|w| w.len() == FEATURES + 1 || (squares && w.len() == 2 * FEATURES + 1))
        };
        if self.mean.len() != FEATURES
            || self.scale.len() != FEATURES
            || !rows_ok(&self.discriminant, false)
            || !rows_ok(&self.regression, true)
        {
            return Err(format!(
                "mean and scale need {FEATURES} values, discriminant 3 rows of {}, regression 3 rows of {} or {} (with squares)",
                FEATURES + 1,
                FEATURES + 1,
                2 * FEATURES + 1
            ));
        }
        let all = self
            .mean
            .iter()
            .chain(&self.scale)
            .chain(self.discriminant.iter().flatten())
            .chain(self.regression.iter().flatten());
        if !all.clone().all(|v| v.is_finite()) || self.scale.iter().any(|s| *s <= 0.0) {
            return Err("every coefficient must be finite and every scale positive".into());
        }
        if !(self.window.is_finite() && self.window > 0.0) {
            return Err(format!("window {} s must be positive", self.window));
        }
        if let Some(r) = &self.release {
            r.validate()?;
        }
        Ok(())
    }

    /// Standardised features.
    pub fn standardise(&self, f: &[f64; FEATURES]) -> [f64; FEATURES] {
        let mut z = [0.0; FEATURES];
        for i in 0..FEATURES {
            z[i] = (f[i] - self.mean[i]) / self.scale[i];
        }
        z
    }

    /// Joint and clearance from a feature vector (the shared crate's
    /// [`edgekf::systems::crank::ClearanceModel::estimate`], the chip's code, in `f64`).
    pub fn estimate_features(&self, f: FeatureVector) -> ModelEstimate {
        let windows = u32::try_from(f.windows).unwrap_or(u32::MAX);
        let e = self.to_shared().estimate_with_release(&f.values, f.release.as_ref(), windows);
        let mut clearance = [0.0; 3];
        clearance[e.joint] = e.clearance;
        ModelEstimate {
            release: e.release,
            joint: Joint::ALL[e.joint],
            clearance,
            scores: e.scores,
            per_joint: e.per_joint,
            features: f,
            operations: f.operations
                + 12 * (FEATURES as u64 + 1)
                + 3 * 20
                + RELEASE_HYPOTHESES as u64 * (2 * RELEASE_TERMS as u64 + 20),
        }
    }

    /// Rows of the estimate file for `rec`: the running estimate after every window (the
    /// recording up to the window's end, as the node reports it), then `whole`, the whole
    /// recording's ([`FastModel::estimate`]).
    pub fn rows(&self, rec: &Recording, whole: &ModelEstimate) -> anyhow::Result<Vec<EstimateRow>> {
        let model = self.to_shared();
        let n = edgekf::systems::crank::window_samples(self.window, rec.sample_rate);
        let mut est =
            edgekf::systems::crank::ClearanceEstimator::new(&model, vec![0.0; n.saturating_sub(1)], rec.sample_rate)
                .map_err(|e| anyhow::anyhow!("window of {n} samples: {e:?}"))?;
        let mut rows = Vec::new();
        for (k, &x) in rec.crank_alpha.iter().enumerate() {
            if est.push(x).is_none() {
                continue;
            }
            let mut release = est.release().features();
            shift_to_release(&mut release, rec);
            let f = est.features();
            let e = model.estimate_with_release(&f.features(), release.as_ref(), f.windows());
            let mut clearance = [0.0; 3];
            clearance[e.joint] = e.clearance;
            rows.push(EstimateRow { t: rec.t[k], clearance });
        }
        rows.push(whole.row(rec));
        Ok(rows)
    }

    /// Joint and clearance from a recording.
    ///
    /// The release stage takes the mechanism as released at `t = 0`. The streaming detector
    /// counts samples from the first one; if the file's first sample is a little after the
    /// release (`0 < t₀ <` [`MAX_FIRST_SAMPLE`], e.g. a simulator that writes its state after
    /// the first step), the contact time is moved by `t₀`. A file whose clock starts anywhere
    /// else is taken to start at release.
    /// A recording at another sample rate than the model's is refused.
    pub fn estimate(&self, rec: &Recording) -> anyhow::Result<ModelEstimate> {
        if let Some(t) = &self.trained_for {
            t.check_rate(rec.sample_rate).map_err(anyhow::Error::msg)?;
        }
        let mut f = feature_vector(&rec.crank_alpha, rec.sample_rate, self.window);
        shift_to_release(&mut f.release, rec);
        if f.windows == 0 {
            anyhow::bail!("the recording is shorter than one {} s window", self.window);
        }
        Ok(self.estimate_features(f))
    }
}
