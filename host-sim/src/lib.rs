//! # edgekf-sim — the host side of edgekf
//!
//! `edgekf` runs Kalman filters on an edge vibration sensor (an ADXL355 read by a Cortex-M4F).
//! This crate is everything around the chip that runs on a workstation:
//!
//! * [`systems`]: one folder per system (`oscillator`, `rotor`, `crank`, `uuv`, `boom`), each with its
//!   reference simulator (`f64`, formulated independently of the reduced model it checks), its
//!   estimators, its residual-loop system, its command line, demo part and configuration;
//! * [`residual_loop`]: the engine that closes the loop with measured data, written against the
//!   `LoopSystem` trait and knowing no system;
//! * [`diagnostics`]: toolkits a system may use beside the engine (bearing diagnosis by envelope
//!   analysis, locating an input from the innovations);
//! * [`report`]: what the loop writes for people and scripts (`report.json`, `report.html`
//!   with its plots, the printed table);
//! * [`io`]: the data contract of every CSV a user gives or gets (time column `t`, SI channels,
//!   `truth_*` columns), read with a report of what was noticed instead of hiding it;
//! * [`matrix`]: effect matrices, the loop scored on a system's own simulator with one rule;
//! * [`linalg`]: dense host linear algebra the simulators and the engine share (matrix
//!   exponential of large systems);
//! * [`trend`]: a machine's history, the loop's reports on many recordings in order of their
//!   start (`trend.csv`, `trend.html`);
//! * [`cli`]: the `edgekf` command line, driven by the systems' registry.
//!
//! ```
//! use edgekf_sim::systems::oscillator::estimate::{run, EstimateOptions};
//! use edgekf_sim::systems::oscillator::scenario::Scenario;
//! // 3 s of the demo: 5 N at 14 Hz on a 20 Hz mode, read by an ADXL355 at 1 kHz.
//! let scenario = Scenario { duration_s: 3.0, ..Default::default() };
//! let data = scenario.simulate().to_data_file();
//! let est = run::<f32>(&data, &scenario.estimator_params(), &EstimateOptions::default()).unwrap();
//! assert_eq!(est.counters.steps, 3000);
//! ```
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod cli;
pub mod diagnostics;
pub mod io;
pub mod linalg;
pub mod matrix;
pub mod report;
pub mod residual_loop;
pub mod systems;
pub mod trend;
