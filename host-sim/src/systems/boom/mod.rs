//! Tip vibration of a long telescoping boom (the fourth paper: a fire-ladder truck's boom
//! measured by a tip gyro and a root inclinometer).
//!
//! * [`config`]: [`BoomConfig`], the TOML configuration (`host-sim/configs/boom_ladder30.toml`);
//! * [`beam`]: the finite-element boom at one length (sections that overlap, the platform,
//!   gravity's geometric stiffness);
//! * [`band`]: Cholesky within the finite elements' band;
//! * [`modal`]: its natural frequencies and the Rayleigh damping fitted to ζ₁, ζ₂;
//! * [`runs`]: the test runs (luffing stops; telescoping while luffing) and the luffing drive;
//! * [`sensors`]: the true gyro (AR(2) noise, bias and drift, scale, quantum) and inclinometer
//!   (lag, offset, noise, quantum);
//! * [`simulate`](mod@simulate): a run integrated into a data file;
//! * [`estimate`](mod@estimate): the shared estimators (`edgekf::systems::boom`) over a file;
//! * [`peaks`]: the peak error of the paper's Table 1;
//! * [`ablation`]: the paper's method with each step replaced by what it stands for;
//! * [`matrix`]: the loop's effect matrix on the simulator's runs;
//! * [`export`](mod@export): the node's constants from a configuration;
//! * [`cli`]: `edgekf boom simulate | estimate | export`.

pub mod ablation;
pub mod band;
pub mod beam;
pub mod cli;
pub mod config;
pub mod demo;
pub mod estimate;
pub mod export;
pub mod loop_system;
pub mod matrix;
pub mod modal;
pub mod peaks;
pub mod plot;
pub mod runs;
pub mod sensors;
pub mod simulate;

pub use config::BoomConfig;
pub use runs::Scenario;
pub use simulate::{simulate, BoomRecording, SimOptions};
