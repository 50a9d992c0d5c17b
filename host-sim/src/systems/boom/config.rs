//! The boom configuration (TOML): the sections from the root up, how they extend, the tip's
//! platform, the damping, the sensors as declared to the estimator, what the simulator's true
//! sensors are instead (`[sim.gyro]`, `[sim.inclinometer]`), the luffing drive and the test
//! runs. `host-sim/configs/boom_ladder30.toml` is our 30 m ladder written out.
//!
//! Unknown keys are refused with their name; every figure is checked, the message names the key.
//!
//! ```
//! use edgekf_sim::systems::boom::BoomConfig;
//! let c = BoomConfig::from_toml_str(edgekf_sim::systems::boom::config::LADDER30).unwrap();
//! assert_eq!(c.section.len(), 4);
//! assert_eq!(c.boom.elements, 60);
//! let e = BoomConfig::from_toml_str("[[section]]\nlength = 9.6\nei = -1.0\nmass_per_length = 100.0\n").unwrap_err();
//! assert!(e.to_string().contains("section[0].ei"), "{e}");
//! ```

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// `host-sim/configs/boom_ladder30.toml`, compiled in (the default of `edgekf boom`).
pub const LADDER30: &str = include_str!("../../../configs/boom_ladder30.toml");

/// One section of the telescope, from the root up; each slides out of the one below.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Section {
    /// Length, m.
    pub length: f64,
    /// Bending stiffness, N·m².
    pub ei: f64,
    /// Mass per length, structural and non-structural, kg/m.
    pub mass_per_length: f64,
}

/// How the sections extend.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Extension {
    /// Section k (0 = base) starts k·e from the root, e = (l − top section's length)/(n − 1).
    Synchronous,
}

/// The boom as a whole.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct BoomTable {
    /// How the sections extend.
    pub extension: Extension,
    /// Finite elements over the current length.
    pub elements: usize,
    /// Gravitational acceleration, m/s².
    pub gravity: f64,
}

impl Default for BoomTable {
    fn default() -> Self {
        Self { extension: Extension::Synchronous, elements: 60, gravity: 9.81 }
    }
}

/// The platform at the tip.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct Tip {
    /// Mass, kg.
    pub mass: f64,
    /// Rotary inertia about the luffing axis through the tip, kg·m².
    pub rotary_inertia: f64,
}

/// Damping ratios of the first two modes (Rayleigh damping fitted to them at every length).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct Damping {
    /// ζ of modes 1 and 2.
    pub zeta: [f64; 2],
}

impl Default for Damping {
    fn default() -> Self {
        Self { zeta: [0.015, 0.020] }
    }
}

/// The tip gyro about the luffing axis, as declared to the estimator.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct Gyro {
    /// Sample rate, Hz.
    pub sample_rate: f64,
    /// Scale factor (reading per rad/s).
    pub scale: f64,
    /// AR(2) coefficients `[a1, a2]` of its noise (identified from the static record if absent).
    pub ar: Option<[f64; 2]>,
    /// Standard deviation of the AR's driving noise, rad/s (likewise).
    pub noise: Option<f64>,
    /// Constant bias, rad/s (likewise).
    pub bias: Option<f64>,
}

impl Default for Gyro {
    fn default() -> Self {
        Self { sample_rate: 100.0, scale: 1.0, ar: None, noise: None, bias: None }
    }
}

/// The root inclinometer, as declared to the estimator.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct Inclinometer {
    /// Sample rate, Hz.
    pub sample_rate: f64,
    /// First-order time constant, s (0: none declared).
    pub lag: f64,
    /// Offset, rad.
    pub offset: f64,
    /// Noise, rad (identified from the record if absent).
    pub noise: Option<f64>,
}

impl Default for Inclinometer {
    fn default() -> Self {
        Self { sample_rate: 100.0, lag: 0.3, offset: 0.0, noise: None }
    }
}

/// What the simulator's true gyro differs in (each key overrides the declared one).
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimGyro {
    /// Scale factor.
    pub scale: Option<f64>,
    /// AR(2) coefficients.
    pub ar: Option<[f64; 2]>,
    /// AR driving noise, rad/s.
    pub noise: Option<f64>,
    /// Bias at the start, rad/s.
    pub bias: Option<f64>,
    /// Bias drift, rad/s per s.
    pub bias_drift: Option<f64>,
    /// Quantisation step, rad/s.
    pub quantum: Option<f64>,
}

/// What the simulator's true inclinometer differs in.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimInclinometer {
    /// First-order time constant, s.
    pub lag: Option<f64>,
    /// Offset, rad.
    pub offset: Option<f64>,
    /// Noise, rad.
    pub noise: Option<f64>,
    /// Quantisation step, rad.
    pub quantum: Option<f64>,
}

/// The boom's sideways bending, out of the luffing plane, which the estimators do not model:
/// wind drives it, and a gyro whose axis leans toward it reads a share of it.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SimLateral {
    /// The sections' sideways EI over their EI in the luffing plane (a ladder is wider than
    /// it is deep).
    pub ei_factor: f64,
    /// RMS of the wind's sideways load per unit of the boom's mass, m/s² (a first-order
    /// process with a 1 s correlation time).
    pub gust: f64,
    /// How far the gyro's axis leans toward the sideways rotation, rad.
    pub misalignment: f64,
}

/// The simulator's own keys.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimTable {
    /// The true gyro.
    pub gyro: SimGyro,
    /// The true inclinometer.
    pub inclinometer: SimInclinometer,
    /// The boom's sideways bending (absent: none).
    pub lateral: Option<SimLateral>,
}

/// The luffing drive: the operator's commanded rate followed with a first-order lag and an
/// acceleration limit (a sharp stop excites the boom).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct Drive {
    /// Time constant of the rate's response, s.
    pub lag: f64,
    /// Largest luffing acceleration, rad/s².
    pub max_accel: f64,
}

impl Default for Drive {
    fn default() -> Self {
        Self { lag: 0.15, max_accel: 0.3 }
    }
}

/// The test runs: luffing stops at full length, and a run that telescopes while luffing.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct Runs {
    /// Boom length of the luffing run and at the end of the extension, m.
    pub length: f64,
    /// Boom length at the start of the extension, m.
    pub extension_from: f64,
    /// Telescoping rate, m/s.
    pub extension_rate: f64,
    /// Luffing rate the operator commands, rad/s.
    pub luff_rate: f64,
    /// How long each luffing move lasts, s.
    pub luff_time: f64,
    /// How long the boom rests after a stop, s (its free decay).
    pub rest_time: f64,
    /// Luffing angle at the start, rad from the horizontal.
    pub start_angle: f64,
}

impl Default for Runs {
    fn default() -> Self {
        Self {
            length: 30.0,
            extension_from: 18.0,
            extension_rate: 0.1,
            luff_rate: 0.05,
            luff_time: 4.0,
            rest_time: 12.0,
            start_angle: 0.5,
        }
    }
}

/// How far the residual loop may take what it fits (`edgekf loop boom`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct Bounds {
    /// Longest first-order lag of a sensor, s.
    pub lag: f64,
}

impl Default for Bounds {
    fn default() -> Self {
        Self { lag: 1.0 }
    }
}

/// The whole configuration.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BoomConfig {
    /// Sections from the root up.
    pub section: Vec<Section>,
    /// The boom as a whole.
    #[serde(default)]
    pub boom: BoomTable,
    /// The tip's platform.
    #[serde(default)]
    pub tip: Tip,
    /// Damping of modes 1 and 2.
    #[serde(default)]
    pub damping: Damping,
    /// The gyro as declared.
    #[serde(default)]
    pub gyro: Gyro,
    /// The inclinometer as declared.
    #[serde(default)]
    pub inclinometer: Inclinometer,
    /// The true sensors of `boom simulate`.
    #[serde(default)]
    pub sim: SimTable,
    /// The luffing drive.
    #[serde(default)]
    pub drive: Drive,
    /// The test runs.
    #[serde(default)]
    pub runs: Runs,
    /// The residual loop's bounds.
    #[serde(default)]
    pub bounds: Bounds,
}

impl Default for BoomConfig {
    /// `boom_ladder30.toml`.
    fn default() -> Self {
        Self::from_toml_str(LADDER30).expect("the shipped configuration is valid")
    }
}

impl BoomConfig {
    /// Parses and validates a configuration text.
    pub fn from_toml_str(text: &str) -> Result<Self> {
        let c: BoomConfig = crate::io::config::parse_toml(text)?;
        c.validate()?;
        Ok(c)
    }

    /// Reads, parses and validates a configuration file; messages name the file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
        Self::from_toml_str(&text).with_context(|| format!("{}", path.display()))
    }

    /// The shortest length the sections allow (all retracted: the longest section) and the
    /// longest (each overlapping the next by a tenth of the shorter), m.
    pub fn length_range(&self) -> (f64, f64) {
        let longest = self.section.iter().map(|s| s.length).fold(0.0, f64::max);
        let n = self.section.len();
        let top = self.section.last().map_or(0.0, |s| s.length);
        let e_max = self.section.windows(2).map(|w| 0.9 * w[0].length.min(w[1].length)).fold(f64::INFINITY, f64::min);
        let max = if n > 1 { top + (n - 1) as f64 * e_max } else { top };
        (longest.min(max), max)
    }

    /// The constants the shared estimators' reduced boom is built from.
    pub fn constants(&self) -> Result<edgekf::systems::boom::BoomConstants> {
        use edgekf::systems::boom::{BoomConstants, BoomSection, MAX_SECTIONS};
        if self.section.len() > MAX_SECTIONS {
            bail!("{} sections: the estimators take at most {MAX_SECTIONS}", self.section.len());
        }
        let mut sections = [BoomSection { length: 1.0, ei: 1.0, mass_per_length: 1.0 }; MAX_SECTIONS];
        for (s, c) in sections.iter_mut().zip(&self.section) {
            *s = BoomSection { length: c.length, ei: c.ei, mass_per_length: c.mass_per_length };
        }
        Ok(BoomConstants {
            sections,
            count: self.section.len(),
            tip_mass: self.tip.mass,
            tip_inertia: self.tip.rotary_inertia,
            gravity: self.boom.gravity,
        })
    }

    /// Checks every figure; the message names the key.
    pub fn validate(&self) -> Result<()> {
        let positive =
            |k: String, v: f64| if v.is_finite() && v > 0.0 { Ok(()) } else { bail!("{k} = {v} must be positive") };
        let not_negative = |k: &str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                bail!("{k} = {v} must be finite and not negative")
            }
        };
        if self.section.is_empty() {
            bail!("no [[section]]: a boom needs at least one");
        }
        for (i, s) in self.section.iter().enumerate() {
            positive(format!("section[{i}].length"), s.length)?;
            positive(format!("section[{i}].ei"), s.ei)?;
            positive(format!("section[{i}].mass_per_length"), s.mass_per_length)?;
        }
        if !(4..=200).contains(&self.boom.elements) {
            bail!("boom.elements = {} must be 4 to 200", self.boom.elements);
        }
        positive("boom.gravity".into(), self.boom.gravity)?;
        not_negative("tip.mass", self.tip.mass)?;
        not_negative("tip.rotary_inertia", self.tip.rotary_inertia)?;
        let z = self.damping.zeta;
        if !(z.iter().all(|v| v.is_finite() && *v > 0.0 && *v < 1.0)) {
            bail!("damping.zeta = {z:?}: each must lie in (0, 1)");
        }
        positive("gyro.sample_rate".into(), self.gyro.sample_rate)?;
        positive("gyro.scale".into(), self.gyro.scale)?;
        positive("inclinometer.sample_rate".into(), self.inclinometer.sample_rate)?;
        if (self.gyro.sample_rate - self.inclinometer.sample_rate).abs() > 1e-9 {
            bail!(
                "gyro.sample_rate = {} and inclinometer.sample_rate = {} must be equal (one row per sample)",
                self.gyro.sample_rate,
                self.inclinometer.sample_rate
            );
        }
        not_negative("inclinometer.lag", self.inclinometer.lag)?;
        positive("bounds.lag".into(), self.bounds.lag)?;
        if !self.inclinometer.offset.is_finite() {
            bail!("inclinometer.offset must be finite");
        }
        for (k, ar) in [("gyro.ar", self.gyro.ar), ("sim.gyro.ar", self.sim.gyro.ar)] {
            if let Some([a1, a2]) = ar {
                // Stationary AR(2): |a2| < 1, a2 ± a1 < 1.
                if !(a1.is_finite() && a2.is_finite() && a2.abs() < 1.0 && a2 + a1 < 1.0 && a2 - a1 < 1.0) {
                    bail!("{k} = [{a1}, {a2}] is not a stationary AR(2)");
                }
            }
        }
        let optional = [
            ("gyro.noise", self.gyro.noise),
            ("gyro.bias", self.gyro.bias.map(f64::abs)),
            ("inclinometer.noise", self.inclinometer.noise),
            ("sim.gyro.noise", self.sim.gyro.noise),
            ("sim.gyro.bias", self.sim.gyro.bias.map(f64::abs)),
            ("sim.gyro.bias_drift", self.sim.gyro.bias_drift.map(f64::abs)),
            ("sim.gyro.quantum", self.sim.gyro.quantum),
            ("sim.inclinometer.lag", self.sim.inclinometer.lag),
            ("sim.inclinometer.offset", self.sim.inclinometer.offset.map(f64::abs)),
            ("sim.inclinometer.noise", self.sim.inclinometer.noise),
            ("sim.inclinometer.quantum", self.sim.inclinometer.quantum),
        ];
        for (k, v) in optional {
            if let Some(v) = v {
                not_negative(k, v)?;
            }
        }
        if let Some(s) = self.sim.gyro.scale {
            positive("sim.gyro.scale".into(), s)?;
        }
        if let Some(l) = self.sim.lateral {
            positive("sim.lateral.ei_factor".into(), l.ei_factor)?;
            not_negative("sim.lateral.gust", l.gust)?;
            if !(l.misalignment.is_finite() && l.misalignment.abs() < 0.5) {
                bail!("sim.lateral.misalignment = {} rad must lie within ±0.5", l.misalignment);
            }
        }
        positive("drive.lag".into(), self.drive.lag)?;
        positive("drive.max_accel".into(), self.drive.max_accel)?;
        let r = &self.runs;
        for (k, v) in [
            ("runs.length", r.length),
            ("runs.extension_from", r.extension_from),
            ("runs.extension_rate", r.extension_rate),
            ("runs.luff_rate", r.luff_rate),
            ("runs.luff_time", r.luff_time),
            ("runs.rest_time", r.rest_time),
        ] {
            positive(k.into(), v)?;
        }
        if !(r.start_angle.is_finite() && r.start_angle.abs() < 1.5) {
            bail!("runs.start_angle = {} must lie within ±1.5 rad", r.start_angle);
        }
        let (lo, hi) = self.length_range();
        for (k, v) in [("runs.length", r.length), ("runs.extension_from", r.extension_from)] {
            if v < lo - 1e-9 || v > hi + 1e-9 {
                bail!("{k} = {v} m: the sections allow {lo:.3} to {hi:.3} m");
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sideways_boom_is_read_and_checked() {
        let with = |table: &str| BoomConfig::from_toml_str(&format!("{LADDER30}\n[sim.lateral]\n{table}"));
        let c = with("ei_factor = 2.5\ngust = 1.0\nmisalignment = 0.05\n").unwrap();
        assert_eq!(c.sim.lateral, Some(SimLateral { ei_factor: 2.5, gust: 1.0, misalignment: 0.05 }));
        let e = with("ei_factor = 2.5\ngust = 1.0\nmisalignment = 0.7\n").unwrap_err();
        assert!(e.to_string().contains("sim.lateral.misalignment"), "{e}");
        let e = with("ei_factor = 0.0\ngust = 1.0\nmisalignment = 0.0\n").unwrap_err();
        assert!(e.to_string().contains("sim.lateral.ei_factor"), "{e}");
        // Every key is needed once the table is there.
        assert!(with("ei_factor = 2.5\n").is_err());
        assert_eq!(BoomConfig::default().sim.lateral, None);
    }
}
