//! Slider-crank joint clearance on the node: the host's fast estimator (ten window features of
//! the crank angular acceleration, a discriminant naming joint A, B or C, a regression per joint
//! for the clearance) streaming in `f32`, with the model compiled in from
//! `src/generated/clearance.rs` (`edgekf crank export --out firmware/src/generated/clearance.rs`;
//! a cross-crate test checks the file is what the built-in `fast_model.toml` gives).
//!
//! Input: `crank_alpha`, rad/s², at [`SAMPLE_RATE_HZ`]. Output: after every 0.25 s window, the
//! joint and clearance for the recording so far. Memory: the window's `|Δα|` (2 499 `f32`,
//! 10 KB, for the exact median), owned by the caller; the rest is about 200 bytes.

use edgekf::systems::crank::{ClearanceEstimate, ClearanceEstimator, ClearanceModel, FeatureError};

#[allow(missing_docs, clippy::excessive_precision, clippy::unreadable_literal)]
mod constants {
    use edgekf::systems::crank::{ClearanceModel, ReleaseModel};
    include!("generated/clearance.rs");
}

/// The compiled-in model in `f64`, as exported (the host's `FastModel::builtin()`).
pub const MODEL_F64: ClearanceModel<f64> = constants::CLEARANCE_MODEL;

/// The model rounded to `f32` at compile time (nothing is converted at run time, and the image
/// carries no `f64` coefficients).
pub static MODEL: ClearanceModel<f32> = ClearanceModel::from_f64(&MODEL_F64);

/// Sample rate of `crank_alpha`, Hz: the simulator's `sensor.sample_rate` (`crank_paper.toml`).
pub const SAMPLE_RATE_HZ: u32 = 10_000;

/// Samples per window: `model.window · SAMPLE_RATE_HZ` (0.25 s → 2 500; checked at compile
/// time against the exported window).
pub const WINDOW: usize = 2500;

const _: () = {
    let n = MODEL_F64.window * SAMPLE_RATE_HZ as f64;
    assert!(n >= WINDOW as f64 - 1e-6 && n <= WINDOW as f64 + 1e-6, "WINDOW must be model.window × rate");
};

/// The channel read from the input file.
pub const CHANNELS: [&str; 1] = ["crank_alpha"];

/// [`release_law`] of an estimate the window features gave.
pub const NO_RELEASE_LAW: u8 = u8::MAX;

/// The release law behind an estimate as one byte for the log: its hypothesis (0: the first
/// contact was seen, 1: the second), or [`NO_RELEASE_LAW`].
///
/// ```
/// use edgekf::systems::crank::ClearanceEstimate;
/// use edgekf_firmware::crank::{release_law, NO_RELEASE_LAW};
/// let mut e = ClearanceEstimate { joint: 0, clearance: 2.5e-4f32, scores: [0.0; 3], per_joint: [2.5e-4; 3], release: None };
/// assert_eq!(release_law(&e), NO_RELEASE_LAW);
/// e.release = Some(1);
/// assert_eq!(release_law(&e), 1);
/// ```
pub fn release_law(e: &ClearanceEstimate<f32>) -> u8 {
    e.release.map_or(NO_RELEASE_LAW, |h| u8::try_from(h).unwrap_or(NO_RELEASE_LAW))
}

/// The window's `|Δα|`, the estimator's one large buffer.
pub type Storage = [f32; WINDOW - 1];

/// A window's report.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowReport {
    /// Windows completed so far (1 for the first).
    pub window: u32,
    /// Input lines read so far, the bad ones included.
    pub samples: u32,
    /// The estimate for the recording up to here.
    pub estimate: ClearanceEstimate<f32>,
}

/// The node's clearance estimator: the shared [`ClearanceEstimator`] with the compiled-in model,
/// plus a count of input lines.
pub struct CrankNode<'s> {
    est: ClearanceEstimator<'static, f32, &'s mut Storage>,
    samples: u32,
}

impl<'s> CrankNode<'s> {
    /// The compiled-in model on `storage` (whose contents are overwritten).
    ///
    /// ```
    /// use edgekf_firmware::crank::{CrankNode, WINDOW};
    /// let mut storage = [0.0f32; WINDOW - 1];
    /// let mut node = CrankNode::new(&mut storage).unwrap();
    /// let reports = (0..2 * WINDOW).filter_map(|k| node.step(Some((k % 13) as f32 * 50.0))).count();
    /// assert_eq!(reports, 2);
    /// assert_eq!(node.step(None), None);
    /// assert_eq!(node.skipped(), 1);
    /// ```
    pub fn new(storage: &'s mut Storage) -> Result<Self, FeatureError> {
        Ok(Self { est: ClearanceEstimator::new(&MODEL, storage, f64::from(SAMPLE_RATE_HZ))?, samples: 0 })
    }

    /// One input line: a sample, or `None` for a line that did not parse or was not finite
    /// (skipped and counted, like a NaN sample). After a completed window, its report.
    pub fn step(&mut self, alpha: Option<f32>) -> Option<WindowReport> {
        self.samples = self.samples.saturating_add(1);
        let estimate = self.est.push(alpha.unwrap_or(f32::NAN))?;
        Some(WindowReport { window: self.est.features().windows(), samples: self.samples, estimate })
    }

    /// The estimate for the completed windows so far.
    pub fn estimate(&self) -> ClearanceEstimate<f32> {
        self.est.estimate()
    }

    /// The recording's features so far (`ln` of the window means).
    pub fn features(&self) -> [f32; edgekf::systems::crank::FEATURES] {
        self.est.features().features()
    }

    /// The first contact after release, once seen: its time (s) and the mean crank
    /// acceleration before it (rad/s²).
    pub fn release_contact(&self) -> Option<edgekf::systems::crank::ReleaseFeatures<f32>> {
        self.est.release().features()
    }

    /// Completed windows.
    pub fn windows(&self) -> u32 {
        self.est.features().windows()
    }

    /// Samples skipped (missing or non-finite).
    pub fn skipped(&self) -> u32 {
        self.est.features().skipped()
    }

    /// Input lines stepped.
    pub fn samples(&self) -> u32 {
        self.samples
    }
}
