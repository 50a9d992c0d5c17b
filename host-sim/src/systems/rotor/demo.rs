//! The loop's part of `edgekf demo`: the paper rotor simulated with an effect nobody declared
//! (disk 12 is 10 % heavier than its configuration says), then the loop run on the declared
//! model, which has to find it.
//!
//! ```no_run
//! let demo = edgekf_sim::systems::rotor::demo::LoopDemo::run(false).unwrap();
//! assert_eq!(demo.report.effects_added[0].location, "disk 12");
//! ```

use super::loop_system::close_loop;
use super::loop_system::effects::Parameter;
use crate::io::data::DataFile;
use crate::residual_loop::{LoopOptions, LoopReport};
use crate::systems::rotor::{RotorConfig, RotorModel, SimOptions};
use anyhow::Result;

/// The undeclared effect: a factor on disk 0's mass.
pub const MASS_FACTOR: f64 = 1.10;
/// Length of the recording, s.
pub const DURATION: f64 = 3.0;
/// Noise seed.
pub const SEED: u64 = 7;

/// The demo's data and the loop's report.
#[derive(Debug, Clone)]
pub struct LoopDemo {
    /// The recording (4 probes and the truth).
    pub data: DataFile,
    /// What the loop found.
    pub report: LoopReport,
}

impl LoopDemo {
    /// Simulates the paper rotor with disk 12 `MASS_FACTOR`× heavier and closes the loop on the
    /// declared model (`progress`: print each candidate to standard error).
    pub fn run(progress: bool) -> Result<Self> {
        let declared =
            RotorConfig::from_toml_str(include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml")))?;
        let mut actual = declared.clone();
        Parameter::DiskMass(0).apply(&mut actual, MASS_FACTOR)?;
        let data = RotorModel::from_config(&actual)?
            .simulate(&SimOptions { duration: DURATION, seed: SEED, ..SimOptions::default() })?
            .to_data_file();
        let model = RotorModel::from_config(&declared)?;
        let report =
            close_loop(&model, &data, &LoopOptions { progress, ..LoopOptions::default() }, &Default::default())?;
        Ok(Self { data, report })
    }

    /// One line saying what was simulated.
    pub fn describe() -> String {
        format!(
            "paper rotor (rotor_paper.toml), {DURATION} s at 1 kHz, 4 probes with 1 µm noise, seed {SEED}; \
             undeclared: disk 12 is {:.0} % heavier than configured",
            (MASS_FACTOR - 1.0) * 100.0
        )
    }
}
