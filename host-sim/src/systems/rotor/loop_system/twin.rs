//! A synthetic twin of the CWRU bearing rig (`configs/rotor_cwru.toml`, 12 kHz, accelerometers
//! on both housings), for the tests that cannot ship the measured records: each housing rings
//! its own resonance near 3 kHz under broadband forces, the motor adds line-frequency
//! harmonics, the sensors their noise, and the shaft turns 0.4 % below its declared speed.
//! Optionally a drive-end bearing defect (impacts at its line's rate with 1.5 % slip, the inner
//! race's load zone modulated at the shaft rate, a ball's at twice its spin, striking both
//! races, carried round at the cage's rate; through the drive-end housing's resonance) and a
//! grown unbalance. Nothing in the configuration declares any of it.
//!
//! ```
//! use edgekf_sim::systems::rotor::loop_system::twin::{rig, Twin};
//! let model = rig().unwrap();
//! let d = Twin { duration: 0.1, ..Twin::default() }.record(&model, 1).unwrap();
//! assert_eq!(d.t.len(), 1200);
//! assert!(d.column("n1_ay").is_some() && d.column("n11_ay").is_some());
//! ```

use super::inject::{inject_bearing_defect, inject_resonance, inject_tones, DefectSignal};
use crate::io::data::DataFile;
use crate::systems::rotor::bearing_geometry::BearingLine;
use crate::systems::rotor::{RotorConfig, RotorModel, SimOptions};
use anyhow::{anyhow, Result};
use std::f64::consts::TAU;

/// The twin's model: `configs/rotor_cwru.toml`.
pub fn rig() -> Result<RotorModel> {
    let cfg = RotorConfig::from_toml_str(include_str!("../../../../configs/rotor_cwru.toml"))?;
    Ok(RotorModel::from_config(&cfg)?)
}

/// The twin's true running speed, rad/s: 0.4 % below the declared.
pub fn true_speed(model: &RotorModel) -> f64 {
    model.config().operation.speed * 0.996
}

/// Housing resonances: (channel, Hz, seed offset).
pub const HOUSINGS: [(&str, f64, u64); 2] = [("n1_ay", 3050.0, 1), ("n11_ay", 3420.0, 2)];

/// One recording of the twin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Twin {
    /// Length, s.
    pub duration: f64,
    /// A defect of the drive-end bearing on this line.
    pub defect: Option<BearingLine>,
    /// The unbalance as a multiple of the configured one.
    pub unbalance: f64,
}

/// The healthy twin's unbalance, as a multiple of the configured (nominal) one: large enough
/// that its 1× line (about 0.02 m/s² on the housings) stands above their noise, as the CWRU
/// records' does, so that the running speed can be read from it.
pub const HEALTHY_UNBALANCE: f64 = 10.0;

impl Default for Twin {
    fn default() -> Self {
        Self { duration: 2.0, defect: None, unbalance: HEALTHY_UNBALANCE }
    }
}

impl Twin {
    /// The recording with noise seed `seed`.
    pub fn record(&self, model: &RotorModel, seed: u64) -> Result<DataFile> {
        let speed = true_speed(model);
        let mut cfg = model.config().clone();
        cfg.unbalances.iter_mut().for_each(|u| u.magnitude *= self.unbalance);
        let actual = RotorModel::from_config(&cfg)?;
        let opts = SimOptions { duration: self.duration, seed, speed: Some(speed), ..SimOptions::default() };
        let mut d = actual.simulate(&opts)?.to_data_file();
        let tones = [(60.0, 0.03, 0.3), (120.0, 0.08, 1.1), (180.0, 0.02, 2.0), (360.0, 0.04, 0.7)];
        for (channel, hz, k) in HOUSINGS {
            inject_resonance(&mut d, channel, hz, 0.04, 0.25, seed * 10 + k)?;
            inject_tones(&mut d, channel, &tones)?;
        }
        if let Some(line) = self.defect {
            let shaft_hz = speed / TAU;
            let geometry = cfg.bearings[0].geometry.ok_or_else(|| anyhow!("the drive-end bearing has no geometry"))?;
            let (strikes, modulation_hz) = match line {
                BearingLine::Bpfi => (1.0, Some(shaft_hz)),
                BearingLine::Bsf => (2.0, Some(geometry.order(BearingLine::Ftf) * shaft_hz)),
                BearingLine::Bpfo | BearingLine::Ftf => (1.0, None),
            };
            let signal = DefectSignal {
                frequency_hz: strikes * geometry.order(line) * shaft_hz,
                peak: 1.5,
                resonance_hz: HOUSINGS[0].1,
                damping: 0.04,
                slip: 0.015,
                modulation_hz,
                load_zone: 0.5,
            };
            inject_bearing_defect(&mut d, "n1_ay", &signal, seed + 100)?;
        }
        Ok(d)
    }
}
