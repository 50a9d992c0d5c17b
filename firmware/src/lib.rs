#![no_std]
#![deny(missing_docs)]
//! edgekf sensor-node firmware, as a library that builds for the Cortex-M4F node and is tested
//! on the host. Hardware stays at the edges (the driver, the binaries); the loop and the
//! estimators in between are plain code that the host tests and the HIL runs share.
//!
//! * [`adxl355`]: driver for the Analog Devices ADXL355 over I²C or SPI, the only place that
//!   knows its registers;
//! * [`virtual_adxl355`]: a software ADXL355 on a virtual I²C bus, fed with samples, so the
//!   real driver and main loop run unchanged in QEMU and in host tests;
//! * [`line_feed`]: CSV lines from a byte stream (a host file over semihosting, or a slice);
//! * [`source`]: the node's sample sources, the ADXL355 through either bus interface or named
//!   channels of a HIL file;
//! * [`node`]: the main loop, generic over the source and the estimator, with its counters;
//! * [`systems`]: each system's chip code, one folder per system (estimator, report frames,
//!   HIL image, soak rows, image rows, bench kernels, generated constants), and the manifest
//!   that registers them;
//! * [`manifest`]: the firmware images as data (binary, flag, HIL tests, budgets, real-time
//!   requirement), which `cargo xtask` reads;
//! * [`monitor`]: the model monitor beside an estimator; [`mismatch`]: the frame it emits;
//! * [`frame`]: report frames defined once, for the defmt emitter and the host's parser alike;
//! * [`hil`]: the HIL images' run, shared by the QEMU entry point and the host reference runs;
//! * [`soak`]: the numerical soak of every filter, the same code on the host and in QEMU;
//! * `semihost` (QEMU images only): host files, exit codes, the QEMU entry skeleton;
//! * `bench` (QEMU images only): the instruction-count markers the systems' bench kernels call;
//! * `stack` (chip only): stack high-water marks by painting.
//!
//! On the chip, feature `no-panic-proof` replaces the images' panic handlers by `panic-never`'s
//! (see the README's firmware section): an image with a reachable panic then fails to link.

pub mod adxl355;
#[cfg(all(target_os = "none", feature = "qemu"))]
pub mod bench;
pub mod capture;
pub mod frame;
pub mod hil;
pub mod line_feed;
pub mod manifest;
pub mod mismatch;
pub mod monitor;
pub mod node;
pub mod pair_source;
#[cfg(all(target_os = "none", feature = "qemu"))]
pub mod semihost;
pub mod soak;
pub mod source;
#[cfg(target_os = "none")]
pub mod stack;
pub mod systems;
pub mod virtual_adxl355;
pub mod virtual_pair;

#[cfg(test)]
extern crate std;

// The no-panic proof (feature `no-panic-proof`): `panic-never`'s handler refers to a symbol
// defined nowhere, so an image links only if no panic path survives optimisation.
#[cfg(all(target_os = "none", feature = "no-panic-proof"))]
use panic_never as _;
