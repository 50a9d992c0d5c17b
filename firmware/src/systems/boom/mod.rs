//! Boom tip vibration on the node: both of the shared estimators in `f32` side by side, the
//! model-based filter ([`edgekf::systems::boom::ModelEstimator`]) and the paper's method
//! ([`edgekf::systems::boom::PaperEstimator`]), on the boom and sensors of a configuration,
//! exported on the host (`edgekf boom export`) into `generated/boom.rs` (the shipped
//! `host-sim/configs/boom_ladder30.toml`'s; a cross-crate test checks it against the file). An
//! image built with `EDGEKF_BOOM_MODEL=path/to/boom.rs` compiles that file in instead (see
//! `build.rs`): how a corrected configuration (the loop's tip mass) reaches the chip.
//!
//! Input: `gyro_rate`, `incl_angle`, `boom_length`, `luff_rate_cmd` ([`CHANNELS`]) at
//! [`SAMPLE_RATE_HZ`]. Output: a [`BoomFrame`] per sample and a [`BoomEnd`] at the end of the
//! run. The gyro's noise model is the declared one ([`GYRO`]): a node has no static record to
//! identify it from until one is recorded on it. Memory: about 3 KB of filter in the caller's
//! [`Storage`]; re-reducing the boom (every 0.5 m of telescoping or 0.1 rad of luffing) takes
//! about 12 KB of stack in `f64`.

use crate::frame::FrameSink;
use crate::hil::{sensors_node, FileEnd, HilError, HilImage, HilNode};
use crate::line_feed::ByteSource;
use crate::monitor::{Monitored, Normalised};
use edgekf::residual::MonitorSettings;
use crate::node::{Innovation, NodeEstimator, Pending, Poll};
use crate::source::ChannelSource;
use edgekf::systems::boom::{
    ModelError, ModelEstimate, ModelEstimator, ModelSettings, PaperEstimator, PaperSettings,
};

#[cfg(all(target_os = "none", feature = "qemu"))]
pub mod bench;
pub mod images;
pub mod soak;

/// The model monitor's settings: the shipped false-alarm rate (one per 100 h) at
/// [`SAMPLE_RATE_HZ`], tests from 2 s after start-up (the filter starts from the boom at rest
/// and its declared covariance), and the oscillator's tolerance of 0.2 autocorrelation. The
/// gyro's channel does not fit the model on healthy runs: its CUSUM alarms, dated from the
/// first sample tested, and its innovations' ρ(1) is −0.15 to −0.48 over 5 s stretches of the
/// luffing run.
pub fn monitor_settings() -> MonitorSettings {
    let rate = f64::from(SAMPLE_RATE_HZ);
    MonitorSettings { settle_s: 2.0, whiteness_tolerance: 0.2, ..MonitorSettings::new(rate) }
}

/// The input channels, in the data file's names.
pub const CHANNELS: [&str; 4] = ["gyro_rate", "incl_angle", "boom_length", "luff_rate_cmd"];

#[allow(missing_docs, clippy::excessive_precision, clippy::unreadable_literal)]
mod constants {
    use edgekf::systems::boom::{Ar2, BoomConstants, BoomSection};
    include!(concat!(env!("OUT_DIR"), "/boom.rs"));
}

/// The node's boom and sensors, compiled in from `edgekf boom export`'s file (see the module
/// doc): the sample rate (`[gyro] sample_rate`), the boom ([`BOOM`]: sections, platform,
/// gravity), `[damping] zeta`, `[drive]` (lag, acceleration limit), the gyro's noise model
/// ([`GYRO`]: the declared one, or the simulator's), `[gyro] scale` and `[inclinometer]` (lag,
/// offset, noise).
pub use constants::{BOOM, DRIVE, GYRO, GYRO_SCALE, INCLINOMETER, SAMPLE_RATE_HZ, ZETA};

/// The length the filter is built at before the first row says otherwise, m.
const START_LENGTH: f64 = 30.0;

/// The model-based filter's settings.
pub fn model_settings() -> ModelSettings {
    let dt = 1.0 / f64::from(SAMPLE_RATE_HZ);
    ModelSettings::new(dt, BOOM, ZETA, DRIVE, GYRO_SCALE, GYRO, INCLINOMETER)
}

/// The paper's method's settings.
pub fn paper_settings() -> PaperSettings {
    PaperSettings::new(1.0 / f64::from(SAMPLE_RATE_HZ), GYRO, GYRO_SCALE, INCLINOMETER.0)
}

/// Both estimators, kept by the caller.
pub type Storage = Option<(ModelEstimator<f32>, PaperEstimator<f32>)>;

/// The built-in estimators.
pub fn estimators() -> Result<(ModelEstimator<f32>, PaperEstimator<f32>), ModelError> {
    Ok((ModelEstimator::new(&model_settings(), START_LENGTH)?, PaperEstimator::new(&paper_settings())))
}

/// The node: both estimators, the samples stepped, and the last estimate until it is reported.
pub struct BoomNode<'s> {
    model: &'s mut ModelEstimator<f32>,
    paper: &'s mut PaperEstimator<f32>,
    samples: u32,
    fusions: u32,
    /// The last finite length (the paper's method has no prediction to bridge with).
    length: f32,
    pending: Pending<BoomFrame>,
}

impl<'s> BoomNode<'s> {
    /// The node on its estimators.
    pub fn new(model: &'s mut ModelEstimator<f32>, paper: &'s mut PaperEstimator<f32>) -> Self {
        Self { model, paper, samples: 0, fusions: 0, length: START_LENGTH as f32, pending: Pending::new() }
    }

    /// One row (`None`: missing or unparsable, predicted through); the frame after it.
    ///
    /// ```
    /// use edgekf_firmware::systems::boom::{estimators, BoomNode};
    /// let (mut model, mut paper) = estimators().unwrap();
    /// let mut node = BoomNode::new(&mut model, &mut paper);
    /// let f = node.step(Some([0.002, 0.5, 30.0, 0.0]));
    /// assert!(f.vibration.abs() < 1e-3 && f.deflection < -0.5); // at rest, sagging
    /// let f = node.step(None);
    /// assert!(f.tip_angle.is_finite() && f.sample == 2);
    /// ```
    pub fn step(&mut self, row: Option<[f32; 4]>) -> BoomFrame {
        self.step_variances(row).0
    }

    /// [`step`](Self::step), with the variances of its innovations (NaN where a reading was
    /// missing).
    fn step_variances(&mut self, row: Option<[f32; 4]>) -> (BoomFrame, [f32; 2]) {
        let [gyro, incl, length, command] = row.unwrap_or([f32::NAN; 4]);
        self.samples = self.samples.saturating_add(1);
        let e: ModelEstimate<f32> = self.model.step(gyro, incl, length, command);
        if length.is_finite() && length > 0.0 {
            self.length = length;
        }
        let p = self.paper.step(gyro, incl, self.length);
        self.fusions = self.fusions.saturating_add(u32::from(p.fused));
        let frame = BoomFrame {
            sample: self.samples,
            tip_angle: e.tip_angle,
            vibration: e.vibration,
            deflection: e.deflection,
            paper_vibration: p.vibration,
            innovation_gyro: e.innovation[0],
            innovation_incl: e.innovation[1],
            nis: e.nis,
        };
        (frame, e.variance)
    }

    /// Samples stepped (rows, and missing rows bridged).
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The model-based filter.
    pub fn model(&self) -> &ModelEstimator<f32> {
        self.model
    }

    /// Equilibrium instants the paper's method fused.
    pub fn fusions(&self) -> u32 {
        self.fusions
    }
}

crate::frame! {
    /// One sample's estimates.
    pub struct BoomFrame = "boom {=u32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32}" {
        /// Samples stepped so far.
        pub sample: u32,
        /// The model's tip angle from the horizontal, rad.
        pub tip_angle: f32,
        /// The model's tip vibration about the static equilibrium, m.
        pub vibration: f32,
        /// The model's tip deflection with the sag, m.
        pub deflection: f32,
        /// The paper's method's tip vibration, m.
        pub paper_vibration: f32,
        /// The model's gyro innovation, rad/s.
        pub innovation_gyro: f32,
        /// Its inclinometer innovation, rad.
        pub innovation_incl: f32,
        /// Its NIS.
        pub nis: f32,
    }
}

crate::frame! {
    /// The end of a run: counts (the file's own in [`FileEnd`], just before).
    pub struct BoomEnd = "boomend {=u32} {=u32} {=u32} {=u32} {=u32}" {
        /// Samples stepped (rows, and missing rows bridged).
        pub samples: u32,
        /// Reductions of the boom that failed (the last good one kept).
        pub reduce_failures: u32,
        /// The model's covariance resets.
        pub covariance_resets: u32,
        /// Its refused updates.
        pub refused_updates: u32,
        /// The paper's method's fusions.
        pub fusions: u32,
    }
}

impl BoomFrame {
    /// What its step gives the block statistics: the NIS (two sequential updates have no one
    /// residual).
    fn innovation(&self) -> Innovation {
        Innovation { residual: None, nis: Some(self.nis) }
    }
}

impl NodeEstimator for BoomNode<'_> {
    type Input = [f32; 4];
    type Frame = BoomFrame;

    fn step(&mut self, input: Option<[f32; 4]>) -> Innovation {
        let f = BoomNode::step(self, input);
        self.pending.keep(Some(f), f.innovation())
    }

    fn report(&mut self, _: &Poll) -> Option<BoomFrame> {
        self.pending.report(|f| f)
    }
}

/// Its two channels: the gyro's innovation (channel 0) and the inclinometer's (channel 1), each
/// over its own variance (the updates are sequential, so each is standard normal on its own).
impl Normalised<2> for BoomNode<'_> {
    fn step_normalised(&mut self, input: Option<[f32; 4]>, z: &mut [f32; 2]) -> Innovation {
        let (f, variance) = self.step_variances(input);
        for ((z, nu), var) in z.iter_mut().zip([f.innovation_gyro, f.innovation_incl]).zip(variance) {
            // A missing reading's variance is NaN, and so is its z.
            *z = nu / libm::sqrtf(var);
        }
        self.pending.keep(Some(f), f.innovation())
    }
}

/// The QEMU image `edgekf-boom-qemu`: the boom's channels from the HIL file (other columns
/// ignored; an empty or NaN cell is a missing reading of that channel alone, lines that do not
/// parse are stepped as missing samples and counted, lines missing by their `t` are bridged
/// for up to [`crate::source::MAX_GAP_S`]); a `boom` frame per sample (a `mismatch` after it when
/// the model monitor found one: channel 0 the gyro, 1 the inclinometer), then `file`
/// ([`FileEnd`]) and `boomend`.
pub struct BoomImage;

impl HilImage for BoomImage {
    const NAME: &'static str = "edgekf-boom-qemu";
    const COLUMNS: &'static [&'static str] = &CHANNELS;
    type Input = [f32; 4];
    type Storage = Storage;
    type Source<B: ByteSource> = ChannelSource<B, 4>;
    type Estimator<'s> = Monitored<BoomNode<'s>, 2>;
    type StartError = ModelError;

    const STORAGE: Storage = None;

    #[inline(never)] // start-up temporaries stay out of the caller's frame
    fn start<B: ByteSource>(input: B, storage: &mut Storage) -> Result<HilNode<'_, Self, B>, HilError<ModelError>> {
        sensors_node(input, CHANNELS, SAMPLE_RATE_HZ, move || {
            let (model, paper) = storage.insert(estimators()?);
            Ok(Monitored::new(BoomNode::new(model, paper), &monitor_settings()))
        })
    }

    fn finish<B: ByteSource>(node: &HilNode<'_, Self, B>, sink: &mut impl FrameSink) {
        sink.frame(&FileEnd::of(node.source()));
        let n = node.estimator();
        let h = n.model().health();
        sink.frame(&BoomEnd {
            samples: n.samples(),
            reduce_failures: n.model().reduce_failures(),
            covariance_resets: h.covariance_resets,
            refused_updates: h.refused_updates,
            fusions: n.fusions(),
        });
    }
}
