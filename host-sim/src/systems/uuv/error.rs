//! Why a vehicle configuration, option or run was refused.

use std::path::PathBuf;

/// An error of the vehicle's simulator or estimator.
#[derive(Debug, thiserror::Error)]
pub enum UuvError {
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
    /// A simulation option is invalid.
    #[error("invalid simulation option: {0}")]
    Options(String),
    /// The integration produced a non-finite state.
    #[error("the simulation failed at t = {t} s: {reason}")]
    Diverged {
        /// Time of the failure, s.
        t: f64,
        /// What went wrong.
        reason: String,
    },
}
