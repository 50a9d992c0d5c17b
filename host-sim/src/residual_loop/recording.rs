//! A system's recording as the engine reads it: the time, the sensor channels, the virtual rows
//! and their truth, for the summaries of its runs and the report's traces. A system builds one
//! from its data ([`Recording`]) instead of restating the summary's set-up.

use super::filter::Run;
use super::report::Traces;
use super::signature::{summarise, Channel, ReferenceLines, RunSummary, SignatureOptions, SummaryContext};
use crate::io::data::DataFile;

/// The data a system's runs are summarised against.
///
/// ```
/// use edgekf_sim::residual_loop::{Channel, Recording};
/// let (t, x) = ([0.0, 0.001], [1e-6, 2e-6]);
/// let ch = [Channel::new("probe", "m")];
/// let rec = Recording { t: &t, channels: &ch, rows: &ch, truth: vec![Some(&x)], sample_rate: 1000.0 };
/// assert_eq!(rec.traces().truth[0].as_deref(), Some(&x[..]));
/// ```
#[derive(Debug, Clone)]
pub struct Recording<'a> {
    /// Time of each sample, s.
    pub t: &'a [f64],
    /// Sensor channels, in the filter's order.
    pub channels: &'a [Channel],
    /// Virtual-sensing rows, in [`Run::outputs`]' order.
    pub rows: &'a [Channel],
    /// Truth of each row, where the data have it.
    pub truth: Vec<Option<&'a [f64]>>,
    /// Samples per second.
    pub sample_rate: f64,
}

impl<'a> Recording<'a> {
    /// The recording of `data` whose rows' truth is in the columns `truth` (absent where the
    /// data have no such column).
    ///
    /// ```
    /// use edgekf_sim::io::data::DataFile;
    /// use edgekf_sim::residual_loop::{Channel, Recording};
    /// let data = DataFile {
    ///     names: vec!["truth_x".into()],
    ///     t: vec![0.0, 0.01],
    ///     columns: vec![vec![1.0, 2.0]],
    ///     sha256: None,
    /// };
    /// let ch = [Channel::new("x", "m")];
    /// let rec = Recording::of(&data, &ch, &ch, &["truth_x", "truth_y"], 100.0);
    /// assert_eq!(rec.truth, vec![Some(&[1.0, 2.0][..]), None]);
    /// ```
    pub fn of(
        data: &'a DataFile,
        channels: &'a [Channel],
        rows: &'a [Channel],
        truth: &[&str],
        sample_rate: f64,
    ) -> Self {
        let truth = truth.iter().map(|c| data.column(c)).collect();
        Self { t: &data.t, channels, rows, truth, sample_rate }
    }

    /// The innovations' statistics of `run` with its lines placed among `lines`.
    pub fn summarise(&self, run: &Run, lines: &ReferenceLines, options: &SignatureOptions) -> RunSummary {
        let ctx = SummaryContext {
            t: self.t,
            channels: self.channels,
            rows: self.rows,
            truth: &self.truth,
            lines,
            sample_rate: self.sample_rate,
        };
        summarise(run, &ctx, options)
    }

    /// The report's traces of this recording (the engine fills in the runs).
    pub fn traces(&self) -> Traces {
        Traces::new(self.t, self.channels, self.rows, &self.truth)
    }
}
