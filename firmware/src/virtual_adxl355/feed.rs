//! What the virtual device measures: samples of "true" acceleration plus injected faults.

use super::csv::{CsvColumns, CsvError};

/// One sample period of input to the [`VirtualAdxl355`](super::VirtualAdxl355).
///
/// Besides the acceleration, each sample may carry fault instructions for the virtual device.
/// The bus faults (`nack`, `timeout`, `garbage`) are queued when the sample's period passes and
/// hit the transactions that follow; the others act on the sample itself.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FeedSample {
    /// True acceleration on X, Y, Z in m/s² (before quantisation and saturation).
    pub accel: [f32; 3],
    /// Number of bus transactions to NACK once this sample is due: a bus glitch the firmware's
    /// retry layer must ride through.
    pub nack: u8,
    /// Number of bus transactions to fail with a timeout once this sample is due: a bus held
    /// low for a while, which the node does not retry within the poll.
    pub timeout: u8,
    /// Number of bus transactions whose read data is garbage (every byte `0xFF`, writes lost)
    /// once this sample is due: the ID registers read back wrong, and the node must not take
    /// the FIFO data of such a transaction for samples.
    pub garbage: u8,
    /// Output frozen: the device repeats its previous output codes instead of this sample,
    /// the signature of a stuck sensor that the diagnostics must catch.
    pub stuck: bool,
    /// The device produces no sample for this period (nothing enters the FIFO): the node must
    /// bridge it by prediction so that the estimator's clock does not slip.
    pub dropped: bool,
    /// The device resets as this sample is due: registers back to their defaults (standby),
    /// FIFO cleared; this sample and every one until the node reconfigures the part are lost.
    pub reset: bool,
}

impl FeedSample {
    /// A fault-free sample.
    pub const fn new(accel: [f32; 3]) -> Self {
        FeedSample { accel, nack: 0, timeout: 0, garbage: 0, stuck: false, dropped: false, reset: false }
    }
}

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
