//! A [`SampleFeed`] over a byte stream of CSV text, read in small chunks.
//!
//! Under QEMU the stream is a host file read through semihosting; on the host it is a byte
//! slice. Lines are assembled in a fixed buffer (no allocation); a line longer than the buffer, or
//! one that does not parse, is skipped and counted, never silently lost.

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

/// Longest CSV line accepted, bytes.
pub const MAX_LINE: usize = 256;

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
    source: S,
    columns: CsvColumns,
    chunk: [u8; 64],
    chunk_len: usize,
    chunk_pos: usize,
    line: [u8; MAX_LINE],
    bad_lines: u32,
    lines: u32,
    eof: bool,
}

/// Why a [`LineFeed`] could not start.
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
        let mut feed = Self {
            source,
            columns: CsvColumns::from_header("t,ax,ay,az").map_err(FeedError::Columns)?,
            chunk: [0; 64],
            chunk_len: 0,
            chunk_pos: 0,
            line: [0; MAX_LINE],
            bad_lines: 0,
            lines: 0,
            eof: false,
        };
        let header = match feed.next_line() {
            None => return Err(FeedError::Empty),
            Some(Err(())) => return Err(FeedError::BadHeader),
            Some(Ok(len)) => len,
        };
        let text = core::str::from_utf8(&feed.line[..header]).map_err(|_| FeedError::BadHeader)?;
        feed.columns = CsvColumns::from_header(text).map_err(FeedError::Columns)?;
        Ok(feed)
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

    fn next_byte(&mut self) -> Option<u8> {
        if self.chunk_pos == self.chunk_len {
            if self.eof {
                return None;
            }
            self.chunk_len = self.source.read_bytes(&mut self.chunk);
            self.chunk_pos = 0;
            if self.chunk_len == 0 {
                self.eof = true;
                return None;
            }
        }
        let b = self.chunk[self.chunk_pos];
        self.chunk_pos += 1;
        Some(b)
    }

    /// Next line into `self.line`: `Ok(len)`, `Err(())` for an over-long line, `None` at the end.
    fn next_line(&mut self) -> Option<Result<usize, ()>> {
        let mut len = 0usize;
        let mut overflow = false;
        let mut any = false;
        while let Some(b) = self.next_byte() {
            any = true;
            if b == b'\n' {
                break;
            }
            if len < MAX_LINE {
                self.line[len] = b;
                len += 1;
            } else {
                overflow = true;
            }
        }
        if !any {
            return None;
        }
        Some(if overflow { Err(()) } else { Ok(len) })
    }
}

impl<S: ByteSource> SampleFeed for LineFeed<S> {
    fn next_sample(&mut self) -> Option<FeedSample> {
        loop {
            let line = self.next_line()?;
            let Ok(len) = line else {
                self.lines += 1;
                self.bad_lines += 1;
                continue;
            };
            let text = core::str::from_utf8(&self.line[..len]).ok();
            if text.is_some_and(|t| t.trim().is_empty()) {
                continue; // blank line (e.g. a trailing one)
            }
            self.lines += 1;
            match text.map(|t| self.columns.parse_line(t)) {
                Some(Ok(sample)) => return Some(sample),
                _ => self.bad_lines += 1,
            }
        }
    }
}
