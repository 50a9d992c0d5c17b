//! What the virtual device measures: samples of "true" acceleration plus injected faults.

use super::csv::{CsvColumns, CsvError};
use super::sample::FeedSample;

/// A source of [`FeedSample`]s, pulled one sample period at a time.
pub trait SampleFeed {
    /// The next sample, or `None` when the recording is over.
    fn next_sample(&mut self) -> Option<FeedSample>;
}

impl<F: SampleFeed + ?Sized> SampleFeed for &mut F {
    fn next_sample(&mut self) -> Option<FeedSample> {
        (**self).next_sample()
    }
}

/// A feed from a closure, e.g. one that reads a host file line by line over semihosting or
/// synthesises a signal.
///
/// ```
/// use edgekf_firmware::virtual_adxl355::{FeedSample, FnFeed, SampleFeed};
/// let mut n = 0;
/// let mut feed = FnFeed(move || { n += 1; (n <= 2).then(|| FeedSample::new([0.0, 0.0, 9.8])) });
/// assert!(feed.next_sample().is_some());
/// assert!(feed.next_sample().is_some());
/// assert!(feed.next_sample().is_none());
/// ```
#[derive(Debug)]
pub struct FnFeed<G>(pub G);

impl<G: FnMut() -> Option<FeedSample>> SampleFeed for FnFeed<G> {
    fn next_sample(&mut self) -> Option<FeedSample> {
        (self.0)()
    }
}

/// A feed over a slice of samples, played once.
#[derive(Clone, Debug)]
pub struct SliceFeed<'a> {
    samples: &'a [FeedSample],
    position: usize,
}

impl<'a> SliceFeed<'a> {
    /// Plays `samples` from the start.
    pub fn new(samples: &'a [FeedSample]) -> Self {
        SliceFeed { samples, position: 0 }
    }

    /// Samples not yet handed out.
    pub fn remaining(&self) -> usize {
        self.samples.len().saturating_sub(self.position)
    }
}

impl SampleFeed for SliceFeed<'_> {
    fn next_sample(&mut self) -> Option<FeedSample> {
        let sample = self.samples.get(self.position).copied()?;
        self.position += 1;
        Some(sample)
    }
}

/// A feed over CSV text in memory (the same format the QEMU image reads from the host): a
/// header line, then one sample per line. See [`CsvColumns`] for the columns.
///
/// Blank lines are skipped silently; lines that do not parse are skipped and counted, so one
/// corrupt line costs one sample instead of the whole run, and the test can still assert that
/// there were none.
///
/// ```
/// use edgekf_firmware::virtual_adxl355::{CsvTextFeed, SampleFeed};
/// let text = "t,ax,ay,az,truth_force\n0.000,0.1,0.2,9.8,1.0\n0.001,oops,0.2,9.8,1.0\n0.002,0.3,0.2,9.8,1.0\n";
/// let mut feed = CsvTextFeed::new(text).unwrap();
/// assert_eq!(feed.next_sample().unwrap().accel, [0.1, 0.2, 9.8]);
/// assert_eq!(feed.next_sample().unwrap().accel, [0.3, 0.2, 9.8]);
/// assert!(feed.next_sample().is_none());
/// assert_eq!(feed.bad_lines(), 1);
/// ```
#[derive(Clone, Debug)]
pub struct CsvTextFeed<'a> {
    lines: core::str::Lines<'a>,
    columns: CsvColumns,
    bad_lines: u32,
}

impl<'a> CsvTextFeed<'a> {
    /// Reads the header (the first non-blank line) of `text`.
    pub fn new(text: &'a str) -> Result<Self, CsvError> {
        let mut lines = text.lines();
        let header = lines.by_ref().find(|l| !l.trim().is_empty()).unwrap_or("");
        let columns = CsvColumns::from_header(header)?;
        Ok(CsvTextFeed { lines, columns, bad_lines: 0 })
    }

    /// The column layout found in the header.
    pub fn columns(&self) -> &CsvColumns {
        &self.columns
    }

    /// Data lines skipped because they did not parse.
    pub fn bad_lines(&self) -> u32 {
        self.bad_lines
    }
}

impl SampleFeed for CsvTextFeed<'_> {
    fn next_sample(&mut self) -> Option<FeedSample> {
        for line in self.lines.by_ref() {
            if line.trim().is_empty() {
                continue;
            }
            match self.columns.parse_line(line) {
                Ok(sample) => return Some(sample),
                Err(_) => self.bad_lines = self.bad_lines.saturating_add(1),
            }
        }
        None
    }
}
