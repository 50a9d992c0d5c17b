//! Rotor virtual sensing on the node: the modally reduced rotor (8 modes, one rotating phasor
//! per unbalance) and its augmented Kalman filter, computed on the host in `f64` and compiled in
//! (`edgekf rotor export --config host-sim/configs/rotor_paper.toml --out
//! firmware/src/systems/rotor/generated/rotor.rs`; a cross-crate test checks the file is current).
//!
//! Inputs: the four proximity probes of the paper rotor (`n5_x, n5_y, n32_x, n32_y`, m).
//! Outputs per sample: the x/y displacement of both disk nodes (12 and 23), which no sensor
//! measures, and the unbalance forces there ([`RotorFrame`], one per sample in the HIL image
//! [`RotorImage`]).

use crate::frame::FrameSink;
use crate::hil::{FileEnd, HilError, HilImage, HilNode};
use crate::line_feed::{ByteSource, ChannelReader};
use crate::node::{Innovation, Node, NodeEstimator, Poll};
use crate::source::ChannelSource;
use edgekf::filter::{FilterHealth, LowRankDesign, LowRankKalmanFilter};
use nalgebra::{ArrayStorage, SMatrix, SVector};

pub mod accel;

#[cfg(all(target_os = "none", feature = "qemu"))]
pub mod bench;
pub mod images;
pub mod soak;

/// The exported model, steady state, prior and start-up term, as the host wrote them (`f64`).
#[allow(missing_docs, clippy::excessive_precision, clippy::unreadable_literal)]
pub mod constants {
    include!("generated/rotor.rs");
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

/// Samples after which the node drops its filter's start-up term and runs the steady-state
/// gain alone: 0.5 s at [`SAMPLE_RATE_HZ`]. Missing samples count too: the schedule follows
/// time since start-up, not the data, so it is the same on every run.
///
/// Why a start-up term: the node starts from rest with a wide prior on the unbalance forces
/// (`P0`), and the time-varying gain, large while that uncertainty shrinks, finds the forces
/// within the start-up transient, where the steady gain alone would take the slow steady-state
/// rate. The filter carries that prior as a deviation of rank [`START_RANK`] from the steady
/// state ([`LowRankKalmanFilter`]): the exact time-varying filter of the prior
/// `P̄ + U₀ U₀ᵀ` (`ROTOR_U0`, the four force directions of `P0 − P̄`) at the cost of the steady
/// one plus `O(N² R)`, real time at 1 kHz from the first sample. The dense time-varying filter
/// of `P0` itself cost about 94 000 instructions a sample, more than the 84 000 cycles a 1 kHz
/// sample has at 84 MHz. Why drop the term at 0.5 s: by then it has decayed below what it
/// changes (`cargo test -p edgekf-tests --test rotor_node`), and it is the schedule of the
/// paper being reproduced.
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

/// Rank of the start-up term (the exporter's `START_RANK`; a test checks `ROTOR_U0`'s width).
pub const START_RANK: usize = 12;

/// An exported `f64` matrix rounded to `f32` element by element, at compile time. `as f32`
/// rounds to nearest in `const` evaluation exactly as at run time, and is what `Real::of_f64`
/// and `LinearModel::cast` do, so the numbers are bit-identical to a run-time conversion (a
/// test below checks). Start-up does not convert in software `f64`, and the image carries the
/// `f32` matrices in flash instead of the `f64` ones.
pub(crate) const fn f32_matrix<const R: usize, const C: usize>(rows: &[[f64; C]; R]) -> SMatrix<f32, R, C> {
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

/// A compiled-in filter design and its output rows in `f32`, built at compile time from a
/// generated file's `f64` constants ([`rotor_design!`]).
pub struct RotorDesign<const N: usize, const R: usize> {
    /// The start-up filter and the steady state it retires to.
    pub filter: LowRankDesign<f32, N, 4, R>,
    /// The disk rows then the force rows, transposed: the outputs are one product `Oᵀ x`.
    pub outputs_t: SMatrix<f32, N, 8>,
}

/// The disk rows then the force rows of a generated file, transposed, in `f32`.
pub(crate) const fn outputs_t<const N: usize>(disk: &[[f64; N]; 4], force: &[[f64; N]; 4]) -> SMatrix<f32, N, 8> {
    let mut cols = [[0.0f32; N]; 8];
    let mut i = 0;
    while i < N {
        let mut j = 0;
        while j < 4 {
            cols[j][i] = disk[j][i] as f32;
            cols[4 + j][i] = force[j][i] as f32;
            j += 1;
        }
        i += 1;
    }
    SMatrix::from_array_storage(ArrayStorage(cols))
}

/// The [`RotorDesign`] of the constants module `$m` (a generated file of `edgekf rotor export`
/// included), at compile time.
macro_rules! rotor_design {
    ($m:ident) => {
        $crate::systems::rotor::RotorDesign {
            filter: edgekf::filter::LowRankDesign {
                a: $crate::systems::rotor::f32_matrix(&$m::ROTOR_A),
                c: $crate::systems::rotor::f32_matrix(&$m::ROTOR_C),
                closed: $crate::systems::rotor::f32_matrix(&$m::ROTOR_CLOSED),
                pct: $crate::systems::rotor::f32_matrix(&$m::ROTOR_PCT),
                s: $crate::systems::rotor::f32_matrix(&$m::ROTOR_S),
                s_inv: $crate::systems::rotor::f32_matrix(&$m::ROTOR_S_INV),
                u0: $crate::systems::rotor::f32_matrix(&$m::ROTOR_U0),
                signs: $crate::systems::rotor::f32_matrix(&$m::ROTOR_SIGNS),
            },
            outputs_t: $crate::systems::rotor::outputs_t(&$m::ROTOR_DISK, &$m::ROTOR_FORCE),
        }
    };
}
pub(crate) use rotor_design;

/// The probes' design (`generated/rotor.rs`).
pub const DESIGN: RotorDesign<STATES, START_RANK> = rotor_design!(constants);

/// The filter with its output rows: `N` states, start-up rank `R` (the probes' model by
/// default; [`accel`] runs the accelerometers' 28 states).
pub struct RotorEstimator<const N: usize = STATES, const R: usize = START_RANK> {
    filter: LowRankKalmanFilter<f32, N, 4, R>,
    /// Samples stepped so far (saturating).
    samples: u32,
    /// Sample at which the start-up term is dropped (`None`: never).
    switch_at: Option<u32>,
    /// `[disk; force]ᵀ`.
    outputs_t: SMatrix<f32, N, 8>,
}

impl Default for RotorEstimator {
    fn default() -> Self {
        Self::new()
    }
}

impl RotorEstimator {
    /// The compiled-in model, starting at rest with the exported prior; the start-up term for
    /// the first [`STEADY_AFTER`] samples, then the exported steady-state gain alone.
    ///
    /// ```
    /// let mut est = edgekf_firmware::systems::rotor::RotorEstimator::new();
    /// let r = est.step(Some([0.0; 4]));
    /// assert!(r.nis.is_finite());
    /// ```
    pub fn new() -> Self {
        Self::with_switch_at(Some(STEADY_AFTER))
    }

    /// Like [`Self::new`], with the start-up term dropped at sample `switch_at` (`Some(0)`:
    /// the steady-state gain from the first sample), or never (`None`: the start-up term
    /// throughout, the reference the switch is measured against).
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
        Self::from_design(&DESIGN, switch_at)
    }
}

impl<const N: usize, const R: usize> RotorEstimator<N, R> {
    /// The filter of `design`, starting at rest, its start-up term dropped at sample
    /// `switch_at` (see [`RotorEstimator::with_switch_at`]).
    pub fn from_design(design: &RotorDesign<N, R>, switch_at: Option<u32>) -> Self {
        Self {
            filter: LowRankKalmanFilter::new(&design.filter, SVector::zeros()),
            samples: 0,
            switch_at,
            outputs_t: design.outputs_t,
        }
    }

    /// One sample: update with the probes' reading (`None` if missing: prediction only),
    /// report, then predict to the next sample.
    pub fn step(&mut self, y: Option<[f32; 4]>) -> RotorReport {
        if Some(self.samples) == self.switch_at {
            self.filter.retire();
        }
        self.samples = self.samples.saturating_add(1);
        let nis = match y {
            None => f32::NAN,
            Some(v) => self.filter.update(&SVector::from(v)).map_or(f32::NAN, |(_, nis)| nis),
        };
        let mut o = SVector::<f32, 8>::zeros();
        edgekf::linalg::mul_tr(&self.outputs_t, self.filter.state(), &mut o, false);
        self.filter.predict();
        RotorReport { disk: [o[0], o[1], o[2], o[3]], force: [o[4], o[5], o[6], o[7]], nis }
    }

    /// The state estimate (predicted to the current sample between steps).
    #[cfg(test)]
    pub(crate) fn state(&self) -> SVector<f32, N> {
        *self.filter.state()
    }

    /// Whether the steady-state gain alone is in use (from sample [`STEADY_AFTER`] on, or
    /// after a repair).
    ///
    /// ```
    /// let est = edgekf_firmware::systems::rotor::RotorEstimator::with_switch_at(Some(0));
    /// assert!(!est.is_steady()); // switches when the first sample arrives
    /// ```
    pub fn is_steady(&self) -> bool {
        !self.filter.is_live()
    }

    /// Repairs and refusals so far (zero in a healthy run): `covariance_resets` counts resets
    /// of a non-finite state or start-up term (the filter then goes on as the steady-state
    /// one); `refused_updates` counts non-finite measurements and innovation covariances that
    /// were not positive definite. A missing sample (`None`) is neither.
    pub fn health(&self) -> FilterHealth {
        self.filter.health()
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
    /// The end of a rotor run (the file's counts in [`FileEnd`], just before).
    #[derive(Eq)]
    pub struct RotorEnd = "rotor {=u32} {=u32} {=u32}" {
        /// Input lines read (one poll each).
        pub samples: u32,
        /// Filter covariance resets (see [`RotorEstimator::health`]).
        pub covariance_resets: u32,
        /// Refused updates.
        pub refused_updates: u32,
    }
}

/// The rotor image's source: the probes' channels, lines missing from the file bridged for up
/// to [`crate::source::MAX_GAP_S`] (see [`crate::hil::clocked_source`]).
pub fn channel_source<B: ByteSource>(reader: ChannelReader<B, 4>) -> ChannelSource<B, 4> {
    crate::hil::clocked_source(reader, SAMPLE_RATE_HZ)
}

/// The rotor estimator as the node runs it: the poll's samples (one line and the missing ones
/// before it for the probes, a FIFO block for the accelerometers), each poll's last reported.
pub struct RotorNode<const N: usize = STATES, const R: usize = START_RANK> {
    estimator: RotorEstimator<N, R>,
    last: Option<RotorReport>,
    steps: u32,
}

impl<const N: usize, const R: usize> RotorNode<N, R> {
    /// Runs `estimator`.
    pub fn new(estimator: RotorEstimator<N, R>) -> Self {
        Self { estimator, last: None, steps: 0 }
    }

    /// The estimator.
    pub fn estimator(&self) -> &RotorEstimator<N, R> {
        &self.estimator
    }
}

impl<const N: usize, const R: usize> NodeEstimator for RotorNode<N, R> {
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
/// columns ignored); a `rot` frame per sample, then `file` ([`FileEnd`]) and `rotor`.
pub struct RotorImage;

impl HilImage for RotorImage {
    const NAME: &'static str = "edgekf-rotor-qemu";
    const COLUMNS: &'static [&'static str] = &CHANNELS;
    type Input = [f32; 4];
    type Storage = ();
    type Source<B: ByteSource> = ChannelSource<B, 4>;
    type Estimator<'s> = RotorNode;
    type StartError = core::convert::Infallible;

    const STORAGE: () = ();

    #[inline(never)] // start-up temporaries stay out of the caller's frame
    fn start<B: ByteSource>(input: B, _: &mut ()) -> Result<HilNode<'_, Self, B>, HilError<Self::StartError>> {
        // Not through `hil::clocked_node`: its closure moves the 11 KB estimator through a
        // `Result`, which costs that much more start-up stack (29 248 B against 18 016 B).
        let reader = ChannelReader::new(input, CHANNELS).map_err(HilError::Header)?;
        Ok(Node::new(channel_source(reader), RotorNode::new(RotorEstimator::new()), Default::default()))
    }

    fn finish<B: ByteSource>(node: &HilNode<'_, Self, B>, sink: &mut impl FrameSink) {
        sink.frame(&FileEnd::of(node.source()));
        let h = node.estimator().estimator().health();
        sink.frame(&RotorEnd {
            samples: node.health().blocks,
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
        let header = include_str!("generated/rotor.rs").lines().next().unwrap();
        assert!(header.contains(&std::format!(" {SAMPLE_RATE_HZ} Hz.")), "{header}");
        assert_eq!(STEADY_AFTER, 500);
    }

    /// The matrices built straight from the constants are the bits a run-time conversion of
    /// the `f64` constants gives. (`ROTOR_U0`'s width is [`START_RANK`], or `DESIGN` would not
    /// compile.)
    #[test]
    fn start_up_matrices_are_bit_identical_to_the_f64_conversion() {
        let d = DESIGN.filter;
        let f = |rows: &[[f64; STATES]; STATES]| matrix(rows).map(|v| v as f32);
        assert_eq!((d.a, d.closed), (f(&ROTOR_A), f(&ROTOR_CLOSED)));
        assert_eq!(d.c, matrix(&ROTOR_C).map(|v| v as f32));
        assert_eq!((d.pct, d.u0), (matrix(&ROTOR_PCT).map(|v| v as f32), matrix(&ROTOR_U0).map(|v| v as f32)));
        assert_eq!((d.s, d.s_inv), (matrix(&ROTOR_S).map(|v| v as f32), matrix(&ROTOR_S_INV).map(|v| v as f32)));
        let est = RotorEstimator::new();
        let (disk, force) = (matrix(&ROTOR_DISK).map(|v| v as f32), matrix(&ROTOR_FORCE).map(|v| v as f32));
        for j in 0..4 {
            assert_eq!(est.outputs_t.column(j), disk.row(j).transpose());
            assert_eq!(est.outputs_t.column(4 + j), force.row(j).transpose());
        }
    }

    /// The dense time-varying Kalman filter of the exported `P0` in `f32` (what the node ran
    /// before the start-up term), over `ys`: its reports.
    fn dense_run(ys: &[[f32; 4]]) -> Vec<RotorReport> {
        let mut kf = edgekf::filter::KalmanFilter::new(
            model(&ROTOR_A, &ROTOR_C, &ROTOR_Q, &ROTOR_R).cast::<f32>(),
            SVector::zeros(),
            matrix(&ROTOR_P0).map(|v| v as f32),
        );
        let (disk, force) = (matrix(&ROTOR_DISK).map(|v| v as f32), matrix(&ROTOR_FORCE).map(|v| v as f32));
        ys.iter()
            .map(|y| {
                let nis = kf.update(&SVector::from(*y)).map_or(f32::NAN, |i| i.nis);
                let x = *kf.state();
                let (d, f) = (disk * x, force * x);
                kf.predict();
                RotorReport { disk: [d[0], d[1], d[2], d[3]], force: [f[0], f[1], f[2], f[3]], nis }
            })
            .collect()
    }

    /// The switch happens at sample `STEADY_AFTER` exactly: before it the node is the filter
    /// with its start-up term bit for bit; from it on, the steady-state filter of the exported
    /// gain started from the node's state there. Both estimate the disks as well as the dense
    /// time-varying filter of `P0` does, from the start-up transient on.
    #[test]
    fn starts_as_the_time_varying_filter_and_switches_at_the_documented_sample() {
        let n = 3000;
        let (ys, truth) = model_data(n);
        let mut node = RotorEstimator::new();
        let mut live = RotorEstimator::with_switch_at(None);
        let (mut node_out, mut live_out) = (Vec::new(), Vec::new());
        let mut reference: Option<edgekf::filter::SteadyStateFilter<f32, STATES, 4>> = None;
        let k0 = STEADY_AFTER as usize;
        for (k, y) in ys.iter().enumerate() {
            if k == k0 {
                let m = model(&ROTOR_A, &ROTOR_C, &ROTOR_Q, &ROTOR_R);
                let f = edgekf::filter::SteadyStateFilter::from_gain(
                    &m,
                    &matrix(&ROTOR_GAIN),
                    &matrix(&ROTOR_S),
                    node.state(),
                );
                reference = Some(f.unwrap());
            }
            let (a, b) = (node.step(Some(*y)), live.step(Some(*y)));
            assert_eq!(node.is_steady(), k >= k0, "sample {k}");
            if k < k0 {
                assert_eq!(a, b, "sample {k}: before the switch the node carries its start-up term");
            } else {
                let f = reference.as_mut().unwrap();
                let (_, nis) = f.update(&SVector::from(*y)).unwrap();
                let d = node.outputs_t.transpose() * *f.state();
                f.predict();
                for i in 0..4 {
                    assert!(
                        (a.disk[i] - d[i]).abs() <= 1e-4 * d.fixed_rows::<4>(0).abs().max() + 1e-12,
                        "{k}: {a:?} {d}"
                    );
                }
                assert!((a.nis - nis).abs() <= 1e-3 * nis.max(1.0), "sample {k}: {} {nis}", a.nis);
            }
            node_out.push(a);
            live_out.push(b);
        }
        assert_ne!(node_out[k0].disk, live_out[k0].disk, "the gain changes at sample {k0}");
        let dense = dense_run(&ys);

        let err = |out: &[RotorReport], from: usize, to: usize| {
            (0..4).map(|i| rms((from..to).map(|k| out[k].disk[i] as f64 - truth[k][i]))).fold(0.0, f64::max)
        };
        let nis_mean =
            |out: &[RotorReport], from: usize| (from..n).map(|k| out[k].nis as f64).sum::<f64>() / (n - from) as f64;
        let amplitude = (0..4).map(|i| rms((1000..n).map(|k| truth[k][i]))).fold(0.0, f64::max);
        let (start_node, start_dense) = (err(&node_out, 100, k0), err(&dense, 100, k0));
        let (e_node, e_live, e_dense) = (err(&node_out, 1000, n), err(&live_out, 1000, n), err(&dense, 1000, n));
        let (nis_node, nis_dense) = (nis_mean(&node_out, 1000), nis_mean(&dense, 1000));
        std::eprintln!(
            "disk amplitude {:.2} µm; error 0.1–0.5 s: node {:.4} µm, dense {:.4} µm; t ≥ 1 s: node {:.4}, \
             start-up term throughout {:.4}, dense {:.4} µm; NIS mean {nis_node:.3} / dense {nis_dense:.3}",
            amplitude * 1e6,
            start_node * 1e6,
            start_dense * 1e6,
            e_node * 1e6,
            e_live * 1e6,
            e_dense * 1e6
        );
        assert!(start_node <= 1.02 * start_dense, "{start_node} vs {start_dense}");
        assert!(e_node <= 1.02 * e_dense && e_live <= 1.02 * e_dense, "{e_node} {e_live} vs {e_dense}");
        assert!((nis_node - nis_dense).abs() <= 0.02 * nis_dense, "{nis_node} vs {nis_dense}");
        assert!(node.health() == FilterHealth::default() && live.health() == FilterHealth::default());
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
        let mut d = SVector::<f32, 8>::zeros();
        edgekf::linalg::mul_tr(&est.outputs_t, &x, &mut d, false);
        assert_eq!(r.disk, [d[0], d[1], d[2], d[3]], "no update on a missing sample");
        let mut ax = SVector::<f32, STATES>::zeros();
        edgekf::linalg::mul_tr(&DESIGN.filter.a.transpose(), &x, &mut ax, false);
        assert_eq!(est.state(), ax, "prediction only");
        assert_eq!(est.health(), FilterHealth::default());
        let r = est.step(Some([f32::NAN, 0.0, 0.0, 0.0]));
        assert!(r.nis.is_nan());
        assert_eq!(est.health(), FilterHealth { covariance_resets: 0, refused_updates: 1 });
        assert!(est.step(Some(ys[STEADY_AFTER as usize + 2])).nis.is_finite());
        assert_eq!(est.health().refused_updates, 1);
    }
}
