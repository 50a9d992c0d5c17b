//! Innovation statistics cheap enough to run on the chip.
//!
//! A consistent filter's innovations are zero-mean, white, and have the covariance the filter
//! predicts (NIS χ²-distributed). These monitors measure how far a run is from that.

mod chi2;
mod cusum;
mod gamma;
mod locate;
mod monitor;
mod running;
mod spectrum;
#[cfg(test)]
mod testutil;
mod whiteness;

pub use chi2::{chi2_cdf, chi2_quantile, chi2_sf, normal_quantile, NisBounds};
pub use cusum::{nis_cusum_arl, nis_cusum_reference, nis_cusum_threshold, Cusum};
pub use gamma::{gamma_p, gamma_q};
pub use locate::{locate_peak, NaturalMatch, Order, OrderMatch, PeakClass, PeakLocation, PeakTolerance};
pub use monitor::{Mismatch, ModelMonitor, MonitorSettings, Statistic, Thresholds, WHITENESS_LAGS};
pub use running::RunningStats;
pub use spectrum::{find_peaks, median_level, FftLen, FftSize, SpectralPeak, Welch};
pub use whiteness::{LjungBox, WhitenessWindow};
