//! A system's recording as the engine reads it: the time, the sensor channels, the virtual rows
//! and their truth, for the summaries of its runs and the report's traces. A system builds one
//! from its data ([`Recording`]) instead of restating the summary's set-up.

use super::filter::Run;
use super::report::Traces;
use super::signature::{summarise, Channel, ReferenceLines, RunSummary, SignatureOptions, SummaryContext};

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

impl Recording<'_> {
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
