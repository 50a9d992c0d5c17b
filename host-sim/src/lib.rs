//! # edgekf-sim — the host side of edgekf
//!
//! `edgekf` runs Kalman filters on an edge vibration sensor (an ADXL355 read by a Cortex-M4F).
//! This crate is everything around the chip that runs on a workstation:
//!
//! * [`io::data`]: the data contract of every CSV a user gives or gets (time column `t`, SI
//!   channels, `truth_*` columns) with a reader that reports what it noticed instead of hiding it;
//! * [`reference`](mod@reference): full-precision reference simulators, integrated differently from the filters
//!   so that an agreement means something;
//! * [`sensor`]: sensor models as seen at their outputs (noise, bias, range);
//! * [`scenario`]: complete synthetic test cases (physics + sensor + faults + filter tuning) from
//!   TOML, shared by the CLI demo and the hardware-in-the-loop tests;
//! * [`estimate`]: the `edgekf` estimators run over a data file, judged against the truth;
//! * [`report`] and [`demo`]: the summaries the `edgekf` binary prints.
//!
//! ```
//! use edgekf_sim::estimate::{run, EstimateOptions};
//! use edgekf_sim::scenario::Scenario;
//! // 3 s of the demo: 5 N at 14 Hz on a 20 Hz mode, read by an ADXL355 at 1 kHz.
//! let scenario = Scenario { duration_s: 3.0, ..Default::default() };
//! let data = scenario.simulate().to_data_file();
//! let est = run::<f32>(&data, &scenario.estimator_params(), &EstimateOptions::default()).unwrap();
//! assert_eq!(est.counters.steps, 3000);
//! ```
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod crank;
pub mod demo;
pub mod estimate;
pub mod export;
pub mod io;
pub mod reference;
pub mod report;
pub mod residual_loop;
pub mod rotor;
pub mod rotor_akf;
pub mod scenario;
pub mod sensor;
