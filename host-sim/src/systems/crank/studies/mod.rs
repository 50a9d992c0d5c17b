//! Research studies on the crank, behind the `studies` feature: they run hundreds of reference
//! simulations and answer a design question rather than estimate anything. Their measured
//! tables are in `docs/`.
//!
//! * [`identify2`]: can a 10 s recording give two clearances (A and B) at once? The ensemble
//!   likelihood surface and Fisher information over (cA, cB) say no, with the window features.

pub mod identify2;
