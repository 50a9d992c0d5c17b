//! Underwater vehicle thruster health on the node: the shared joint UKF of the vehicle's state
//! and its thrusters' health factors ([`edgekf::systems::uuv::UuvEstimator`], 20 states: both
//! health factors, the six IMU biases and the current) with its CUSUM per thruster, in `f32`,
//! on a configuration's vehicle and estimator, exported on the host (`edgekf uuv export`) into
//! `generated/uuv.rs` (the shipped `host-sim/configs/uuv_remus100.toml`'s: REMUS 100, 50 Hz; a
//! cross-crate test checks it against the file). An image built with
//! `EDGEKF_UUV_MODEL=path/to/uuv.rs` compiles that file in instead (see `build.rs`).
//!
//! Input: the vehicle data file's 15 channels ([`CHANNELS`]); the DVL's cells are empty between
//! its readings and are read as missing, not as bad lines. Output: a [`UuvFrame`] per sample,
//! and a [`UuvEnd`] at the end of the run. Memory: the estimator (about 8 KB of matrices) lives
//! in the caller's [`Storage`], not on the stack of every call.

use crate::frame::FrameSink;
use crate::hil::{clocked_node, FileEnd, HilError, HilImage, HilNode};
use crate::line_feed::{ByteSource, ChannelReader};
use crate::node::{Innovation, NodeEstimator, Poll};
use crate::source::ChannelSource;
use edgekf::systems::uuv::{
    Command, Estimate, EstimatorError, Layout, Sample, Status, UuvEstimator,
};

#[cfg(all(target_os = "none", feature = "qemu"))]
pub mod bench;
pub mod images;
pub mod soak;

#[allow(missing_docs, clippy::excessive_precision, clippy::unreadable_literal)]
mod constants {
    use edgekf::systems::uuv::{
        Actuators, DetectorSettings, EstimatorSettings, Hydro, InitialSpread, Layout, MeasurementNoise, ProcessNoise,
        Vehicle,
    };
    include!(concat!(env!("OUT_DIR"), "/uuv.rs"));
}

/// The node's vehicle and estimator, compiled in from `edgekf uuv export`'s file (see the
/// module doc): the sample rate (`[sensors] rate`), the vehicle (`[vehicle]`) and the
/// estimator's settings (`[estimator]`).
pub use constants::{ESTIMATOR, SAMPLE_RATE_HZ, VEHICLE};

/// The filter's states (the shipped file's: both health factors, the biases and the current).
pub const LAYOUT: Layout = ESTIMATOR.layout;

/// Its size.
pub const STATES: usize = LAYOUT.len();

/// The input channels, in the data file's names and order.
pub use edgekf::systems::uuv::CHANNELS;

/// The estimator, kept by the caller.
pub type Storage = Option<UuvEstimator<f32, STATES>>;

/// A status as one byte: 0 healthy, 1 degraded, 2 failed.
///
/// ```
/// use edgekf::systems::uuv::Status;
/// use edgekf_firmware::systems::uuv::status_code;
/// assert_eq!([Status::Healthy, Status::Degraded, Status::Failed].map(status_code), [0, 1, 2]);
/// ```
pub const fn status_code(s: Status) -> u8 {
    match s {
        Status::Healthy => 0,
        Status::Degraded => 1,
        Status::Failed => 2,
    }
}

/// One input row as the estimator's sample; a missing row (`None`) is a sample with nothing
/// present, which the estimator predicts through with the last commands.
///
/// ```
/// use edgekf_firmware::systems::uuv::sample;
/// let s = sample(None);
/// assert!(s.depth.is_nan() && s.dvl.is_none() && s.command.n_t.is_nan());
/// let mut row = [0.0f32; 15];
/// row[8..11].copy_from_slice(&[1.5, 0.0, 0.01]);
/// assert_eq!(sample(Some(row)).dvl, Some([1.5, 0.0, 0.01]));
/// ```
pub fn sample(row: Option<[f32; 15]>) -> Sample<f32> {
    let v = row.unwrap_or([f32::NAN; 15]);
    let dvl = [v[8], v[9], v[10]];
    Sample {
        acc: [v[0], v[1], v[2]],
        gyro: [v[3], v[4], v[5]],
        depth: v[6],
        heading: v[7],
        dvl: dvl.iter().all(|d| d.is_finite()).then_some(dvl),
        command: Command { n_t: v[11], n_v: v[12], rudder: v[13], elevator: v[14] },
    }
}

/// The built-in estimator: [`VEHICLE`] and [`ESTIMATOR`].
pub fn estimator() -> Result<UuvEstimator<f32, STATES>, EstimatorError> {
    UuvEstimator::new(&VEHICLE, &ESTIMATOR)
}

/// The node: the estimator, the samples stepped, and the last estimate until it is reported.
pub struct UuvNode<'s> {
    est: &'s mut UuvEstimator<f32, STATES>,
    samples: u32,
    pending: Option<Estimate<f32>>,
}

impl<'s> UuvNode<'s> {
    /// The node on an estimator.
    pub fn new(est: &'s mut UuvEstimator<f32, STATES>) -> Self {
        Self { est, samples: 0, pending: None }
    }

    /// One row (`None`: missing or unparsable); the estimate after it.
    ///
    /// ```
    /// use edgekf_firmware::systems::uuv::{estimator, UuvNode};
    /// let mut est = estimator().unwrap();
    /// let mut node = UuvNode::new(&mut est);
    /// let mut row = [0.0f32; 15];
    /// row[2] = -9.77;
    /// row[6] = 10.0;
    /// row[11] = 1500.0;
    /// let e = node.step(Some(row));
    /// assert_eq!(e.main.unwrap().k, 1.0);
    /// let e = node.step(None); // predicted through
    /// assert!(e.z.is_finite());
    /// assert_eq!(node.samples(), 2);
    /// ```
    pub fn step(&mut self, row: Option<[f32; 15]>) -> Estimate<f32> {
        self.samples = self.samples.saturating_add(1);
        self.est.step(&sample(row))
    }

    /// Samples stepped (rows, and missing rows bridged).
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The estimator.
    pub fn estimator(&self) -> &UuvEstimator<f32, STATES> {
        self.est
    }
}

crate::frame! {
    /// One sample's estimate.
    pub struct UuvFrame = "uuv {=u32} {=f32} {=f32} {=f32} {=f32} {=u8} {=u8} {=f32} {=f32} {=f32} {=f32} {=f32}" {
        /// Samples stepped so far.
        pub sample: u32,
        /// Main thruster's health factor.
        pub k_t: f32,
        /// Its standard deviation.
        pub k_t_std: f32,
        /// Vertical thruster's health factor.
        pub k_v: f32,
        /// Its standard deviation.
        pub k_v_std: f32,
        /// Main thruster's status ([`status_code`]).
        pub status_t: u8,
        /// Vertical thruster's status.
        pub status_v: u8,
        /// Depth, m.
        pub z: f32,
        /// Heading, rad.
        pub psi: f32,
        /// Surge over ground, m/s.
        pub u: f32,
        /// Roll, rad.
        pub phi: f32,
        /// NIS of the IMU update (NaN when none was applied).
        pub imu_nis: f32,
    }
}

impl UuvFrame {
    /// The frame of estimate `e` after `sample` samples.
    pub fn of(sample: u32, e: &Estimate<f32>) -> Self {
        let nan = f32::NAN;
        let (main, vertical) = (e.main, e.vertical);
        Self {
            sample,
            k_t: main.map_or(nan, |h| h.k),
            k_t_std: main.map_or(nan, |h| h.sd),
            k_v: vertical.map_or(nan, |h| h.k),
            k_v_std: vertical.map_or(nan, |h| h.sd),
            status_t: main.map_or(u8::MAX, |h| status_code(h.status)),
            status_v: vertical.map_or(u8::MAX, |h| status_code(h.status)),
            z: e.z,
            psi: e.attitude[2],
            u: e.nu[0],
            phi: e.attitude[0],
            imu_nis: e.imu_nis.unwrap_or(nan),
        }
    }
}

crate::frame! {
    /// The end of a run: counts (the file's own in [`FileEnd`], just before).
    pub struct UuvEnd = "uuvend {=u32} {=u32} {=u32} {=u32} {=u32}" {
        /// Samples stepped (rows, and missing rows bridged).
        pub samples: u32,
        /// CUSUM alarms of the main thruster.
        pub alarms_t: u32,
        /// Of the vertical thruster.
        pub alarms_v: u32,
        /// The filter's covariance resets.
        pub covariance_resets: u32,
        /// Its refused updates.
        pub refused_updates: u32,
    }
}

impl NodeEstimator for UuvNode<'_> {
    type Input = [f32; 15];
    type Frame = UuvFrame;

    fn step(&mut self, input: Option<[f32; 15]>) -> Innovation {
        let e = UuvNode::step(self, input);
        self.pending = Some(e);
        Innovation::default()
    }

    fn report(&mut self, _: &Poll) -> Option<UuvFrame> {
        self.pending.take().map(|e| UuvFrame::of(self.samples, &e))
    }
}

/// The QEMU image `edgekf-uuv-qemu`: the vehicle's channels from the HIL file (other columns
/// ignored; empty cells are missing values, lines that do not parse are stepped as missing
/// samples and counted, lines missing by their `t` are bridged for up to
/// [`crate::source::MAX_GAP_S`]); a `uuv` frame per sample, then `file` ([`FileEnd`]) and `uuvend`.
pub struct UuvImage;

impl HilImage for UuvImage {
    const NAME: &'static str = "edgekf-uuv-qemu";
    const COLUMNS: &'static [&'static str] = &CHANNELS;
    type Input = [f32; 15];
    type Storage = Storage;
    type Source<B: ByteSource> = ChannelSource<B, 15>;
    type Estimator<'s> = UuvNode<'s>;
    type StartError = EstimatorError;

    fn storage() -> Storage {
        None
    }

    #[inline(never)] // start-up temporaries stay out of the caller's frame
    fn start<B: ByteSource>(input: B, storage: &mut Storage) -> Result<HilNode<'_, Self, B>, HilError<EstimatorError>> {
        let reader = ChannelReader::new(input, CHANNELS).map(ChannelReader::with_empty_cells);
        clocked_node(reader, SAMPLE_RATE_HZ, move || Ok(UuvNode::new(storage.insert(estimator()?))))
    }

    fn finish<B: ByteSource>(node: &HilNode<'_, Self, B>, sink: &mut impl FrameSink) {
        sink.frame(&FileEnd::of(node.source()));
        let n = node.estimator();
        let est = n.estimator();
        let h = est.health();
        sink.frame(&UuvEnd {
            samples: n.samples(),
            alarms_t: est.alarms()[0],
            alarms_v: est.alarms()[1],
            covariance_resets: h.covariance_resets,
            refused_updates: h.refused_updates,
        });
    }
}
