//! The CSV sample format shared by the QEMU image and the host tests.
//!
//! One header line names the columns; the order is free. Required: `t` (s), `ax`, `ay`, `az`
//! (m/s²). Optional: `fault_nack` (transactions to NACK, an integer 0..=255) and `fault_stuck`
//! (0 or 1). Any other column (e.g. the simulator's `truth_*` columns) is ignored, so one file
//! can carry both the sensor input and the answers the tests check against.

use core::fmt;

use super::feed::FeedSample;

/// Most columns a header may have (the column index is reported as a `u8`).
pub const MAX_CSV_COLUMNS: usize = 64;

/// Why a header or a line was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CsvError {
    /// The header lacks this required column.
    MissingColumn(&'static str),
    /// The field in this column (0-based) is missing, unparsable, NaN or infinite; also
    /// reported for a line with more fields than the header (at the first extra one).
    BadField {
        /// 0-based column index.
        column: u8,
    },
    /// The header has more than [`MAX_CSV_COLUMNS`] columns.
    TooManyColumns,
}

impl fmt::Display for CsvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CsvError::MissingColumn(name) => write!(f, "CSV header lacks column `{name}`"),
            CsvError::BadField { column } => write!(f, "bad CSV field in column {column}"),
            CsvError::TooManyColumns => write!(f, "CSV header has more than {MAX_CSV_COLUMNS} columns"),
        }
    }
}

impl core::error::Error for CsvError {}

/// Where the used columns sit in a CSV file, learned from its header.
///
/// ```
/// use edgekf_firmware::virtual_adxl355::{CsvColumns, CsvError};
/// let cols = CsvColumns::from_header("t,truth_x,ax,ay,az,fault_nack\r").unwrap();
/// assert_eq!(cols.ignored(), 1);
/// let s = cols.parse_line("0.5, 7.0, 1.0, -2.0, 9.81, 3\r").unwrap();
/// assert_eq!((s.accel, s.nack, s.stuck), ([1.0, -2.0, 9.81], 3, false));
/// assert_eq!(cols.parse_line("0.5,7.0,NaN,-2.0,9.81,0"), Err(CsvError::BadField { column: 2 }));
/// assert_eq!(CsvColumns::from_header("t,ax,ay").unwrap_err(), CsvError::MissingColumn("az"));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CsvColumns {
    t: u8,
    accel: [u8; 3],
    fault_nack: Option<u8>,
    fault_stuck: Option<u8>,
    count: u8,
    ignored: u8,
}

/// What one column means.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Role {
    Time,
    Accel(usize),
    Nack,
    Stuck,
    Ignored,
}

impl CsvColumns {
    /// Learns the layout from the header line. Names are matched exactly after trimming
    /// whitespace (and a UTF-8 byte-order mark); if a name repeats, the first one is used and
    /// the others are ignored.
    pub fn from_header(line: &str) -> Result<Self, CsvError> {
        let line = line.strip_prefix('\u{feff}').unwrap_or(line);
        let mut t = None;
        let mut accel = [None; 3];
        let mut fault_nack = None;
        let mut fault_stuck = None;
        let mut count: u8 = 0;
        let mut ignored: u8 = 0;
        for (index, name) in line.split(',').enumerate() {
            if index >= MAX_CSV_COLUMNS {
                return Err(CsvError::TooManyColumns);
            }
            let index = u8::try_from(index).map_err(|_| CsvError::TooManyColumns)?;
            count = index.saturating_add(1);
            let slot = match name.trim() {
                "t" => &mut t,
                "ax" => &mut accel[0],
                "ay" => &mut accel[1],
                "az" => &mut accel[2],
                "fault_nack" => &mut fault_nack,
                "fault_stuck" => &mut fault_stuck,
                _ => {
                    ignored = ignored.saturating_add(1);
                    continue;
                }
            };
            if slot.is_none() {
                *slot = Some(index);
            } else {
                ignored = ignored.saturating_add(1);
            }
        }
        let t = t.ok_or(CsvError::MissingColumn("t"))?;
        let [ax, ay, az] = accel;
        let accel = [
            ax.ok_or(CsvError::MissingColumn("ax"))?,
            ay.ok_or(CsvError::MissingColumn("ay"))?,
            az.ok_or(CsvError::MissingColumn("az"))?,
        ];
        Ok(CsvColumns { t, accel, fault_nack, fault_stuck, count, ignored })
    }

    /// Number of columns in the header.
    pub fn column_count(&self) -> usize {
        usize::from(self.count)
    }

    /// Number of header columns this parser does not use (e.g. `truth_*`).
    pub fn ignored(&self) -> usize {
        usize::from(self.ignored)
    }

    /// Whether the file carries fault-injection columns.
    pub fn has_faults(&self) -> bool {
        self.fault_nack.is_some() || self.fault_stuck.is_some()
    }

    fn role(&self, column: u8) -> Role {
        if column == self.t {
            Role::Time
        } else if let Some(axis) = self.accel.iter().position(|&c| c == column) {
            Role::Accel(axis)
        } else if self.fault_nack == Some(column) {
            Role::Nack
        } else if self.fault_stuck == Some(column) {
            Role::Stuck
        } else {
            Role::Ignored
        }
    }

    /// Parses one data line into the sample it describes.
    ///
    /// Fields are trimmed (spaces, a trailing `\r` from CRLF files). The line must have exactly
    /// as many fields as the header. `t`, `ax`, `ay` and `az` must parse as finite `f32`;
    /// `fault_nack` must be an integer 0..=255 and `fault_stuck` 0 or 1 (`2.0`-style integral
    /// floats are accepted for both, as are empty fault fields, meaning no fault). Ignored
    /// columns are not looked at.
    pub fn parse_line(&self, line: &str) -> Result<FeedSample, CsvError> {
        self.parse_record(line).map(|(_, sample)| sample)
    }

    /// Like [`parse_line`](Self::parse_line), also returning the `t` column (s).
    pub fn parse_record(&self, line: &str) -> Result<(f32, FeedSample), CsvError> {
        let mut t = None;
        let mut accel = [None; 3];
        let mut sample = FeedSample::default();
        let mut fields: u8 = 0;
        for (index, field) in line.split(',').enumerate() {
            let column = u8::try_from(index).unwrap_or(u8::MAX);
            if column >= self.count {
                return Err(CsvError::BadField { column });
            }
            fields = column.saturating_add(1);
            let field = field.trim();
            let bad = CsvError::BadField { column };
            match self.role(column) {
                Role::Time => t = Some(parse_finite(field).ok_or(bad)?),
                Role::Accel(axis) => {
                    if let Some(slot) = accel.get_mut(axis) {
                        *slot = Some(parse_finite(field).ok_or(bad)?);
                    }
                }
                Role::Nack => sample.nack = parse_count(field, u8::MAX).ok_or(bad)?,
                Role::Stuck => sample.stuck = parse_count(field, 1).ok_or(bad)? == 1,
                Role::Ignored => {}
            }
        }
        if fields < self.count {
            return Err(CsvError::BadField { column: fields });
        }
        let t = t.ok_or(CsvError::BadField { column: self.t })?;
        for ((slot, value), column) in sample.accel.iter_mut().zip(accel).zip(self.accel) {
            *slot = value.ok_or(CsvError::BadField { column })?;
        }
        Ok((t, sample))
    }
}

/// A finite `f32`, or `None`.
fn parse_finite(field: &str) -> Option<f32> {
    field.parse::<f32>().ok().filter(|v| v.is_finite())
}

/// A whole number in `0..=max` written as an integer or an integral float; empty means 0.
fn parse_count(field: &str, max: u8) -> Option<u8> {
    if field.is_empty() {
        return Some(0);
    }
    let value = match field.parse::<u8>() {
        Ok(v) => v,
        Err(_) => {
            let f = parse_finite(field)?;
            if f < 0.0 || f > f32::from(max) || libm::truncf(f) != f {
                return None;
            }
            f as u8
        }
    };
    (value <= max).then_some(value)
}
