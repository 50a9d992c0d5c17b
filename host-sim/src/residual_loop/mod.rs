//! Closing the loop with measured data (issue 6): run the filter, read the innovations'
//! signatures (bias, NIS, whiteness, spectral lines placed at running-speed orders, natural
//! frequencies or bearing lines, steps in power), propose small model augmentations
//! ("effects"), and keep an effect only if it raises the innovations' log-likelihood by more
//! than its BIC cost in both halves of the run; repeat until the innovations are consistent or
//! nothing helps, then report what is left.
//!
//! * [`model`]: the library of effects (`sensor_bias`, `sensor_scale`, `sensor_delay`,
//!   `harmonic_force`, `unknown_input`, `parameter`, `extra_mode`, `bearing_defect`) and the
//!   augmented continuous model composed from the
//!   [`ReducedRotor`](crate::rotor_akf::ReducedRotor)'s public matrices.
//! * [`filter`]: a dynamic-size Kalman filter for the host search (time-varying gain until the
//!   covariance converges, then frozen).
//! * [`signature`]: the innovations' statistics and what is left unexplained.
//! * [`optimize`]: the one-dimensional maximum-likelihood fit of an effect's scalar.
//! * [`search`]: the engine: the [`LoopSystem`] trait every system implements, the loop and its
//!   report;
//! * [`rotor_system`]: the rotor as a [`LoopSystem`] ([`close_loop`]); [`speed`]: its running
//!   speed read from the data.
//! * [`inject`]: undeclared effects added to simulated data; [`cases`]: the ones the tests and
//!   the README use.
//! * [`cli`]: `edgekf loop rotor`; [`demo`]: the loop's part of `edgekf demo`.

pub mod cases;
pub mod cli;
pub mod demo;
pub mod filter;
pub mod html;
pub mod inject;
pub mod model;
pub mod optimize;
pub mod rotor_system;
pub mod search;
pub mod signature;
pub mod speed;

pub use model::{augment, AugmentedModel, Effect, EffectTuning, Flexibility, Parameter};
pub use rotor_system::{close_loop, RotorSystem};
pub use search::{
    search, AddedEffect, EffectLabel, LoopOptions, LoopReport, LoopSystem, NotIdentifiable, RunSummary, Traces,
};
pub use signature::{Signature, SignatureOptions};
