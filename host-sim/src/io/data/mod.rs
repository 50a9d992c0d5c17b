//! The data contract: how every CSV that a user gives to, or gets from, `edgekf` looks.
//!
//! * a header row, fields separated by commas (surrounding spaces are trimmed; blank lines and
//!   lines starting with `#` are skipped);
//! * column names are unique and plain: no comma, double quote or line break, even quoted;
//! * first column `t`, the time in seconds. Uniform sampling is expected, but gaps and jitter
//!   are measured and reported ([`TimingReport`]), not hidden;
//! * then named channels in SI units (`ax` in m/s², …);
//! * ground truth, when a simulator knows it, in columns prefixed `truth_` (`truth_x`, …);
//! * columns the reader does not know are dropped and listed in [`DataReport::ignored_columns`];
//! * an empty or `NaN` cell in a channel is kept as NaN (a missing sample) and counted in
//!   [`DataReport::nan_cells`]; it is never dropped silently.
//!
//! A file that breaks the contract is refused with a [`DataError`] naming the file and the line.
//! Numbers are written in the shortest form that reads back to the same `f64`, so a file written
//! by [`write()`] and read by [`read()`] gives back identical bits.
//!
//! ```
//! use edgekf_sim::io::data::read_from;
//! use std::path::Path;
//! let csv = "t,ax,truth_x,comment\n0.000,0.5,1e-3,a\n0.001,,2e-3,b\n0.002,0.7,3e-3,c\n";
//! let (data, report) = read_from(csv.as_bytes(), Path::new("example.csv"), &["ax"]).unwrap();
//! assert_eq!(data.names, ["ax", "truth_x"]);
//! assert!(data.column("ax").unwrap()[1].is_nan());
//! assert_eq!(report.ignored_columns, ["comment"]);
//! assert_eq!(report.nan_cells, [("ax".to_string(), 1)]);
//! assert!((report.timing.sample_rate - 1000.0).abs() < 1e-6);
//! ```

mod error;
mod timing;

pub use error::DataError;
pub use timing::{Gap, TimingReport, GAP_FACTOR, UNIFORM_JITTER};

use edgekf::csv_header::Header;
use std::fmt::{self, Write as _};
use std::io::Read;
use std::path::Path;

/// Prefix of the ground-truth columns written by simulators.
pub const TRUTH_PREFIX: &str = "truth_";

/// A data file in memory: the time column and the kept channels, column by column.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DataFile {
    /// Channel names, in file order, without `t`.
    pub names: Vec<String>,
    /// Time of each row, s (strictly increasing).
    pub t: Vec<f64>,
    /// One vector per name, each as long as `t`; NaN marks a missing value.
    pub columns: Vec<Vec<f64>>,
    /// SHA-256 of the bytes it was read from, lower-case hex: which recording a report or a
    /// baseline was made from, taken in the one read (`None` for data made in memory).
    pub sha256: Option<String>,
}

impl DataFile {
    /// Reads a data file; the same as [`read()`].
    pub fn read(path: &Path, known: &[&str]) -> Result<(DataFile, DataReport), DataError> {
        read(path, known)
    }

    /// The channel called `name`, if the file has it.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names.iter().position(|n| n == name).map(|i| self.columns[i].as_slice())
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Regularity of the time column.
    pub fn timing(&self) -> TimingReport {
        TimingReport::of(&self.t)
    }

    /// The file as CSV text, in the contract's format.
    pub fn to_csv_string(&self) -> Result<String, DataError> {
        let names: Vec<&str> = self.names.iter().map(String::as_str).collect();
        let cols: Vec<&[f64]> = self.columns.iter().map(Vec::as_slice).collect();
        to_csv_string(Path::new("<memory>"), &names, &self.t, &cols)
    }
}

/// What the reader noticed about a file that it accepted.
#[derive(Debug, Clone, PartialEq)]
pub struct DataReport {
    /// Data rows read.
    pub rows: usize,
    /// Columns dropped because the caller does not know them (and they are not `truth_`).
    pub ignored_columns: Vec<String>,
    /// Kept columns with empty or NaN cells, and how many (only columns with at least one).
    pub nan_cells: Vec<(String, usize)>,
    /// Where those cells lie: each such column's runs of consecutive missing cells, as the
    /// times of a run's first and last cell, s (a burst of NaN is a time range, not a count).
    pub nan_runs: Vec<(String, Vec<[f64; 2]>)>,
    /// Regularity of the time column.
    pub timing: TimingReport,
    /// The line number of the last row when the file does not end with a newline: a file
    /// still being written, or cut in transfer, may have lost part of that row.
    pub unterminated_last_line: Option<u64>,
}

impl DataReport {
    /// One human-readable line per thing a user should know: ignored columns, missing values,
    /// gaps and jitter. Empty for a clean, uniformly sampled file.
    pub fn notices(&self) -> Vec<String> {
        let mut out = Vec::new();
        for name in &self.ignored_columns {
            out.push(format!("ignored column `{name}`: not a channel this command uses"));
        }
        for (name, n) in &self.nan_cells {
            let runs = self.nan_runs.iter().find(|(c, _)| c == name).map_or(&[][..], |(_, r)| r.as_slice());
            out.push(format!(
                "column `{name}`: {n} empty/NaN cell(s) of {} ({:.2} %){}, treated as missing samples",
                self.rows,
                100.0 * *n as f64 / self.rows as f64,
                describe_runs(runs)
            ));
        }
        out.extend(self.timing.notices());
        if let Some(line) = self.unterminated_last_line {
            out.push(format!("the last line ({line}) has no newline: the file may have been cut there"));
        }
        out
    }
}

impl fmt::Display for DataReport {
    /// A summary line followed by the notices, one per line.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} rows, {}", self.rows, self.timing)?;
        for n in self.notices() {
            write!(f, "\nnotice: {n}")?;
        }
        Ok(())
    }
}

/// The runs of consecutive NaN in `column`, as `[t of the first, t of the last]`.
fn missing_runs(t: &[f64], column: &[f64]) -> Vec<[f64; 2]> {
    let mut runs: Vec<[f64; 2]> = Vec::new();
    let mut open = false;
    for (&tk, v) in t.iter().zip(column) {
        match (v.is_nan(), open, runs.last_mut()) {
            (true, true, Some(run)) => run[1] = tk,
            (true, _, _) => runs.push([tk, tk]),
            _ => {}
        }
        open = v.is_nan();
    }
    runs
}

/// ` in 1 run (1.200–1.350 s)` or ` in 37 runs, the longest 0.150 s from 1.200 s; the first
/// 0.001 s, 2.5–2.6 s, 4.000 s`: where the missing cells are, for a notice.
fn describe_runs(runs: &[[f64; 2]]) -> String {
    let span = |[a, b]: [f64; 2]| if a == b { format!("{a:.3} s") } else { format!("{a:.3}–{b:.3} s") };
    match runs {
        [] => String::new(),
        [one] => format!(" in 1 run ({})", span(*one)),
        _ => {
            let longest =
                runs.iter().max_by(|x, y| (x[1] - x[0]).total_cmp(&(y[1] - y[0]))).copied().unwrap_or_default();
            let first: Vec<String> = runs.iter().take(3).map(|r| span(*r)).collect();
            let more = if runs.len() > 3 { ", …" } else { "" };
            format!(
                " in {} runs, the longest {:.3} s from {:.3} s; the first {}{more}",
                runs.len(),
                longest[1] - longest[0],
                longest[0],
                first.join(", ")
            )
        }
    }
}

/// Reads a data file. `known` lists the channels the caller understands; `truth_` columns are
/// always kept, anything else is dropped and reported.
pub fn read(path: &Path, known: &[&str]) -> Result<(DataFile, DataReport), DataError> {
    read_required(path, &[], known)
}

/// Like [`read`], and the header must hold every channel of `required` (kept like `known`):
/// a missing one is refused with the header's line rather than found missing later.
///
/// ```
/// use edgekf_sim::io::data::read_required;
/// use std::path::Path;
/// let dir = std::env::temp_dir().join(format!("edgekf-doc-req-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let path = dir.join("r.csv");
/// std::fs::write(&path, "# probes\nt,n5_x\n0,1\n0.001,2\n").unwrap();
/// let e = read_required(&path, &["n5_x", "n5_y"], &[]).unwrap_err();
/// assert_eq!(e.to_string(), format!("{}:2: no column `n5_y`", path.display()));
/// assert!(read_required(&path, &["n5_x"], &[]).is_ok());
/// # std::fs::remove_dir_all(&dir).ok();
/// ```
pub fn read_required(path: &Path, required: &[&str], known: &[&str]) -> Result<(DataFile, DataReport), DataError> {
    let file = std::fs::File::open(path).map_err(|reason| DataError::Io { path: path.to_owned(), reason })?;
    read_from_required(std::io::BufReader::new(file), path, required, known)
}

/// Like [`read`], from any reader; `path` is only used in messages.
pub fn read_from<R: Read>(reader: R, path: &Path, known: &[&str]) -> Result<(DataFile, DataReport), DataError> {
    read_from_required(reader, path, &[], known)
}

/// Like [`read_required`], from any reader; `path` is only used in messages.
pub fn read_from_required<R: Read>(
    mut reader: R,
    path: &Path,
    required: &[&str],
    known: &[&str],
) -> Result<(DataFile, DataReport), DataError> {
    // Read whole, so that line numbers can be counted from the bytes (see `LineIndex`).
    let mut bytes = Vec::new();
    reader.read_to_end(&mut bytes).map_err(|reason| DataError::Io { path: path.to_owned(), reason })?;
    let lines = LineIndex::new(&bytes);
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(bytes.as_slice());
    let csv_err = |e: csv::Error| {
        let line = e.position().map_or(0, |p| lines.line_of(p.byte()));
        let message = e.to_string();
        match e.into_kind() {
            csv::ErrorKind::Io(reason) => DataError::Io { path: path.to_owned(), reason },
            _ => DataError::Csv { path: path.to_owned(), line, message },
        }
    };

    let mut records = rdr.records();
    let header = match records.next() {
        None => return Err(DataError::Empty { path: path.to_owned() }),
        Some(r) => r.map_err(csv_err)?,
    };
    let header_line = header.position().map_or(1, |p| lines.line_of(p.byte()));
    let layout = Layout::from_header(&header, header_line, path, required, known)?;

    let mut data = DataFile {
        sha256: Some(hex_sha256(&bytes)),
        names: layout.kept.iter().map(|(_, n)| n.clone()).collect(),
        t: Vec::new(),
        columns: vec![Vec::new(); layout.kept.len()],
    };
    let mut nan_counts = vec![0usize; layout.kept.len()];
    let mut last_line = header_line;
    for record in records {
        let record = record.map_err(csv_err)?;
        let line = record.position().map_or(0, |p| lines.line_of(p.byte()));
        last_line = line;
        if record.len() != layout.width {
            return Err(DataError::Ragged { path: path.to_owned(), line, expected: layout.width, found: record.len() });
        }
        let bad = |column: &str, text: &str| DataError::BadNumber {
            path: path.to_owned(),
            line,
            column: column.to_owned(),
            text: text.to_owned(),
        };
        let t_text = &record[0];
        let t = t_text.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| bad("t", t_text))?;
        if let Some(&previous) = data.t.last() {
            if t <= previous {
                return Err(DataError::NonIncreasingTime { path: path.to_owned(), line, t, previous });
            }
        }
        data.t.push(t);
        for (k, (col, name)) in layout.kept.iter().enumerate() {
            let text = &record[*col];
            let v = parse_cell(text).ok_or_else(|| bad(name, text))?;
            if v.is_nan() {
                nan_counts[k] += 1;
            }
            data.columns[k].push(v);
        }
    }
    if data.t.len() < 2 {
        return Err(DataError::TooFewRows { path: path.to_owned(), rows: data.t.len() });
    }
    let report = DataReport {
        rows: data.t.len(),
        ignored_columns: layout.ignored,
        nan_runs: nan_counts
            .iter()
            .zip(data.names.iter().zip(&data.columns))
            .filter(|(n, _)| **n > 0)
            .map(|(_, (name, column))| (name.clone(), missing_runs(&data.t, column)))
            .collect(),
        nan_cells: data.names.iter().cloned().zip(nan_counts).filter(|(_, n)| *n > 0).collect(),
        timing: data.timing(),
        unterminated_last_line: (!bytes.ends_with(b"\n")).then_some(last_line),
    };
    Ok((data, report))
}

/// Line numbers of records, from the csv reader's byte positions.
///
/// The csv crate positions a record where the previous one ended (before the line terminator's
/// `\n` with CRLF, and before the blank and comment lines it skips), and its own line count leaves
/// those lines out. This index skips them the same way and counts every line, so messages point
/// at the line an editor shows.
struct LineIndex<'a> {
    bytes: &'a [u8],
    /// Byte offset of every `\n`.
    newlines: Vec<usize>,
}

impl<'a> LineIndex<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, newlines: bytes.iter().enumerate().filter(|(_, &b)| b == b'\n').map(|(i, _)| i).collect() }
    }

    /// 1-based line of the record positioned at `byte`.
    fn line_of(&self, byte: u64) -> u64 {
        let bytes = self.bytes;
        let mut b = usize::try_from(byte).unwrap_or(usize::MAX).min(bytes.len());
        loop {
            while b < bytes.len() && matches!(bytes[b], b'\n' | b'\r') {
                b += 1;
            }
            let line_start = b == 0 || matches!(bytes[b - 1], b'\n' | b'\r');
            if b < bytes.len() && bytes[b] == b'#' && line_start {
                while b < bytes.len() && bytes[b] != b'\n' {
                    b += 1;
                }
                continue;
            }
            break;
        }
        self.newlines.partition_point(|&nl| nl < b) as u64 + 1
    }
}

/// Which columns of a file are kept, from its header.
struct Layout {
    width: usize,
    /// (column index, name) of each kept channel.
    kept: Vec<(usize, String)>,
    ignored: Vec<String>,
}

impl Layout {
    /// The header checked by the contract's rules ([`edgekf::csv_header`], shared with the
    /// node), then split into kept (`required`, `known`, `truth_`) and ignored columns.
    fn from_header(
        header: &csv::StringRecord,
        line: u64,
        path: &Path,
        required: &[&str],
        known: &[&str],
    ) -> Result<Self, DataError> {
        let refused = |error| DataError::Header { path: path.to_owned(), line, error };
        let checked = Header::parse(header.iter(), usize::MAX).map_err(refused)?;
        for name in required {
            checked.find(name).map_err(refused)?;
        }
        let (mut kept, mut ignored) = (Vec::new(), Vec::new());
        if let Some(name) = checked.names().find(|n| !plain_name(n)) {
            return Err(DataError::BadColumnName { path: path.to_owned(), line, name: name.to_owned() });
        }
        for (i, name) in checked.names().enumerate().skip(1) {
            if required.contains(&name) || known.contains(&name) || name.starts_with(TRUTH_PREFIX) {
                kept.push((i, name.to_owned()));
            } else {
                ignored.push(name.to_owned());
            }
        }
        Ok(Self { width: checked.width(), kept, ignored })
    }
}

/// Whether a column name is written as it is: no comma, double quote or line break (a
/// quoted header cell may hold them, but the writer does not quote).
fn plain_name(name: &str) -> bool {
    !name.contains([',', '"', '\r', '\n'])
}

/// A channel cell: a finite number, or NaN for an empty / `NaN` cell. Infinity is refused: no
/// sensor reads it, so it is a corrupted file rather than a missing sample.
fn parse_cell(text: &str) -> Option<f64> {
    if text.is_empty() || text.eq_ignore_ascii_case("nan") {
        return Some(f64::NAN);
    }
    text.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// Formats a value so that it reads back to the same bits: integers without a decimal point
/// (`0`, `3`: counters and flags stay integers), everything else in Rust's shortest round-trip
/// form (`0.001`, `4.2e-7`), NaN as `NaN`.
pub fn format_value(v: f64) -> String {
    let mut s = String::new();
    push_value(&mut s, v);
    s
}

fn push_value(out: &mut String, v: f64) {
    // Writing to a String cannot fail.
    let _ = if v.fract() == 0.0 && v.abs() < 1e15 { write!(out, "{v}") } else { write!(out, "{v:?}") };
}

/// The CSV text of a data file: header `t,names…`, then one row per time. `path` is only used
/// in the errors: a column's length differs from `t`'s, or a name holds a comma, double quote
/// or line break (it would not read back).
pub fn to_csv_string(path: &Path, names: &[&str], t: &[f64], columns: &[&[f64]]) -> Result<String, DataError> {
    csv_text(path, names, t, columns, false)
}

/// The same text with missing values (NaN) as empty cells: for channels slower than the file's
/// rate, which have no value between their readings (a 5 Hz DVL in a 50 Hz file).
///
/// ```
/// use edgekf_sim::io::data::to_csv_string_sparse;
/// let text = to_csv_string_sparse("x.csv".as_ref(), &["dvl_u"], &[0.0, 0.02], &[&[1.5, f64::NAN]]).unwrap();
/// assert_eq!(text, "t,dvl_u\n0,1.5\n0.02,\n");
/// ```
pub fn to_csv_string_sparse(path: &Path, names: &[&str], t: &[f64], columns: &[&[f64]]) -> Result<String, DataError> {
    csv_text(path, names, t, columns, true)
}

fn csv_text(path: &Path, names: &[&str], t: &[f64], columns: &[&[f64]], empty: bool) -> Result<String, DataError> {
    if names.len() != columns.len() {
        return Err(DataError::LengthMismatch {
            path: path.to_owned(),
            name: format!("<{} names for {} columns>", names.len(), columns.len()),
            len: columns.len(),
            expected: names.len(),
        });
    }
    for (name, col) in names.iter().zip(columns) {
        if col.len() != t.len() {
            return Err(DataError::LengthMismatch {
                path: path.to_owned(),
                name: (*name).to_owned(),
                len: col.len(),
                expected: t.len(),
            });
        }
    }
    if let Some(name) = names.iter().find(|n| !plain_name(n)) {
        return Err(DataError::BadColumnName { path: path.to_owned(), line: 1, name: (*name).to_owned() });
    }
    let mut out = String::with_capacity(t.len() * 12 * (names.len() + 1));
    out.push('t');
    for n in names {
        out.push(',');
        out.push_str(n);
    }
    out.push('\n');
    for (k, &tk) in t.iter().enumerate() {
        push_value(&mut out, tk);
        for col in columns {
            out.push(',');
            if !(empty && col[k].is_nan()) {
                push_value(&mut out, col[k]);
            }
        }
        out.push('\n');
    }
    Ok(out)
}

/// Writes a data file (see [`to_csv_string`]).
///
/// ```
/// use edgekf_sim::io::data::{read, write};
/// let dir = std::env::temp_dir().join(format!("edgekf-doc-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let path = dir.join("w.csv");
/// let t = [0.0, 0.001, 0.002];
/// let ax = [0.1, f64::NAN, 1.0 / 3.0];
/// write(&path, &["ax"], &t, &[&ax]).unwrap();
/// let (back, _) = read(&path, &["ax"]).unwrap();
/// assert_eq!(back.column("ax").unwrap()[2], 1.0 / 3.0); // bit-exact
/// # std::fs::remove_dir_all(&dir).ok();
/// ```
pub fn write(path: &Path, names: &[&str], t: &[f64], columns: &[&[f64]]) -> Result<(), DataError> {
    let text = to_csv_string(path, names, t, columns)?;
    crate::io::output::write_atomic(path, text).map_err(|reason| DataError::Write { path: path.to_owned(), reason })
}

#[cfg(test)]
mod tests;

/// SHA-256 of `bytes`, lower-case hex.
///
/// ```
/// assert_eq!(
///     edgekf_sim::io::data::hex_sha256(b"abc"),
///     "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
/// );
/// ```
pub fn hex_sha256(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}
