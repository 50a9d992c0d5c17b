//! Tip vibration of a long telescoping boom from a tip gyro and a root inclinometer (the
//! fourth paper: a fire-ladder truck), on the chip.
//!
//! * [`Ar2`]: the gyro noise's AR(2) model, identified from a static record (Yule–Walker);
//! * [`PaperEstimator`]: the paper's method, step by step: the Kalman filter on the gyro's AR(2)
//!   noise (with the rate it rides on in its state), Simpson integration to the tip angle, fusion
//!   with the inclinometer at the equilibrium instants, `y = α l θ` and a moving average;
//! * [`BoomConstants::reduce`]: the reduced boom (Rayleigh–Ritz on the boom's own static
//!   deflection shapes) for the model-based filter: its first modes, their tip values and
//!   participation, the gravity sag;
//! * [`ModelEstimator`]: the model-based design, one Kalman filter on the reduced boom with the
//!   luffing command as input, the gyro's bias and AR noise and the inclinometer's lag in its
//!   state.
//!
//! The host's reference boom (`edgekf_sim::systems::boom`) is a finite-element model written
//! apart from anything here.

mod ar;
mod model;
mod paper;
mod reduced;

pub use ar::{Ar2, ArError};
pub use model::{
    slot, ExtraMode, LastStep, ModelError, ModelEstimate, ModelEstimator, ModelSettings, MEASUREMENTS, STATES,
};
pub use paper::{PaperEstimate, PaperEstimator, PaperSettings, ROOT_WINDOW_MAX, ROOT_WINDOW_S, SMOOTHING_MAX};
pub use reduced::{BoomConstants, BoomSection, Mode, ReducedBoom, ReducedError, BASIS, MAX_SECTIONS, MODES};
