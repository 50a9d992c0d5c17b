//! Each system's chip code: the reduced model, estimator or detector that the node runs and the
//! host runs too (in `f64`), one folder per system. What every system uses (filters, linear
//! algebra, residual statistics) stays in the crate's shared rooms.
//!
//! * [`oscillator`]: a single mode driven by a harmonic force at a known frequency (the
//!   unbalance pattern of rotating machines), estimated from one accelerometer axis;
//! * [`crank`]: a slider-crank's joint clearance from its crank angular acceleration;
//! * [`uuv`]: an underwater vehicle's thruster health from its IMU, depth, heading and DVL;
//! * [`boom`]: a long telescoping boom's tip vibration from a tip gyro and a root inclinometer;
//! * `sdof` (feature `sdof`, a test system): a base-excited mount's relative motion from the
//!   mass's absolute acceleration.

pub mod boom;
pub mod crank;
pub mod oscillator;
#[cfg(feature = "sdof")]
pub mod sdof;
pub mod uuv;
