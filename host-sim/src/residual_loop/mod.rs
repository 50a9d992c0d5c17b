//! The residual-loop engine: closing the loop with measured data for any system. Run the
//! system's filter, read the innovations' signatures (bias, NIS, whiteness, spectral lines
//! placed at the system's reference lines, steps in power), ask the system for candidate
//! effects, and keep an effect only if it raises the innovations' log-likelihood by more than
//! its BIC cost in both halves of the run; repeat until the innovations are consistent or
//! nothing helps, then report what is left.
//!
//! The engine knows no system: a system implements [`LoopSystem`] in its own folder.
//!
//! * [`search`]: the [`LoopSystem`] trait and the loop;
//! * [`vocabulary`]: the effect kinds, their extra fields and [`Applied`] effects;
//! * [`report`]: what a run reports (`report.json`'s layout);
//! * [`onset`]: effects that start mid-run (the onset's placement, the halves after it);
//! * [`signature`]: the innovations' statistics and what is left unexplained;
//! * [`baseline`]: a healthy baseline's source and the comparison of a record with it;
//! * [`bounds`]: what the model allows an effect to be (`[bounds]`), refusals beyond it;
//! * [`envelope`]: envelope analysis (kurtogram, squared envelope, lines in its spectrum);
//! * [`cyclic`]: a resonance rung by periodic impacts, fitted to the innovations by likelihood;
//! * [`direction`]: where an input the model lacks acts, ranked from the innovations' directions;
//! * [`impacts`]: the first stage, periodic impacts named by envelope lines and taken out;
//! * [`filter`]: a dynamic-size Kalman filter for the host search (time-varying gain until the
//!   covariance converges, then frozen);
//! * [`modal_form`]: the transition in real modal form, so that a covariance step is `O(n²)`;
//! * [`optimize`]: the one-dimensional maximum-likelihood fit of an effect's scalar.

pub mod baseline;
pub mod bounds;
pub mod cyclic;
pub mod direction;
pub mod envelope;
pub mod filter;
pub mod impacts;
pub mod modal_form;
pub mod onset;
pub mod optimize;
pub mod report;
pub mod search;
pub mod signature;
pub mod vocabulary;

pub use search::{
    search, AddedEffect, Applied, EffectLabel, LoopOptions, LoopReport, LoopSystem, NotIdentifiable, RunSummary, Traces,
};
pub use signature::{Channel, Signature, SignatureOptions};
