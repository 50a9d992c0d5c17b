//! CSV text from a byte stream, read in small chunks: [`LineReader`] assembles lines in a
//! fixed buffer, [`LineFeed`] turns them into samples for the virtual ADXL355, and
//! [`ChannelReader`] picks named `f32` channels (for sensors that are not an ADXL355, e.g. the
//! rotor's proximity probes).
//!
//! Under QEMU the stream is a host file read through semihosting; on the host it is a byte
//! slice. No allocation; a line longer than the buffer, or one that does not parse, is skipped
//! and counted, never silently lost.

use crate::virtual_adxl355::{CsvColumns, CsvError, FeedSample, SampleFeed};
use edgekf::csv_header::{fields, Header};
use edgekf::decimal::{parse_f32, parse_f64};

/// Anything that yields bytes in chunks.
pub trait ByteSource {
    /// Fills `buf` with up to `buf.len()` bytes; returns how many, 0 at the end.
    fn read_bytes(&mut self, buf: &mut [u8]) -> usize;
}

impl ByteSource for &[u8] {
    fn read_bytes(&mut self, buf: &mut [u8]) -> usize {
        let n = buf.len().min(self.len());
        buf[..n].copy_from_slice(&self[..n]);
        *self = &self[n..];
        n
    }
}

/// Longest CSV line a [`LineFeed`] accepts, bytes (`t, ax, ay, az` and a few more columns).
pub const MAX_LINE: usize = 256;
/// Longest CSV line a [`ChannelReader`] accepts, bytes (a rotor file with every node's truth
/// has about 90 columns).
pub const MAX_WIDE_LINE: usize = 4096;

/// Lines of a byte stream, one at a time, in a fixed buffer of `L` bytes.
///
/// ```
/// use edgekf_firmware::line_feed::LineReader;
/// let mut r = LineReader::<_, 16>::new(&b"a,b\r\n1,2\n"[..]);
/// assert_eq!(r.next_line(), Some(Ok("a,b")));
/// assert_eq!(r.next_line(), Some(Ok("1,2")));
/// assert_eq!(r.next_line(), None);
/// ```
pub struct LineReader<S: ByteSource, const L: usize> {
    source: S,
    chunk: [u8; 64],
    chunk_len: usize,
    chunk_pos: usize,
    line: [u8; L],
    eof: bool,
}

/// A line that could not be used: longer than the buffer or not UTF-8.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BadLine;

impl<S: ByteSource, const L: usize> LineReader<S, L> {
    /// Reads from `source`.
    pub fn new(source: S) -> Self {
        Self { source, chunk: [0; 64], chunk_len: 0, chunk_pos: 0, line: [0; L], eof: false }
    }

    fn next_byte(&mut self) -> Option<u8> {
        if self.chunk_pos == self.chunk_len {
            if self.eof {
                return None;
            }
            // A source that claims more than the chunk holds is clamped to it.
            self.chunk_len = self.source.read_bytes(&mut self.chunk).min(self.chunk.len());
            self.chunk_pos = 0;
            if self.chunk_len == 0 {
                self.eof = true;
                return None;
            }
        }
        let b = *self.chunk.get(self.chunk_pos)?;
        self.chunk_pos += 1;
        Some(b)
    }

    /// The next line without its end (`\n` or `\r\n`); `None` at the end of the stream.
    pub fn next_line(&mut self) -> Option<Result<&str, BadLine>> {
        let mut len = 0usize;
        let mut overflow = false;
        let mut any = false;
        while let Some(b) = self.next_byte() {
            any = true;
            if b == b'\n' {
                break;
            }
            if len < L {
                self.line[len] = b;
                len += 1;
            } else {
                overflow = true;
            }
        }
        if !any {
            return None;
        }
        if overflow {
            return Some(Err(BadLine));
        }
        let Some(bytes) = self.line.get(..len) else { return Some(Err(BadLine)) };
        let text = core::str::from_utf8(bytes).map_err(|_| BadLine);
        Some(text.map(|t| t.strip_suffix('\r').unwrap_or(t)))
    }
}

/// CSV text → [`FeedSample`]s, with the header checked first.
///
/// ```
/// use edgekf_firmware::line_feed::LineFeed;
/// use edgekf_firmware::virtual_adxl355::SampleFeed;
/// let text = b"t,ax,ay,az,truth_x\n0,1.5,0,9.8,0.1\n0.001,oops,0,0,0\n0.002,2,0,0,0\n";
/// let mut feed = LineFeed::new(&text[..]).unwrap();
/// assert_eq!(feed.next_sample().unwrap().accel[0], 1.5);
/// assert_eq!(feed.next_sample().unwrap().accel[0], 2.0);
/// assert!(feed.next_sample().is_none());
/// assert_eq!(feed.bad_lines(), 1);
/// ```
pub struct LineFeed<S: ByteSource> {
    reader: LineReader<S, MAX_LINE>,
    columns: CsvColumns,
    bad_lines: u32,
    lines: u32,
}

/// Why a [`LineFeed`] or [`ChannelReader`] could not start.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FeedError {
    /// The stream was empty.
    Empty,
    /// The header line was longer than [`MAX_LINE`] or not UTF-8.
    BadHeader,
    /// The header breaks the header rules or lacks a required column.
    Columns(CsvError),
}

impl<S: ByteSource> LineFeed<S> {
    /// Reads and checks the header line.
    pub fn new(source: S) -> Result<Self, FeedError> {
        let mut reader = LineReader::new(source);
        let columns = match reader.next_line() {
            None => return Err(FeedError::Empty),
            Some(Err(BadLine)) => return Err(FeedError::BadHeader),
            Some(Ok(header)) => CsvColumns::from_header(header).map_err(FeedError::Columns)?,
        };
        Ok(Self { reader, columns, bad_lines: 0, lines: 0 })
    }

    /// Data lines skipped because they did not parse or were too long.
    pub fn bad_lines(&self) -> u32 {
        self.bad_lines
    }

    /// Data lines read (good and bad).
    pub fn lines(&self) -> u32 {
        self.lines
    }

    /// Columns found in the header.
    pub fn columns(&self) -> &CsvColumns {
        &self.columns
    }
}

impl<S: ByteSource> SampleFeed for LineFeed<S> {
    fn next_sample(&mut self) -> Option<FeedSample> {
        loop {
            let parsed = match self.reader.next_line()? {
                Ok(text) if text.trim().is_empty() => continue, // blank line (e.g. a trailing one)
                Ok(text) => self.columns.parse_line(text).ok(),
                Err(BadLine) => None,
            };
            self.lines = self.lines.saturating_add(1);
            match parsed {
                Some(sample) => return Some(sample),
                None => self.bad_lines += 1,
            }
        }
    }
}

/// A line of named channels and its `t`, as [`ChannelReader::next_timed`] reads it: `t` if it
/// is a finite number, the values or why not.
pub type TimedLine<const M: usize> = (Option<f64>, Result<[f32; M], BadLine>);

/// Most columns a [`ChannelReader`] header may have.
pub const MAX_COLUMNS: usize = 128;

/// Named `f32` channels from CSV text: the header is searched for `names`, other columns are
/// ignored (and counted); each data line yields the `M` values in the order of `names`.
///
/// ```
/// use edgekf_firmware::line_feed::ChannelReader;
/// let text = b"t,n5_x,truth_n5_x,n32_x\n0,1e-6,0,2e-6\n0.001,bad,0,1\n";
/// let mut r = ChannelReader::new(&text[..], ["n32_x", "n5_x"]).unwrap();
/// assert_eq!(r.next_values(), Some(Ok([2e-6, 1e-6])));
/// assert!(r.next_values().unwrap().is_err());
/// assert_eq!(r.ignored_columns(), 2);
/// ```
pub struct ChannelReader<S: ByteSource, const M: usize> {
    reader: LineReader<S, MAX_WIDE_LINE>,
    index: [u8; M],
    width: usize,
    ignored: usize,
    bad_lines: u32,
    empty_cells: bool,
}

impl<S: ByteSource, const M: usize> ChannelReader<S, M> {
    /// Reads the header and locates `names` in it, by the shared header rules
    /// ([`edgekf::csv_header`]: `t` first, no repeated names, at most [`MAX_COLUMNS`] columns).
    pub fn new(source: S, names: [&'static str; M]) -> Result<Self, FeedError> {
        let mut reader = LineReader::new(source);
        let (index, width) = match reader.next_line() {
            None => return Err(FeedError::Empty),
            Some(Err(BadLine)) => return Err(FeedError::BadHeader),
            Some(Ok(line)) => {
                let columns = |e| FeedError::Columns(CsvError::Header(e));
                let header = Header::parse(fields(line), MAX_COLUMNS).map_err(columns)?;
                // Indices are below MAX_COLUMNS (128): they fit a u8.
                let index = header.find_all(names).map_err(columns)?.map(|i| u8::try_from(i).unwrap_or(u8::MAX));
                (index, header.width())
            }
        };
        Ok(Self { reader, index, width, ignored: width.saturating_sub(M), bad_lines: 0, empty_cells: false })
    }

    /// Reads an empty or `NaN` cell as a missing value (NaN) instead of a bad line: for files
    /// whose channels have their own rates (a 5 Hz DVL in 50 Hz rows, empty between its
    /// readings) and estimators that update with each channel group on its own. Garbage and
    /// infinities are still bad lines.
    ///
    /// ```
    /// use edgekf_firmware::line_feed::ChannelReader;
    /// let text = b"t,a,b\n0,1.5,\n0.02,x,2\n0.04,NaN,2\n";
    /// let mut r = ChannelReader::new(&text[..], ["a", "b"]).unwrap().with_empty_cells();
    /// let first = r.next_values().unwrap().unwrap();
    /// assert!(first[0] == 1.5 && first[1].is_nan());
    /// assert!(r.next_values().unwrap().is_err());
    /// assert!(r.next_values().unwrap().unwrap()[0].is_nan());
    /// ```
    pub fn with_empty_cells(self) -> Self {
        Self { empty_cells: true, ..self }
    }

    /// The next line's values; `Err` for a line that does not parse (counted), `None` at the end.
    pub fn next_values(&mut self) -> Option<Result<[f32; M], BadLine>> {
        self.next_line_values(false).map(|(_, values)| values)
    }

    /// Like [`next_values`](Self::next_values), also returning the line's `t` (the first
    /// column, parsed as `f64` so that sample times keep their spacing in long recordings) when
    /// it reads as a finite number, whether or not the channels do: a line whose values are bad
    /// still says when it was.
    ///
    /// ```
    /// use edgekf_firmware::line_feed::ChannelReader;
    /// let text = b"t,a\n0.001,1.5\n0.002,x\nnope,2\n";
    /// let mut r = ChannelReader::new(&text[..], ["a"]).unwrap();
    /// assert_eq!(r.next_timed(), Some((Some(0.001), Ok([1.5]))));
    /// assert!(matches!(r.next_timed(), Some((Some(t), Err(_))) if t == 0.002));
    /// assert_eq!(r.next_timed(), Some((None, Ok([2.0]))));
    /// ```
    pub fn next_timed(&mut self) -> Option<TimedLine<M>> {
        self.next_line_values(true)
    }

    fn next_line_values(&mut self, timed: bool) -> Option<TimedLine<M>> {
        loop {
            let line = match self.reader.next_line()? {
                Ok(text) if text.trim().is_empty() => continue,
                Ok(text) => text,
                Err(BadLine) => {
                    self.bad_lines = self.bad_lines.saturating_add(1);
                    return Some((None, Err(BadLine)));
                }
            };
            let mut t = None;
            let mut values = [f32::NAN; M];
            let mut width = 0;
            let mut bad = false;
            for (i, field) in fields(line).enumerate() {
                width = i + 1;
                if timed && i == 0 {
                    t = parse_f64(field.trim()).filter(|v| v.is_finite());
                }
                if bad {
                    continue;
                }
                if let Some(k) = self.index.iter().position(|&c| usize::from(c) == i) {
                    let cell = field.trim();
                    if self.empty_cells && (cell.is_empty() || cell.eq_ignore_ascii_case("nan")) {
                        continue; // stays NaN: no reading in this row
                    }
                    match (parse_f32(cell), values.get_mut(k)) {
                        (Some(v), Some(slot)) if v.is_finite() => *slot = v,
                        _ => bad = true,
                    }
                }
            }
            if bad || width != self.width {
                self.bad_lines = self.bad_lines.saturating_add(1);
                return Some((t, Err(BadLine)));
            }
            return Some((t, Ok(values)));
        }
    }

    /// Header columns not among the requested channels.
    pub fn ignored_columns(&self) -> usize {
        self.ignored
    }

    /// Lines that did not parse.
    pub fn bad_lines(&self) -> u32 {
        self.bad_lines
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use edgekf::csv_header::{ColumnName, HeaderError};

    fn channels(text: &str) -> Result<ChannelReader<&[u8], 2>, FeedError> {
        ChannelReader::new(text.as_bytes(), ["n5_x", "n32_x"])
    }

    fn refused(e: HeaderError) -> Option<FeedError> {
        Some(FeedError::Columns(CsvError::Header(e)))
    }

    #[test]
    fn channel_headers_follow_the_shared_rules() {
        // A BOM before `t`, spaces around names.
        let mut r = channels("\u{feff}t, n32_x ,truth_n5_x,n5_x\r\n0,2,9,1\r\n").unwrap();
        assert_eq!(r.next_values(), Some(Ok([1.0, 2.0])));
        assert_eq!(r.ignored_columns(), 2);
        let name = ColumnName::new;
        // A repeated channel used to be read from its last column; now it is refused, naming both.
        assert_eq!(
            channels("t,n5_x,n32_x,n5_x\n0,1,2,3\n").err(),
            refused(HeaderError::Duplicate { name: name("n5_x"), first: 2, second: 4 })
        );
        assert_eq!(channels("t,n5_x\n0,1\n").err(), refused(HeaderError::MissingChannel { name: name("n32_x") }));
        assert_eq!(
            channels("n5_x,n32_x,t\n1,2,0\n").err(),
            refused(HeaderError::FirstColumnNotTime { found: name("n5_x") })
        );
        assert_eq!(channels("").err(), Some(FeedError::Empty));
        let wide: std::string::String = (0..MAX_COLUMNS).map(|i| std::format!(",c{i}")).collect();
        assert_eq!(
            channels(&(std::string::String::from("t,n5_x,n32_x") + &wide)).err(),
            refused(HeaderError::TooManyColumns { max: MAX_COLUMNS })
        );
    }

    #[test]
    fn the_adxl_feed_refuses_a_repeated_axis() {
        let e = LineFeed::new(&b"t,ax,ay,az,az\n0,1,2,3,4\n"[..]).err();
        let dup = HeaderError::Duplicate { name: ColumnName::new("az"), first: 4, second: 5 };
        assert_eq!(e, refused(dup));
    }

    proptest::proptest! {
        #![proptest_config(proptest::test_runner::Config { cases: 512, failure_persistence: None, ..Default::default() })]

        /// No header, however broken (any characters, BOMs, empty and repeated names, too many
        /// columns, invalid UTF-8), makes a reader panic; one it accepts yields its channels.
        #[test]
        fn no_header_makes_a_reader_panic(
            header in proptest::collection::vec(proptest::prop_oneof![
                proptest::strategy::Just(b"t".to_vec()),
                proptest::strategy::Just(b"n5_x".to_vec()),
                proptest::strategy::Just(b"ax".to_vec()),
                proptest::strategy::Just("\u{feff}".as_bytes().to_vec()),
                proptest::collection::vec(proptest::num::u8::ANY, 0..6),
            ], 0..200),
        ) {
            let mut line: std::vec::Vec<u8> = header.join(&b","[..]);
            line.extend_from_slice(b"\n0,1,2\n");
            if let Ok(mut r) = ChannelReader::new(line.as_slice(), ["n5_x", "t"]) {
                proptest::prop_assert!(r.next_values().is_some());
            }
            let _ = LineFeed::new(line.as_slice());
            if let Ok(text) = core::str::from_utf8(&line) {
                let _ = crate::virtual_adxl355::CsvTextFeed::new(text);
            }
        }
    }
}
