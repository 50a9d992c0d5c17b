//! Innovation statistics cheap enough to run on the chip.
//!
//! A consistent filter's innovations are zero-mean, white, and have the covariance the filter
//! predicts (NIS χ²-distributed). These monitors measure how far a run is from that.

mod chi2;
mod running;

pub use chi2::{chi2_quantile, normal_quantile, NisBounds};
pub use running::RunningStats;
