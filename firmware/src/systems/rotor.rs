//! Rotor virtual sensing on the node: the modally reduced rotor (8 modes, one rotating phasor
//! per unbalance) and its augmented Kalman filter, computed on the host in `f64` and compiled in
//! (`edgekf rotor export --config host-sim/configs/rotor_paper.toml --out
//! firmware/src/generated/rotor.rs`; a cross-crate test checks the file is current).
//!
//! Inputs: the four proximity probes of the paper rotor (`n5_x, n5_y, n32_x, n32_y`, m).
//! Outputs per sample: the x/y displacement of both disk nodes (12 and 23), which no sensor
//! measures, and the unbalance forces there ([`RotorFrame`], one per sample in the HIL image
//! [`RotorImage`]).

use crate::frame::FrameSink;
use crate::hil::{HilError, HilImage, HilNode};
use crate::line_feed::{ByteSource, ChannelReader};
use crate::node::{Innovation, Node, NodeEstimator, Poll};
use crate::source::ChannelSource;
use edgekf::filter::{FilterHealth, KalmanFilter, RiccatiError, SteadyStateFilter};
use nalgebra::{ArrayStorage, SMatrix, SVector};

#[allow(missing_docs, clippy::excessive_precision, clippy::unreadable_literal)]
mod constants {
    include!("../generated/rotor.rs");
}

/// States of the reduced model.
pub const STATES: usize = 20;
/// Sensor channels, in the order the filter takes them.
pub const CHANNELS: [&str; 4] = ["n5_x", "n5_y", "n32_x", "n32_y"];
/// Disk nodes whose displacement the node reports.
pub const DISK_NODES: [usize; 2] = [12, 23];

/// One sample's estimates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotorReport {
    /// `x, y` of disk node 12 then of disk node 23, m.
    pub disk: [f32; 4],
    /// `F_x, F_y` at node 12 then at node 23, N.
    pub force: [f32; 4],
    /// NIS of this sample's update (NaN if the sample was missing or refused).
    pub nis: f32,
}

/// Sample rate the compiled-in model was discretised at, Hz: `operation.sample_rate` of
/// `rotor_paper.toml`, the "1000 Hz" in the header of `generated/rotor.rs` (a test below checks
/// the header, a cross-crate test the configuration).
pub const SAMPLE_RATE_HZ: u32 = 1000;

/// Samples the node runs the time-varying filter for before it switches to the steady-state
/// gain: 0.5 s at [`SAMPLE_RATE_HZ`]. Missing samples count too: the schedule follows time
/// since start-up, not the data, so it is the same on every run.
///
/// Why a switch at all: the time-varying step costs about 95 000 Cortex-M4 instructions per
/// sample (`cargo xtask bench`, `rotor_node_step`), more than the 84 000 cycles a 1 kHz sample
/// has at 84 MHz; the steady-state step (`rotor_node_steady`, about 12 700) has no covariance
/// arithmetic. Why not the steady gain from the start: the node starts from rest with the wide
/// exported prior `P0`, and the time-varying gain, large while `P` shrinks, finds the unbalance
/// forces within the start-up transient, where the steady gain alone would take the slow
/// steady-state rate. Why 0.5 s: by then the gain has converged far enough that the switch
/// costs nothing measurable (reference data, 4 s, t ≥ 1 s: disk error 0.351 µm switched
/// against 0.357 µm with the time-varying filter throughout, NIS mean 3.96 in both;
/// `cargo test -p edgekf-tests --test rotor_node`), and it is the schedule of the paper being
/// reproduced.
///
/// The start-up phase itself does not fit 1 kHz at 84 MHz: a node sampling in real time falls
/// behind by at least 70 samples over it (one cycle per instruction; more with flash wait
/// states) and must buffer them; the steady-state step then catches up within about 100
/// samples.
///
/// ```
/// use edgekf_firmware::systems::rotor::{RotorEstimator, STEADY_AFTER};
/// let mut est = RotorEstimator::new();
/// for _ in 0..STEADY_AFTER {
///     est.step(Some([0.0; 4]));
/// }
/// assert!(!est.is_steady()); // the switch happens at the start of sample STEADY_AFTER
/// est.step(Some([0.0; 4]));
/// assert!(est.is_steady());
/// ```
pub const STEADY_AFTER: u32 = SAMPLE_RATE_HZ / 2;

/// An exported `f64` matrix rounded to `f32` element by element, at compile time. `as f32`
/// rounds to nearest in `const` evaluation exactly as at run time, and is what `Real::of_f64`
/// and `LinearModel::cast` do, so the numbers are bit-identical to the former
/// `model(..).cast::<f32>()` (a test below checks). Start-up no longer converts in software
/// `f64` nor holds 20 × 20 `f64` temporaries (the image needed 46 KB of stack there), and the
/// image carries the `f32` matrices in flash instead of the `f64` ones.
const fn f32_matrix<const R: usize, const C: usize>(rows: &[[f64; C]; R]) -> SMatrix<f32, R, C> {
    // nalgebra stores column-major.
    let mut cols = [[0.0f32; R]; C];
    let mut i = 0;
    while i < R {
        let mut j = 0;
        while j < C {
            cols[j][i] = rows[i][j] as f32;
            j += 1;
        }
        i += 1;
    }
    SMatrix::from_array_storage(ArrayStorage(cols))
}

/// An exported matrix as an `f64` nalgebra matrix (for `S`, inverted in `f64`).
fn f64_matrix<const R: usize, const C: usize>(rows: &[[f64; C]; R]) -> SMatrix<f64, R, C> {
    SMatrix::from_fn(|i, j| rows[i][j])
}

/// The compiled-in model, prior and output rows in `f32`.
mod f32_constants {
    use super::constants::*;
    use super::{f32_matrix, SMatrix, STATES};
    use edgekf::filter::LinearModel;

    pub const MODEL: LinearModel<f32, STATES, 4> = LinearModel {
        a: f32_matrix(&ROTOR_A),
        c: f32_matrix(&ROTOR_C),
        q: f32_matrix(&ROTOR_Q),
        r: f32_matrix(&ROTOR_R),
    };
    pub const P0: SMatrix<f32, STATES, STATES> = f32_matrix(&ROTOR_P0);
    pub const GAIN: SMatrix<f32, STATES, 4> = f32_matrix(&ROTOR_GAIN);
    pub const DISK: SMatrix<f32, 4, STATES> = f32_matrix(&ROTOR_DISK);
    pub const FORCE: SMatrix<f32, 4, STATES> = f32_matrix(&ROTOR_FORCE);
}

/// The filter in use: the time-varying one during start-up, then the steady-state one in the
/// same memory (no allocator here, and the time-varying filter is not needed again).
#[allow(clippy::large_enum_variant)]
enum Filter {
    TimeVarying(KalmanFilter<f32, STATES, 4>),
    Steady(SteadyStateFilter<f32, STATES, 4>),
}

/// The filter with its output rows.
pub struct RotorEstimator {
    filter: Filter,
    /// Samples stepped so far (saturating).
    samples: u32,
    /// Sample at which the steady-state gain takes over (`None`: never).
    switch_at: Option<u32>,
    /// The time-varying filter's repair counters at the switch, kept for [`Self::health`].
    before_switch: FilterHealth,
    /// Non-finite measurements the steady-state filter refused.
    refused_steady: u32,
    disk: SMatrix<f32, 4, STATES>,
    force: SMatrix<f32, 4, STATES>,
}

/// The steady-state filter from the compiled-in `A`, `C`, `K` (`f32`, the time-varying
/// filter's own bits) and `S` (`f64`), starting at `x`.
#[inline(never)]
fn steady_filter(x: &SVector<f32, STATES>) -> Result<SteadyStateFilter<f32, STATES, 4>, RiccatiError> {
    use f32_constants::{GAIN, MODEL};
    SteadyStateFilter::from_parts(&MODEL.a, &MODEL.c, &GAIN, &f64_matrix(&constants::ROTOR_S), *x)
}

impl Default for RotorEstimator {
    fn default() -> Self {
        Self::new()
    }
}

impl RotorEstimator {
    /// The compiled-in model, starting at rest with the exported prior; the time-varying
    /// filter for the first [`STEADY_AFTER`] samples, then the exported steady-state gain.
    ///
    /// ```
    /// let mut est = edgekf_firmware::systems::rotor::RotorEstimator::new();
    /// let r = est.step(Some([0.0; 4]));
    /// assert!(r.nis.is_finite());
    /// ```
    pub fn new() -> Self {
        Self::with_switch_at(Some(STEADY_AFTER))
    }

    /// Like [`Self::new`], with the switch to the steady-state gain at sample `switch_at`
    /// (`Some(0)`: steady-state from the first sample), or never (`None`: the time-varying
    /// filter throughout, the reference the switch is measured against).
    ///
    /// ```
    /// use edgekf_firmware::systems::rotor::RotorEstimator;
    /// let mut est = RotorEstimator::with_switch_at(None);
    /// for _ in 0..1000 {
    ///     est.step(Some([0.0; 4]));
    /// }
    /// assert!(!est.is_steady());
    /// ```
    pub fn with_switch_at(switch_at: Option<u32>) -> Self {
        use f32_constants::*;
        Self {
            filter: Filter::TimeVarying(KalmanFilter::new(MODEL, SVector::zeros(), P0)),
            samples: 0,
            switch_at,
            before_switch: FilterHealth::default(),
            refused_steady: 0,
            disk: DISK,
            force: FORCE,
        }
    }

    /// One sample: update with the probes' reading (`None` if missing: prediction only),
    /// report, then predict to the next sample.
    pub fn step(&mut self, y: Option<[f32; 4]>) -> RotorReport {
        if Some(self.samples) == self.switch_at {
            self.switch_to_steady();
        }
        self.samples = self.samples.saturating_add(1);
        self.filter_step(y)
    }

    /// Update, outputs, prediction. Out of line, like the switch, so that the two frames are
    /// never on the stack together (the time-varying update's temporaries are several KB).
    #[inline(never)]
    fn filter_step(&mut self, y: Option<[f32; 4]>) -> RotorReport {
        let nis = match (&mut self.filter, y) {
            (_, None) => f32::NAN,
            (Filter::TimeVarying(kf), Some(v)) => kf.update(&SVector::from(v)).map_or(f32::NAN, |inn| inn.nis),
            (Filter::Steady(f), Some(v)) => match f.update(&SVector::from(v)) {
                Some((_, nis)) => nis,
                None => {
                    self.refused_steady = self.refused_steady.saturating_add(1);
                    f32::NAN
                }
            },
        };
        let x = self.state();
        let (d, f) = (self.disk * x, self.force * x);
        match &mut self.filter {
            Filter::TimeVarying(kf) => kf.predict(),
            Filter::Steady(f) => f.predict(),
        }
        RotorReport { disk: [d[0], d[1], d[2], d[3]], force: [f[0], f[1], f[2], f[3]], nis }
    }

    /// Replaces the time-varying filter by the steady-state one, `x⁺ = x + K (y − C x)`,
    /// `x ← A x` with the exported `K` (`ROTOR_GAIN`), starting from the time-varying filter's
    /// predicted state. `S` (`ROTOR_S`) is inverted once, here, in `f64`, for the NIS.
    ///
    /// Out of line (as are [`steady_filter`] and `filter_step`), so that the one-off
    /// temporaries of building the new filter, about 6 KB, are never on the stack together
    /// with the time-varying step's.
    #[inline(never)]
    fn switch_to_steady(&mut self) {
        let Filter::TimeVarying(kf) = &self.filter else { return };
        let health = kf.health();
        // The exported S is the converged Riccati solution's, positive definite, so this does
        // not fail; if it ever did, the node would stay on the (correct, slower) time-varying
        // filter rather than stop.
        if let Ok(steady) = steady_filter(kf.state()) {
            self.before_switch = health;
            self.filter = Filter::Steady(steady);
        }
    }

    /// The state estimate (predicted to the current sample between steps).
    fn state(&self) -> SVector<f32, STATES> {
        match &self.filter {
            Filter::TimeVarying(kf) => *kf.state(),
            Filter::Steady(f) => *f.state(),
        }
    }

    /// Whether the steady-state gain is in use (from sample [`STEADY_AFTER`] on).
    ///
    /// ```
    /// let est = edgekf_firmware::systems::rotor::RotorEstimator::with_switch_at(Some(0));
    /// assert!(!est.is_steady()); // switches when the first sample arrives
    /// ```
    pub fn is_steady(&self) -> bool {
        matches!(self.filter, Filter::Steady(_))
    }

    /// Repairs and refusals so far (zero in a healthy run), over both phases:
    /// `covariance_resets` counts the time-varying filter's covariance resets and, after the
    /// switch, the steady-state filter's resets of a non-finite state; `refused_updates`
    /// counts non-finite measurements (and, before the switch, innovation covariances that
    /// were not positive definite). A missing sample (`None`) is neither.
    pub fn health(&self) -> FilterHealth {
        match &self.filter {
            Filter::TimeVarying(kf) => kf.health(),
            Filter::Steady(f) => FilterHealth {
                covariance_resets: self.before_switch.covariance_resets.saturating_add(f.resets()),
                refused_updates: self.before_switch.refused_updates.saturating_add(self.refused_steady),
            },
        }
    }
}

crate::frame! {
    /// One sample's estimates, as the HIL image reports them.
    pub struct RotorFrame = "rot {=u32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32}" {
        /// Sample number, from 0.
        pub sample: u32,
        /// Disk node 12, x, m.
        pub disk12_x: f32,
        /// Disk node 12, y, m.
        pub disk12_y: f32,
        /// Disk node 23, x, m.
        pub disk23_x: f32,
        /// Disk node 23, y, m.
        pub disk23_y: f32,
        /// Unbalance force at node 12, x, N.
        pub force12_x: f32,
        /// Unbalance force at node 12, y, N.
        pub force12_y: f32,
        /// Unbalance force at node 23, x, N.
        pub force23_x: f32,
        /// Unbalance force at node 23, y, N.
        pub force23_y: f32,
        /// NIS of the sample's update (NaN if missing or refused).
        pub nis: f32,
    }
}

impl RotorFrame {
    /// Sample `sample`'s report as a frame.
    pub fn new(sample: u32, r: &RotorReport) -> Self {
        let ([disk12_x, disk12_y, disk23_x, disk23_y], [force12_x, force12_y, force23_x, force23_y]) =
            (r.disk, r.force);
        Self { sample, disk12_x, disk12_y, disk23_x, disk23_y, force12_x, force12_y, force23_x, force23_y, nis: r.nis }
    }

    /// The report the frame carries.
    pub fn report(&self) -> RotorReport {
        RotorReport {
            disk: [self.disk12_x, self.disk12_y, self.disk23_x, self.disk23_y],
            force: [self.force12_x, self.force12_y, self.force23_x, self.force23_y],
            nis: self.nis,
        }
    }
}

crate::frame! {
    /// The end of a rotor run.
    #[derive(Eq)]
    pub struct RotorEnd = "rotor {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32}" {
        /// Input lines read (one poll each).
        pub samples: u32,
        /// Of those, lines that did not parse (stepped as missing if their `t` did).
        pub bad_lines: u32,
        /// Lines without a usable `t` (not stepped).
        pub untimed_lines: u32,
        /// Lines missing from the file (by their `t`), bridged by prediction.
        pub missing_lines: u32,
        /// Lines whose `t` was off the sample grid (not bridged; see
        /// [`ChannelSource`]).
        pub time_jumps: u32,
        /// Filter covariance resets (see [`RotorEstimator::health`]).
        pub covariance_resets: u32,
        /// Refused updates.
        pub refused_updates: u32,
    }
}

/// The rotor image's source: the probes' channels, lines missing from the file bridged for up
/// to [`crate::source::MAX_GAP_S`] (see [`ChannelSource::with_clock`]).
pub fn channel_source<B: ByteSource>(reader: ChannelReader<B, 4>) -> ChannelSource<B, 4> {
    let max_gap = crate::source::MAX_GAP_S * f64::from(SAMPLE_RATE_HZ);
    ChannelSource::new(reader).with_clock(1.0 / f64::from(SAMPLE_RATE_HZ), max_gap as u32)
}

/// The rotor estimator as the node runs it: one sample per poll (and the missing ones before
/// it), each poll's last reported.
pub struct RotorNode {
    estimator: RotorEstimator,
    last: Option<RotorReport>,
    steps: u32,
}

impl RotorNode {
    /// Runs `estimator`.
    pub fn new(estimator: RotorEstimator) -> Self {
        Self { estimator, last: None, steps: 0 }
    }

    /// The estimator.
    pub fn estimator(&self) -> &RotorEstimator {
        &self.estimator
    }
}

impl NodeEstimator for RotorNode {
    type Input = [f32; 4];
    type Frame = RotorFrame;

    fn step(&mut self, input: Option<[f32; 4]>) -> Innovation {
        let r = self.estimator.step(input);
        self.last = Some(r);
        self.steps = self.steps.saturating_add(1);
        Innovation { residual: None, nis: Some(r.nis).filter(|n| n.is_finite()) }
    }

    /// The poll's last sample, numbered by the estimator's steps (bridged samples included),
    /// so that a missing line shows as a skipped number.
    fn report(&mut self, _: &Poll) -> Option<RotorFrame> {
        let sample = self.steps.saturating_sub(1);
        self.last.take().map(|r| RotorFrame::new(sample, &r))
    }
}

/// The QEMU image `edgekf-rotor-qemu`: the four probes' readings from the HIL file (other
/// columns ignored); a `rot` frame per sample, then `rotor`.
pub struct RotorImage;

impl HilImage for RotorImage {
    const NAME: &'static str = "edgekf-rotor-qemu";
    const COLUMNS: &'static [&'static str] = &CHANNELS;
    type Input = [f32; 4];
    type Storage = ();
    type Source<B: ByteSource> = ChannelSource<B, 4>;
    type Estimator<'s> = RotorNode;
    type StartError = core::convert::Infallible;

    fn storage() {}

    #[inline(never)] // start-up temporaries stay out of the caller's frame
    fn start<B: ByteSource>(input: B, _: &mut ()) -> Result<HilNode<'_, Self, B>, HilError<Self::StartError>> {
        let reader = ChannelReader::new(input, CHANNELS).map_err(HilError::Header)?;
        Ok(Node::new(channel_source(reader), RotorNode::new(RotorEstimator::new()), Default::default()))
    }

    fn finish<B: ByteSource>(node: &HilNode<'_, Self, B>, sink: &mut impl FrameSink) {
        let h = node.estimator().estimator().health();
        sink.frame(&RotorEnd {
            samples: node.health().blocks,
            bad_lines: node.source().reader().bad_lines(),
            untimed_lines: node.source().untimed_lines(),
            missing_lines: node.source().missing_lines(),
            time_jumps: node.source().time_jumps(),
            covariance_resets: h.covariance_resets,
            refused_updates: h.refused_updates,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::constants::*;
    use super::*;
    use edgekf::export::{matrix, model};
    use edgekf::models::synthetic::Lcg;
    use std::vec::Vec;

    /// Probe readings from the filter's own model (in `f64`): the rotor at rest, driven from
    /// sample 0 by unbalance forces of 2 N at node 12 and 1.5 N at node 23, read with 1 µm RMS
    /// noise (the exported `R`). Returns the readings and the true disk displacements.
    fn model_data(n: usize) -> (Vec<[f32; 4]>, Vec<[f64; 4]>) {
        let (a, c, disk) = (matrix(&ROTOR_A), matrix(&ROTOR_C), matrix(&ROTOR_DISK));
        let mut x = SVector::<f64, STATES>::zeros();
        x[16] = 2.0;
        x[19] = 1.5;
        let mut rng = Lcg(0x5EED_0001);
        let (mut ys, mut truth) = (Vec::new(), Vec::new());
        for _ in 0..n {
            let y = c * x;
            // Uniform on [−√3, √3) µm: 1 µm standard deviation.
            ys.push(core::array::from_fn(|i| (y[i] + 1.732_050_8e-6 * rng.next()) as f32));
            let d = disk * x;
            truth.push([d[0], d[1], d[2], d[3]]);
            x = a * x;
        }
        (ys, truth)
    }

    fn rms(v: impl Iterator<Item = f64>) -> f64 {
        let (s, n) = v.fold((0.0, 0usize), |(s, n), e| (s + e * e, n + 1));
        (s / n.max(1) as f64).sqrt()
    }

    #[test]
    fn sample_rate_is_the_generated_models() {
        let header = include_str!("../generated/rotor.rs").lines().next().unwrap();
        assert!(header.contains(&std::format!(" {SAMPLE_RATE_HZ} Hz.")), "{header}");
        assert_eq!(STEADY_AFTER, 500);
    }

    /// The matrices built straight from the constants are the bits the former
    /// `model(..).cast::<f32>()` and `matrix(..).map(|v| v as f32)` gave.
    #[test]
    fn start_up_matrices_are_bit_identical_to_the_f64_conversion() {
        let est = RotorEstimator::new();
        let Filter::TimeVarying(kf) = &est.filter else { panic!("starts time-varying") };
        assert_eq!(*kf.model(), model(&ROTOR_A, &ROTOR_C, &ROTOR_Q, &ROTOR_R).cast::<f32>());
        assert_eq!(*kf.covariance(), matrix(&ROTOR_P0).map(|v| v as f32));
        assert_eq!(est.disk, matrix(&ROTOR_DISK).map(|v| v as f32));
        assert_eq!(est.force, matrix(&ROTOR_FORCE).map(|v| v as f32));
    }

    /// The switch happens at sample `STEADY_AFTER` exactly, to the exported gain and `S`:
    /// before it the node is the time-varying filter bit for bit; from it on, the steady-state
    /// filter built the host's way (`from_gain` on the `f64` model, `--steady-after`) from the
    /// time-varying filter's state at that sample, bit for bit; and it estimates the disks as
    /// well as the time-varying filter does.
    #[test]
    fn switches_to_the_exported_steady_gain_at_the_documented_sample() {
        let n = 3000;
        let (ys, truth) = model_data(n);
        let mut node = RotorEstimator::new();
        let mut tv = RotorEstimator::with_switch_at(None);
        let (mut node_out, mut tv_out) = (Vec::new(), Vec::new());
        let mut reference: Option<SteadyStateFilter<f32, STATES, 4>> = None;
        for (k, y) in ys.iter().enumerate() {
            if k == STEADY_AFTER as usize {
                let Filter::TimeVarying(kf) = &tv.filter else { unreachable!() };
                let m = model(&ROTOR_A, &ROTOR_C, &ROTOR_Q, &ROTOR_R);
                let f = SteadyStateFilter::from_gain(&m, &matrix(&ROTOR_GAIN), &matrix(&ROTOR_S), *kf.state());
                reference = Some(f.unwrap());
            }
            let (a, b) = (node.step(Some(*y)), tv.step(Some(*y)));
            assert_eq!(node.is_steady(), k >= STEADY_AFTER as usize, "sample {k}");
            if k < STEADY_AFTER as usize {
                assert_eq!(a, b, "sample {k}: before the switch the node is the time-varying filter");
            } else {
                let f = reference.as_mut().unwrap();
                let (_, nis) = f.update(&SVector::from(*y)).unwrap();
                let x = *f.state();
                f.predict();
                let d = node.disk * x;
                assert_eq!(a.disk, [d[0], d[1], d[2], d[3]], "sample {k}");
                assert_eq!(a.nis, nis, "sample {k}");
            }
            node_out.push(a);
            tv_out.push(b);
        }
        // The first steady-state sample already differs: the gain changed there, not later.
        let k0 = STEADY_AFTER as usize;
        assert_ne!(node_out[k0].disk, tv_out[k0].disk);

        // Accuracy against the truth for t ≥ 1 s, and agreement with the time-varying run.
        let err = |out: &[RotorReport]| {
            (0..4).map(|i| rms((1000..n).map(|k| out[k].disk[i] as f64 - truth[k][i]))).fold(0.0, f64::max)
        };
        let amplitude = (0..4).map(|i| rms((1000..n).map(|k| truth[k][i]))).fold(0.0, f64::max);
        let diff = (0..4)
            .map(|i| rms((1000..n).map(|k| (node_out[k].disk[i] - tv_out[k].disk[i]) as f64)))
            .fold(0.0, f64::max);
        let nis_mean = |out: &[RotorReport]| (1000..n).map(|k| out[k].nis as f64).sum::<f64>() / (n - 1000) as f64;
        let (e_node, e_tv) = (err(&node_out), err(&tv_out));
        let (nis_node, nis_tv) = (nis_mean(&node_out), nis_mean(&tv_out));
        std::eprintln!(
            "disk amplitude {:.2} µm; error t ≥ 1 s: switched {:.4} µm, time-varying {:.4} µm; \
             difference {:.4} µm; NIS mean {nis_node:.3} / {nis_tv:.3}",
            amplitude * 1e6,
            e_node * 1e6,
            e_tv * 1e6,
            diff * 1e6
        );
        assert!(e_node <= 1.1 * e_tv, "{e_node} vs {e_tv}");
        // The time-varying gain is still creeping towards the steady one at 3 s (the Riccati
        // recursion took 70 000 steps to settle), so the two runs differ by a fraction of their
        // error, and by far less than the displacement they estimate (0.15 µm of 31 µm).
        assert!(diff <= 0.01 * amplitude, "{diff}");
        assert!((nis_node - nis_tv).abs() <= 0.05 * nis_tv, "{nis_node} vs {nis_tv}");
        assert!(node.health() == FilterHealth::default() && tv.health() == FilterHealth::default());
    }

    /// After the switch a missing sample is bridged by prediction alone and counted nowhere; a
    /// non-finite reading is refused and counted.
    #[test]
    fn missing_and_non_finite_samples_after_the_switch() {
        let (ys, _) = model_data(STEADY_AFTER as usize + 3);
        let mut est = RotorEstimator::new();
        for y in &ys[..STEADY_AFTER as usize + 1] {
            est.step(Some(*y));
        }
        assert!(est.is_steady());
        let x = est.state();
        let r = est.step(None);
        assert!(r.nis.is_nan());
        let d = est.disk * x;
        assert_eq!(r.disk, [d[0], d[1], d[2], d[3]], "no update on a missing sample");
        assert_eq!(est.state(), f32_constants::MODEL.a * x, "prediction only");
        assert_eq!(est.health(), FilterHealth::default());
        let r = est.step(Some([f32::NAN, 0.0, 0.0, 0.0]));
        assert!(r.nis.is_nan());
        assert_eq!(est.health(), FilterHealth { covariance_resets: 0, refused_updates: 1 });
        assert!(est.step(Some(ys[STEADY_AFTER as usize + 2])).nis.is_finite());
        assert_eq!(est.health().refused_updates, 1);
    }
}
