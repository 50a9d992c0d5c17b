//! Slider-crank joint clearance on the node: the host's fast estimator (ten window features of
//! the crank angular acceleration, a discriminant naming joint A, B or C, a regression per joint
//! for the clearance) streaming in `f32`, with the model compiled in from
//! `generated/clearance.rs` (`edgekf crank export --out firmware/src/systems/crank/generated/clearance.rs`;
//! a cross-crate test checks the file is what the built-in `fast_model.toml` gives).
//!
//! Input: `crank_alpha`, rad/s², at [`SAMPLE_RATE_HZ`]. Output: after every 0.25 s window, the
//! joint and clearance for the recording so far. Memory: the window's `|Δα|` (2 499 `f32`,
//! 10 KB, for the exact median), owned by the caller; the rest is about 200 bytes.

use crate::frame::FrameSink;
use crate::hil::{clocked_node, FileEnd, HilError, HilImage, HilNode};
use crate::line_feed::{ByteSource, ChannelReader};
use crate::node::{Innovation, NodeEstimator, Pending, Poll};
use crate::source::ChannelSource;
use edgekf::systems::crank::{ClearanceEstimate, ClearanceEstimator, ClearanceModel, FeatureError, FEATURES};

#[cfg(all(target_os = "none", feature = "qemu"))]
pub mod bench;
pub mod images;
pub mod soak;

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
/// use edgekf_firmware::systems::crank::{release_law, NO_RELEASE_LAW};
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
    /// Samples stepped so far: input lines, the bad ones included, and lines missing from the
    /// file, bridged.
    pub samples: u32,
    /// The estimate for the recording up to here.
    pub estimate: ClearanceEstimate<f32>,
}

/// The node's clearance estimator: the shared [`ClearanceEstimator`] with the compiled-in model,
/// plus a count of input lines.
pub struct CrankNode<'s> {
    est: ClearanceEstimator<'static, f32, &'s mut Storage>,
    samples: u32,
    /// The last window's report, until the node reports it.
    pending: Pending<WindowReport>,
}

impl<'s> CrankNode<'s> {
    /// The compiled-in model on `storage` (whose contents are overwritten).
    ///
    /// ```
    /// use edgekf_firmware::systems::crank::{CrankNode, WINDOW};
    /// let mut storage = [0.0f32; WINDOW - 1];
    /// let mut node = CrankNode::new(&mut storage).unwrap();
    /// let reports = (0..2 * WINDOW).filter_map(|k| node.step(Some((k % 13) as f32 * 50.0))).count();
    /// assert_eq!(reports, 2);
    /// assert_eq!(node.step(None), None);
    /// assert_eq!(node.skipped(), 1);
    /// ```
    pub fn new(storage: &'s mut Storage) -> Result<Self, FeatureError> {
        Ok(Self {
            est: ClearanceEstimator::new(&MODEL, storage, f64::from(SAMPLE_RATE_HZ))?,
            samples: 0,
            pending: Pending::new(),
        })
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
    pub fn features(&self) -> [f32; FEATURES] {
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

    /// Samples stepped (input lines, and missing lines bridged).
    pub fn samples(&self) -> u32 {
        self.samples
    }
}

/// A frame carrying a clearance estimate between `$before` and `$after` fields: the joint, its
/// clearance, the three scores, the three per-joint clearances and the release law, with the
/// conversions from and to [`ClearanceEstimate`] (one definition for the `win` and `crank`
/// frames).
macro_rules! clearance_frame {
    ($(#[$meta:meta])* $name:ident = $format:literal { $($before:tt)* } { $($after:tt)* }) => {
        crate::frame! {
            $(#[$meta])*
            pub struct $name = $format {
                $($before)*
                /// The joint named (0, 1, 2: A, B, C).
                pub joint: u8,
                /// Its clearance, m.
                pub clearance: f32,
                /// Discriminant score of joint A.
                pub score_a: f32,
                /// Of joint B.
                pub score_b: f32,
                /// Of joint C.
                pub score_c: f32,
                /// Clearance if the joint is A, m.
                pub clearance_a: f32,
                /// If B.
                pub clearance_b: f32,
                /// If C.
                pub clearance_c: f32,
                /// The release law behind the clearance ([`release_law`]).
                pub release_law: u8,
                $($after)*
            }
        }

        impl $name {
            /// The estimate the frame carries; `None` for a joint other than 0, 1, 2.
            pub fn estimate(&self) -> Option<ClearanceEstimate<f32>> {
                let release = (self.release_law != NO_RELEASE_LAW).then_some(usize::from(self.release_law));
                (self.joint < 3).then_some(ClearanceEstimate {
                    joint: usize::from(self.joint),
                    clearance: self.clearance,
                    scores: [self.score_a, self.score_b, self.score_c],
                    per_joint: [self.clearance_a, self.clearance_b, self.clearance_c],
                    release,
                })
            }

            /// The frame with the estimate fields set from `e`.
            fn with_estimate(self, e: &ClearanceEstimate<f32>) -> Self {
                let ([score_a, score_b, score_c], [clearance_a, clearance_b, clearance_c]) = (e.scores, e.per_joint);
                Self {
                    joint: e.joint as u8,
                    clearance: e.clearance,
                    score_a,
                    score_b,
                    score_c,
                    clearance_a,
                    clearance_b,
                    clearance_c,
                    release_law: release_law(e),
                    ..self
                }
            }
        }
    };
}

clearance_frame! {
    /// A window's report.
    WindowFrame = "win {=u32} {=u32} {=u8} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=u8}" {
        /// Windows completed so far.
        pub window: u32,
        /// Samples stepped so far (lines, and missing lines bridged).
        pub samples: u32,
    } {}
}

impl From<&WindowReport> for WindowFrame {
    fn from(r: &WindowReport) -> Self {
        Self { window: r.window, samples: r.samples, ..Self::default() }.with_estimate(&r.estimate)
    }
}

impl WindowFrame {
    /// The report the frame carries; `None` for a joint other than 0, 1, 2.
    pub fn report(&self) -> Option<WindowReport> {
        Some(WindowReport { window: self.window, samples: self.samples, estimate: self.estimate()? })
    }
}

crate::frame! {
    /// The recording's features at the end of a run (`ln` of the window means, in the order of
    /// [`edgekf::systems::crank::FEATURE_NAMES`]).
    pub struct FeaturesFrame = "feat {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32}" {
        /// RMS.
        pub ln_rms: f32,
        /// RMS of the first difference.
        pub ln_diff_rms: f32,
        /// RMS of the second difference.
        pub ln_diff2_rms: f32,
        /// RMS after the high-pass.
        pub ln_highpass_rms: f32,
        /// Kurtosis of the first difference.
        pub ln_diff_kurtosis: f32,
        /// Kurtosis.
        pub ln_kurtosis: f32,
        /// Impacts per second.
        pub ln_impact_rate: f32,
        /// Mean impact peak over the median.
        pub ln_impact_peak: f32,
        /// Mean impact width, samples.
        pub ln_impact_width: f32,
        /// Median of the first difference's magnitude.
        pub ln_diff_median: f32,
    }
}

impl FeaturesFrame {
    /// The features as an array.
    pub fn values(&self) -> [f32; FEATURES] {
        [
            self.ln_rms,
            self.ln_diff_rms,
            self.ln_diff2_rms,
            self.ln_highpass_rms,
            self.ln_diff_kurtosis,
            self.ln_kurtosis,
            self.ln_impact_rate,
            self.ln_impact_peak,
            self.ln_impact_width,
            self.ln_diff_median,
        ]
    }
}

impl From<[f32; FEATURES]> for FeaturesFrame {
    fn from(f: [f32; FEATURES]) -> Self {
        let [ln_rms, ln_diff_rms, ln_diff2_rms, ln_highpass_rms, ln_diff_kurtosis, ln_kurtosis, ln_impact_rate, ln_impact_peak, ln_impact_width, ln_diff_median] =
            f;
        Self {
            ln_rms,
            ln_diff_rms,
            ln_diff2_rms,
            ln_highpass_rms,
            ln_diff_kurtosis,
            ln_kurtosis,
            ln_impact_rate,
            ln_impact_peak,
            ln_impact_width,
            ln_diff_median,
        }
    }
}

clearance_frame! {
    /// The end of a crank run: the whole recording's estimate and the counts (the file's own in [`FileEnd`]).
    CrankEnd = "crank {=u8} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=u8} {=u32} {=u32} {=u32}" {} {
        /// Windows completed.
        pub windows: u32,
        /// Samples stepped (lines, and missing lines bridged).
        pub samples: u32,
        /// Samples skipped (missing or non-finite).
        pub skipped: u32,
    }
}

impl NodeEstimator for CrankNode<'_> {
    type Input = [f32; 1];
    type Frame = WindowFrame;

    fn step(&mut self, input: Option<[f32; 1]>) -> Innovation {
        let report = CrankNode::step(self, input.map(|[a]| a));
        self.pending.keep(report, Innovation::default())
    }

    fn report(&mut self, _: &Poll) -> Option<WindowFrame> {
        self.pending.report(|r| WindowFrame::from(&r))
    }
}

/// The QEMU image `edgekf-crank-qemu`: the crank acceleration from the HIL file (other columns
/// ignored; lines that do not parse or hold a non-finite value are skipped and counted); a
/// `win` frame after every window, then `file` ([`FileEnd`]), `feat` and `crank`.
pub struct CrankImage;

impl HilImage for CrankImage {
    const NAME: &'static str = "edgekf-crank-qemu";
    const COLUMNS: &'static [&'static str] = &CHANNELS;
    type Input = [f32; 1];
    type Storage = Storage;
    type Source<B: ByteSource> = ChannelSource<B, 1>;
    type Estimator<'s> = CrankNode<'s>;
    type StartError = FeatureError;

    const STORAGE: Storage = [0.0; WINDOW - 1];

    #[inline(never)] // start-up temporaries stay out of the caller's frame
    fn start<B: ByteSource>(input: B, storage: &mut Storage) -> Result<HilNode<'_, Self, B>, HilError<FeatureError>> {
        // Lines missing from the file are stepped as missing samples: the window statistics
        // skip them, and the release detector counts their time, so a line lost before the
        // first contact does not move it earlier.
        clocked_node(ChannelReader::new(input, CHANNELS), SAMPLE_RATE_HZ, || CrankNode::new(storage))
    }

    fn finish<B: ByteSource>(node: &HilNode<'_, Self, B>, sink: &mut impl FrameSink) {
        sink.frame(&FileEnd::of(node.source()));
        let est = node.estimator();
        sink.frame(&FeaturesFrame::from(est.features()));
        let end = CrankEnd {
            windows: est.windows(),
            samples: est.samples(),
            skipped: est.skipped(),
            ..CrankEnd::default()
        };
        sink.frame(&end.with_estimate(&est.estimate()));
    }
}
