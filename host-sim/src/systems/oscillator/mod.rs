//! The oscillator: a single structural mode driven by a harmonic force at a known frequency,
//! read by one ADXL355 axis; the node's first system and the demo's first part.
//!
//! * [`sim`]: the reference simulator (RK4 at 20 sub-steps per sample, on purpose not the
//!   filter's exact discretisation, so an agreement is evidence rather than a tautology);
//! * [`sensor`]: the ADXL355 as seen at its output (noise, bias, range);
//! * [`scenario`]: a complete synthetic test case (mode, force schedule, sensor, faults) from
//!   TOML, shared by the CLI, the demo and the hardware-in-the-loop tests;
//! * [`estimate`]: the harmonic-force estimator (`edgekf::systems::oscillator`) over a data
//!   file, judged against the truth; [`report`]: its summary;
//! * [`export`]: the model and steady-state gain as Rust constants for the firmware;
//! * [`loop_system`]: the oscillator as a system of the residual loop (`edgekf loop oscillator`);
//! * [`demo`]: the demo's first part; [`cli`]: `edgekf oscillator …`.

pub mod cli;
pub mod demo;
pub mod estimate;
pub mod export;
pub mod loop_system;
pub mod matrix;
pub mod report;
pub mod scenario;
pub mod sensor;
pub mod sim;
