//! The undeclared effects the loop is tested on, as data: the paper rotor simulated for 3 s with
//! one (or two) effects its configuration does not declare. The tests and the README's table
//! (`cargo run --release -p edgekf-sim --example loop_table`) use the same cases.
//!
//! ```
//! use edgekf_sim::systems::rotor::loop_system::cases::Case;
//! assert_eq!(Case::ALL.len(), 13);
//! assert!(Case::Scale.describe().contains("5 %"));
//! ```

use super::effects::Parameter;
use super::inject::{inject_bias, inject_delay, inject_harmonic_force, inject_scale, HarmonicForce};
use crate::io::data::DataFile;
use crate::systems::rotor::config::PointMassConfig;
use crate::systems::rotor::{RotorConfig, RotorModel, SimOptions};
use anyhow::Result;

/// Length of each recording, s.
pub const DURATION: f64 = 3.0;

/// One test case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Case {
    /// Nothing undeclared.
    Clean,
    /// +20 µm on probe `n5_x`.
    Bias,
    /// A 1.5 N force at 2× the running speed at disk node 12.
    TwoX,
    /// A 1.0 N force at 3× at disk node 23.
    ThreeX,
    /// Probe `n32_y` reads 5 % high.
    Scale,
    /// Disk 12 is 10 % heavier.
    DiskMass,
    /// The shaft is 5 % less stiff (Young's modulus).
    ShaftYoung,
    /// −25 µm on `n32_x` and a 2 N 2× force at node 23 at once.
    Two,
    /// Bearing 4's `kxx` is half the declared value (too small to see).
    SoftBearing,
    /// Probe `n5_x`'s gain switches from 1 to 1.15 at 1.5 s (no effect of the library fits).
    GainSwitch,
    /// Probe `n32_x` lags the others by 2 ms (two samples).
    Delay,
    /// A 1.5 N force at 2× at node 17, between the disks (away from every force site the
    /// model declares).
    OffDisk,
    /// A 0.8 kg mass without inertia at node 18, between the disks (a collar the
    /// configuration does not declare).
    PointMass,
}

impl Case {
    /// Every case.
    pub const ALL: [Case; 13] = [
        Case::Clean,
        Case::Bias,
        Case::TwoX,
        Case::ThreeX,
        Case::Scale,
        Case::DiskMass,
        Case::ShaftYoung,
        Case::Two,
        Case::SoftBearing,
        Case::GainSwitch,
        Case::Delay,
        Case::OffDisk,
        Case::PointMass,
    ];

    /// What was done to the data.
    pub fn describe(self) -> &'static str {
        match self {
            Case::Clean => "clean",
            Case::Bias => "+20 µm bias on n5_x",
            Case::TwoX => "1.5 N at 2× running speed, node 12",
            Case::ThreeX => "1.0 N at 3×, node 23",
            Case::Scale => "n32_y reads 5 % high",
            Case::DiskMass => "disk 12 mass +10 %",
            Case::ShaftYoung => "shaft Young's modulus −5 %",
            Case::Two => "−25 µm bias on n32_x and 2 N at 2×, node 23",
            Case::SoftBearing => "bearing 4 kxx halved",
            Case::GainSwitch => "n5_x gain 1 → 1.15 at 1.5 s",
            Case::Delay => "n32_x lags by 2 ms",
            Case::OffDisk => "1.5 N at 2×, node 17 (between the disks)",
            Case::PointMass => "0.8 kg mass at node 18 (between the disks)",
        }
    }

    /// The declared rotor (what the loop is given).
    pub fn declared() -> Result<RotorModel> {
        let cfg =
            RotorConfig::from_toml_str(include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml")))?;
        Ok(RotorModel::from_config(&cfg)?)
    }

    /// The case's data with noise seed `seed` (the same seed gives the same sensor noise in
    /// every case, so `Case::Clean.data(seed)` is its clean twin).
    pub fn data(self, seed: u64) -> Result<DataFile> {
        let declared = Self::declared()?;
        let simulate = |m: &RotorModel| -> Result<DataFile> {
            Ok(m.simulate(&SimOptions { duration: DURATION, seed, ..SimOptions::default() })?.to_data_file())
        };
        let with = |p: Parameter, factor: f64| -> Result<DataFile> {
            let mut cfg = declared.config().clone();
            p.apply(&mut cfg, factor)?;
            simulate(&RotorModel::from_config(&cfg)?)
        };
        let speed = declared.config().operation.speed;
        let mut d = match self {
            Case::DiskMass => return with(Parameter::DiskMass(0), 1.10),
            Case::ShaftYoung => return with(Parameter::ShaftYoung, 0.95),
            Case::SoftBearing => return with(Parameter::BearingKxx(0), 0.5),
            Case::PointMass => {
                let mut cfg = declared.config().clone();
                cfg.masses.push(PointMassConfig { node: 18, mass: 0.8, ip: 0.0, id: 0.0 });
                return simulate(&RotorModel::from_config(&cfg)?);
            }
            _ => simulate(&declared)?,
        };
        match self {
            Case::Bias => inject_bias(&mut d, "n5_x", 20e-6)?,
            Case::TwoX => inject_harmonic_force(&mut d, &declared, speed, &force(12, 2.0, 1.5, 0.3))?,
            Case::OffDisk => inject_harmonic_force(&mut d, &declared, speed, &force(17, 2.0, 1.5, 0.3))?,
            Case::ThreeX => inject_harmonic_force(&mut d, &declared, speed, &force(23, 3.0, 1.0, -1.0))?,
            Case::Scale => inject_scale(&mut d, "n32_y", 1.05, None)?,
            Case::Two => {
                inject_bias(&mut d, "n32_x", -25e-6)?;
                inject_harmonic_force(&mut d, &declared, speed, &force(23, 2.0, 2.0, 1.0))?;
            }
            Case::GainSwitch => inject_scale(&mut d, "n5_x", 1.15, Some(1.5))?,
            Case::Delay => inject_delay(&mut d, "n32_x", 2e-3)?,
            _ => {}
        }
        Ok(d)
    }
}

/// A [`HarmonicForce`] at `node`, `order`, `amplitude` (N) and `phase_rad`.
fn force(node: usize, order: f64, amplitude: f64, phase_rad: f64) -> HarmonicForce {
    HarmonicForce { node, order, amplitude, phase_rad }
}
