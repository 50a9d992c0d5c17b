//! Why a data file was refused.
//!
//! Each variant names the file and, where there is one, the line (1-based, as an editor shows
//! it), so a user can go straight to the problem.

use std::path::PathBuf;

/// A data file that does not follow the data contract (see [`crate::io::data`]).
#[derive(Debug, thiserror::Error)]
pub enum DataError {
    /// The file could not be opened or read.
    #[error("{}: cannot read: {reason}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said (in the message, not a second link of the chain).
        reason: std::io::Error,
    },
    /// The file could not be written.
    #[error("{}: cannot write: {reason}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// What the operating system said (in the message, not a second link of the chain).
        reason: std::io::Error,
    },
    /// The CSV itself is malformed (e.g. not UTF-8, unbalanced quotes).
    #[error("{}:{line}: malformed CSV: {message}", path.display())]
    Csv {
        /// The file.
        path: PathBuf,
        /// Line of the problem (0 when unknown).
        line: u64,
        /// What the CSV parser said.
        message: String,
    },
    /// The file has no header row.
    #[error("{}: empty file: expected a header row starting with `t`", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// The header breaks the contract's header rules ([`edgekf::csv_header`], the same rules
    /// the node applies): `t` first, no empty or repeated names, every required channel there.
    #[error("{}:{line}: {error}", path.display())]
    Header {
        /// The file.
        path: PathBuf,
        /// Line of the header.
        line: u64,
        /// Which rule.
        error: edgekf::csv_header::HeaderError,
    },
    /// A column name holds a comma, a double quote or a line break (possible in a quoted
    /// header cell): the contract's writer could not write it back.
    #[error("{}:{line}: column name {name:?} holds a comma, quote or line break", path.display())]
    BadColumnName {
        /// The file.
        path: PathBuf,
        /// Line of the header.
        line: u64,
        /// The name.
        name: String,
    },
    /// A row has a different number of fields than the header.
    #[error("{}:{line}: {found} field(s), but the header has {expected}", path.display())]
    Ragged {
        /// The file.
        path: PathBuf,
        /// Line of the row.
        line: u64,
        /// Fields in the header.
        expected: usize,
        /// Fields in the row.
        found: usize,
    },
    /// A cell is not a number (empty and `NaN` cells are allowed in channels, not in `t`).
    #[error("{}:{line}: column `{column}`: `{text}` is not a finite number", path.display())]
    BadNumber {
        /// The file.
        path: PathBuf,
        /// Line of the row.
        line: u64,
        /// Column name.
        column: String,
        /// The cell as written.
        text: String,
    },
    /// The time column does not strictly increase.
    #[error("{}:{line}: time does not increase: t = {t} s after t = {previous} s", path.display())]
    NonIncreasingTime {
        /// The file.
        path: PathBuf,
        /// Line of the row.
        line: u64,
        /// Its time.
        t: f64,
        /// Time of the row before.
        previous: f64,
    },
    /// Fewer than two data rows: no sample rate can be measured.
    #[error("{}: {rows} data row(s); at least 2 are needed", path.display())]
    TooFewRows {
        /// The file.
        path: PathBuf,
        /// Rows found.
        rows: usize,
    },
    /// Columns given to the writer do not match the time column.
    #[error("{}: column `{name}` has {len} values but `t` has {expected}", path.display())]
    LengthMismatch {
        /// The file.
        path: PathBuf,
        /// Column name.
        name: String,
        /// Its length.
        len: usize,
        /// Length of `t`.
        expected: usize,
    },
}
