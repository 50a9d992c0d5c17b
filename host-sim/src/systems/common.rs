//! What the systems' reference simulators mean alike, as one type each: how a run is asked for
//! ([`SimOptions`]), how a recording's columns are read ([`column_of`], [`data_file`]) and why a
//! configuration, option or run is refused ([`SimError`]). Each system keeps its own name for
//! them (`boom::SimOptions`, `uuv::UuvError`, …) as an alias, so callers need not change.

use crate::io::data::DataFile;
use std::path::PathBuf;

/// What to simulate: a system's `scenario` (the boom's run, the vehicle's health timeline) for
/// `duration` seconds, with the noise drawn from `seed`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimOptions<S> {
    /// The run.
    pub scenario: S,
    /// Length of the recording, s.
    pub duration: f64,
    /// Seed of the noise (sensors, and the sea's current for the vehicle).
    pub seed: u64,
}

/// The column `name` of a recording whose columns are `columns`, named `names` in order.
pub fn column_of<'a>(names: &[&str], columns: &'a [Vec<f64>], name: &str) -> Option<&'a [f64]> {
    names.iter().position(|n| *n == name).map(|i| columns[i].as_slice())
}

/// A recording as the data file a reader of its CSV would get.
pub fn data_file(names: &[&str], t: &[f64], columns: &[Vec<f64>]) -> DataFile {
    DataFile {
        sha256: None,
        names: names.iter().map(|n| n.to_string()).collect(),
        t: t.to_vec(),
        columns: columns.to_vec(),
    }
}

/// An error of a system's simulator or estimator. Library calls return these instead of
/// panicking, so an estimator that runs thousands of short simulations (one per sigma point per
/// window, the crank's) can discard a bad one and go on.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A configuration value is out of range or inconsistent; the message names the key.
    #[error("{0}")]
    Config(String),
    /// A configuration file could not be read.
    #[error("{}: cannot read: {reason}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said (in the message, not a second link of the chain).
        reason: std::io::Error,
    },
    /// The recording cannot serve the estimator (a missing sample where every one is needed);
    /// the caller names the file.
    #[error("{0}")]
    Data(String),
    /// A simulation option (duration, step, tolerance, initial state …) is invalid.
    #[error("invalid simulation option: {0}")]
    Options(String),
    /// The integration produced a non-finite state or could not keep its error in bounds.
    #[error("the simulation failed at t = {t} s: {reason}")]
    Diverged {
        /// Time of the failure, s.
        t: f64,
        /// What went wrong.
        reason: String,
    },
}
