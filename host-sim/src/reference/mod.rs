//! Full-precision reference simulators: the "truth" that estimators are compared with.
//!
//! They run in `f64` on the host only, with integrators chosen to differ from the estimators'
//! own discretisations, so an agreement is evidence rather than a tautology.

pub mod oscillator;
