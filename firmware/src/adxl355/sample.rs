//! Decoded data: raw samples, status flags and the FIFO burst decoder.

use super::config::{RATED_FULL_SCALE_CODE, RAW_MAX, RAW_MIN};
use super::registers;

/// One X/Y/Z sample as sign-extended 20-bit codes (`RAW_MIN..=RAW_MAX`).
///
/// Kept raw (not in m/s²) so that saturation stays visible: a code at the rail means "at least
/// this much", not "this much", and the estimators must treat it differently.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RawSample {
    /// X axis code.
    pub x: i32,
    /// Y axis code.
    pub y: i32,
    /// Z axis code.
    pub z: i32,
}

impl RawSample {
    /// Whether any axis is at or beyond the rated range (±2/4/8 g, which is ±512 000 codes in
    /// every range): the part is specified only up to there and the ADC clips shortly after
    /// (at the 20-bit rails), so such a value means "at least this much", not "this much".
    ///
    /// ```
    /// use edgekf_firmware::adxl355::{RawSample, RAW_MAX};
    /// assert!(RawSample { x: 0, y: RAW_MAX, z: 0 }.is_saturated());
    /// assert!(RawSample { x: -512_000, y: 0, z: 0 }.is_saturated());
    /// assert!(!RawSample { x: 511_999, y: -1, z: 0 }.is_saturated());
    /// ```
    pub fn is_saturated(&self) -> bool {
        [self.x, self.y, self.z].iter().any(|&c| c.unsigned_abs() >= RATED_FULL_SCALE_CODE as u32)
    }
}

/// The `STATUS` register's flags that the driver uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// A new sample is available.
    pub data_ready: bool,
    /// The FIFO holds at least the watermark number of entries.
    pub fifo_full: bool,
    /// The FIFO overflowed and lost entries since `STATUS` was last read.
    pub fifo_overrun: bool,
}

impl Status {
    /// Decodes the `STATUS` register (other bits ignored).
    pub const fn from_bits(bits: u8) -> Self {
        Status {
            data_ready: bits & registers::STATUS_DATA_RDY != 0,
            fifo_full: bits & registers::STATUS_FIFO_FULL != 0,
            fifo_overrun: bits & registers::STATUS_FIFO_OVR != 0,
        }
    }
}

/// What [`Adxl355::poll_status`](super::Adxl355::poll_status) read: the part's status and
/// its FIFO's fill, from a read whose IDs were right.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PollStatus {
    /// The `STATUS` flags.
    pub status: Status,
    /// Entries (axes) in the FIFO, 0..=96.
    pub fifo_entries: u8,
}

/// Outcome of [`Adxl355::read_fifo`](super::Adxl355::read_fifo).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FifoRead {
    /// Complete samples written to the front of the output slice.
    pub samples: usize,
    /// FIFO entries read but not delivered: entries before the first X marker (realignment),
    /// entries flagged empty, and incomplete X/Y/Z sets (including one cut off at the end of
    /// the burst). Nonzero means data was lost or the FIFO was out of step.
    pub skipped_entries: u8,
}

/// Decodes a 20-bit left-justified code from `[DATA3, DATA2, DATA1]` (DATA1 bits 3:0, the FIFO
/// flags, are ignored) and sign-extends it.
pub const fn decode_axis(bytes: [u8; 3]) -> i32 {
    let [d3, d2, d1] = bytes;
    let value = ((d3 as u32) << 12) | ((d2 as u32) << 4) | ((d1 as u32) >> 4);
    // Move bit 19 to bit 31, reinterpret as signed, shift back arithmetically.
    ((value << 12) as i32) >> 12
}

/// Encodes a code into `[DATA3, DATA2, DATA1]` with `flags` in DATA1 bits 3:0; codes outside
/// the 20-bit range are clamped to it first. The inverse of [`decode_axis`].
pub const fn encode_axis(code: i32, flags: u8) -> [u8; 3] {
    let clamped = if code > RAW_MAX {
        RAW_MAX
    } else if code < RAW_MIN {
        RAW_MIN
    } else {
        code
    };
    let value = (clamped as u32) & 0x000F_FFFF;
    [(value >> 12) as u8, (value >> 4) as u8, (((value & 0x0F) as u8) << 4) | (flags & 0x0F)]
}

/// Decodes the 9 bytes of `XDATA3..=ZDATA1`.
pub fn decode_xyz(bytes: &[u8; 9]) -> RawSample {
    let [x3, x2, x1, y3, y2, y1, z3, z2, z1] = *bytes;
    RawSample { x: decode_axis([x3, x2, x1]), y: decode_axis([y3, y2, y1]), z: decode_axis([z3, z2, z1]) }
}

/// Decodes a FIFO burst (3 bytes per entry) into whole X/Y/Z samples at the front of `out`.
///
/// The FIFO stores axes, not samples, so a reader that starts mid-set would silently rotate the
/// axes (reading Y as X). The part marks each X entry, so the decoder only starts a sample at a
/// marked entry: leading unmarked entries are skipped, an X marker arriving before a set is
/// complete drops the partial set, and entries flagged empty drop any partial set too. All of
/// those are counted in [`FifoRead::skipped_entries`], as are complete sets that no longer fit
/// in `out`. Trailing bytes that do not form a whole entry are ignored.
pub fn decode_fifo(bytes: &[u8], out: &mut [RawSample]) -> FifoRead {
    let mut result = FifoRead::default();
    let mut skipped: usize = 0;
    // Axes collected for the current set: `have` entries of `axes` are valid.
    let mut axes = [0i32; 3];
    let mut have: usize = 0;

    for chunk in bytes.chunks_exact(registers::FIFO_ENTRY_BYTES) {
        let &[d3, d2, d1] = chunk else { continue };
        let flags = d1 & 0x0F;
        if flags & registers::FIFO_EMPTY_INDICATOR != 0 {
            skipped += have + 1;
            have = 0;
            continue;
        }
        let is_x = flags & registers::FIFO_X_MARKER != 0;
        if is_x {
            // A new set starts; a partial one in progress is lost.
            skipped += have;
            have = 0;
        } else if have == 0 {
            // Not aligned yet: a Y or Z entry without its X.
            skipped += 1;
            continue;
        }
        if let Some(slot) = axes.get_mut(have) {
            *slot = decode_axis([d3, d2, d1]);
        }
        have += 1;
        if have == 3 {
            have = 0;
            let [x, y, z] = axes;
            match out.get_mut(result.samples) {
                Some(slot) => {
                    *slot = RawSample { x, y, z };
                    result.samples += 1;
                }
                None => {
                    skipped += 3;
                }
            }
        }
    }
    skipped += have;
    result.skipped_entries = u8::try_from(skipped).unwrap_or(u8::MAX);
    result
}
