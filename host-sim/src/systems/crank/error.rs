//! Why a slider-crank configuration, option or run was refused.
//!
//! Library calls return these instead of panicking, so an estimator that runs thousands of short
//! simulations (one per sigma point per window) can discard a bad sigma point and go on.

use std::path::PathBuf;

/// An error of the slider-crank simulator.
#[derive(Debug, thiserror::Error)]
pub enum CrankError {
    /// A configuration value is out of range or inconsistent; the message names the key.
    #[error("{0}")]
    Config(String),
    /// A configuration file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
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
