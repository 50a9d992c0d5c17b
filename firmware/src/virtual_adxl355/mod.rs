//! A software ADXL355 on a virtual I2C bus: test equipment for hardware-in-the-loop runs.
//!
//! [`VirtualAdxl355`] implements [`embedded_hal::i2c::I2c`] and answers at address 0x1D with
//! the part's register protocol, so the real [`Adxl355`](crate::adxl355::Adxl355) driver and
//! the main loop run on it unchanged, in QEMU and in host tests. Instead of a MEMS element it
//! has a [`SampleFeed`]: recorded or simulated acceleration, with bus faults (NACKs,
//! timeouts, garbage reads), frozen output, dropped samples and resets injected where the feed
//! says so.
//!
//! # Time model
//!
//! The device has no clock of its own: the harness advances it, one watermark period at a time,
//! with [`VirtualAdxl355::advance_period`]. A period is `FIFO_SAMPLES / 3` samples (at least
//! one) as programmed when measurement last started, i.e. the poll period of the node that
//! programmed it; a reset of the part does not change the harness's clock. Before the first
//! measurement nothing happens (the recording starts when the node starts the part). From then
//! on each period takes its samples from the feed: in measurement mode (`POWER_CTL` bit 0 clear)
//! into the FIFO, in standby (after a reset) into nothing, since time does not stop while the
//! part waits to be reconfigured. Time passes whether or not the firmware manages to talk to the
//! device, exactly as on a real bus: a NACK burst that lasts several periods lets the FIFO
//! overrun. Runs are deterministic and independent of how fast the host or QEMU executes.
//!
//! # Data path
//!
//! Each sample becomes three FIFO entries (X carrying the marker bit, then Y, Z) with codes
//! `round(accel / 9.80665 × lsb_per_g)` computed in f32 for the range in `RANGE`, clamped to
//! the 20-bit rails as the real part saturates. The FIFO holds 96 entries; on overflow the
//! oldest entries are discarded, counted, and `STATUS` bit 2 (FIFO_OVR) is set until `STATUS`
//! is next read. `XDATA..ZDATA` hold the most recent sample. `FIFO_DATA` (0x11) does not
//! auto-increment and pops an entry per 3 bytes; an empty FIFO yields `00 00 02` (the empty
//! indicator). Other reads auto-increment; registers past 0x2F read 0.
//!
//! # Faults
//!
//! Bus faults are queued when their sample is due and served one per transaction, timeouts
//! first, then NACKs, then garbage reads; a faulty transaction has no effect on the part.
//!
//! * `nack`: that many transactions fail with `NoAcknowledge(Address)`.
//! * `timeout`: that many transactions fail with [`VirtualBusError::Timeout`], of kind
//!   `ErrorKind::Other` (embedded-hal 1.0 has no timeout kind; STM32 HALs report theirs so).
//! * `garbage`: that many transactions to the part's address complete, but every byte read is
//!   `0xFF` (the ID registers included) and writes are lost: a marginal bus, a corrupt
//!   register.
//! * `stuck`: the sample is replaced by the previous output codes.
//! * `dropped`: the part produces nothing for this sample (a stall): the FIFO and the data
//!   registers are left alone.
//! * `reset`: the part resets as the sample is due (registers to their defaults, standby,
//!   FIFO cleared); this sample and the following ones are lost until the node reconfigures it.
//!
//! ```
//! use edgekf_firmware::adxl355::{Adxl355, Config, RawSample};
//! use edgekf_firmware::virtual_adxl355::{FeedSample, SliceFeed, VirtualAdxl355};
//!
//! let input = [FeedSample::new([0.0, 0.0, 9.80665]); 32];
//! let mut adxl = Adxl355::new_i2c(VirtualAdxl355::new(SliceFeed::new(&input)), 0x1D);
//! adxl.init(Config { fifo_watermark: 48, ..Config::default() }).unwrap();
//! adxl.interface_mut().bus_mut().advance_period(); // one watermark period: 16 samples
//! assert!(adxl.status().unwrap().fifo_full);
//! let mut block = [RawSample::default(); 32];
//! let read = adxl.read_fifo(&mut block).unwrap();
//! assert_eq!(read.samples, 16);
//! assert_eq!(block[0], RawSample { x: 0, y: 0, z: 256_000 });
//! ```
#![deny(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod csv;
mod feed;
mod sample;
#[cfg(test)]
mod tests;

pub use csv::{CsvColumns, CsvError, FAULT_COLUMNS, MAX_CSV_COLUMNS};
pub use feed::{CsvTextFeed, FnFeed, SampleFeed, SliceFeed};
pub use sample::FeedSample;

use core::fmt;

use embedded_hal::i2c::{ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation};
use heapless::Deque;

use crate::adxl355::registers as reg;
use crate::adxl355::{encode_axis, Range, STANDARD_GRAVITY};

/// The I2C address the virtual part answers at (ASEL low).
pub const VIRTUAL_ADDRESS: u8 = 0x1D;

/// Number of implemented registers (0x00..=0x2F).
const REGISTER_COUNT: usize = reg::LAST_REGISTER as usize + 1;
/// FIFO depth in entries.
const FIFO_DEPTH: usize = reg::FIFO_CAPACITY as usize;
/// What `FIFO_DATA` returns when the FIFO is empty.
const EMPTY_ENTRY: [u8; 3] = [0x00, 0x00, reg::FIFO_EMPTY_INDICATOR];
/// Temperature registers at reset: 1885 LSB, the datasheet's nominal 25 °C intercept.
const TEMP_25C: [u8; 2] = [0x07, 0x5D];

/// What every byte of a garbage read returns.
pub const GARBAGE_BYTE: u8 = 0xFF;

/// Why the virtual bus refused a transaction. The NACKs report
/// `ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address)`, as a real bus would; a timeout
/// reports `ErrorKind::Other`, where embedded-hal 1.0 HALs (stm32f4xx-hal among them) put theirs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum VirtualBusError {
    /// Nobody at that address.
    AddressNack,
    /// A NACK injected by the feed (`FeedSample::nack`).
    InjectedNack,
    /// A timeout injected by the feed (`FeedSample::timeout`).
    Timeout,
}

impl embedded_hal::i2c::Error for VirtualBusError {
    fn kind(&self) -> ErrorKind {
        match self {
            VirtualBusError::AddressNack | VirtualBusError::InjectedNack => {
                ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address)
            }
            VirtualBusError::Timeout => ErrorKind::Other,
        }
    }
}

impl fmt::Display for VirtualBusError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            VirtualBusError::AddressNack => f.write_str("no device at this address"),
            VirtualBusError::InjectedNack => f.write_str("injected NACK"),
            VirtualBusError::Timeout => f.write_str("injected bus timeout"),
        }
    }
}

crate::frame! {
    /// What the virtual device has done so far, for the test to check against the feed; also the
    /// `virtual` frame the oscillator image reports them in, so that the counts are listed once.
    #[derive(Eq)]
    #[cfg_attr(feature = "defmt", derive(defmt::Format))]
    pub struct VirtualCounters = "virtual {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32}" {
        /// Samples taken from the feed into the FIFO.
        pub samples_loaded: u32,
        /// Injected NACKs sent (wrong-address NACKs are not counted).
        pub nacks_sent: u32,
        /// FIFO entries (axes) discarded because the FIFO overflowed.
        pub overrun_entries: u32,
        /// Injected timeouts sent.
        pub timeouts_sent: u32,
        /// Garbage reads served (transactions answered with `0xFF` bytes).
        pub garbage_sent: u32,
        /// Samples the feed marked `dropped` that were due while measuring (nothing loaded).
        pub samples_dropped: u32,
        /// Resets injected by the feed.
        pub resets: u32,
        /// Samples lost to a reset: in the FIFO when it was cleared, or due while the part sat in
        /// standby after it.
        pub samples_discarded: u32,
    }
}

/// A software ADXL355 on a virtual I2C bus. See the [module docs](self) for the model.
#[derive(Debug)]
pub struct VirtualAdxl355<F: SampleFeed> {
    feed: F,
    registers: [u8; REGISTER_COUNT],
    fifo: Deque<[u8; 3], FIFO_DEPTH>,
    /// Codes of the most recent sample (what a stuck sensor repeats).
    last_codes: [i32; 3],
    overrun: bool,
    pending_nacks: u32,
    pending_timeouts: u32,
    pending_garbage: u32,
    /// Samples per period, latched when measurement starts (0: never measured yet).
    period: u8,
    /// Samples the feed supplied in the last period.
    last_taken: u8,
    feed_ended: bool,
    pointer: u8,
    counters: VirtualCounters,
}

impl<F: SampleFeed> VirtualAdxl355<F> {
    /// A device in its reset state (standby) that will measure `feed`.
    pub fn new(feed: F) -> Self {
        let mut device = VirtualAdxl355 {
            feed,
            registers: [0; REGISTER_COUNT],
            fifo: Deque::new(),
            last_codes: [0; 3],
            overrun: false,
            pending_nacks: 0,
            pending_timeouts: 0,
            pending_garbage: 0,
            period: 0,
            last_taken: 0,
            feed_ended: false,
            pointer: 0,
            counters: VirtualCounters::default(),
        };
        device.reset();
        device
    }

    /// Whether the run is over: the feed has returned `None` and the FIFO is drained.
    pub fn is_exhausted(&self) -> bool {
        self.feed_ended && self.fifo.is_empty()
    }

    /// The counters so far.
    pub fn counters(&self) -> VirtualCounters {
        self.counters
    }

    /// NACKs still queued.
    pub fn pending_nacks(&self) -> u32 {
        self.pending_nacks
    }

    /// Bus faults of every kind (timeouts, NACKs, garbage reads) still queued.
    pub fn pending_bus_faults(&self) -> u32 {
        self.pending_timeouts.saturating_add(self.pending_nacks).saturating_add(self.pending_garbage)
    }

    /// Samples per period (0 before the first measurement).
    pub fn period_samples(&self) -> usize {
        usize::from(self.period)
    }

    /// Samples of the last period that the feed did not have, because it ended: a recording
    /// that stops mid-period. Those samples were never due.
    pub fn period_shortfall(&self) -> usize {
        usize::from(self.period.saturating_sub(self.last_taken))
    }

    /// Entries in the FIFO.
    pub fn fifo_len(&self) -> usize {
        self.fifo.len()
    }

    /// Value of a stored register, without the side effects of a bus read (`STATUS`,
    /// `FIFO_ENTRIES` and `FIFO_DATA` are computed on a bus read and read 0 here).
    pub fn peek_register(&self, address: u8) -> u8 {
        self.registers.get(usize::from(address)).copied().unwrap_or(0)
    }

    /// The feed.
    pub fn feed(&self) -> &F {
        &self.feed
    }

    /// The feed, mutably.
    pub fn feed_mut(&mut self) -> &mut F {
        &mut self.feed
    }

    /// Software reset: registers to their reset values, FIFO and output cleared. Injected
    /// bus faults still pending, the harness's period and the counters are test-bench state and
    /// survive.
    fn reset(&mut self) {
        self.registers = [0; REGISTER_COUNT];
        let defaults = [
            (reg::DEVID_AD, reg::DEVID_AD_VALUE),
            (reg::DEVID_MST, reg::DEVID_MST_VALUE),
            (reg::PARTID, reg::PARTID_VALUE),
            (reg::REVID, 0x01),
            (reg::TEMP2, TEMP_25C[0]),
            (reg::TEMP1, TEMP_25C[1]),
            (reg::FILTER, reg::FILTER_RESET_VALUE),
            (reg::FIFO_SAMPLES, reg::FIFO_SAMPLES_RESET_VALUE),
            (reg::RANGE, reg::RANGE_RESET_VALUE),
            (reg::POWER_CTL, reg::POWER_CTL_RESET_VALUE),
        ];
        for (address, value) in defaults {
            self.set(address, value);
        }
        self.fifo.clear();
        self.last_codes = [0; 3];
        self.overrun = false;
    }

    fn set(&mut self, address: u8, value: u8) {
        if let Some(r) = self.registers.get_mut(usize::from(address)) {
            *r = value;
        }
    }

    fn measuring(&self) -> bool {
        self.peek_register(reg::POWER_CTL) & reg::POWER_CTL_STANDBY == 0
    }

    fn range(&self) -> Range {
        Range::from_register_code(self.peek_register(reg::RANGE)).unwrap_or(Range::G2)
    }

    /// One watermark period passes: from the first measurement on, `period_samples()` samples
    /// are taken from the feed, loaded into the FIFO in measurement mode, lost in standby.
    /// Returns how many were loaded (0 before the first measurement, in standby or once the
    /// feed has ended).
    pub fn advance_period(&mut self) -> usize {
        let mut loaded = 0;
        self.last_taken = 0;
        for _ in 0..self.period {
            let Some(sample) = self.feed.next_sample() else {
                self.feed_ended = true;
                break;
            };
            self.feed_ended = false;
            self.last_taken = self.last_taken.saturating_add(1);
            self.queue_bus_faults(&sample);
            if sample.reset {
                self.counters.resets = self.counters.resets.saturating_add(1);
                let cleared = u32::try_from(self.fifo.len() / 3).unwrap_or(u32::MAX);
                self.counters.samples_discarded = self.counters.samples_discarded.saturating_add(cleared);
                self.reset();
            }
            if !self.measuring() {
                self.counters.samples_discarded = self.counters.samples_discarded.saturating_add(1);
            } else if sample.dropped {
                self.counters.samples_dropped = self.counters.samples_dropped.saturating_add(1);
            } else {
                self.load(sample);
                loaded += 1;
            }
        }
        loaded
    }

    fn queue_bus_faults(&mut self, sample: &FeedSample) {
        self.pending_nacks = self.pending_nacks.saturating_add(u32::from(sample.nack));
        self.pending_timeouts = self.pending_timeouts.saturating_add(u32::from(sample.timeout));
        self.pending_garbage = self.pending_garbage.saturating_add(u32::from(sample.garbage));
    }

    /// Converts one sample and pushes it into the FIFO and the data registers.
    fn load(&mut self, sample: FeedSample) {
        let codes = if sample.stuck {
            self.last_codes
        } else {
            let lsb_per_g = self.range().lsb_per_g();
            sample.accel.map(|a| to_code(a, lsb_per_g))
        };
        let mut data_address = reg::XDATA3;
        for (axis, &code) in codes.iter().enumerate() {
            let marker = if axis == 0 { reg::FIFO_X_MARKER } else { 0 };
            self.push_entry(encode_axis(code, marker));
            for byte in encode_axis(code, 0) {
                self.set(data_address, byte);
                data_address = data_address.wrapping_add(1);
            }
        }
        self.last_codes = codes;
        self.counters.samples_loaded = self.counters.samples_loaded.saturating_add(1);
    }

    fn push_entry(&mut self, entry: [u8; 3]) {
        if self.fifo.is_full() {
            self.fifo.pop_front();
            self.note_overrun();
        }
        if self.fifo.push_back(entry).is_err() {
            self.note_overrun();
        }
    }

    fn note_overrun(&mut self) {
        self.overrun = true;
        self.counters.overrun_entries = self.counters.overrun_entries.saturating_add(1);
    }

    fn status_bits(&self) -> u8 {
        let entries = self.fifo.len();
        let mut bits = 0;
        if entries >= 3 {
            bits |= reg::STATUS_DATA_RDY;
        }
        if entries > 0 && entries >= usize::from(self.peek_register(reg::FIFO_SAMPLES)) {
            bits |= reg::STATUS_FIFO_FULL;
        }
        if self.overrun {
            bits |= reg::STATUS_FIFO_OVR;
        }
        bits
    }

    fn write_bytes(&mut self, bytes: &[u8]) {
        let Some((&start, data)) = bytes.split_first() else { return };
        self.pointer = start;
        for &value in data {
            self.write_register(self.pointer, value);
            self.pointer = self.pointer.wrapping_add(1);
        }
    }

    /// A register write as the part handles it: only 0x1E..=0x2F are writable, and `RESET`
    /// acts (on the reset code) instead of storing.
    fn write_register(&mut self, address: u8, value: u8) {
        match address {
            reg::RESET if value == reg::RESET_CODE => self.reset(),
            reg::OFFSET_X_H..=reg::SELF_TEST => {
                let starts = address == reg::POWER_CTL && !self.measuring() && value & reg::POWER_CTL_STANDBY == 0;
                self.set(address, value);
                if starts {
                    // Measurement starts: the period is the watermark programmed now.
                    self.period = (self.peek_register(reg::FIFO_SAMPLES).min(reg::FIFO_CAPACITY) / 3).max(1);
                }
            }
            _ => {}
        }
    }

    fn read_bytes(&mut self, buf: &mut [u8]) {
        // A FIFO entry being read out, and the next byte of it.
        let mut entry = EMPTY_ENTRY;
        let mut entry_pos = entry.len();
        for byte in buf.iter_mut() {
            let address = self.pointer;
            *byte = match address {
                reg::STATUS => {
                    let bits = self.status_bits();
                    self.overrun = false;
                    bits
                }
                // At most 96: fits the 7-bit field.
                reg::FIFO_ENTRIES => u8::try_from(self.fifo.len()).unwrap_or(reg::FIFO_CAPACITY),
                reg::FIFO_DATA => {
                    if entry_pos >= entry.len() {
                        entry = self.fifo.pop_front().unwrap_or(EMPTY_ENTRY);
                        entry_pos = 0;
                    }
                    let value = entry.get(entry_pos).copied().unwrap_or(0);
                    entry_pos += 1;
                    value
                }
                _ => self.peek_register(address),
            };
            if address != reg::FIFO_DATA {
                self.pointer = address.wrapping_add(1);
            }
        }
    }
}

/// `round(accel / g × lsb_per_g)` in f32, clamped to the 20-bit rails; NaN reads as 0.
fn to_code(accel: f32, lsb_per_g: f32) -> i32 {
    let code = libm::roundf(accel / STANDARD_GRAVITY * lsb_per_g);
    // `as` saturates and maps NaN to 0; the clamp is the part's own saturation.
    (code as i32).clamp(crate::adxl355::RAW_MIN, crate::adxl355::RAW_MAX)
}

impl<F: SampleFeed> ErrorType for VirtualAdxl355<F> {
    type Error = VirtualBusError;
}

impl<F: SampleFeed> I2c for VirtualAdxl355<F> {
    fn transaction(&mut self, address: u8, operations: &mut [Operation<'_>]) -> Result<(), Self::Error> {
        if self.pending_timeouts > 0 {
            self.pending_timeouts -= 1;
            self.counters.timeouts_sent = self.counters.timeouts_sent.saturating_add(1);
            return Err(VirtualBusError::Timeout);
        }
        if self.pending_nacks > 0 {
            self.pending_nacks -= 1;
            self.counters.nacks_sent = self.counters.nacks_sent.saturating_add(1);
            return Err(VirtualBusError::InjectedNack);
        }
        if address != VIRTUAL_ADDRESS {
            return Err(VirtualBusError::AddressNack);
        }
        if self.pending_garbage > 0 {
            self.pending_garbage -= 1;
            self.counters.garbage_sent = self.counters.garbage_sent.saturating_add(1);
            for operation in operations {
                if let Operation::Read(buf) = operation {
                    buf.fill(GARBAGE_BYTE);
                }
            }
            return Ok(());
        }
        for operation in operations {
            match operation {
                Operation::Write(bytes) => self.write_bytes(bytes),
                Operation::Read(buf) => self.read_bytes(buf),
            }
        }
        Ok(())
    }
}
