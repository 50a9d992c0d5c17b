//! The learned map from the ten features to the joint and its clearance, and the streaming
//! estimator that combines it with [`CrankFeatures`].

use super::features::{CrankFeatures, FeatureError};
use super::release::{ReleaseDetector, ReleaseFeatures, ReleaseModel, RELEASE_HYPOTHESES, RELEASE_TERMS};
use super::ClearanceFloat;
use super::{FEATURES, FEATURE_NAMES};
use core::fmt::{self, Write};

/// Regressors of a [`ClearanceModel`] regression: 1, the standardised features, their squares.
pub const REGRESSORS: usize = 2 * FEATURES + 1;

/// The fast clearance model: standardisation, one linear discriminant per joint (A, B, C; the
/// largest score names the joint) and one regression of `ln(clearance / m)` per joint on the
/// standardised features and their squares. Learned on the host (`edgekf crank train`), written
/// for the firmware by [`ClearanceModel::write_rust`].
///
/// A model without square terms has zeros in their place.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClearanceModel<T> {
    /// Window length of the features, s.
    pub window: f64,
    /// Feature means of the training set.
    pub mean: [T; FEATURES],
    /// Feature standard deviations of the training set.
    pub scale: [T; FEATURES],
    /// Per joint: `[bias, w₁ … w_F]` of the discriminant score.
    pub discriminant: [[T; FEATURES + 1]; 3],
    /// Per joint: `[bias, w₁ … w_F, v₁ … v_F]` of `ln c` on `z` and `z²`.
    pub regression: [[T; REGRESSORS]; 3],
    /// The release-transient stage, which refines the named joint's clearance
    /// ([`super::release`]).
    pub release: ReleaseModel<T>,
}

/// What a [`ClearanceModel`] says about a feature vector.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ClearanceEstimate<T> {
    /// The joint judged to have the clearance: 0, 1, 2 for A, B, C.
    pub joint: usize,
    /// Its clearance, m (within 0.01–1 mm, the range the model was trained for).
    pub clearance: T,
    /// Discriminant scores of A, B, C.
    pub scores: [T; 3],
    /// The clearance each joint's regression gives, m, whichever joint is named.
    pub per_joint: [T; 3],
    /// The release law's hypothesis that gave `clearance` (0: first contact seen, 1: second,
    /// 2: third),
    /// or `None` where the window features' regression gave it.
    pub release: Option<usize>,
}

/// Clearances the estimate is clamped to, m.
pub const CLEARANCE_RANGE: (f64, f64) = (1e-5, 1e-3);

impl<T: ClearanceFloat> ClearanceModel<T> {
    /// Joint and clearance from the recording's features ([`CrankFeatures::features`]).
    ///
    /// ```
    /// use edgekf::systems::crank::{ClearanceModel, ReleaseModel, FEATURES, REGRESSORS};
    /// // A toy model: the joint is C when feature 0 is above its mean, and ln c = ln 1e-4 + z₀.
    /// let mut m = ClearanceModel { window: 0.25, mean: [1.0f64; FEATURES], scale: [2.0; FEATURES],
    ///     discriminant: [[0.0; FEATURES + 1]; 3], regression: [[0.0; REGRESSORS]; 3],
    ///     release: ReleaseModel::off() };
    /// m.discriminant[2][1] = 1.0;
    /// m.regression[2][0] = 1e-4f64.ln();
    /// m.regression[2][1] = 1.0;
    /// let mut f = [1.0; FEATURES];
    /// f[0] = 2.0; // z₀ = 0.5
    /// let e = m.estimate(&f);
    /// assert_eq!(e.joint, 2);
    /// assert!((e.clearance - 1e-4 * 0.5f64.exp()).abs() < 1e-18);
    /// ```
    pub fn estimate(&self, features: &[T; FEATURES]) -> ClearanceEstimate<T> {
        self.estimate_with_release(features, None, 0)
    }

    /// As [`ClearanceModel::estimate`], then the release stage ([`ReleaseModel::refine`]) on
    /// the named joint if the release features are known; `windows`: the windows the features
    /// are the mean of.
    pub fn estimate_with_release(
        &self,
        features: &[T; FEATURES],
        release: Option<&ReleaseFeatures<T>>,
        windows: u32,
    ) -> ClearanceEstimate<T> {
        let mut z = [T::zero(); FEATURES];
        for i in 0..FEATURES {
            z[i] = (features[i] - self.mean[i]) / self.scale[i];
        }
        let linear = |w: &[T]| {
            let mut s = T::zero();
            for (c, &wc) in w.iter().enumerate() {
                let r = match c {
                    0 => T::one(),
                    // `get`: a weight row longer than the terms meets zeros (no panic path).
                    c if c <= FEATURES => z.get(c - 1).copied().unwrap_or_else(T::zero),
                    c => z.get(c - 1 - FEATURES).map_or_else(T::zero, |&v| v * v),
                };
                s += wc * r;
            }
            s
        };
        let scores = self.discriminant.each_ref().map(|w| linear(w));
        let (lo, hi) = (T::of_f64(CLEARANCE_RANGE.0), T::of_f64(CLEARANCE_RANGE.1));
        let per_joint = self.regression.each_ref().map(|w| linear(w).exp_m().max(lo).min(hi));
        // The largest score; the later joint on a tie (as `Iterator::max_by`).
        let mut joint = 0;
        for j in 1..3 {
            if scores[j] >= scores[joint] {
                joint = j;
            }
        }
        let refined = release.and_then(|f| self.release.refine(joint, per_joint[joint], f, windows));
        let clearance = refined.map_or(per_joint[joint], |(c, _)| c.max(lo).min(hi));
        ClearanceEstimate { joint, clearance, scores, per_joint, release: refined.map(|(_, h)| h) }
    }
}

impl ClearanceModel<f32> {
    /// The model rounded to `f32` (to nearest, as `as f32`), usable in a `const`, so the
    /// firmware carries only the `f32` coefficients and converts nothing at run time.
    pub const fn from_f64(m: &ClearanceModel<f64>) -> Self {
        let mut out = ClearanceModel {
            window: m.window,
            mean: [0.0; FEATURES],
            scale: [0.0; FEATURES],
            discriminant: [[0.0; FEATURES + 1]; 3],
            regression: [[0.0; REGRESSORS]; 3],
            release: ReleaseModel {
                max_step: m.release.max_step as f32,
                spread: m.release.spread as f32,
                windows: m.release.windows as f32,
                centre: [0.0; 3],
                level: [[0.0; 2]; 3],
                prior: [[0.0; RELEASE_HYPOTHESES]; 3],
                weights: [[[0.0; RELEASE_TERMS]; RELEASE_HYPOTHESES]; 3],
            },
        };
        let mut i = 0;
        while i < FEATURES {
            out.mean[i] = m.mean[i] as f32;
            out.scale[i] = m.scale[i] as f32;
            i += 1;
        }
        let mut j = 0;
        while j < 3 {
            let mut c = 0;
            while c < REGRESSORS {
                if c <= FEATURES {
                    out.discriminant[j][c] = m.discriminant[j][c] as f32;
                }
                out.regression[j][c] = m.regression[j][c] as f32;
                c += 1;
            }
            out.release.centre[j] = m.release.centre[j] as f32;
            out.release.level[j] = [m.release.level[j][0] as f32, m.release.level[j][1] as f32];
            let mut h = 0;
            while h < RELEASE_HYPOTHESES {
                out.release.prior[j][h] = m.release.prior[j][h] as f32;
                let mut r = 0;
                while r < RELEASE_TERMS {
                    out.release.weights[j][h][r] = m.release.weights[j][h][r] as f32;
                    r += 1;
                }
                h += 1;
            }
            j += 1;
        }
        out
    }
}

impl ClearanceModel<f64> {
    /// Writes the model as Rust source, `pub const {name}: ClearanceModel<f64> = …;`, for the
    /// firmware to `include!` (with `ClearanceModel` in scope). `header` becomes `//` comment
    /// lines above it. Values are in shortest round-trip form, so the constant is bit-identical
    /// to this model. Fails (`fmt::Error`) on a non-finite value.
    ///
    /// ```
    /// use edgekf::systems::crank::{ClearanceModel, ReleaseModel, FEATURES, REGRESSORS};
    /// let m = ClearanceModel { window: 0.25, mean: [0.5f64; FEATURES], scale: [1.0; FEATURES],
    ///     discriminant: [[0.0; FEATURES + 1]; 3], regression: [[-8.0; REGRESSORS]; 3],
    ///     release: ReleaseModel::off() };
    /// let mut s = String::new();
    /// m.write_rust(&mut s, "MODEL", "a test").unwrap();
    /// assert!(s.starts_with("// a test\n"));
    /// assert!(s.contains("pub const MODEL: ClearanceModel<f64> = ClearanceModel {\n    window: 0.25,\n"));
    /// assert!(s.contains("    mean: [0.5, 0.5,"));
    /// ```
    pub fn write_rust(&self, out: &mut impl Write, name: &str, header: &str) -> fmt::Result {
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let rows_finite = self.discriminant.iter().all(|r| finite(r))
            && self.regression.iter().all(|r| finite(r))
            && self.release.weights.iter().flatten().all(|r| finite(r))
            && finite(&self.release.centre)
            && self.release.level.iter().all(|r| finite(r))
            && self.release.prior.iter().all(|r| finite(r))
            && self.release.max_step.is_finite()
            && self.release.spread.is_finite()
            && self.release.windows.is_finite();
        if !(self.window.is_finite() && finite(&self.mean) && finite(&self.scale) && rows_finite) {
            return Err(fmt::Error);
        }
        for line in header.lines() {
            writeln!(out, "// {line}")?;
        }
        let list = |out: &mut dyn Write, v: &[f64]| -> fmt::Result {
            write!(out, "[")?;
            for (i, x) in v.iter().enumerate() {
                if i > 0 {
                    write!(out, ", ")?;
                }
                write!(out, "{x:?}")?;
            }
            write!(out, "]")
        };
        // `field: [` then one row per line at `indent`, then `]` (no trailing comma).
        let rows = |out: &mut dyn Write, field: &str, indent: &str, rows: &mut dyn Iterator<Item = &[f64]>| {
            if field.is_empty() {
                writeln!(out, "[")?;
            } else {
                writeln!(out, "{field}: [")?;
            }
            for row in rows {
                write!(out, "{indent}    ")?;
                list(out, row)?;
                writeln!(out, ",")?;
            }
            write!(out, "{indent}]")
        };
        write!(out, "/// The fast clearance model; features: ")?;
        for (i, name) in FEATURE_NAMES.iter().enumerate() {
            write!(out, "{}{name}", if i > 0 { ", " } else { "" })?;
        }
        writeln!(out, ".")?;
        writeln!(out, "pub const {name}: ClearanceModel<f64> = ClearanceModel {{")?;
        writeln!(out, "    window: {:?},", self.window)?;
        write!(out, "    mean: ")?;
        list(out, &self.mean)?;
        write!(out, ",\n    scale: ")?;
        list(out, &self.scale)?;
        write!(out, ",\n    ")?;
        rows(out, "discriminant", "    ", &mut self.discriminant.iter().map(|r| &r[..]))?;
        write!(out, ",\n    ")?;
        rows(out, "regression", "    ", &mut self.regression.iter().map(|r| &r[..]))?;
        writeln!(out, ",\n    release: ReleaseModel {{\n        max_step: {:?},", self.release.max_step)?;
        writeln!(out, "        spread: {:?},", self.release.spread)?;
        writeln!(out, "        windows: {:?},", self.release.windows)?;
        write!(out, "        centre: ")?;
        list(out, &self.release.centre)?;
        write!(out, ",\n        ")?;
        rows(out, "level", "        ", &mut self.release.level.iter().map(|r| &r[..]))?;
        write!(out, ",\n        ")?;
        rows(out, "prior", "        ", &mut self.release.prior.iter().map(|r| &r[..]))?;
        writeln!(out, ",\n        weights: [")?;
        for joint in &self.release.weights {
            write!(out, "            ")?;
            rows(out, "", "            ", &mut joint.iter().map(|r| &r[..]))?;
            writeln!(out, ",")?;
        }
        writeln!(out, "        ],\n    }},\n}};")
    }
}

/// The chip-side estimator: [`CrankFeatures`] and a [`ClearanceModel`], one sample at a time;
/// after every completed window it gives the estimate for the recording so far.
///
/// ```
/// use edgekf::systems::crank::{ClearanceEstimator, ClearanceModel, ReleaseModel, FEATURES, REGRESSORS};
/// let model = ClearanceModel { window: 0.025, mean: [0.0f32; FEATURES], scale: [1.0; FEATURES],
///     discriminant: [[0.0; FEATURES + 1]; 3], regression: [[-8.0; REGRESSORS]; 3],
///     release: ReleaseModel::off() };
/// // 0.025 s at 1 kHz: 25 samples per window.
/// let mut est = ClearanceEstimator::new(&model, [0.0f32; 24], 1000.0).unwrap();
/// let mut reports = 0;
/// for k in 0..100 {
///     if let Some(e) = est.push((k % 5) as f32) {
///         assert!(e.clearance >= 1e-5 && e.clearance <= 1e-3);
///         reports += 1;
///     }
/// }
/// assert_eq!(reports, 4);
/// ```
#[derive(Debug, Clone)]
pub struct ClearanceEstimator<'m, T: ClearanceFloat, S: AsRef<[T]> + AsMut<[T]>> {
    model: &'m ClearanceModel<T>,
    features: CrankFeatures<T, S>,
    release: ReleaseDetector<T>,
}

/// Samples in a window of `window_s` seconds at `rate` Hz: `round(window_s · rate)`, at least
/// [`super::MIN_WINDOW`] (0 if that is not representable).
pub fn window_samples(window_s: f64, rate: f64) -> usize {
    let n = libm::round(window_s * rate);
    if (0.0..1e12).contains(&n) {
        (n as usize).max(super::MIN_WINDOW)
    } else {
        0
    }
}

impl<'m, T: ClearanceFloat, S: AsRef<[T]> + AsMut<[T]>> ClearanceEstimator<'m, T, S> {
    /// Runs `model` on samples at `rate` Hz, windows of `model.window` seconds
    /// ([`window_samples`]); `storage` must hold one value less than a window.
    pub fn new(model: &'m ClearanceModel<T>, storage: S, rate: f64) -> Result<Self, FeatureError> {
        let n = window_samples(model.window, rate);
        Ok(Self {
            model,
            features: CrankFeatures::new(storage, n, T::of_f64(rate))?,
            release: ReleaseDetector::new(rate),
        })
    }

    /// Adds a sample (rad/s²; non-finite ones are skipped and counted); after a completed
    /// window, the estimate for everything so far.
    pub fn push(&mut self, x: T) -> Option<ClearanceEstimate<T>> {
        self.release.push(x);
        self.features.push(x).then(|| self.estimate())
    }

    /// The estimate for the completed windows so far. Out of line, like the window's end,
    /// so that the per-sample path does not carry this once-a-window frame.
    #[inline(never)]
    pub fn estimate(&self) -> ClearanceEstimate<T> {
        let f = &self.features;
        self.model.estimate_with_release(&f.features(), self.release.features().as_ref(), f.windows())
    }

    /// The release transient's detector.
    pub fn release(&self) -> &ReleaseDetector<T> {
        &self.release
    }

    /// The features behind it.
    pub fn features(&self) -> &CrankFeatures<T, S> {
        &self.features
    }
}
