//! Closing the loop with measured data (issue 6): run the filter, read the innovations'
//! signatures (bias, NIS, whiteness, spectral peaks placed at running-speed orders or natural
//! frequencies), propose small model augmentations ("effects"), and keep an effect only if it
//! raises the innovations' log-likelihood by more than its BIC cost; repeat until the
//! innovations are consistent or nothing helps.
//!
//! * [`model`]: the effects (`sensor_bias`, `harmonic_force`) and the augmented continuous
//!   model composed from the [`ReducedRotor`](crate::rotor_akf::ReducedRotor)'s public matrices.
//! * [`filter`]: a dynamic-size Kalman filter for the host search (time-varying gain until the
//!   covariance converges, then frozen).
//! * [`search`]: signatures, candidates, the loop and its report.
//! * [`inject`]: undeclared effects added to simulated data (for tests and demonstrations).
//! * [`cli`]: `edgekf loop rotor`.

pub mod cli;
pub mod filter;
pub mod inject;
pub mod model;
pub mod search;

pub use model::{augment, AugmentedModel, Effect, EffectTuning, Flexibility};
pub use search::{close_loop, AddedEffect, LoopOptions, LoopReport, RunSummary};
