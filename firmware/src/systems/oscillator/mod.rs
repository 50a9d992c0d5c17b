//! The harmonic-force oscillator on the node: one ADXL355 axis, the single-mode model driven by
//! a force at the running speed ([`edgekf::systems::oscillator`]), its block report and its HIL
//! image.
//!
//! The model and its steady-state gain are computed on the host in `f64` and compiled in: no
//! discretisation and no Riccati solve at start-up (which would cost about 15 KB of stack and a
//! few hundred thousand software-`f64` operations on the Cortex-M4F). Regenerate after changing
//! `NodeConfig::default().estimator` (a test below fails until then):
//! `cargo run -p edgekf-sim -- oscillator export --out firmware/src/systems/oscillator/generated/harmonic.rs`.
//! An image built with `EDGEKF_OSCILLATOR_MODEL=path/to/harmonic.rs` compiles that file in
//! instead (see `build.rs`): how `cargo xtask roundtrip oscillator` runs a corrected model.

use crate::adxl355::{self, Adxl355, Interface};
use crate::capture::{Captured, WindowState};
use crate::frame::FrameSink;
use crate::hil::{HilError, HilImage, HilNode};
use crate::line_feed::{ByteSource, LineFeed};
use crate::monitor::{Monitored, Normalised};
use crate::node::{Health, Innovation, Node, NodeEstimator, Poll};
use crate::source::{Adxl355Settings, Adxl355Source, VirtualSource};
use crate::virtual_adxl355::VirtualAdxl355;
use edgekf::export::{matrix, model};
use edgekf::residual::MonitorSettings;
use edgekf::systems::oscillator::{EstimatorCounters, HarmonicForceEstimator, HarmonicForceParams, ModelError};

#[cfg(all(target_os = "none", feature = "qemu"))]
pub mod bench;
pub mod images;
pub mod soak;

#[allow(missing_docs, clippy::excessive_precision, clippy::unreadable_literal)]
mod constants {
    include!(concat!(env!("OUT_DIR"), "/harmonic.rs"));
}

/// The estimator from the compiled-in model and gain, with `params` for the physical scaling
/// (natural frequency, modal mass) and the gate.
///
/// ```
/// use edgekf::systems::oscillator::HarmonicForceParams;
/// let est = edgekf_firmware::systems::oscillator::compiled_estimator(&HarmonicForceParams::default()).unwrap();
/// assert_eq!(est.counters().steps, 0);
/// ```
pub fn compiled_estimator(params: &HarmonicForceParams) -> Result<HarmonicForceEstimator<f32>, ModelError> {
    use constants::*;
    let m = model(&HARMONIC_A, &HARMONIC_C, &HARMONIC_Q, &HARMONIC_R);
    HarmonicForceEstimator::from_gain(params, &m, &matrix(&HARMONIC_GAIN), &matrix(&HARMONIC_S))
}

/// The model monitor's settings at `sample_rate_hz`: the shipped false-alarm rate (one per
/// 100 h); tests from 1 s after start-up (started from rest with the steady-state gain, the
/// estimator's NIS averages 6·10⁴ over its first 0.13 s and back near 1 from 0.5 s on, on the default
/// recording); 0.2 of autocorrelation tolerated (on healthy recordings the innovations have
/// ρ(1) = −0.16, ρ(2) = −0.12, ρ(3) = −0.10: the steady-state gain's process noise is above the
/// truth's).
pub fn monitor_settings(sample_rate_hz: f64) -> MonitorSettings {
    MonitorSettings { settle_s: 1.0, whiteness_tolerance: 0.2, ..MonitorSettings::new(sample_rate_hz) }
}

/// Everything the oscillator node needs to start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeConfig {
    /// I²C address of the ADXL355 (0x1D with ASEL low).
    pub address: u8,
    /// How the ADXL355 is driven.
    pub source: Adxl355Settings,
    /// Estimator model and tuning.
    pub estimator: HarmonicForceParams,
}

impl Default for NodeConfig {
    /// ADXL355 at 0x1D, ±2 g, 1 kHz, 16-sample blocks, X axis, the default harmonic model.
    fn default() -> Self {
        let source = Adxl355Settings::default();
        Self {
            address: adxl355::ADDRESS_ASEL_LOW,
            source,
            estimator: HarmonicForceParams {
                sample_rate_hz: source.sensor.odr.hz() as f64,
                ..HarmonicForceParams::default()
            },
        }
    }
}

crate::frame! {
    /// What one poll produced: the estimate at the end of the block and block statistics.
    #[cfg_attr(feature = "defmt", derive(defmt::Format))]
    pub struct BlockReport = "blk {=u32} {=u16} {=u16} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32}" {
        /// Poll number, from 0.
        pub block: u32,
        /// Samples read from the FIFO in this poll.
        pub read: u16,
        /// Samples given to the estimator as missing (lost, saturated, stuck).
        pub missing: u16,
        /// Modal displacement, m.
        pub displacement: f32,
        /// Modal velocity, m/s.
        pub velocity: f32,
        /// In-phase force, N.
        pub force_cos: f32,
        /// Quadrature force, N.
        pub force_sin: f32,
        /// Force amplitude, N.
        pub force_amplitude: f32,
        /// RMS of this block's innovations, m/s² (0 if none).
        pub innovation_rms: f32,
        /// Mean NIS of this block's innovations (0 if none).
        pub nis_mean: f32,
    }
}

crate::frame! {
    /// The estimator's counters at the end of a run.
    #[derive(Eq)]
    pub struct EstimatorFrame = "estimator {=u32} {=u32} {=u32} {=u32} {=u32}" {
        /// Samples processed (present or missing).
        pub steps: u32,
        /// Samples that were missing.
        pub missing: u32,
        /// Samples rejected by the innovation gate.
        pub gated: u32,
        /// Covariance resets.
        pub covariance_resets: u32,
        /// Refused updates.
        pub refused_updates: u32,
    }
}

impl From<EstimatorCounters> for EstimatorFrame {
    fn from(e: EstimatorCounters) -> Self {
        Self {
            steps: e.steps,
            missing: e.missing,
            gated: e.gated,
            covariance_resets: e.filter.covariance_resets,
            refused_updates: e.filter.refused_updates,
        }
    }
}

crate::frame! {
    /// The node's settings, right after start-up.
    pub struct StartFrame = "start odr={=f32} watermark={=u8}" {
        /// Output data rate, Hz.
        pub odr: f32,
        /// FIFO watermark, entries.
        pub watermark: u8,
    }
}

impl NodeEstimator for HarmonicForceEstimator<f32> {
    type Input = f32;
    type Frame = BlockReport;

    fn step(&mut self, input: Option<f32>) -> Innovation {
        let s = HarmonicForceEstimator::step(self, input);
        Innovation { residual: s.innovation, nis: s.nis }
    }

    fn report(&mut self, poll: &Poll) -> Option<BlockReport> {
        let now = self.current();
        Some(BlockReport {
            block: poll.block,
            read: poll.read,
            missing: poll.missing,
            displacement: now.displacement,
            velocity: now.velocity,
            force_cos: now.force_cos,
            force_sin: now.force_sin,
            force_amplitude: now.force_amplitude,
            innovation_rms: poll.innovations.rms(),
            nis_mean: poll.nis.mean(),
        })
    }
}

/// The estimator as the QEMU image runs it, for its model monitor: the compiled-in estimator
/// and `1/√S` of its steady-state gain. `S` is a constant there, so the normalised innovation
/// is a product: `√NIS` would be a software square root (libm's: the monitored step measured
/// 1 040 instructions with it on the Cortex-M4F, against 751 now). Each sample has the declared
/// accelerometer offset (`HARMONIC_ACCEL_OFFSET`) taken off before the filter sees it: one
/// subtraction, and with the committed offset of 0 the same bits as without it.
pub struct Watched {
    filter: HarmonicForceEstimator<f32>,
    inv_sd: f32,
    offset: f32,
}

impl Watched {
    /// `filter`, built by [`compiled_estimator`] (whose `S` and offset this takes), watched.
    pub fn compiled(filter: HarmonicForceEstimator<f32>) -> Self {
        let inv_sd = (1.0 / libm::sqrt(constants::HARMONIC_S[0][0])) as f32;
        Self { filter, inv_sd, offset: accel_offset() }
    }
}

/// The accelerometer offset the compiled-in model declares, m/s² (the scenario's `[filter]
/// accel_offset_m_s2` it was exported from), subtracted from each sample by [`Watched`].
pub fn accel_offset() -> f32 {
    constants::HARMONIC_ACCEL_OFFSET as f32
}

impl core::ops::Deref for Watched {
    type Target = HarmonicForceEstimator<f32>;
    fn deref(&self) -> &Self::Target {
        &self.filter
    }
}

impl NodeEstimator for Watched {
    type Input = f32;
    type Frame = BlockReport;

    fn step(&mut self, input: Option<f32>) -> Innovation {
        NodeEstimator::step(&mut self.filter, input.map(|a| a - self.offset))
    }

    fn report(&mut self, poll: &Poll) -> Option<BlockReport> {
        NodeEstimator::report(&mut self.filter, poll)
    }
}

/// Its one channel, the accelerometer axis.
impl Normalised<1> for Watched {
    fn step_normalised(&mut self, input: Option<f32>, [z]: &mut [f32; 1]) -> Innovation {
        let s = HarmonicForceEstimator::step(&mut self.filter, input.map(|a| a - self.offset));
        *z = match (s.innovation, s.nis) {
            (Some(r), Some(_)) => r * self.inv_sd,
            _ => f32::NAN,
        };
        Innovation { residual: s.innovation, nis: s.nis }
    }
}

/// Samples the oscillator's node keeps for the window hand-over ([`crate::capture`]): 4.096 s
/// at 1 kHz. What the loop needs: `edgekf loop oscillator` names a 0.05 m/s² offset (and a
/// second harmonic, the mode's frequency and damping at 3× their limits) on 4 s runs (its
/// effect matrix), the filter settling in the first 0.5 s of them. RAM: 16 KB of `f32`, an
/// eighth of the part's 128 KB, beside the node's few KB.
pub const WINDOW: usize = 4096;

crate::frame! {
    /// The estimator's state when the window froze (at its last sample), and the offset the
    /// node took off each sample (the window's samples are raw).
    pub struct WindowStateFrame = "window_state displacement={=f32} velocity={=f32} force_cos={=f32} force_sin={=f32} offset={=f32}" {
        /// Modal displacement, m.
        pub displacement: f32,
        /// Modal velocity, m/s.
        pub velocity: f32,
        /// In-phase force, N.
        pub force_cos: f32,
        /// Quadrature force, N.
        pub force_sin: f32,
        /// The declared accelerometer offset ([`accel_offset`]), m/s².
        pub offset: f32,
    }
}

impl WindowState for Monitored<Watched, 1> {
    type State = WindowStateFrame;
    fn window_state(&self) -> WindowStateFrame {
        let now = self.current();
        WindowStateFrame {
            displacement: now.displacement,
            velocity: now.velocity,
            force_cos: now.force_cos,
            force_sin: now.force_sin,
            offset: self.offset,
        }
    }
}

/// Why the node could not start.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StartError<E> {
    /// The accelerometer did not initialise within the attempt budget (last error kept).
    Sensor(adxl355::Error<E>),
    /// The estimator's model could not be built from the parameters.
    Model(ModelError),
}

/// The oscillator node on an ADXL355 behind interface `IF`: the compiled-in estimator, the
/// declared accelerometer offset taken off each sample ([`Watched`]), on the board as in QEMU.
pub type OscillatorNode<IF> = Node<Adxl355Source<IF>, Watched>;

/// Builds the estimator from the compiled-in model ([`compiled_estimator`]; `config.estimator`
/// supplies its scaling) and initialises the accelerometer (with retries). On failure the
/// driver is handed back with the reason, so the caller can retry later.
#[allow(clippy::type_complexity)]
#[inline(never)] // start-up temporaries stay out of the caller's (main's) frame
pub fn start<IF: Interface>(
    sensor: Adxl355<IF>,
    config: &NodeConfig,
) -> Result<OscillatorNode<IF>, (StartError<IF::Error>, Adxl355<IF>)> {
    let estimator = match compiled_estimator(&config.estimator) {
        Ok(e) => Watched::compiled(e),
        Err(e) => return Err((StartError::Model(e), sensor)),
    };
    let mut health = Health::default();
    match Adxl355Source::start(sensor, config.source, &mut health) {
        Ok(source) => Ok(Node::new(source, estimator, health)),
        Err((e, sensor)) => Err((StartError::Sensor(e), sensor)),
    }
}

crate::frame! {
    /// The HIL input as the virtual device's feed saw it.
    #[derive(Eq)]
    pub struct FeedFrame = "feed {=u32} {=u32} {=u32}" {
        /// Data lines read (good and bad).
        pub lines: u32,
        /// Data lines skipped.
        pub bad_lines: u32,
        /// Header columns the device ignored.
        pub ignored_columns: u32,
    }
}

/// What the virtual ADXL355 did: the faults it injected, for the test to check the node's
/// counts against. The device's own counters are the frame (one list of the counts).
pub type VirtualFrame = crate::virtual_adxl355::VirtualCounters;

/// The QEMU image `edgekf-qemu`: the real driver and loop on a virtual ADXL355 whose samples
/// come from the HIL file (columns `t, ax, ay, az`, optional fault columns), with the model
/// monitor on the estimator's one channel (the X axis, channel 0) and the last [`WINDOW`]
/// samples kept for the hand-over. Frames: `start`, one `blk` per poll (a `mismatch` after it
/// when the monitor found one; after the first, the window's frames: [`crate::capture`]), then
/// `health`, `estimator`, `feed`, `virtual`.
pub struct OscillatorImage;

impl HilImage for OscillatorImage {
    const NAME: &'static str = "edgekf-qemu";
    const COLUMNS: &'static [&'static str] = &["t", "ax", "ay", "az"];
    type Input = f32;
    type Storage = [f32; WINDOW];
    type Source<B: ByteSource> = VirtualSource<B>;
    type Estimator<'s> = Captured<'s, Monitored<Watched, 1>, WINDOW>;
    type StartError = StartError<crate::virtual_adxl355::VirtualBusError>;

    const STORAGE: [f32; WINDOW] = [f32::NAN; WINDOW];

    #[inline(never)] // start-up temporaries stay out of the caller's frame
    fn start<B: ByteSource>(
        input: B,
        ring: &mut [f32; WINDOW],
    ) -> Result<HilNode<'_, Self, B>, HilError<Self::StartError>> {
        let feed = LineFeed::new(input).map_err(HilError::Header)?;
        let config = NodeConfig::default();
        let sensor = Adxl355::new_i2c(VirtualAdxl355::new(feed), config.address);
        let node = start(sensor, &config).map_err(|(e, _)| HilError::Start(e))?;
        let settings = monitor_settings(config.estimator.sample_rate_hz);
        let rate = config.source.sensor.odr.hz() as u32;
        Ok(node.map_estimator(|watched| Captured::new(Monitored::new(watched, &settings), ring, rate)))
    }

    fn started<B: ByteSource>(node: &HilNode<'_, Self, B>, sink: &mut impl FrameSink) {
        let sensor = node.source().settings().sensor;
        sink.frame(&StartFrame { odr: sensor.odr.hz(), watermark: sensor.fifo_watermark });
    }

    fn finish<B: ByteSource>(node: &HilNode<'_, Self, B>, sink: &mut impl FrameSink) {
        sink.frame(&node.health());
        sink.frame(&EstimatorFrame::from(node.estimator().counters()));
        let device = node.source().device();
        let feed = device.feed();
        sink.frame(&FeedFrame {
            lines: feed.lines(),
            bad_lines: feed.bad_lines(),
            ignored_columns: feed.columns().ignored() as u32,
        });
        sink.frame(&device.counters());
    }
}

#[cfg(test)]
mod tests;
