//! Rotor virtual sensing from accelerometers: the paper rotor read by four ADXL355-like
//! channels at the probes' places (`n5_ax, n5_ay, n32_ax, n32_ay`, m/s²), the sensors'
//! 2nd-order Butterworth low-pass (250 Hz) inside the model: 28 states (8 modes, one phasor per
//! unbalance, two states per low-pass), the robust tuning (`Tuning::robust`: it holds the disk
//! error near 1 µm with the model's stiffness or speed a little off). Computed on the host in
//! `f64` and compiled in (`edgekf rotor export --config host-sim/configs/rotor_paper_accel.toml
//! --robust --out firmware/src/systems/rotor/generated/rotor_accel.rs`; a cross-crate test checks the file is
//! current). Outputs and schedule are the probes' node's ([`super`]): the disk nodes'
//! displacement and the unbalance forces, the start-up term of rank [`ACCEL_START_RANK`] for
//! [`STEADY_AFTER`] samples, then the steady-state gain.

use super::{rotor_design, RotorDesign, RotorEstimator, RotorNode, STEADY_AFTER};
use crate::frame::FrameSink;
use crate::hil::{HilError, HilImage, HilNode};
use crate::line_feed::{ByteSource, ChannelReader};
use crate::node::Node;
use crate::source::{Adxl355Settings, Axis, AxisPair};
use crate::virtual_pair::{PairStartError, VirtualPairSource};

/// The exported model, steady state, prior and start-up term, as the host wrote them (`f64`).
#[allow(missing_docs, clippy::excessive_precision, clippy::unreadable_literal)]
pub mod constants {
    include!("generated/rotor_accel.rs");
}

/// States of the model: the probes' 20 and two per accelerometer low-pass.
pub const ACCEL_STATES: usize = 28;
/// Sensor channels, in the order the filter takes them, m/s².
pub const ACCEL_CHANNELS: [&str; 4] = ["n5_ax", "n5_ay", "n32_ax", "n32_ay"];
/// Rank of the start-up term (the exporter's `ACCEL_START_RANK`; `ROTOR_U0`'s width, or
/// [`ACCEL_DESIGN`] would not compile).
pub const ACCEL_START_RANK: usize = 12;

/// The accelerometers' design (`generated/rotor_accel.rs`).
pub const ACCEL_DESIGN: RotorDesign<ACCEL_STATES, ACCEL_START_RANK> = rotor_design!(constants);

/// The accelerometer rotor's estimator.
pub type AccelEstimator = RotorEstimator<ACCEL_STATES, ACCEL_START_RANK>;

impl RotorEstimator<ACCEL_STATES, ACCEL_START_RANK> {
    /// The accelerometers' compiled-in model at rest with the exported prior: the start-up
    /// term for the first [`STEADY_AFTER`] samples, then the steady-state gain alone.
    ///
    /// ```
    /// let mut est = edgekf_firmware::systems::rotor::accel::AccelEstimator::accel();
    /// assert!(est.step(Some([0.0; 4])).nis.is_finite());
    /// ```
    pub fn accel() -> Self {
        Self::from_design(&ACCEL_DESIGN, Some(STEADY_AFTER))
    }
}

crate::frame! {
    /// The end of an accelerometer rotor run.
    #[derive(Eq)]
    pub struct RotorAccelEnd = "rotor_accel {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32}" {
        /// Polls (FIFO periods).
        pub polls: u32,
        /// Input lines read.
        pub lines: u32,
        /// Of those, lines that did not parse (stepped as missing).
        pub bad_lines: u32,
        /// Samples refused as frozen, over both parts (a bad line counts once per part).
        pub stuck: u32,
        /// Samples bridged by prediction (lost in a FIFO, never produced), over both parts.
        pub bridged: u32,
        /// Bus errors, over both parts.
        pub bus_errors: u32,
        /// Polls given up, over both parts.
        pub failed_polls: u32,
        /// Filter covariance resets (see [`RotorEstimator::health`]).
        pub covariance_resets: u32,
        /// Refused updates.
        pub refused_updates: u32,
    }
}

/// The QEMU image `edgekf-rotor-accel-qemu`: two virtual ADXL355s (x and y at node 5, x and y
/// at node 32) fed from the HIL file's `n5_ax, n5_ay, n32_ax, n32_ay` (m/s²; other columns
/// ignored), read through the driver in FIFO blocks and paired in lockstep
/// ([`VirtualPairSource`]); a `rot` frame ([`super::RotorFrame`]) per poll (its last sample),
/// then `rotor_accel`.
pub struct RotorAccelImage;

impl HilImage for RotorAccelImage {
    const NAME: &'static str = "edgekf-rotor-accel-qemu";
    const COLUMNS: &'static [&'static str] = &ACCEL_CHANNELS;
    type Input = [f32; 4];
    type Storage = ();
    type Source<B: ByteSource> = VirtualPairSource<B>;
    type Estimator<'s> = RotorNode<ACCEL_STATES, ACCEL_START_RANK>;
    type StartError = PairStartError;

    const STORAGE: () = ();

    #[inline(never)] // start-up temporaries stay out of the caller's frame
    fn start<B: ByteSource>(input: B, _: &mut ()) -> Result<HilNode<'_, Self, B>, HilError<Self::StartError>> {
        let reader = ChannelReader::new(input, ACCEL_CHANNELS).map_err(HilError::Header)?;
        let settings = Adxl355Settings::default().with_axes(AxisPair(Axis::X, Axis::Y));
        let mut health = Default::default();
        let source = VirtualPairSource::start(reader, settings, &mut health).map_err(HilError::Start)?;
        Ok(Node::new(source, RotorNode::new(AccelEstimator::accel()), health))
    }

    fn finish<B: ByteSource>(node: &HilNode<'_, Self, B>, sink: &mut impl FrameSink) {
        let (h, f) = (node.health(), node.estimator().estimator().health());
        sink.frame(&RotorAccelEnd {
            polls: h.blocks,
            lines: node.source().lines(),
            bad_lines: node.source().reader().bad_lines(),
            stuck: h.stuck,
            bridged: h.bridged,
            bus_errors: h.bus_errors,
            failed_polls: h.failed_polls,
            covariance_resets: f.covariance_resets,
            refused_updates: f.refused_updates,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::constants::*;
    use super::*;
    use edgekf::export::matrix;

    /// The model was discretised at the probes' node's rate, so the schedule is the same.
    #[test]
    fn generated_header_is_the_accelerometer_model_at_the_node_rate() {
        let mut lines = include_str!("generated/rotor_accel.rs").lines();
        let header = lines.next().unwrap();
        let rate = std::format!(" {} Hz.", super::super::SAMPLE_RATE_HZ);
        assert!(header.contains(&rate) && header.contains("--robust"), "{header}");
        assert!(lines.next().unwrap().contains(&std::format!("Sensors: {}.", ACCEL_CHANNELS.join(", "))));
    }

    /// The compile-time `f32` design is the run-time conversion of the `f64` constants.
    #[test]
    fn design_is_bit_identical_to_the_f64_conversion() {
        let d = ACCEL_DESIGN.filter;
        let f = |rows: &[[f64; ACCEL_STATES]; ACCEL_STATES]| matrix(rows).map(|v| v as f32);
        assert_eq!((d.a, d.closed), (f(&ROTOR_A), f(&ROTOR_CLOSED)));
        assert_eq!((d.c, d.pct), (matrix(&ROTOR_C).map(|v| v as f32), matrix(&ROTOR_PCT).map(|v| v as f32)));
        assert_eq!((d.s, d.s_inv), (matrix(&ROTOR_S).map(|v| v as f32), matrix(&ROTOR_S_INV).map(|v| v as f32)));
        assert_eq!((d.u0, d.signs), (matrix(&ROTOR_U0).map(|v| v as f32), matrix(&ROTOR_SIGNS).map(|v| v as f32)));
        let (disk, force) = (matrix(&ROTOR_DISK).map(|v| v as f32), matrix(&ROTOR_FORCE).map(|v| v as f32));
        assert_eq!(
            ACCEL_DESIGN.outputs_t,
            nalgebra::SMatrix::<f32, 8, ACCEL_STATES>::from_fn(|i, j| {
                if i < 4 {
                    disk[(i, j)]
                } else {
                    force[(i - 4, j)]
                }
            })
            .transpose()
        );
    }

    /// The accelerometer node switches at the documented sample, as the probes' node does.
    #[test]
    fn switches_to_the_steady_gain_at_steady_after() {
        let mut est = AccelEstimator::accel();
        for _ in 0..STEADY_AFTER {
            est.step(Some([0.0; 4]));
        }
        assert!(!est.is_steady());
        est.step(Some([0.0; 4]));
        assert!(est.is_steady() && est.health() == edgekf::filter::FilterHealth::default());
    }
}
