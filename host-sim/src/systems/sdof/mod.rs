//! A base-excited single-degree-of-freedom mount (feature `sdof`): the sixth system, kept as
//! small as a system can honestly be, to show what adding one costs. A mass on a spring and a
//! damper whose base shakes; an ADXL355 axis on the mass; the node estimates the relative
//! displacement and velocity of the mount, which no sensor measures
//! ([`edgekf::systems::sdof`]).
//!
//! * [`sim`]: the reference simulator (RK4 of the continuous equation at four sub-steps per
//!   sample, a base acceleration of seeded sinusoids: not the filter's model);
//! * [`estimate`]: the node's filter over a data file, in `f64` or `f32`;
//! * [`cli`]: `edgekf sdof simulate` and `edgekf sdof estimate`.

pub mod cli;
pub mod estimate;
pub mod sim;

#[cfg(test)]
mod tests;
