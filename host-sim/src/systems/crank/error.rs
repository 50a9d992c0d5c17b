//! Why a slider-crank configuration, option or run was refused.
//!
//! Library calls return these instead of panicking, so an estimator that runs thousands of short
//! simulations (one per sigma point per window) can discard a bad sigma point and go on.

/// An error of the slider-crank simulator: the systems' common [`SimError`](crate::systems::common::SimError).
pub type CrankError = crate::systems::common::SimError;
