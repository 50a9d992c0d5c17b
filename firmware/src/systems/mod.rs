//! Each system's node estimator, its report frames and its HIL image, one file per system.
//! Adding a system means a file here (a [`crate::node::NodeEstimator`] and a
//! [`crate::hil::HilImage`]), a one-line QEMU binary and a row in `xtask`'s image table.
//!
//! * [`oscillator`]: the harmonic force driving a structural mode, from one ADXL355 axis;
//! * [`rotor`]: rotor virtual sensing (disk motion and unbalance forces from four probes, or
//!   from four accelerometer axes: [`rotor::accel`]);
//! * [`crank`]: slider-crank joint clearance from the crank angular acceleration;
//! * [`uuv`]: an underwater vehicle's thruster health from its IMU, depth, compass and DVL;
//! * [`boom`]: a telescoping boom's tip vibration from a tip gyro and a root inclinometer.

pub mod boom;
pub mod crank;
pub mod oscillator;
pub mod rotor;
pub mod uuv;
