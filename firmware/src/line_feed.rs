//! CSV text from a byte stream, read in small chunks: [`LineReader`] assembles lines in a
//! fixed buffer, [`LineFeed`] turns them into samples for the virtual ADXL355, and
//! [`ChannelReader`] picks named `f32` channels (for sensors that are not an ADXL355, e.g. the
//! rotor's proximity probes).
//!
//! Under QEMU the stream is a host file read through semihosting; on the host it is a byte
//! slice. No allocation; a line longer than the buffer, or one that does not parse, is skipped
//! and counted, never silently lost.

use crate::virtual_adxl355::{CsvColumns, CsvError, FeedSample, SampleFeed};

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
    /// The header lacks a required column or has too many.
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
}

impl<S: ByteSource, const M: usize> ChannelReader<S, M> {
    /// Reads the header and locates `names` in it.
    pub fn new(source: S, names: [&'static str; M]) -> Result<Self, FeedError> {
        let mut reader = LineReader::new(source);
        let mut index = [u8::MAX; M];
        let width = match reader.next_line() {
            None => return Err(FeedError::Empty),
            Some(Err(BadLine)) => return Err(FeedError::BadHeader),
            Some(Ok(header)) => {
                let mut width = 0;
                for (i, field) in header.split(',').enumerate() {
                    if i >= MAX_COLUMNS {
                        return Err(FeedError::Columns(CsvError::TooManyColumns));
                    }
                    if let Some(k) = names.iter().position(|n| *n == field.trim()) {
                        index[k] = i as u8;
                    }
                    width = i + 1;
                }
                width
            }
        };
        if let Some(k) = index.iter().position(|&i| i == u8::MAX) {
            return Err(FeedError::Columns(CsvError::MissingColumn(names[k])));
        }
        Ok(Self { reader, index, width, ignored: width.saturating_sub(M), bad_lines: 0 })
    }

    /// The next line's values; `Err` for a line that does not parse (counted), `None` at the end.
    pub fn next_values(&mut self) -> Option<Result<[f32; M], BadLine>> {
        loop {
            let line = match self.reader.next_line()? {
                Ok(text) if text.trim().is_empty() => continue,
                Ok(text) => text,
                Err(BadLine) => {
                    self.bad_lines = self.bad_lines.saturating_add(1);
                    return Some(Err(BadLine));
                }
            };
            let mut values = [f32::NAN; M];
            let mut fields = 0;
            for (i, field) in line.split(',').enumerate() {
                fields = i + 1;
                if let Some(k) = self.index.iter().position(|&c| usize::from(c) == i) {
                    match field.trim().parse::<f32>() {
                        Ok(v) if v.is_finite() => values[k] = v,
                        _ => {
                            self.bad_lines = self.bad_lines.saturating_add(1);
                            return Some(Err(BadLine));
                        }
                    }
                }
            }
            if fields != self.width {
                self.bad_lines = self.bad_lines.saturating_add(1);
                return Some(Err(BadLine));
            }
            return Some(Ok(values));
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
