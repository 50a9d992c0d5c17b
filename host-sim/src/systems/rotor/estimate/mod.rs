//! Virtual sensing on a rotor: a modally reduced model of the finite-element rotor with the
//! unbalance forces as rotating phasors, and the augmented Kalman filter that estimates every
//! node's motion and the forces from a few sensors.
//!
//! * [`reduce`]: modal truncation (mass-normalised modes of the non-rotating rotor with its
//!   bearings), with static correction for the truncated modes, into a continuous state-space
//!   model; one forward-rotating phasor per unbalance node (or, for comparison, the paper's
//!   random-walk forces).
//! * [`filter`]: discretisation (exact, Van Loan), the filter run over a data file, and the
//!   virtual-sensing outputs.
//! * [`tune`]: the noise parameters from data, by the paper's compromise objective under
//!   differential evolution or by the innovations' maximum likelihood.
//!
//! Why a phasor: an unbalance force at constant speed is `F_x = A cos(Ωt + φ)`,
//! `F_y = A sin(Ωt + φ)`, a vector rotating forward at the known running speed. Two states per
//! unbalance with a slow random walk follow a changing unbalance but cannot absorb content at
//! other frequencies, so the filter's floor is set by the sensors, not by the force model, and
//! what the model lacks stays visible in the innovations. The paper's free random-walk forces
//! (two per node, `F_x` and `F_y`) soak up almost any model error instead.

pub mod filter;
pub mod reduce;
pub mod tune;

pub use filter::{run, run_with, Estimates, FilterPrecision, RunOptions};
pub use reduce::{reduce, ForceModel, ReducedRotor, Tuning};
