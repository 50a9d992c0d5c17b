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
//!
//! The image runs the model monitor ([`crate::monitor::Monitored`]) on the normalised
//! innovations of its eleven measured channels ([`MONITORED`]), read from the estimator's own
//! updates ([`UpdateObserver`]) rather than from a second filter. Two channels do not fit the
//! model on healthy flights: the window means of `acc_x` (0) and of the heading (7) alarm on
//! most 300 s flights of the simulator (10 of seeds 1–12), as the boom's gyro does; the
//! vehicle's reduced dynamics leave slow errors in surge and yaw there that the cautious
//! process noise follows but does not whiten. The DVL's channels (8–10) are quiet on healthy
//! flights and flag a DVL offset (`cargo xtask roundtrip uuv`).

use crate::frame::FrameSink;
use crate::hil::{sensors_node, FileEnd, HilError, HilImage, HilNode};
use crate::line_feed::ByteSource;
use crate::monitor::{Monitored, Normalised};
use crate::node::{Innovation, NodeEstimator, Pending, Poll};
use crate::source::ChannelSource;
use edgekf::residual::MonitorSettings;
use edgekf::systems::uuv::{
    Command, Estimate, EstimatorError, Layout, Sample, Status, UpdateObserver, UuvEstimator,
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

/// The channels the model monitor watches: every measured one, in the data file's names and
/// order (`acc_x` … `gyro_z`, `depth`, `heading`, `dvl_u`, `dvl_v`, `dvl_w`), so that a
/// `mismatch` frame's channel is the sensor whose readings the model stopped explaining.
pub const MONITORED: usize = 11;

/// The model monitor's settings: the shipped false-alarm rate (one per 100 h) at
/// [`SAMPLE_RATE_HZ`], tests from 30 s after start-up, and the oscillator's tolerance of 0.2
/// autocorrelation. Why 30 s: the filter starts its velocity, attitude and biases from one
/// sample with wide spreads, and its innovations exceed their covariance until it has
/// converged. The DVL's channels update one sample in ten: their run length, counted in their
/// own updates, is ten times as long in time, so they alarm less often than their share (on
/// the safe side), and a bias window of 256 readings spans 51 s.
pub fn monitor_settings() -> MonitorSettings {
    let rate = f64::from(SAMPLE_RATE_HZ);
    MonitorSettings { settle_s: 30.0, whiteness_tolerance: 0.2, ..MonitorSettings::new(rate) }
}

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
    pending: Pending<Estimate<f32>>,
}

impl<'s> UuvNode<'s> {
    /// The node on an estimator.
    pub fn new(est: &'s mut UuvEstimator<f32, STATES>) -> Self {
        Self { est, samples: 0, pending: Pending::new() }
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

    /// [`step`](Self::step), writing each monitored channel's normalised innovation into `z`
    /// (left as it was where the channel had no update).
    fn step_normalised_into(&mut self, row: Option<[f32; 15]>, z: &mut [f32; MONITORED]) -> Estimate<f32> {
        self.samples = self.samples.saturating_add(1);
        self.est.step_observed(&sample(row), &mut Normalise(z))
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
        self.pending.keep(Some(e), Innovation::default())
    }

    fn report(&mut self, _: &Poll) -> Option<UuvFrame> {
        let samples = self.samples;
        self.pending.report(|e| UuvFrame::of(samples, &e))
    }
}

/// Writes an applied update's innovations, each over its own standard deviation `√Sᵢᵢ`, into
/// the monitor's channels. The IMU, depth and heading are one joint update: each of its
/// channels is standard normal on its own (its marginal), which is what the monitor tests.
struct Normalise<'z>(&'z mut [f32; MONITORED]);

impl UpdateObserver<f32> for Normalise<'_> {
    fn seen<const K: usize>(&mut self, innovation: &edgekf::filter::Innovation<f32, K>, channels: [usize; K]) {
        for (i, c) in channels.into_iter().enumerate() {
            if let (Some(z), Some(&nu), Some(&s)) =
                (self.0.get_mut(c), innovation.residual.get(i), innovation.s.get((i, i)))
            {
                // A variance that is not positive gives a NaN or infinite z: skipped by the
                // monitor as a channel without an update.
                *z = nu / libm::sqrtf(s);
            }
        }
    }
}

/// Its eleven channels ([`MONITORED`]): every measured channel's innovation over its own
/// variance.
impl Normalised<MONITORED> for UuvNode<'_> {
    fn step_normalised(&mut self, input: Option<[f32; 15]>, z: &mut [f32; MONITORED]) -> Innovation {
        let e = self.step_normalised_into(input, z);
        self.pending.keep(Some(e), Innovation::default())
    }
}

/// The QEMU image `edgekf-uuv-qemu`: the vehicle's channels from the HIL file (other columns
/// ignored; empty cells are missing values, lines that do not parse are stepped as missing
/// samples and counted, lines missing by their `t` are bridged for up to
/// [`crate::source::MAX_GAP_S`]); a `uuv` frame per sample (a `mismatch` after it when the
/// model monitor found one: the channel is [`MONITORED`]'s number, 0 `acc_x` … 10 `dvl_w`), then
/// `file` ([`FileEnd`]) and `uuvend`.
pub struct UuvImage;

impl HilImage for UuvImage {
    const NAME: &'static str = "edgekf-uuv-qemu";
    const COLUMNS: &'static [&'static str] = &CHANNELS;
    type Input = [f32; 15];
    type Storage = Storage;
    type Source<B: ByteSource> = ChannelSource<B, 15>;
    type Estimator<'s> = Monitored<UuvNode<'s>, MONITORED>;
    type StartError = EstimatorError;

    const STORAGE: Storage = None;

    #[inline(never)] // start-up temporaries stay out of the caller's frame
    fn start<B: ByteSource>(input: B, storage: &mut Storage) -> Result<HilNode<'_, Self, B>, HilError<EstimatorError>> {
        sensors_node(input, CHANNELS, SAMPLE_RATE_HZ, move || {
            Ok(Monitored::new(UuvNode::new(storage.insert(estimator()?)), &monitor_settings()))
        })
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A level row at 1500 rpm, with a DVL reading when `dvl`.
    fn row(dvl: bool) -> Option<[f32; 15]> {
        let d = if dvl { [1.54, 0.0, 0.0] } else { [f32::NAN; 3] };
        Some([0.0, -0.9, -9.77, 0.0, 0.0, 0.0, 10.0, 0.785, d[0], d[1], d[2], 1500.0, 1670.0, 0.0, 0.0])
    }

    #[test]
    fn each_update_writes_its_channels_normalised_and_only_those() {
        let mut est = estimator().unwrap();
        let mut node = UuvNode::new(&mut est);
        let mut z = [f32::NAN; MONITORED];
        // The first sample starts the filter: no update, nothing written.
        node.step_normalised(row(true), &mut z);
        assert!(z.iter().all(|v| v.is_nan()), "{z:?}");
        node.step_normalised(row(false), &mut z);
        assert!(z[..8].iter().all(|v| v.is_finite()) && z[8..].iter().all(|v| v.is_nan()), "{z:?}");
        let mut z = [f32::NAN; MONITORED];
        node.step_normalised(row(true), &mut z);
        assert!(z.iter().all(|v| v.is_finite()), "{z:?}");
        // A missing row is a prediction: no channel is written.
        let mut z = [f32::NAN; MONITORED];
        node.step_normalised(None, &mut z);
        assert!(z.iter().all(|v| v.is_nan()), "{z:?}");
        assert_eq!(node.samples(), 4);
    }

    #[test]
    fn a_dvl_offset_in_the_readings_is_a_biased_normalised_innovation() {
        // 0.1 m/s on w (twenty of the DVL's σ), which the filter's vertical speed cannot take
        // up at once: the first reading's normalised w innovation is far beyond the others.
        let mut est = estimator().unwrap();
        let mut node = UuvNode::new(&mut est);
        let mut z = [f32::NAN; MONITORED];
        for k in 0..40 {
            node.step_normalised(row(k % 10 == 0 && k < 30), &mut z);
        }
        let mut biased = row(true);
        if let Some(r) = biased.as_mut() {
            r[10] += 0.1;
        }
        let mut z = [f32::NAN; MONITORED];
        node.step_normalised(biased, &mut z);
        assert!(z[10] > 3.0 && z[8].abs() < 3.0, "{z:?}");
    }
}
