//! Each system's chip code, one folder per system: `<name>/mod.rs` its node estimator, report
//! frames and HIL image, `<name>/soak.rs` its filters' numerical soak rows, `<name>/generated/`
//! the constants the host exports for it. Adding a system means a folder here (a
//! [`crate::node::NodeEstimator`], a [`crate::hil::HilImage`] and its soak rows), its rows in
//! [`crate::soak::SOAKS`], a one-line QEMU binary and a row in `xtask`'s image table.
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
