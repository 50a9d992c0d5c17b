//! Measurement configuration: range, output data rate and FIFO watermark.

use super::registers;

/// Standard gravity in m/s² (ISO 80000-3), the factor between the part's g-based sensitivity
/// and the SI units the estimators use.
pub const STANDARD_GRAVITY: f32 = 9.806_65;

/// Largest 20-bit output code: a reading at or above full scale on the positive side.
pub const RAW_MAX: i32 = 524_287;
/// Code of the rated full scale (2 g at ±2 g, 4 g at ±4 g, 8 g at ±8 g: the same count in every
/// range). Codes at or beyond it are treated as saturated.
pub const RATED_FULL_SCALE_CODE: i32 = 512_000;
/// Smallest 20-bit output code: a reading at or below full scale on the negative side.
pub const RAW_MIN: i32 = -524_288;

/// Group delay we assume for the part's decimation and low-pass filter, in output samples.
///
/// See [`OutputDataRate::filter_delay_samples`] for why this is a model and not a datasheet
/// figure.
pub const DEFAULT_FILTER_DELAY_SAMPLES: f32 = 2.5;

/// Measurement range (`RANGE` register, bits 1:0).
///
/// The part is digital: the range only sets how the 20-bit code maps to g. The 20-bit codes
/// span ±2^19 LSB, so the real clipping points are ±2.048 g, ±4.096 g and ±8.192 g.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Range {
    /// ±2 g (±2.048 g), 256 000 LSB/g: the finest resolution.
    #[default]
    G2,
    /// ±4 g (±4.096 g), 128 000 LSB/g.
    G4,
    /// ±8 g (±8.192 g), 64 000 LSB/g.
    G8,
}

impl Range {
    /// Nominal sensitivity in LSB per g.
    pub const fn lsb_per_g(self) -> f32 {
        match self {
            Range::G2 => 256_000.0,
            Range::G4 => 128_000.0,
            Range::G8 => 64_000.0,
        }
    }

    /// Acceleration in g at which the output code saturates (2^19 / sensitivity), i.e. 2.048,
    /// 4.096 or 8.192. This, not the marketing figure, is what limits a measurement.
    pub const fn full_scale_g(self) -> f32 {
        (1u32 << 19) as f32 / self.lsb_per_g()
    }

    /// The value of the `RANGE` register's range field (1, 2 or 3).
    pub const fn register_code(self) -> u8 {
        match self {
            Range::G2 => 1,
            Range::G4 => 2,
            Range::G8 => 3,
        }
    }

    /// Decodes the `RANGE` register's range field; `None` for the reserved code 0.
    pub const fn from_register_code(code: u8) -> Option<Self> {
        match code & registers::RANGE_MASK {
            1 => Some(Range::G2),
            2 => Some(Range::G4),
            3 => Some(Range::G8),
            _ => None,
        }
    }
}

/// Output data rate and the matching low-pass corner (`FILTER` register, bits 3:0).
///
/// The part ties the low-pass corner to the ODR (corner = ODR / 4), so choosing one chooses both.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum OutputDataRate {
    /// 4000 Hz, low-pass 1000 Hz.
    Hz4000,
    /// 2000 Hz, low-pass 500 Hz.
    Hz2000,
    /// 1000 Hz, low-pass 250 Hz.
    #[default]
    Hz1000,
    /// 500 Hz, low-pass 125 Hz.
    Hz500,
    /// 250 Hz, low-pass 62.5 Hz.
    Hz250,
    /// 125 Hz, low-pass 31.25 Hz.
    Hz125,
    /// 62.5 Hz, low-pass 15.625 Hz.
    Hz62_5,
    /// 31.25 Hz, low-pass 7.813 Hz.
    Hz31_25,
    /// 15.625 Hz, low-pass 3.906 Hz.
    Hz15_625,
    /// 7.813 Hz, low-pass 1.953 Hz.
    Hz7_813,
    /// 3.906 Hz, low-pass 0.977 Hz.
    Hz3_906,
}

impl OutputDataRate {
    /// Every rate, fastest first (the order of the register codes).
    pub const ALL: [OutputDataRate; 11] = [
        OutputDataRate::Hz4000,
        OutputDataRate::Hz2000,
        OutputDataRate::Hz1000,
        OutputDataRate::Hz500,
        OutputDataRate::Hz250,
        OutputDataRate::Hz125,
        OutputDataRate::Hz62_5,
        OutputDataRate::Hz31_25,
        OutputDataRate::Hz15_625,
        OutputDataRate::Hz7_813,
        OutputDataRate::Hz3_906,
    ];

    /// Output data rate in Hz, as the datasheet table states it.
    pub const fn hz(self) -> f32 {
        match self {
            OutputDataRate::Hz4000 => 4000.0,
            OutputDataRate::Hz2000 => 2000.0,
            OutputDataRate::Hz1000 => 1000.0,
            OutputDataRate::Hz500 => 500.0,
            OutputDataRate::Hz250 => 250.0,
            OutputDataRate::Hz125 => 125.0,
            OutputDataRate::Hz62_5 => 62.5,
            OutputDataRate::Hz31_25 => 31.25,
            OutputDataRate::Hz15_625 => 15.625,
            OutputDataRate::Hz7_813 => 7.813,
            OutputDataRate::Hz3_906 => 3.906,
        }
    }

    /// Low-pass (anti-alias) corner in Hz, as the datasheet table states it.
    pub const fn lowpass_hz(self) -> f32 {
        match self {
            OutputDataRate::Hz4000 => 1000.0,
            OutputDataRate::Hz2000 => 500.0,
            OutputDataRate::Hz1000 => 250.0,
            OutputDataRate::Hz500 => 125.0,
            OutputDataRate::Hz250 => 62.5,
            OutputDataRate::Hz125 => 31.25,
            OutputDataRate::Hz62_5 => 15.625,
            OutputDataRate::Hz31_25 => 7.813,
            OutputDataRate::Hz15_625 => 3.906,
            OutputDataRate::Hz7_813 => 1.953,
            OutputDataRate::Hz3_906 => 0.977,
        }
    }

    /// Group delay of the part's internal decimation and low-pass filter, in output samples.
    ///
    /// Every sample leaves the ADXL355 late: the sigma-delta decimator and the digital low-pass
    /// filter behind it average over past inputs, so a sample stamped "now" describes the motion
    /// some time ago. An estimator that compares the measurement with a model (a phase, an
    /// innovation, a force at a known frequency) must account for that delay or it reads it as
    /// a phase error.
    ///
    /// **This is a model, not a datasheet number.** The exact figure could not be looked up
    /// when this driver was written, so we treat the filter as a pure delay of
    /// [`DEFAULT_FILTER_DELAY_SAMPLES`] (2.5) output samples, the same for every ODR when
    /// counted in output samples (the filter is clocked at the output rate, so its delay scales
    /// with the sample period). It is an assumption to be verified on the bench, e.g. by a step
    /// or tap test timed against an external trigger; callers that measured a different value
    /// should use their own figure instead of this one.
    pub const fn filter_delay_samples(self) -> f32 {
        DEFAULT_FILTER_DELAY_SAMPLES
    }

    /// [`filter_delay_samples`](Self::filter_delay_samples) converted to seconds at this rate.
    pub fn filter_delay_s(self) -> f32 {
        self.filter_delay_samples() / self.hz()
    }

    /// Sample period in seconds.
    pub fn period_s(self) -> f32 {
        1.0 / self.hz()
    }

    /// The value of the `FILTER` register's ODR field (0..=10).
    pub const fn register_code(self) -> u8 {
        self as u8
    }

    /// Decodes the `FILTER` register's ODR field; `None` for the reserved codes 11..=15.
    pub fn from_register_code(code: u8) -> Option<Self> {
        Self::ALL.get(usize::from(code & registers::FILTER_ODR_MASK)).copied()
    }
}

/// What [`Adxl355::init`](super::Adxl355::init) programs into the part.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Measurement range.
    pub range: Range,
    /// Output data rate (and with it the low-pass corner).
    pub odr: OutputDataRate,
    /// FIFO watermark in entries (one entry is one axis): 3..=96 and a multiple of 3, so that
    /// the watermark always falls on a whole X/Y/Z set.
    pub fifo_watermark: u8,
}

impl Default for Config {
    /// ±2 g, 1000 Hz, a watermark of 48 entries (16 samples, half the FIFO): leaves half the
    /// FIFO as slack for a late read.
    fn default() -> Self {
        Config { range: Range::G2, odr: OutputDataRate::Hz1000, fifo_watermark: 48 }
    }
}

impl Config {
    /// Whether [`Adxl355::init`](super::Adxl355::init) accepts this configuration (the
    /// watermark is 3..=96 and a multiple of 3).
    pub const fn is_valid(&self) -> bool {
        self.fifo_watermark >= 3 && self.fifo_watermark <= registers::FIFO_CAPACITY && self.fifo_watermark % 3 == 0
    }

    /// Whole X/Y/Z samples per watermark.
    pub const fn samples_per_watermark(&self) -> u8 {
        self.fifo_watermark / 3
    }

    /// Scale from a raw code to m/s² for this range.
    pub fn mps2_per_lsb(&self) -> f32 {
        STANDARD_GRAVITY / self.range.lsb_per_g()
    }
}
