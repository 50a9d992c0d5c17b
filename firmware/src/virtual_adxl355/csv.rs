//! The CSV sample format shared by the QEMU image and the host tests.
//!
//! One header line names the columns, under the data contract's header rules
//! ([`edgekf::csv_header`], the host reader's too): `t` (s) first, then in any order `ax`, `ay`,
//! `az` (m/s², required), and the optional fault instructions of [`FeedSample`]: `fault_nack`,
//! `fault_timeout` and `fault_garbage` (transactions, an integer 0..=255), `fault_stuck`,
//! `fault_drop` and `fault_reset` (0 or 1). Any other column (e.g. the simulator's `truth_*`
//! columns) is ignored, so one file can carry both the sensor input and the answers the tests
//! check against. A repeated name is refused, as on the host.

use core::fmt;

use edgekf::csv_header::{fields, Header, HeaderError};
use edgekf::decimal::parse_f32;

use super::sample::FeedSample;

/// Most columns a header may have (the column index is reported as a `u8`).
pub const MAX_CSV_COLUMNS: usize = 64;

/// Why a header or a line was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CsvError {
    /// The header breaks the header rules or lacks a required column (see
    /// [`edgekf::csv_header`]).
    Header(HeaderError),
    /// The field in this column (0-based) is missing, unparsable, NaN or infinite; also
    /// reported for a line with more fields than the header (at the first extra one).
    BadField {
        /// 0-based column index.
        column: u8,
    },
}

impl fmt::Display for CsvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CsvError::Header(e) => write!(f, "CSV header: {e}"),
            CsvError::BadField { column } => write!(f, "bad CSV field in column {column}"),
        }
    }
}

impl core::error::Error for CsvError {}

/// Where the used columns sit in a CSV file, learned from its header.
///
/// ```
/// use edgekf::csv_header::{ColumnName, HeaderError};
/// use edgekf_firmware::virtual_adxl355::{CsvColumns, CsvError};
/// let cols = CsvColumns::from_header("t,truth_x,ax,ay,az,fault_nack\r").unwrap();
/// assert_eq!(cols.ignored(), 1);
/// let s = cols.parse_line("0.5, 7.0, 1.0, -2.0, 9.81, 3\r").unwrap();
/// assert_eq!((s.accel, s.nack, s.stuck), ([1.0, -2.0, 9.81], 3, false));
/// assert_eq!(cols.parse_line("0.5,7.0,NaN,-2.0,9.81,0"), Err(CsvError::BadField { column: 2 }));
/// let missing = HeaderError::MissingChannel { name: ColumnName::new("az") };
/// assert_eq!(CsvColumns::from_header("t,ax,ay").unwrap_err(), CsvError::Header(missing));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CsvColumns {
    accel: [u8; 3],
    /// Where each of [`FAULT_COLUMNS`] sits, if present.
    faults: [Option<u8>; FAULT_COLUMNS.len()],
    count: u8,
    ignored: u8,
}

/// The optional fault columns, in the order of [`Fault`].
pub const FAULT_COLUMNS: [&str; 6] =
    ["fault_nack", "fault_timeout", "fault_garbage", "fault_stuck", "fault_drop", "fault_reset"];

/// Which fault instruction a column carries (index into [`FAULT_COLUMNS`]).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Fault {
    Nack,
    Timeout,
    Garbage,
    Stuck,
    Drop,
    Reset,
}

impl Fault {
    const ALL: [Fault; FAULT_COLUMNS.len()] =
        [Fault::Nack, Fault::Timeout, Fault::Garbage, Fault::Stuck, Fault::Drop, Fault::Reset];

    /// Parses the field into `sample`: a transaction count (0..=255) or a flag (0 or 1).
    fn apply(self, field: &str, sample: &mut FeedSample) -> Option<()> {
        let flag = |field| parse_count(field, 1).map(|v| v == 1);
        match self {
            Fault::Nack => sample.nack = parse_count(field, u8::MAX)?,
            Fault::Timeout => sample.timeout = parse_count(field, u8::MAX)?,
            Fault::Garbage => sample.garbage = parse_count(field, u8::MAX)?,
            Fault::Stuck => sample.stuck = flag(field)?,
            Fault::Drop => sample.dropped = flag(field)?,
            Fault::Reset => sample.reset = flag(field)?,
        }
        Some(())
    }
}

/// What one column means.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Role {
    Time,
    Accel(usize),
    Fault(Fault),
    Ignored,
}

impl CsvColumns {
    /// Learns the layout from the header line, by the shared header rules (a BOM and spaces
    /// dropped, `t` first, no repeated names) and at most [`MAX_CSV_COLUMNS`] columns.
    pub fn from_header(line: &str) -> Result<Self, CsvError> {
        let header = Header::parse(fields(line), MAX_CSV_COLUMNS).map_err(CsvError::Header)?;
        let accel = header.find_all(["ax", "ay", "az"]).map_err(CsvError::Header)?;
        // Every index and count is below MAX_CSV_COLUMNS (64), so the conversions are exact.
        let small = |v: usize| u8::try_from(v).unwrap_or(u8::MAX);
        let faults = FAULT_COLUMNS.map(|name| header.position(name).map(small));
        let used = 1 + accel.len() + faults.iter().filter(|f| f.is_some()).count();
        Ok(CsvColumns {
            accel: accel.map(small),
            faults,
            count: small(header.width()),
            ignored: small(header.width().saturating_sub(used)),
        })
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
        self.faults.iter().any(Option::is_some)
    }

    fn role(&self, column: u8) -> Role {
        if column == 0 {
            Role::Time
        } else if let Some(axis) = self.accel.iter().position(|&c| c == column) {
            Role::Accel(axis)
        } else if let Some(k) = self.faults.iter().position(|&c| c == Some(column)) {
            Fault::ALL.get(k).map_or(Role::Ignored, |&f| Role::Fault(f))
        } else {
            Role::Ignored
        }
    }

    /// Parses one data line into the sample it describes.
    ///
    /// Fields are trimmed (spaces, a trailing `\r` from CRLF files). The line must have exactly
    /// as many fields as the header. `t`, `ax`, `ay` and `az` must parse as finite `f32`;
    /// the transaction counts (`fault_nack`, `fault_timeout`, `fault_garbage`) must be integers
    /// 0..=255 and the flags (`fault_stuck`, `fault_drop`, `fault_reset`) 0 or 1 (`2.0`-style
    /// integral floats are accepted for all, as are empty fault fields, meaning no fault).
    /// Ignored columns are not looked at.
    pub fn parse_line(&self, line: &str) -> Result<FeedSample, CsvError> {
        self.parse_record(line).map(|(_, sample)| sample)
    }

    /// Like [`parse_line`](Self::parse_line), also returning the `t` column (s).
    pub fn parse_record(&self, line: &str) -> Result<(f32, FeedSample), CsvError> {
        let mut t = None;
        let mut accel = [None; 3];
        let mut sample = FeedSample::default();
        let mut seen: u8 = 0;
        for (index, field) in fields(line).enumerate() {
            let column = u8::try_from(index).unwrap_or(u8::MAX);
            if column >= self.count {
                return Err(CsvError::BadField { column });
            }
            seen = column.saturating_add(1);
            let field = field.trim();
            let bad = CsvError::BadField { column };
            match self.role(column) {
                Role::Time => t = Some(parse_finite(field).ok_or(bad)?),
                Role::Accel(axis) => {
                    if let Some(slot) = accel.get_mut(axis) {
                        *slot = Some(parse_finite(field).ok_or(bad)?);
                    }
                }
                Role::Fault(fault) => fault.apply(field, &mut sample).ok_or(bad)?,
                Role::Ignored => {}
            }
        }
        if seen < self.count {
            return Err(CsvError::BadField { column: seen });
        }
        let t = t.ok_or(CsvError::BadField { column: 0 })?;
        for ((slot, value), column) in sample.accel.iter_mut().zip(accel).zip(self.accel) {
            *slot = value.ok_or(CsvError::BadField { column })?;
        }
        Ok((t, sample))
    }
}

/// A finite `f32`, or `None`.
fn parse_finite(field: &str) -> Option<f32> {
    parse_f32(field).filter(|v| v.is_finite())
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
