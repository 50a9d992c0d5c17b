//! ADXL355 register map and bit fields (datasheet Rev. A, "Register Map").
//!
//! Kept in one place so that the driver and the virtual device speak the same protocol. The
//! driver's tests deliberately restate these numbers as literals instead of importing them, so a
//! typo here shows up as a failing test rather than as two agreeing copies of the same mistake.

/// Analog Devices vendor ID register (reads [`DEVID_AD_VALUE`]).
pub const DEVID_AD: u8 = 0x00;
/// MEMS device ID register (reads [`DEVID_MST_VALUE`]).
pub const DEVID_MST: u8 = 0x01;
/// Part ID register (reads [`PARTID_VALUE`]).
pub const PARTID: u8 = 0x02;
/// Silicon revision register.
pub const REVID: u8 = 0x03;
/// Status flags, see the `STATUS_*` masks.
pub const STATUS: u8 = 0x04;
/// Number of valid entries in the FIFO (bits 6:0); one entry is one axis.
pub const FIFO_ENTRIES: u8 = 0x05;
/// Temperature, bits 11:8 (in bits 3:0).
pub const TEMP2: u8 = 0x06;
/// Temperature, bits 7:0.
pub const TEMP1: u8 = 0x07;
/// X axis bits 19:12; Y and Z follow, three bytes each, up to [`ZDATA1`].
pub const XDATA3: u8 = 0x08;
/// Y axis bits 19:12.
pub const YDATA3: u8 = 0x0B;
/// Z axis bits 19:12.
pub const ZDATA3: u8 = 0x0E;
/// Z axis bits 3:0 (in bits 7:4): the last data register.
pub const ZDATA1: u8 = 0x10;
/// FIFO read port. Unlike every other register it does not auto-increment: each byte read
/// here pops the next FIFO byte, so a whole burst is read with one transaction.
pub const FIFO_DATA: u8 = 0x11;
/// X offset trim, high byte (`OFFSET_X_L` .. `OFFSET_Z_L` follow up to 0x23).
pub const OFFSET_X_H: u8 = 0x1E;
/// Z offset trim, low byte.
pub const OFFSET_Z_L: u8 = 0x23;
/// High-pass corner (bits 6:4) and output data rate / low-pass corner (bits 3:0).
pub const FILTER: u8 = 0x28;
/// FIFO watermark in entries, 1..=96.
pub const FIFO_SAMPLES: u8 = 0x29;
/// Interrupt pin mapping.
pub const INT_MAP: u8 = 0x2A;
/// External sync and clock selection.
pub const SYNC: u8 = 0x2B;
/// Range (bits 1:0), interrupt polarity (bit 6) and I2C high-speed mode (bit 7).
pub const RANGE: u8 = 0x2C;
/// Standby / measurement and the temperature and data-ready enables.
pub const POWER_CTL: u8 = 0x2D;
/// Self-test forces.
pub const SELF_TEST: u8 = 0x2E;
/// Software reset: writing [`RESET_CODE`] resets the part.
pub const RESET: u8 = 0x2F;
/// Highest register address the part implements.
pub const LAST_REGISTER: u8 = RESET;

/// Value of [`DEVID_AD`].
pub const DEVID_AD_VALUE: u8 = 0xAD;
/// Value of [`DEVID_MST`].
pub const DEVID_MST_VALUE: u8 = 0x1D;
/// Value of [`PARTID`].
pub const PARTID_VALUE: u8 = 0xED;
/// The code that triggers a software reset when written to [`RESET`].
pub const RESET_CODE: u8 = 0x52;

/// [`STATUS`]: a new sample is ready.
pub const STATUS_DATA_RDY: u8 = 1 << 0;
/// [`STATUS`]: the FIFO holds at least the watermark number of entries.
pub const STATUS_FIFO_FULL: u8 = 1 << 1;
/// [`STATUS`]: entries were lost because the FIFO overflowed.
pub const STATUS_FIFO_OVR: u8 = 1 << 2;
/// [`STATUS`]: activity detected.
pub const STATUS_ACTIVITY: u8 = 1 << 3;
/// [`STATUS`]: the NVM controller is busy (after reset).
pub const STATUS_NVM_BUSY: u8 = 1 << 4;

/// [`FIFO_ENTRIES`]: the valid bits.
pub const FIFO_ENTRIES_MASK: u8 = 0x7F;
/// Capacity of the FIFO in entries (32 complete X/Y/Z sets).
pub const FIFO_CAPACITY: u8 = 96;
/// Bytes per FIFO entry.
pub const FIFO_ENTRY_BYTES: usize = 3;
/// Third byte of a FIFO entry: this entry is the X axis (start of an X/Y/Z set).
pub const FIFO_X_MARKER: u8 = 1 << 0;
/// Third byte of a FIFO entry: the FIFO was empty, the entry carries no data.
pub const FIFO_EMPTY_INDICATOR: u8 = 1 << 1;

/// [`FILTER`]: the ODR / low-pass field.
pub const FILTER_ODR_MASK: u8 = 0x0F;
/// [`RANGE`]: the range field.
pub const RANGE_MASK: u8 = 0x03;
/// [`RANGE`]: I2C high-speed mode enable (set at reset).
pub const RANGE_I2C_HS: u8 = 1 << 7;
/// [`RANGE`]: interrupt polarity (clear at reset: active low).
pub const RANGE_INT_POL: u8 = 1 << 6;
/// [`POWER_CTL`]: standby when set (reset default), measurement when clear.
pub const POWER_CTL_STANDBY: u8 = 1 << 0;
/// [`POWER_CTL`]: temperature sensor off.
pub const POWER_CTL_TEMP_OFF: u8 = 1 << 1;
/// [`POWER_CTL`]: data-ready output off.
pub const POWER_CTL_DRDY_OFF: u8 = 1 << 2;

/// Reset value of [`RANGE`].
pub const RANGE_RESET_VALUE: u8 = 0x81;
/// Reset value of [`POWER_CTL`].
pub const POWER_CTL_RESET_VALUE: u8 = 0x01;
/// Reset value of [`FIFO_SAMPLES`].
pub const FIFO_SAMPLES_RESET_VALUE: u8 = 0x60;
/// Reset value of [`FILTER`].
pub const FILTER_RESET_VALUE: u8 = 0x00;
