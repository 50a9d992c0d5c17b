//! Underwater vehicle thruster health, the third paper's system (a joint UKF of a vehicle's
//! state and its thrusters' health factors): REMUS 100 with a vertical tunnel thruster.
//!
//! * [`config`]: [`UuvConfig`], the TOML configuration (`host-sim/configs/uuv_remus100.toml`);
//! * [`reference`]: the independent 6-DOF reference model (vector form, quaternions, RK4);
//! * [`sea`], [`sensors`], [`autopilot`]: the current, the sensors, the closed loop;
//! * [`scenario`]: the health timelines (`paper`, `vertical`, `healthy`);
//! * [`simulate`](mod@simulate): a scenario flown into a data file;
//! * [`estimate`](mod@estimate): the shared estimator (`edgekf::systems::uuv`) over a data
//!   file;
//! * [`loop_system`]: the vehicle as a system of the residual loop (`edgekf loop uuv`);
//! * [`matrix`]: its effect matrix (`cargo xtask loop-matrix uuv`);
//! * [`plot`]: the health factors against truth (`edgekf uuv estimate --plot`);
//! * [`export`](mod@export): the node's constants from a configuration;
//! * [`cli`]: `edgekf uuv simulate | estimate | export`, `edgekf loop uuv`.

pub mod autopilot;
pub mod cli;
pub mod config;
pub mod demo;
mod error;
pub mod estimate;
pub mod export;
pub mod loop_system;
pub mod matrix;
pub mod plot;
pub mod reference;
pub mod scenario;
pub mod sea;
pub mod sensors;
pub mod simulate;

pub use config::UuvConfig;
pub use error::UuvError;
pub use estimate::{estimate, EstimateTable};
pub use scenario::Scenario;
pub use simulate::{simulate, SimOptions, UuvRecording};
