//! The base-excited mount on the node (feature `sdof`, the sixth, test system): one ADXL355
//! axis on the mass, the 2-state filter of the mount's relative motion
//! ([`edgekf::systems::sdof`]), a report per FIFO block and the HIL image `edgekf-sdof-qemu`.
//!
//! The model is discretised at start-up (Van Loan of a 4 × 4 block in software `f64`, once):
//! two states cost the chip too little to make compiling constants in worth a generator.

use crate::adxl355::{self, Adxl355};
use crate::frame::FrameSink;
use crate::hil::{HilError, HilImage, HilNode};
use crate::line_feed::{ByteSource, LineFeed};
use crate::node::{Health, Innovation, Node, NodeEstimator, Poll};
use crate::source::{Adxl355Settings, Adxl355Source, VirtualSource};
use crate::virtual_adxl355::{VirtualAdxl355, VirtualBusError};
use edgekf::linalg::LinalgError;
use edgekf::systems::sdof::{SdofCounters, SdofEstimator, SdofParams};

#[cfg(all(target_os = "none", feature = "qemu"))]
pub mod bench;
pub mod images;
pub mod soak;

/// The mount the node is built for: [`SdofParams::default`] at the ADXL355's default rate
/// (1 kHz, as the default parameters say; a test checks the two agree).
pub fn params() -> SdofParams {
    SdofParams { sample_rate_hz: Adxl355Settings::default().sensor.odr.hz() as f64, ..SdofParams::default() }
}

crate::frame! {
    /// What one poll produced: the estimate at the end of the block and block statistics.
    #[cfg_attr(feature = "defmt", derive(defmt::Format))]
    pub struct SdofBlock = "sdof {=u32} {=u16} {=u16} {=f32} {=f32} {=f32} {=f32}" {
        /// Poll number, from 0.
        pub block: u32,
        /// Samples read from the FIFO in this poll.
        pub read: u16,
        /// Samples given to the estimator as missing (lost, saturated, stuck).
        pub missing: u16,
        /// Relative displacement of the mass, m.
        pub displacement: f32,
        /// Relative velocity, m/s.
        pub velocity: f32,
        /// RMS of this block's innovations, m/s² (0 if none).
        pub innovation_rms: f32,
        /// Mean NIS of this block's innovations (0 if none).
        pub nis_mean: f32,
    }
}

crate::frame! {
    /// The end of a run: the estimator's counters and what the virtual device's feed saw.
    #[derive(Eq)]
    pub struct SdofEnd = "sdofend {=u32} {=u32} {=u32} {=u32} {=u32} {=u32}" {
        /// Samples processed (present or missing).
        pub steps: u32,
        /// Samples that were missing.
        pub missing: u32,
        /// Covariance resets.
        pub covariance_resets: u32,
        /// Refused updates.
        pub refused_updates: u32,
        /// Data lines the feed read (good and bad).
        pub lines: u32,
        /// Data lines it skipped.
        pub bad_lines: u32,
    }
}

impl NodeEstimator for SdofEstimator<f32> {
    type Input = f32;
    type Frame = SdofBlock;

    fn step(&mut self, input: Option<f32>) -> Innovation {
        let s = SdofEstimator::step(self, input);
        Innovation { residual: s.innovation, nis: s.nis }
    }

    fn report(&mut self, poll: &Poll) -> Option<SdofBlock> {
        let now = self.current();
        Some(SdofBlock {
            block: poll.block,
            read: poll.read,
            missing: poll.missing,
            displacement: now.displacement,
            velocity: now.velocity,
            innovation_rms: poll.innovations.rms(),
            nis_mean: poll.nis.mean(),
        })
    }
}

/// Why the node could not start.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StartError {
    /// The accelerometer did not initialise within the attempt budget (last error kept).
    Sensor(adxl355::Error<VirtualBusError>),
    /// The mount's model could not be discretised.
    Model(LinalgError),
}

/// The QEMU image `edgekf-sdof-qemu`: the real driver and loop on a virtual ADXL355 whose
/// samples come from the HIL file (columns `t, ax, ay, az`; `ax` along the mount). Frames: one
/// `sdof` per poll, then `health` and `sdofend`.
pub struct SdofImage;

impl HilImage for SdofImage {
    const NAME: &'static str = "edgekf-sdof-qemu";
    const COLUMNS: &'static [&'static str] = &["t", "ax", "ay", "az"];
    type Input = f32;
    type Storage = ();
    type Source<B: ByteSource> = VirtualSource<B>;
    type Estimator<'s> = SdofEstimator<f32>;
    type StartError = StartError;

    const STORAGE: () = ();

    #[inline(never)] // start-up temporaries (the discretisation) stay out of the caller's frame
    fn start<B: ByteSource>(input: B, _: &mut ()) -> Result<HilNode<'_, Self, B>, HilError<StartError>> {
        let feed = LineFeed::new(input).map_err(HilError::Header)?;
        let estimator = SdofEstimator::new(&params()).map_err(|e| HilError::Start(StartError::Model(e)))?;
        let sensor = Adxl355::new_i2c(VirtualAdxl355::new(feed), adxl355::ADDRESS_ASEL_LOW);
        let mut health = Health::default();
        match Adxl355Source::start(sensor, Adxl355Settings::default(), &mut health) {
            Ok(source) => Ok(Node::new(source, estimator, health)),
            Err((e, _)) => Err(HilError::Start(StartError::Sensor(e))),
        }
    }

    fn finish<B: ByteSource>(node: &HilNode<'_, Self, B>, sink: &mut impl FrameSink) {
        sink.frame(&node.health());
        let SdofCounters { steps, missing, filter } = node.estimator().counters();
        let feed = node.source().device().feed();
        sink.frame(&SdofEnd {
            steps,
            missing,
            covariance_resets: filter.covariance_resets,
            refused_updates: filter.refused_updates,
            lines: feed.lines(),
            bad_lines: feed.bad_lines(),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_node_runs_the_default_mount_at_the_sensors_rate() {
        assert_eq!(params(), SdofParams::default());
    }

    #[test]
    fn a_file_without_the_axes_is_refused_with_its_reason() {
        let r = SdofImage::start(&b"t,ax\n0,1\n"[..], &mut ());
        assert!(matches!(r, Err(HilError::Header(_))));
    }
}
