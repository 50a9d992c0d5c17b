//! The sensor node's main loop, generic over where samples come from ([`SampleSource`]) and
//! what estimates from them ([`NodeEstimator`]): read what one period delivered, run the
//! estimator over it, report.
//!
//! One loop for every system and every input: the ADXL355 through either bus interface
//! ([`crate::source::Adxl355Source`]: the board's I²C, the virtual ADXL355 under QEMU and in host
//! tests, an SPI bus) or named channels of a HIL file ([`crate::source::ChannelSource`]), feeding
//! the harmonic-force, rotor or crank estimator ([`crate::systems`]). Nothing here panics: the
//! source retries and counts bus errors and screens bad samples, which reach the estimator as
//! missing (`None`) and are bridged by prediction or skipped, and counted.
//!
//! ## Timing contract
//! [`Node::poll`] is called once per source period: for the ADXL355 once per FIFO watermark
//! period (`watermark / 3` samples at the output data rate), on the board from a timer, under
//! QEMU and in host tests right after the harness advances the virtual device's clock by one
//! period ([`Recorded::advance`]); for a channel source once per line. A poll never comes before
//! its period has ended. Samples that could not be read stay in the FIFO and are read late;
//! samples that never arrive (the FIFO overwrote them, the part did not produce them or reset,
//! a line is missing from the file) are bridged by prediction-only steps, so the estimator's
//! clock never slips against the physical one.

use edgekf::residual::RunningStats;

crate::frame! {
    /// Counted events. A clean run has only `samples` and `blocks` non-zero. Every counter
    /// saturates.
    #[derive(Eq)]
    #[cfg_attr(feature = "defmt", derive(defmt::Format))]
    pub struct Health = "health {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32}" {
        /// Polls made.
        pub blocks: u32,
        /// Samples the estimator updated with (an innovation and its NIS).
        pub samples: u32,
        /// Failed bus operations (each attempt): NACKs, timeouts, garbage reads (wrong IDs) and
        /// other bus errors.
        pub bus_errors: u32,
        /// Of those, NACKs.
        pub nacks: u32,
        /// Of those, timeouts (not retried: the poll is given up).
        pub timeouts: u32,
        /// Of those, reads whose ID registers came back wrong (a bus returning garbage; the
        /// FIFO is not read on them).
        pub bad_id: u32,
        /// Operations that succeeded after at least one retry.
        pub recovered: u32,
        /// Polls given up (the FIFO could not be read within the attempt budget, or a part that
        /// reset could not be reconfigured yet).
        pub failed_polls: u32,
        /// FIFO overruns reported by the sensor.
        pub fifo_overruns: u32,
        /// FIFO entries skipped to realign on the X marker.
        pub skipped_entries: u32,
        /// Samples with an axis at full scale (not used).
        pub saturated: u32,
        /// Samples identical to the previous one on all axes (frozen output, not used).
        pub stuck: u32,
        /// Samples due that were never read, bridged by prediction: overwritten in the FIFO,
        /// never produced, or lost to a reset.
        pub bridged: u32,
        /// Of those, samples the part did not deliver without a FIFO overrun: a stall, or a
        /// reset (the FIFO cleared, standby until reconfigured).
        pub dropped: u32,
        /// Configuration read-backs: polls that found the FIFO empty although samples were due.
        pub config_checks: u32,
        /// Resets detected (the configuration read back at its defaults); each one leads to a
        /// re-initialisation.
        pub resets: u32,
    }
}

/// Where the node's samples come from.
pub trait SampleSource {
    /// One sample as the estimator takes it (an axis in m/s², a set of channels).
    type Sample: Copy;

    /// Reads what this period delivered and hands every sample to `each`, in time order:
    /// `None` for one that is due but unusable (lost in the FIFO, saturated, frozen, a line
    /// that does not parse). Counts bus and sample events in `health`. Returns the number of
    /// samples read from the device or file (lost ones excluded).
    fn read(&mut self, health: &mut Health, each: impl FnMut(Option<Self::Sample>)) -> u16;
}

/// A source replaying recorded data (HIL and host runs), which knows when it has run out.
pub trait Recorded {
    /// Lets one period pass (loads the next samples or line); `false` once the data has run
    /// out and everything has been delivered.
    fn advance(&mut self) -> bool;
}

/// What one estimator step gives the block statistics.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Innovation {
    /// The innovation of a scalar measurement, in its unit (`None`: no update, or a vector
    /// measurement).
    pub residual: Option<f32>,
    /// Its normalised innovation squared (`None`: no update).
    pub nis: Option<f32>,
}

/// What a node's steps keep for its next poll, where a poll reports the last of its steps'
/// results (a sample's frame or estimate, a completed window's report): the one slot of the
/// boom's, the vehicle's and the crank's nodes.
///
/// ```
/// use edgekf_firmware::node::{Innovation, Pending};
/// let mut pending = Pending::new();
/// assert_eq!(pending.keep(Some(1u32), Innovation::default()), Innovation::default());
/// pending.keep(Some(2), Innovation::default());
/// pending.keep(None, Innovation::default()); // a step with nothing new keeps the last
/// assert_eq!(pending.report(|n| n * 10), Some(20));
/// assert_eq!(pending.report(|n| n * 10), None); // reported once
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pending<T>(Option<T>);

impl<T> Pending<T> {
    /// Nothing kept.
    pub const fn new() -> Self {
        Self(None)
    }

    /// Keeps a step's result, if it has one (in place of the earlier steps' of this poll);
    /// returns the step's `innovation`, for [`NodeEstimator::step`] to give.
    pub fn keep(&mut self, result: Option<T>, innovation: Innovation) -> Innovation {
        if result.is_some() {
            self.0 = result;
        }
        innovation
    }

    /// The poll's report: the kept result as its frame (`frame` of it), taken, so that the next
    /// poll reports only what its own steps keep.
    pub fn report<F>(&mut self, frame: impl FnOnce(T) -> F) -> Option<F> {
        self.0.take().map(frame)
    }
}

impl<T> Default for Pending<T> {
    fn default() -> Self {
        Self::new()
    }
}

/// What one poll did, for the estimator's report.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Poll {
    /// Poll number, from 0.
    pub block: u32,
    /// Samples read from the source.
    pub read: u16,
    /// Samples given to the estimator as missing (lost, saturated, stuck, unparsable).
    pub missing: u16,
    /// This poll's innovations (those with both a residual and a NIS).
    pub innovations: RunningStats<f32>,
    /// This poll's NIS values (of the same samples).
    pub nis: RunningStats<f32>,
}

/// A system's estimator as the node runs it (see [`crate::systems`]).
pub trait NodeEstimator {
    /// One sample's input.
    type Input: Copy;
    /// What a poll reports.
    type Frame: crate::frame::Frame;

    /// One sample period: `Some` reading, or `None` for a missing one (bridged by prediction
    /// or skipped, and counted by the estimator).
    fn step(&mut self, input: Option<Self::Input>) -> Innovation;

    /// The poll's report, if it has one (a block estimate; a window's, once per window).
    fn report(&mut self, poll: &Poll) -> Option<Self::Frame>;

    /// The next model mismatch its monitor found and has not handed over yet (none without a
    /// monitor: see [`crate::monitor::Monitored`]). Asked after every poll until `None`.
    fn take_mismatch(&mut self) -> Option<crate::mismatch::MismatchFrame> {
        None
    }

    /// Frames of a captured window due after this poll (none without a ring: see
    /// [`crate::capture::Captured`]). Asked after every poll, after the mismatches.
    fn hand_over<S: crate::frame::FrameSink>(&mut self, sink: &mut S) {
        let _ = sink;
    }
}

/// The main loop's state: a source, an estimator and the node's counters.
pub struct Node<S, E> {
    source: S,
    estimator: E,
    health: Health,
}

impl<S: SampleSource, E: NodeEstimator<Input = S::Sample>> Node<S, E> {
    /// A node over a started source and estimator, with the counters start-up left (for
    /// example the retries the sensor's initialisation needed).
    pub fn new(source: S, estimator: E, health: Health) -> Self {
        Self { source, estimator, health }
    }

    /// One period: read what the source delivered, run the estimator over it, report.
    pub fn poll(&mut self) -> Option<E::Frame> {
        let block = self.health.blocks;
        self.health.blocks = self.health.blocks.saturating_add(1);
        let (estimator, health) = (&mut self.estimator, &mut self.health);
        let (mut innovations, mut nis) = (RunningStats::new(), RunningStats::new());
        let (mut missing, mut used) = (0u16, 0u32);
        let read = self.source.read(health, |sample| {
            if sample.is_none() {
                missing = missing.saturating_add(1);
            }
            if let Innovation { residual: Some(r), nis: Some(n) } = estimator.step(sample) {
                innovations.push(r);
                nis.push(n);
                used = used.saturating_add(1);
            }
        });
        self.health.samples = self.health.samples.saturating_add(used);
        self.estimator.report(&Poll { block, read, missing, innovations, nis })
    }

    /// Counted events so far.
    pub fn health(&self) -> Health {
        self.health
    }

    /// The estimator (its own counters, its running estimate).
    pub fn estimator(&self) -> &E {
        &self.estimator
    }

    /// The estimator, mutably (its monitor's events are taken through it).
    pub fn estimator_mut(&mut self) -> &mut E {
        &mut self.estimator
    }

    /// The same node with its estimator wrapped (by a [`crate::monitor::Monitored`], say).
    pub fn map_estimator<F: NodeEstimator<Input = S::Sample>>(self, wrap: impl FnOnce(E) -> F) -> Node<S, F> {
        Node { source: self.source, estimator: wrap(self.estimator), health: self.health }
    }

    /// The source (its counters; a virtual device's state).
    pub fn source(&self) -> &S {
        &self.source
    }

    /// The source, mutably (a recorded source is advanced through it).
    pub fn source_mut(&mut self) -> &mut S {
        &mut self.source
    }
}

impl<S: SampleSource + Recorded, E: NodeEstimator<Input = S::Sample>> Node<S, E> {
    /// Polls once per period until the recorded data has run out, handing every report to
    /// `report`.
    pub fn run(&mut self, mut report: impl FnMut(&E::Frame)) {
        while self.source.advance() {
            if let Some(frame) = self.poll() {
                report(&frame);
            }
        }
    }
}
