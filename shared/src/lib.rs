//! # edgekf — model-based estimation for edge vibration sensors
//!
//! `no_std`, allocation-free building blocks that run unchanged on a Cortex-M4F sensor node and
//! on the host:
//!
//! * [`linalg`]: matrix exponential, zero-order-hold and Van Loan discretisation (deterministic:
//!   only `+ − × ÷`, so the chip and the host compute the same bits);
//! * [`filter`]: fixed-size linear Kalman filter (Joseph form, sequential scalar updates),
//!   steady-state gain from the Riccati equation, unscented Kalman filter (Van der Merwe sigma
//!   points) and joint state–parameter estimation; every filter guards its covariance and counts
//!   and recovers instead of panicking;
//! * [`models`]: model builders that know no system: augmented Kalman filter models for unknown
//!   inputs on structures, synthetic benchmark systems;
//! * [`systems`]: each system's chip code that the host runs too, one folder per system (the
//!   harmonic-force oscillator, the slider-crank's joint clearance, the vehicle's thruster
//!   health, the boom's tip vibration: the list is in [`systems`]' own doc);
//! * [`csv_header`]: the data contract's header rules (BOM, `t` first, no repeated names), one
//!   parser for the host's reader and the node's, and [`csv_header::fields`], its panic-free
//!   field splitter;
//! * [`decimal`]: decimal text to `f32`/`f64` rounded as `core` does, without `core`'s panic
//!   paths, so the node's CSV readers pass the link-time no-panic proof;
//! * [`export`]: models and steady-state gains written as Rust constants for the firmware;
//! * [`residual`]: innovation diagnostics cheap enough for the chip: running mean and variance,
//!   NIS with exact χ² bounds, Ljung–Box whiteness over a window, a Welch innovation spectrum
//!   (microfft) with peak finding, and a classifier that places a spectral peak relative to the
//!   running speed's orders and the model's natural frequencies.
//!
//! Every filter is generic over [`Real`] (`f32` on the chip, `f64` on the host) and over its sizes
//! through const generics, so one implementation serves both.
//!
//! ```
//! use edgekf::systems::oscillator::{HarmonicForceEstimator, HarmonicForceParams};
//! let params = HarmonicForceParams::default();
//! let mut est = HarmonicForceEstimator::<f32>::new(&params).unwrap();
//! let report = est.step(Some(0.0));
//! assert!(report.force_amplitude.is_finite());
//! ```
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod csv_header;
pub mod decimal;
pub mod export;
pub mod filter;
pub mod linalg;
pub mod models;
mod real;
pub mod residual;
pub mod systems;
pub mod trig;

pub use real::Real;
