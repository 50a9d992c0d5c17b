//! The node's sample sources: the ADXL355 over any bus interface, and named channels of a CSV
//! stream (the HIL files of sensors that are not an ADXL355).
//!
//! Each source owns what is specific to its input: the ADXL355 source the FIFO timing (what is
//! due, what never arrived), bus retries, the part's health (wrong IDs, a reset) and the
//! screening of saturated and frozen samples; the channel source the line parsing and the
//! lines missing from the file. The node sees only samples or `None`.
//!
//! ## ADXL355 faults and what the source does
//!
//! | fault | seen as | action | counted in [`Health`] |
//! |---|---|---|---|
//! | NACK | bus error of kind `NoAcknowledge` | retried, up to `attempts` per operation | `nacks` |
//! | timeout | bus error of kind `Other` | not retried: the poll is given up | `timeouts` |
//! | garbage read | wrong IDs in the poll's status read | retried; the FIFO is not read on it | `bad_id` |
//! | FIFO overrun | `STATUS` FIFO_OVR | the overwritten samples bridged | `fifo_overruns`, `bridged` |
//! | dropped samples | fewer samples than due, no overrun | bridged (where the stall was, as far as the FIFO tells) | `dropped`, `bridged` |
//! | reset | empty FIFO, configuration read back at its defaults | re-initialised, the samples lost bridged | `config_checks`, `resets`, `dropped`, `bridged` |
//! | saturated axis | a code at the rated full scale | sample not used | `saturated` |
//! | frozen output | three codes repeated exactly | sample not used | `stuck` |
//!
//! Why timeouts are not retried: each one already cost the HAL's wait (a bus held low), and a
//! retry right away most likely burns another; the samples stay in the FIFO, whose 32 samples
//! give one poll of slack, and what a longer outage overwrites is bridged. A garbage read costs
//! only its bytes, so it is retried like a NACK.
//!
//! Reset detection costs nothing on the bus in a normal poll: the IDs come in the same burst as
//! `STATUS` and `FIFO_ENTRIES` ([`Adxl355::poll_status`], one transaction fewer than reading
//! those two apart), and the configuration is read back ([`Adxl355::config_matches`], one 7-byte
//! transaction) only in a poll that finds the FIFO empty although samples are due, which is
//! what a reset leaves (standby, FIFO cleared). A stall passes the check and its samples count
//! as dropped.
#![deny(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use crate::adxl355::{self, Adxl355, Config, I2cInterface, Interface, RawSample};
use crate::line_feed::{BadLine, ByteSource, ChannelReader, LineFeed};
use crate::node::{Health, Recorded, SampleSource};
use crate::virtual_adxl355::VirtualAdxl355;

/// Largest block one poll can read.
pub const MAX_BLOCK: usize = 32;

/// Longest run of missing lines a channel source bridges, s: the host's default
/// `[timeline] max_gap_s`, beyond which the host restarts its filters instead. The node does not
/// restart; it counts a longer gap as a time jump and carries on.
pub const MAX_GAP_S: f64 = 2.0;

/// Accelerometer axis that carries the mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Axis {
    /// X axis.
    X,
    /// Y axis.
    Y,
    /// Z axis.
    Z,
}

/// The axes of a sample handed to the estimator: one [`Axis`] (a scalar) or an [`AxisPair`].
pub trait Axes: Copy {
    /// What the estimator takes from one sample.
    type Sample: Copy;
    /// These axes of a sample in m/s² (`x, y, z`).
    fn pick(self, mps2: [f32; 3]) -> Self::Sample;
}

impl Axes for Axis {
    type Sample = f32;

    fn pick(self, [x, y, z]: [f32; 3]) -> f32 {
        match self {
            Axis::X => x,
            Axis::Y => y,
            Axis::Z => z,
        }
    }
}

/// Two axes of one part, in this order (e.g. x and y of a bearing housing).
///
/// ```
/// use edgekf_firmware::source::{Axes, Axis, AxisPair};
/// assert_eq!(AxisPair(Axis::Y, Axis::X).pick([1.0, 2.0, 3.0]), [2.0, 1.0]);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AxisPair(pub Axis, pub Axis);

impl Axes for AxisPair {
    type Sample = [f32; 2];

    fn pick(self, mps2: [f32; 3]) -> [f32; 2] {
        [self.0.pick(mps2), self.1.pick(mps2)]
    }
}

/// How the node drives the ADXL355.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adxl355Settings<A = Axis> {
    /// Accelerometer settings.
    pub sensor: Config,
    /// Axes handed to the estimator.
    pub axis: A,
    /// Attempts per bus operation before it is given up for this period (at least 1).
    pub attempts: u8,
}

impl Default for Adxl355Settings {
    /// ±2 g, 1 kHz, 16-sample blocks, X axis, 4 attempts.
    fn default() -> Self {
        Self { sensor: Config::default(), axis: Axis::X, attempts: 4 }
    }
}

impl<A> Adxl355Settings<A> {
    /// These settings with the axes `axis` handed to the estimator.
    pub fn with_axes<B>(self, axis: B) -> Adxl355Settings<B> {
        Adxl355Settings { sensor: self.sensor, axis, attempts: self.attempts }
    }
}

/// The ADXL355 read in FIFO blocks, one block per watermark period; the estimator gets the
/// axes `A` of each sample (one [`Axis`] by default).
pub struct Adxl355Source<IF, A = Axis> {
    sensor: Adxl355<IF>,
    settings: Adxl355Settings<A>,
    previous: Option<RawSample>,
    /// Samples due (per the timing contract) but not yet read.
    pending: u32,
    overrun_seen: bool,
    /// The part reset and is not reconfigured yet.
    needs_init: bool,
    /// The last read was short of samples the part did not produce: a stall in progress.
    stalled: bool,
    /// Samples of the coming poll that were never due (a recording that ended mid-period).
    not_due: u32,
    block: [RawSample; MAX_BLOCK],
}

impl<IF: Interface, A: Axes> Adxl355Source<IF, A> {
    /// Initialises the part (with retries, counted in `health`). On failure the driver is
    /// handed back with the last error, so the caller can retry later.
    #[allow(clippy::type_complexity)]
    pub fn start(
        mut sensor: Adxl355<IF>,
        settings: Adxl355Settings<A>,
        health: &mut Health,
    ) -> Result<Self, (adxl355::Error<IF::Error>, Adxl355<IF>)> {
        match retry::<_, IF>(health, settings.attempts, || sensor.init(settings.sensor)) {
            Ok(()) => Ok(Self {
                sensor,
                settings,
                previous: None,
                pending: 0,
                overrun_seen: false,
                needs_init: false,
                stalled: false,
                not_due: 0,
                block: [RawSample::default(); MAX_BLOCK],
            }),
            Err(e) => Err((e, sensor)),
        }
    }

    /// Samples per watermark period.
    pub fn samples_per_poll(&self) -> u32 {
        u32::from(self.settings.sensor.fifo_watermark / 3)
    }

    /// The settings in use.
    pub fn settings(&self) -> &Adxl355Settings<A> {
        &self.settings
    }

    /// The driver (to reach the bus: a virtual device's clock and counters).
    pub fn sensor(&self) -> &Adxl355<IF> {
        &self.sensor
    }

    /// The driver, mutably.
    pub fn sensor_mut(&mut self) -> &mut Adxl355<IF> {
        &mut self.sensor
    }

    /// Whether the part reset and waits to be reconfigured (tried again at every poll).
    pub fn needs_init(&self) -> bool {
        self.needs_init
    }

    /// Checks one raw sample; `None` if it must not reach the estimator.
    fn screen(&mut self, raw: RawSample, health: &mut Health) -> Option<A::Sample> {
        let frozen = self.previous == Some(raw);
        self.previous = Some(raw);
        if raw.is_saturated() {
            health.saturated = health.saturated.saturating_add(1);
            return None;
        }
        if frozen {
            // A 20-bit sensor with ~100 LSB of noise repeating all three codes exactly is frozen
            // (probability ~1e-7 per sample for a live part).
            health.stuck = health.stuck.saturating_add(1);
            return None;
        }
        Some(self.settings.axis.pick(self.sensor.to_mps2(raw)))
    }

    /// Steps `lost` due samples as missing; `dropped`: the part never produced them (no
    /// overrun), as opposed to the FIFO overwriting them.
    fn bridge(lost: u32, dropped: bool, health: &mut Health, each: &mut impl FnMut(Option<A::Sample>)) {
        for _ in 0..lost {
            each(None);
        }
        health.bridged = health.bridged.saturating_add(lost);
        if dropped {
            health.dropped = health.dropped.saturating_add(lost);
        }
    }

    /// Re-initialises a part that reset. On success its FIFO starts empty, so every sample due
    /// until now is lost: they are bridged, and counted as dropped.
    fn reconfigure(&mut self, health: &mut Health, each: &mut impl FnMut(Option<A::Sample>)) -> u16 {
        let (sensor, config) = (&mut self.sensor, self.settings.sensor);
        match retry::<_, IF>(health, self.settings.attempts, || sensor.init(config)) {
            Ok(()) => {
                self.needs_init = false;
                self.previous = None;
                self.overrun_seen = false;
                self.stalled = false;
                Self::bridge(core::mem::take(&mut self.pending), true, health, each);
            }
            Err(_) => health.failed_polls = health.failed_polls.saturating_add(1),
        }
        0
    }
}

impl<IF: Interface, A: Axes> SampleSource for Adxl355Source<IF, A> {
    type Sample = A::Sample;

    fn read(&mut self, health: &mut Health, mut each: impl FnMut(Option<A::Sample>)) -> u16 {
        let due = self.pending.saturating_add(self.samples_per_poll());
        self.pending = due.saturating_sub(core::mem::take(&mut self.not_due));
        if self.needs_init {
            return self.reconfigure(health, &mut each);
        }
        let attempts = self.settings.attempts;
        let sensor = &mut self.sensor;
        let poll = match retry::<_, IF>(health, attempts, || sensor.poll_status()) {
            Ok(poll) => poll,
            Err(_) => {
                health.failed_polls = health.failed_polls.saturating_add(1);
                return 0;
            }
        };
        if poll.status.fifo_overrun {
            health.fifo_overruns = health.fifo_overruns.saturating_add(1);
            self.overrun_seen = true;
        }
        if poll.fifo_entries < 3 && self.pending > 0 {
            // Empty although samples are due: the part stalled, or it reset (standby, FIFO
            // cleared). Its configuration tells which.
            health.config_checks = health.config_checks.saturating_add(1);
            match retry::<_, IF>(health, attempts, || sensor.config_matches()) {
                Ok(true) => {}
                Ok(false) => {
                    health.resets = health.resets.saturating_add(1);
                    self.needs_init = true;
                    return self.reconfigure(health, &mut each);
                }
                Err(_) => {
                    health.failed_polls = health.failed_polls.saturating_add(1);
                    return 0;
                }
            }
        }
        let block = &mut self.block;
        let read =
            match retry::<_, IF>(health, attempts, || sensor.read_fifo_entries(poll.fifo_entries, &mut block[..])) {
                Ok(r) => r,
                Err(_) => {
                    health.failed_polls = health.failed_polls.saturating_add(1);
                    return 0;
                }
            };
        health.skipped_entries = health.skipped_entries.saturating_add(u32::from(read.skipped_entries));
        let n = read.samples.min(MAX_BLOCK);
        // The read drained the FIFO (it holds at most MAX_BLOCK samples), and a poll never comes
        // before its period has ended (the timing contract): a due sample that was not in it
        // was overwritten (the part said so) or never produced, and is lost for good. Bridge
        // those with prediction where they were: overwritten ones are the oldest, before the
        // block; a stall that began in this period (the last read was complete) came after the
        // samples the part did produce, one that goes on or ends here before them. (The FIFO
        // has no time stamps: a stall of a few samples inside one period is placed at its end.)
        let lost = core::mem::take(&mut self.pending).saturating_sub(n as u32);
        let dropped = !self.overrun_seen;
        let after = dropped && !self.stalled;
        if !after {
            Self::bridge(lost, dropped, health, &mut each);
        }
        for k in 0..n {
            let raw = self.block.get(k).copied().unwrap_or_default();
            each(self.screen(raw, health));
        }
        if after {
            Self::bridge(lost, dropped, health, &mut each);
        }
        self.stalled = dropped && lost > 0;
        self.overrun_seen = false;
        n as u16
    }
}

impl<F: crate::virtual_adxl355::SampleFeed, A> Recorded for Adxl355Source<I2cInterface<VirtualAdxl355<F>>, A> {
    /// One watermark period of the virtual device's clock; `false` once the data has run out
    /// and the FIFO is drained. Samples a period lacks because the recording ended were never
    /// due.
    fn advance(&mut self) -> bool {
        let bus = self.sensor.interface_mut().bus_mut();
        let loaded = bus.advance_period();
        self.not_due = u32::try_from(bus.period_shortfall()).unwrap_or(u32::MAX);
        loaded > 0 || !bus.is_exhausted()
    }
}

/// The virtual ADXL355 source of a HIL file.
pub type VirtualSource<B, A = Axis> = Adxl355Source<I2cInterface<VirtualAdxl355<LineFeed<B>>>, A>;

impl<B: ByteSource, A> VirtualSource<B, A> {
    /// The virtual device behind the driver.
    pub fn device(&self) -> &VirtualAdxl355<LineFeed<B>> {
        self.sensor.interface().bus()
    }
}

/// Runs `op` up to `attempts` times (at least once), counting failures by kind. A timeout ends
/// the attempts at once (see the module docs), as does an invalid configuration, which no retry
/// changes.
fn retry<T, IF: Interface>(
    health: &mut Health,
    attempts: u8,
    mut op: impl FnMut() -> Result<T, adxl355::Error<IF::Error>>,
) -> Result<T, adxl355::Error<IF::Error>> {
    let mut tries = 0u8;
    loop {
        tries = tries.saturating_add(1);
        match op() {
            Ok(v) => {
                if tries > 1 {
                    health.recovered = health.recovered.saturating_add(1);
                }
                return Ok(v);
            }
            Err(adxl355::Error::InvalidConfig) => return Err(adxl355::Error::InvalidConfig),
            Err(e) => {
                health.bus_errors = health.bus_errors.saturating_add(1);
                let timeout = match &e {
                    adxl355::Error::Comm(c) if IF::is_nack(c) => {
                        health.nacks = health.nacks.saturating_add(1);
                        false
                    }
                    adxl355::Error::Comm(c) if IF::is_timeout(c) => {
                        health.timeouts = health.timeouts.saturating_add(1);
                        true
                    }
                    adxl355::Error::WrongDevice { .. } => {
                        health.bad_id = health.bad_id.saturating_add(1);
                        false
                    }
                    _ => false,
                };
                if timeout || tries >= attempts.max(1) {
                    return Err(e);
                }
            }
        }
    }
}

/// Named channels of a CSV stream, one line per period.
///
/// With a clock ([`with_clock`](Self::with_clock)) the source also reads each line's `t` and
/// bridges lines missing from the file: a line whose `t` is a whole number `k ≥ 2` of sample
/// periods (within a quarter period) after the previous timed line's is preceded by `k − 1`
/// missing samples (`None`), so that the estimator's clock does not slip, up to `max_gap` of
/// them. A line off that grid (a repeated or earlier `t`, a gap of 1.5 periods, a longer gap, a
/// `t` that is garbage but a number) is a time jump: counted, not bridged, and its `t` the new
/// reference. A line whose channels do not parse but whose `t` does is stepped as missing, at
/// its time. A line without a usable `t` is not stepped at all: if it stood for a sample, the
/// next line's `t` shows the gap and bridges it; if it was inserted junk, stepping it would
/// slip the clock. Without a clock every line is one sample, bad ones stepped as missing.
///
/// ```
/// use edgekf_firmware::line_feed::ChannelReader;
/// use edgekf_firmware::node::{Health, Recorded, SampleSource};
/// use edgekf_firmware::source::ChannelSource;
/// // 0.2 is missing, 0.3 garbage, and a line of junk sits between 0.4 and 0.5.
/// let text = b"t,a\n0,1.5\n0.1,x\n#?\n0.4,2\njunk\n0.5,3\n";
/// let mut src = ChannelSource::new(ChannelReader::new(&text[..], ["a"]).unwrap()).with_clock(0.1, 10);
/// let mut got = Vec::new();
/// while src.advance() {
///     src.read(&mut Health::default(), |s| got.push(s));
/// }
/// assert_eq!(got, [Some([1.5]), None, None, None, Some([2.0]), Some([3.0])]);
/// assert_eq!(src.reader().bad_lines(), 3);
/// assert_eq!((src.missing_lines(), src.untimed_lines(), src.time_jumps()), (2, 2, 0));
/// ```
pub struct ChannelSource<B: ByteSource, const M: usize> {
    reader: ChannelReader<B, M>,
    line: Option<Result<[f32; M], BadLine>>,
    clock: Option<Clock>,
    /// Missing lines to bridge before the current one.
    gap: u32,
    missing_lines: u32,
    time_jumps: u32,
    untimed_lines: u32,
}

/// A channel source's sample clock.
#[derive(Debug, Clone, Copy)]
struct Clock {
    period_s: f64,
    max_gap: u32,
    /// `t` of the last line whose `t` parsed.
    last: Option<f64>,
}

impl Clock {
    /// The samples missing before a line at `t`, or `None` for a time jump (see
    /// [`ChannelSource`]); the first timed line is on time.
    fn missing_before(&mut self, t: f64) -> Option<u32> {
        let Some(last) = self.last.replace(t) else { return Some(0) };
        let periods = (t - last) / self.period_s;
        let whole = libm::round(periods);
        let on_grid = libm::fabs(periods - whole) <= 0.25 && whole >= 1.0 && whole - 1.0 <= f64::from(self.max_gap);
        // On the grid `whole - 1` is a whole number in 0..=max_gap: the conversion is exact.
        on_grid.then_some((whole - 1.0) as u32)
    }
}

impl<B: ByteSource, const M: usize> ChannelSource<B, M> {
    /// Lines of `reader`, its header already read; one sample per line.
    pub fn new(reader: ChannelReader<B, M>) -> Self {
        Self { reader, line: None, clock: None, gap: 0, missing_lines: 0, time_jumps: 0, untimed_lines: 0 }
    }

    /// Bridges lines missing from the file by their `t`, for samples `period_s` apart, up to
    /// `max_gap` missing samples in a row (see the type's docs).
    pub fn with_clock(self, period_s: f64, max_gap: u32) -> Self {
        Self { clock: Some(Clock { period_s, max_gap, last: None }), ..self }
    }

    /// The reader (its counters).
    pub fn reader(&self) -> &ChannelReader<B, M> {
        &self.reader
    }

    /// Samples bridged because their lines were missing from the file.
    pub fn missing_lines(&self) -> u32 {
        self.missing_lines
    }

    /// Lines whose `t` was off the sample grid (see the type's docs), not bridged.
    pub fn time_jumps(&self) -> u32 {
        self.time_jumps
    }

    /// Lines without a usable `t`, not stepped (with a clock only). A line that is garbage
    /// throughout is also one of the reader's bad lines.
    pub fn untimed_lines(&self) -> u32 {
        self.untimed_lines
    }
}

impl<B: ByteSource, const M: usize> SampleSource for ChannelSource<B, M> {
    type Sample = [f32; M];

    fn read(&mut self, health: &mut Health, mut each: impl FnMut(Option<[f32; M]>)) -> u16 {
        match self.line.take() {
            Some(line) => {
                let gap = core::mem::take(&mut self.gap);
                for _ in 0..gap {
                    each(None);
                }
                health.bridged = health.bridged.saturating_add(gap);
                health.dropped = health.dropped.saturating_add(gap);
                each(line.ok());
                1
            }
            None => 0,
        }
    }
}

impl<B: ByteSource, const M: usize> Recorded for ChannelSource<B, M> {
    fn advance(&mut self) -> bool {
        let next = match self.clock {
            Some(_) => self.reader.next_timed(),
            None => self.reader.next_values().map(|values| (None, values)),
        };
        let Some((t, line)) = next else {
            self.line = None;
            return false;
        };
        self.line = Some(line);
        if let Some(clock) = self.clock.as_mut() {
            let Some(t) = t else {
                self.untimed_lines = self.untimed_lines.saturating_add(1);
                self.line = None;
                return true;
            };
            match clock.missing_before(t) {
                Some(gap) => {
                    self.gap = gap;
                    self.missing_lines = self.missing_lines.saturating_add(gap);
                }
                None => self.time_jumps = self.time_jumps.saturating_add(1),
            }
        }
        true
    }
}

#[cfg(test)]
pub(crate) mod tests {
    #![allow(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use super::*;
    use embedded_hal::i2c::{ErrorKind, NoAcknowledgeSource};
    use embedded_hal_mock::eh1::i2c::{Mock, Transaction};
    use std::vec;
    use std::vec::Vec;

    pub(crate) const ADDR: u8 = 0x1D;

    /// The bus traffic of the default configuration's initialisation.
    pub(crate) fn init_traffic() -> Vec<Transaction> {
        vec![
            Transaction::write_read(ADDR, vec![0x00], vec![0xAD, 0x1D, 0xED]),
            Transaction::write(ADDR, vec![0x2F, 0x52]),
            Transaction::write(ADDR, vec![0x28, 0x02]),
            Transaction::write(ADDR, vec![0x2C, 0x81]),
            Transaction::write(ADDR, vec![0x29, 48]),
            Transaction::write(ADDR, vec![0x2D, 0x00]),
        ]
    }

    /// A reset whose re-initialisation fails at first (the bus NACKs every attempt): the poll
    /// is given up, the next poll starts with the re-initialisation, and once it succeeds the
    /// two periods lost are bridged before the part's new samples.
    #[test]
    fn a_failed_reconfiguration_is_tried_again_at_the_next_poll() {
        let nack = ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address);
        let mut traffic = init_traffic();
        // Poll 1: the FIFO is empty, the configuration reads its defaults; the IDs of the
        // re-initialisation are NACKed four times.
        traffic.push(Transaction::write_read(ADDR, vec![0x00], vec![0xAD, 0x1D, 0xED, 0x01, 0, 0]));
        traffic.push(Transaction::write_read(ADDR, vec![0x28], vec![0x00, 0x60, 0, 0, 0x81, 0x01]));
        for _ in 0..4 {
            traffic.push(Transaction::write_read(ADDR, vec![0x00], vec![0; 3]).with_error(nack));
        }
        // Poll 2: re-initialised.
        traffic.extend(init_traffic());
        // Poll 3: 16 new samples.
        let data: Vec<u8> = (0..16)
            .flat_map(|k| [(k * 1000, 1), (-k, 0), (256_000, 0)])
            .flat_map(|(c, f)| adxl355::encode_axis(c, f))
            .collect();
        traffic.push(Transaction::write_read(ADDR, vec![0x00], vec![0xAD, 0x1D, 0xED, 0x01, 0b11, 48]));
        traffic.push(Transaction::write_read(ADDR, vec![0x11], data));

        let mut health = Health::default();
        let sensor = Adxl355::new_i2c(Mock::new(&traffic), ADDR);
        let mut source =
            Adxl355Source::start(sensor, Adxl355Settings::default(), &mut health).map_err(|(e, _)| e).unwrap();
        let mut got: Vec<Option<f32>> = Vec::new();
        assert_eq!(source.read(&mut health, |s| got.push(s)), 0);
        assert!(got.is_empty() && source.needs_init());
        assert_eq!(source.read(&mut health, |s| got.push(s)), 0);
        assert!(got.len() == 32 && got.iter().all(Option::is_none) && !source.needs_init());
        assert_eq!(source.read(&mut health, |s| got.push(s)), 16);
        assert_eq!(got[32..].iter().filter(|s| s.is_some()).count(), 16);
        assert_eq!((got[33].unwrap() * 256_000.0 / 9.80665).round(), 1000.0);
        let expected = Health {
            bus_errors: 4,
            nacks: 4,
            failed_polls: 1,
            bridged: 32,
            dropped: 32,
            config_checks: 1,
            resets: 1,
            ..Health::default()
        };
        assert_eq!(health, expected);
        source.sensor.release().release().done();
    }
}
