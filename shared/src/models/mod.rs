//! Model builders that know no system (each system's own model is in [`crate::systems`]).
//!
//! Each model is a small module: its parameters (plain `f64`, set on the host or from a config),
//! the discrete model it builds (computed once, in `f64`, by exact discretisation), and an
//! estimator that wraps a filter from [`crate::filter`] with what the model needs around it
//! (missing samples, gating, counters).

pub mod augmented;
pub mod synthetic;
