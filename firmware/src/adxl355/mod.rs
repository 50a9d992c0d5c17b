//! Driver for the Analog Devices ADXL355: 3-axis, 20-bit, ±2/4/8 g, I2C or SPI, 96-entry FIFO.
//!
//! The node reads the part in FIFO blocks: [`Adxl355::init`] programs the rate, range and
//! watermark and starts measuring; the main loop then polls [`Adxl355::poll_status`] (the IDs,
//! `STATUS` and `FIFO_ENTRIES` in one burst) and drains the FIFO with
//! [`Adxl355::read_fifo_entries`], one bus transaction per block. When the FIFO is empty although
//! samples are due, [`Adxl355::config_matches`] tells a stalled part from one that reset.
//!
//! ```
//! use edgekf_firmware::adxl355::{Adxl355, Config};
//! use embedded_hal_mock::eh1::i2c::{Mock, Transaction};
//!
//! let expectations = [
//!     Transaction::write_read(0x1D, vec![0x00], vec![0xAD, 0x1D, 0xED]), // IDs
//!     Transaction::write(0x1D, vec![0x2F, 0x52]),                       // reset
//!     Transaction::write(0x1D, vec![0x28, 0x02]),                       // 1000 Hz
//!     Transaction::write(0x1D, vec![0x2C, 0x81]),                       // ±2 g
//!     Transaction::write(0x1D, vec![0x29, 48]),                         // watermark
//!     Transaction::write(0x1D, vec![0x2D, 0x00]),                       // measure
//!     Transaction::write_read(0x1D, vec![0x08], vec![0x3E, 0x80, 0x00, 0, 0, 0, 0xFF, 0xFF, 0xF0]),
//! ];
//! let mut adxl = Adxl355::new_i2c(Mock::new(&expectations), 0x1D);
//! adxl.init(Config::default()).unwrap();
//! let raw = adxl.read_xyz().unwrap();
//! assert_eq!((raw.x, raw.y, raw.z), (256_000, 0, -1));
//! assert!((adxl.to_mps2(raw)[0] - 9.80665).abs() < 1e-5);
//! adxl.release().release().done();
//! ```
#![deny(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod config;
mod error;
mod interface;
pub mod registers;
mod sample;
#[cfg(test)]
mod tests;

pub use config::{
    Config, OutputDataRate, Range, DEFAULT_FILTER_DELAY_SAMPLES, RATED_FULL_SCALE_CODE, RAW_MAX, RAW_MIN,
    STANDARD_GRAVITY,
};
pub use error::{is_nack, is_timeout, Error};
pub use interface::{I2cInterface, Interface, SpiInterface};
pub use sample::{decode_axis, decode_fifo, decode_xyz, encode_axis, FifoRead, PollStatus, RawSample, Status};

use embedded_hal::i2c::I2c;
use embedded_hal::spi::SpiDevice;

/// I2C address with the ASEL pin low.
pub const ADDRESS_ASEL_LOW: u8 = 0x1D;
/// I2C address with the ASEL pin high.
pub const ADDRESS_ASEL_HIGH: u8 = 0x53;

/// Largest FIFO burst in bytes (96 entries of 3 bytes).
const FIFO_BURST_MAX: usize = registers::FIFO_CAPACITY as usize * registers::FIFO_ENTRY_BYTES;

/// An ADXL355 behind some [`Interface`].
///
/// The driver keeps the configuration it last programmed, so conversions to m/s² need no bus
/// access and cannot disagree with the part's range (as long as nobody else writes `RANGE`).
#[derive(Debug)]
pub struct Adxl355<IFACE> {
    iface: IFACE,
    config: Config,
    /// m/s² per LSB for `config.range`, computed once so every conversion uses the same f32.
    scale: f32,
}

impl<I2C: I2c> Adxl355<I2cInterface<I2C>> {
    /// A driver for the part at `address` ([`ADDRESS_ASEL_LOW`] or [`ADDRESS_ASEL_HIGH`]) on
    /// `i2c`. No bus traffic until [`init`](Self::init).
    pub fn new_i2c(i2c: I2C, address: u8) -> Self {
        Self::new(I2cInterface::new(i2c, address))
    }
}

impl<SPI: SpiDevice> Adxl355<SpiInterface<SPI>> {
    /// A driver for the part on `spi`. No bus traffic until [`init`](Self::init).
    pub fn new_spi(spi: SPI) -> Self {
        Self::new(SpiInterface::new(spi))
    }
}

impl<IFACE> Adxl355<IFACE> {
    /// A driver over any interface (e.g. a bus wrapper with retries). The configuration reads
    /// as [`Config::default`] until [`init`](Adxl355::init) succeeds.
    pub fn new(iface: IFACE) -> Self {
        let config = Config::default();
        Adxl355 { iface, config, scale: config.mps2_per_lsb() }
    }

    /// The configuration last programmed by a successful [`init`](Adxl355::init) (the default
    /// before that).
    pub fn config(&self) -> Config {
        self.config
    }

    /// Converts a raw sample to m/s²: `code × (9.80665 / lsb_per_g)`, in f32 with the scale
    /// precomputed at init.
    pub fn to_mps2(&self, raw: RawSample) -> [f32; 3] {
        [raw.x as f32 * self.scale, raw.y as f32 * self.scale, raw.z as f32 * self.scale]
    }

    /// The m/s² per LSB used by [`to_mps2`](Self::to_mps2).
    pub fn mps2_per_lsb(&self) -> f32 {
        self.scale
    }

    /// The interface.
    pub fn interface(&self) -> &IFACE {
        &self.iface
    }

    /// The interface, mutably (e.g. to reach the bus of an [`I2cInterface`]).
    pub fn interface_mut(&mut self) -> &mut IFACE {
        &mut self.iface
    }

    /// Gives the interface back.
    pub fn release(self) -> IFACE {
        self.iface
    }
}

impl<IFACE: Interface> Adxl355<IFACE> {
    /// Checks the part's identity, resets it and starts measuring with `config`.
    ///
    /// Sequence: read `DEVID_AD..=PARTID` in one burst and compare; write `RESET` = 0x52;
    /// write `FILTER` (ODR, high-pass off), `RANGE` (0x80 | range: I2C high-speed kept on,
    /// interrupt polarity at its default), `FIFO_SAMPLES` (watermark) and finally `POWER_CTL`
    /// = 0 (measurement, temperature and data-ready on). An invalid `config` is rejected with
    /// [`Error::InvalidConfig`] before any bus traffic. On any error the stored configuration
    /// is left unchanged.
    pub fn init(&mut self, config: Config) -> Result<(), Error<IFACE::Error>> {
        if !config.is_valid() {
            return Err(Error::InvalidConfig);
        }
        let mut ids = [0u8; 3];
        self.iface.read_registers(registers::DEVID_AD, &mut ids)?;
        let [ad, mst, part] = ids;
        if ad != registers::DEVID_AD_VALUE || mst != registers::DEVID_MST_VALUE || part != registers::PARTID_VALUE {
            return Err(Error::WrongDevice { ad, mst, part });
        }
        self.iface.write_register(registers::RESET, registers::RESET_CODE)?;
        self.iface.write_register(registers::FILTER, config.odr.register_code())?;
        self.iface.write_register(registers::RANGE, registers::RANGE_I2C_HS | config.range.register_code())?;
        self.iface.write_register(registers::FIFO_SAMPLES, config.fifo_watermark)?;
        self.iface.write_register(registers::POWER_CTL, 0)?;
        self.config = config;
        self.scale = config.mps2_per_lsb();
        Ok(())
    }

    /// Reads `STATUS`. On the part, reading it clears the overrun flag.
    pub fn status(&mut self) -> Result<Status, Error<IFACE::Error>> {
        let mut buf = [0u8; 1];
        self.iface.read_registers(registers::STATUS, &mut buf)?;
        let [bits] = buf;
        Ok(Status::from_bits(bits))
    }

    /// What a poll needs to know, in one 6-byte burst from `DEVID_AD` to `FIFO_ENTRIES`: the
    /// identity, `STATUS` (clearing the overrun flag) and the FIFO's fill.
    ///
    /// Why the IDs ride along: a bus that returns garbage (all ones, all zeros) reads back
    /// wrong IDs, and its `STATUS` and FIFO count must not be trusted, let alone its FIFO data.
    /// The check costs 4 bytes more than `STATUS` alone (90 µs at 400 kHz) and saves the
    /// separate `FIFO_ENTRIES` transaction [`read_fifo`](Self::read_fifo) would make. Wrong IDs
    /// give [`Error::WrongDevice`], as at [`init`](Self::init).
    pub fn poll_status(&mut self) -> Result<PollStatus, Error<IFACE::Error>> {
        let mut buf = [0u8; 6];
        self.iface.read_registers(registers::DEVID_AD, &mut buf)?;
        let [ad, mst, part, _revid, status, entries] = buf;
        if ad != registers::DEVID_AD_VALUE || mst != registers::DEVID_MST_VALUE || part != registers::PARTID_VALUE {
            return Err(Error::WrongDevice { ad, mst, part });
        }
        Ok(PollStatus {
            status: Status::from_bits(status),
            fifo_entries: (entries & registers::FIFO_ENTRIES_MASK).min(registers::FIFO_CAPACITY),
        })
    }

    /// Whether the part still holds the configuration [`init`](Self::init) programmed: one
    /// 6-byte burst from `FILTER` to `POWER_CTL`, compared with the values written (`FILTER`,
    /// `FIFO_SAMPLES`, `RANGE`, `POWER_CTL` measuring). A part that reset reads its defaults
    /// (standby, ±2 g with the reset `RANGE` bits, a 96-entry watermark) and fails.
    pub fn config_matches(&mut self) -> Result<bool, Error<IFACE::Error>> {
        let mut buf = [0u8; 6];
        self.iface.read_registers(registers::FILTER, &mut buf)?;
        let [filter, watermark, _int_map, _sync, range, power] = buf;
        let c = self.config;
        Ok(filter == c.odr.register_code()
            && watermark == c.fifo_watermark
            && range == registers::RANGE_I2C_HS | c.range.register_code()
            && power == 0)
    }

    /// Number of entries (axes, not samples) in the FIFO, 0..=96.
    pub fn fifo_entries(&mut self) -> Result<u8, Error<IFACE::Error>> {
        let mut buf = [0u8; 1];
        self.iface.read_registers(registers::FIFO_ENTRIES, &mut buf)?;
        let [bits] = buf;
        Ok(bits & registers::FIFO_ENTRIES_MASK)
    }

    /// Reads the latest sample from the data registers (one 9-byte burst from `XDATA3`, so the
    /// three axes belong to the same sample).
    pub fn read_xyz(&mut self) -> Result<RawSample, Error<IFACE::Error>> {
        let mut buf = [0u8; 9];
        self.iface.read_registers(registers::XDATA3, &mut buf)?;
        Ok(decode_xyz(&buf))
    }

    /// Drains up to `out.len()` samples from the FIFO into the front of `out`.
    ///
    /// Reads `FIFO_ENTRIES`, then drains as [`read_fifo_entries`](Self::read_fifo_entries).
    pub fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<FifoRead, Error<IFACE::Error>> {
        if out.is_empty() {
            return Ok(FifoRead::default());
        }
        let available = self.fifo_entries()?;
        self.read_fifo_entries(available, out)
    }

    /// Drains up to `out.len()` samples from a FIFO known to hold `available` entries (as
    /// [`poll_status`](Self::poll_status) read them) into the front of `out`.
    ///
    /// Reads `n` entries from `FIFO_DATA` in a single transaction, where `n` is `available`
    /// rounded down to whole sets and capped at `3 × out.len()` (and at 96). The burst is
    /// decoded with [`decode_fifo`], which realigns on the X marker if the FIFO is out of step.
    /// An empty `out` or fewer than 3 entries return zero samples without any bus traffic.
    ///
    /// The part pops every byte that is read, so entries skipped during realignment are gone;
    /// [`FifoRead::skipped_entries`] reports them.
    pub fn read_fifo_entries(&mut self, available: u8, out: &mut [RawSample]) -> Result<FifoRead, Error<IFACE::Error>> {
        let available = usize::from(available.min(registers::FIFO_CAPACITY));
        let whole = available - available % 3;
        let entries = whole.min(out.len().saturating_mul(3));
        if entries == 0 {
            return Ok(FifoRead::default());
        }
        let mut burst = [0u8; FIFO_BURST_MAX];
        let Some(bytes) = burst.get_mut(..entries * registers::FIFO_ENTRY_BYTES) else {
            return Ok(FifoRead::default());
        };
        self.iface.read_registers(registers::FIFO_DATA, bytes)?;
        Ok(decode_fifo(bytes, out))
    }
}
