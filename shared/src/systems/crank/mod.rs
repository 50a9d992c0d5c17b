//! Joint clearance of a slider-crank from its crank angular acceleration, on the chip: the
//! fast estimator of the host (`edgekf crank estimate --method fast`) as a streaming,
//! allocation-free computation.
//!
//! * [`CrankFeatures`]: ten statistics per window of α (levels of α, of its differences and of
//!   a high-pass residual, kurtoses, impacts: rate, peak and width), pushed one sample at a
//!   time, averaged over the windows and taken in logarithms;
//! * [`ClearanceModel`]: a linear discriminant that names the joint (A, B or C) and a ridge
//!   regression per joint for `ln c`, learned on the host from the reference simulator and
//!   compiled into the firmware ([`ClearanceModel::write_rust`], [`ClearanceModel::from_f64`]);
//! * [`ReleaseDetector`] and [`ReleaseModel`]: the first contact after release, whose time is
//!   not chaotic, refines the named joint's clearance;
//! * [`ClearanceEstimator`]: all of it, with an estimate after every window;
//! * [`select_nth`]: the exact median of a window without reordering it.
//!
//! The host's `FastModel` computes its features and estimates with this code in `f64`, so the
//! chip (`f32`) and the host run one implementation.

mod features;
mod float;
mod model;
mod release;
mod select;

pub use features::{CrankFeatures, FeatureError, MIN_WINDOW};
pub use float::ClearanceFloat;
pub use model::{window_samples, ClearanceEstimate, ClearanceEstimator, ClearanceModel, CLEARANCE_RANGE, REGRESSORS};
pub use release::{
    release_regressors, ReleaseDetector, ReleaseFeatures, ReleaseModel, MIN_FIT, MIN_SIGMA, RELEASE_HYPOTHESES,
    RELEASE_SPAN, RELEASE_TERMS, THRESHOLD_SIGMAS,
};
pub use select::select_nth;

/// Number of features.
pub const FEATURES: usize = 10;

/// Names of the features, in order (natural logarithms of window means).
pub const FEATURE_NAMES: [&str; FEATURES] = [
    "ln_rms",
    "ln_diff_rms",
    "ln_diff2_rms",
    "ln_highpass_rms",
    "ln_diff_kurtosis",
    "ln_kurtosis",
    "ln_impact_rate",
    "ln_impact_peak",
    "ln_impact_width",
    "ln_diff_median",
];
