#![no_std]
#![deny(missing_docs)]
//! edgekf sensor-node firmware, as a library that builds for the Cortex-M4F node and is tested
//! on the host.
//!
//! * [`adxl355`]: driver for the Analog Devices ADXL355 accelerometer over I2C or SPI;
//! * [`virtual_adxl355`]: a software ADXL355 on a virtual I2C bus, fed with samples, so the
//!   real driver and main loop run unchanged in QEMU and in host tests;
//! * [`crank`]: slider-crank joint clearance from the crank angular acceleration (the host's fast
//!   estimator, streaming in `f32`, model compiled in).

pub mod adxl355;
pub mod crank;
pub mod line_feed;
pub mod model;
pub mod node;
pub mod rotor;
#[cfg(all(target_os = "none", feature = "qemu"))]
pub mod semihost;
#[cfg(target_os = "none")]
pub mod stack;
pub mod virtual_adxl355;

#[cfg(test)]
extern crate std;
