//! The slider-crank configuration: mechanism, release, contact material, sensor, integrator
//! and the estimator's `[timeline]`, read from TOML (`host-sim/configs/crank_paper.toml` is the
//! paper's case written out).
//!
//! Every table may be left out and then takes the paper's values; inside `[crank]` and `[rod]`
//! all three numbers are required (a bar half described is more likely a typo than a wish).
//! Unknown keys are refused with the key's name, so a misspelt `restitusion` cannot silently
//! fall back to a default.
//!
//! ```
//! use edgekf_sim::systems::crank::CrankConfig;
//! let c = CrankConfig::from_toml_str("[contact]\nrestitution = 0.8\n").unwrap();
//! assert_eq!(c.contact.restitution, 0.8);
//! assert_eq!(c.rod.length, 0.12); // untouched tables keep the paper's values
//! let err = CrankConfig::from_toml_str("[contact]\nrestitusion = 0.8\n").unwrap_err();
//! assert!(err.to_string().contains("restitusion"));
//! // `crank estimate` bridges gaps in `t` up to `[timeline] max_gap_s` (default 2 s).
//! assert_eq!(CrankConfig::from_toml_str("[timeline]\nmax_gap_s = 0.5\n").unwrap().timeline.max_gap_s, 0.5);
//! let err = CrankConfig::from_toml_str("[timeline]\nmax_gap_s = -1\n").unwrap_err();
//! assert!(err.to_string().contains("timeline.max_gap_s"));
//! ```

use super::error::CrankError;
use super::Joint;
use crate::io::timeline::TimelineOptions;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A rigid bar between two joints, centre of mass at mid-length.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BarConfig {
    /// Mass, kg.
    pub mass: f64,
    /// Distance between the two joint centres, m.
    pub length: f64,
    /// Moment of inertia about the centre of mass, kg·m².
    pub inertia: f64,
}

/// The slider on its guide.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct SliderConfig {
    /// Mass, kg. The guide is horizontal, frictionless and passes through the crank's ground
    /// joint A, so the slider's weight is carried by the guide and does no work.
    pub mass: f64,
}

impl Default for SliderConfig {
    /// The paper's 0.14 kg.
    fn default() -> Self {
        Self { mass: 0.14 }
    }
}

/// Gravity.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct WorldConfig {
    /// Gravitational acceleration, m/s², perpendicular to the guide (pointing to −y; the guide
    /// is the x axis).
    pub gravity: f64,
}

impl Default for WorldConfig {
    /// 9.81 m/s², as in the paper.
    fn default() -> Self {
        Self { gravity: 9.81 }
    }
}

/// How the mechanism starts.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct ReleaseConfig {
    /// Crank angle at release, degrees, from the guide direction (+x, towards the slider),
    /// counter-clockwise. The mechanism starts at rest with every journal centred in its
    /// bearing, so each clearance joint first falls freely across part of its clearance.
    pub crank_angle_deg: f64,
}

impl Default for ReleaseConfig {
    /// 30°.
    fn default() -> Self {
        Self { crank_angle_deg: 30.0 }
    }
}

/// Material and geometry of the clearance joints (journal in bearing), and the contact law's
/// numerical choices.
///
/// The Hertz stiffness of a joint follows from the material, its journal radius `R` and its
/// radial clearance `c` (bearing radius `R + c`), see
/// [`hertz_stiffness`](super::contact::hertz_stiffness).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct ContactConfig {
    /// Coefficient of restitution of the Lankarani–Nikravesh hysteresis damping, (0, 1].
    pub restitution: f64,
    /// Young's modulus of journal and bearing, Pa.
    pub young: f64,
    /// Poisson's ratio of journal and bearing.
    pub poisson: f64,
    /// Journal radius of every joint, m (the paper does not give it; 10 mm is our choice).
    pub journal_radius: f64,
    /// Journal radius of joint A, m, overriding `journal_radius`.
    #[serde(rename = "journal_radius_A", skip_serializing_if = "Option::is_none")]
    pub journal_radius_a: Option<f64>,
    /// Journal radius of joint B, m, overriding `journal_radius`.
    #[serde(rename = "journal_radius_B", skip_serializing_if = "Option::is_none")]
    pub journal_radius_b: Option<f64>,
    /// Journal radius of joint C, m, overriding `journal_radius`.
    #[serde(rename = "journal_radius_C", skip_serializing_if = "Option::is_none")]
    pub journal_radius_c: Option<f64>,
    /// Floor on the impact velocity `δ̇⁻` that divides the hysteresis damping, m/s.
    ///
    /// The Lankarani–Nikravesh damping coefficient is `3 K (1 − e²) δ^1.5 / (4 δ̇⁻)`: a grazing
    /// contact (`δ̇⁻ → 0`) would get an unbounded damping coefficient, which is not physics but
    /// an artefact of the model, and which makes any explicit integrator unstable. Impacts
    /// slower than this floor are damped as if they came at this speed (slightly more elastic
    /// than the model says). 1 mm/s is 1–2 % of a typical impact speed with 0.25 mm clearance.
    pub min_impact_velocity: f64,
}

impl Default for ContactConfig {
    /// The paper's steel (207 GPa, ν = 0.3), restitution 0.9; 10 mm journals; 1 mm/s floor.
    fn default() -> Self {
        Self {
            restitution: 0.9,
            young: 207e9,
            poisson: 0.3,
            journal_radius: 0.010,
            journal_radius_a: None,
            journal_radius_b: None,
            journal_radius_c: None,
            min_impact_velocity: 1e-3,
        }
    }
}

impl ContactConfig {
    /// Journal radius of `joint`, m (its override, or the common value).
    pub fn journal_radius_of(&self, joint: Joint) -> f64 {
        let o = match joint {
            Joint::A => self.journal_radius_a,
            Joint::B => self.journal_radius_b,
            Joint::C => self.journal_radius_c,
        };
        o.unwrap_or(self.journal_radius)
    }
}

/// The sensor on the crank: an angular accelerometer.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct SensorConfig {
    /// Standard deviation of the white measurement noise, rad/s².
    pub noise_std: f64,
    /// Sample rate, Hz. The truth is point-sampled (no anti-aliasing filter is modelled: the
    /// impacts' spectrum reaches beyond any practical rate, as for the paper's raw signal).
    pub sample_rate: f64,
}

impl Default for SensorConfig {
    /// 5 rad/s² at 10 kHz.
    fn default() -> Self {
        Self { noise_std: 5.0, sample_rate: 10_000.0 }
    }
}

/// Which integrator runs the simulation (TOML `method = "symplectic"` or `"adaptive"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Symplectic (semi-implicit) Euler at a fixed step, as in the paper.
    #[default]
    Symplectic,
    /// Dormand–Prince 5(4) with error control, dense output and located contact events.
    Adaptive,
}

/// Integrator settings.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct IntegratorConfig {
    /// Which integrator.
    pub method: Method,
    /// Step of the symplectic Euler integrator, s (the paper: 0.01 ms). Reduced, if needed, to
    /// the largest step that divides the sample period.
    pub step: f64,
    /// Relative error tolerance per step of the adaptive integrator.
    pub tolerance: f64,
    /// Largest step of the adaptive integrator, s.
    pub max_step: f64,
}

impl Default for IntegratorConfig {
    /// Symplectic Euler at 1e-5 s; adaptive at tolerance 1e-8, steps up to 1 ms.
    fn default() -> Self {
        Self { method: Method::Symplectic, step: 1e-5, tolerance: 1e-8, max_step: 1e-3 }
    }
}

/// The whole slider-crank configuration. `Default` is the paper's case.
///
/// ```
/// use edgekf_sim::systems::crank::CrankConfig;
/// let c = CrankConfig::default();
/// assert_eq!((c.crank.mass, c.crank.length, c.crank.inertia), (0.3, 0.05, 1e-5));
/// assert_eq!((c.rod.mass, c.rod.length, c.rod.inertia), (0.21, 0.12, 2.5e-4));
/// assert_eq!(c.slider.mass, 0.14);
/// assert!(c.validate().is_ok());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct CrankConfig {
    /// The crank A–B.
    pub crank: BarConfig,
    /// The connecting rod B–C.
    pub rod: BarConfig,
    /// The slider at C.
    pub slider: SliderConfig,
    /// Gravity.
    pub world: WorldConfig,
    /// Initial configuration.
    pub release: ReleaseConfig,
    /// Clearance-joint contact.
    pub contact: ContactConfig,
    /// The crank's angular accelerometer.
    pub sensor: SensorConfig,
    /// Integrator.
    pub integrator: IntegratorConfig,
    /// How `crank estimate` puts a recording with gaps in its time column on one timeline
    /// (`[timeline] max_gap_s`; see [`super::estimate::Recording::read`]).
    pub timeline: TimelineOptions,
}

impl Default for CrankConfig {
    fn default() -> Self {
        Self {
            crank: BarConfig { mass: 0.3, length: 0.05, inertia: 1e-5 },
            rod: BarConfig { mass: 0.21, length: 0.12, inertia: 2.5e-4 },
            slider: SliderConfig::default(),
            world: WorldConfig::default(),
            release: ReleaseConfig::default(),
            contact: ContactConfig::default(),
            sensor: SensorConfig::default(),
            integrator: IntegratorConfig::default(),
            timeline: TimelineOptions::default(),
        }
    }
}

fn positive(name: &str, v: f64) -> Result<(), CrankError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(CrankError::Config(format!("{name} = {v} must be a positive number")))
    }
}

impl CrankConfig {
    /// Parses and validates a configuration from TOML text.
    pub fn from_toml_str(text: &str) -> Result<Self, CrankError> {
        let c: CrankConfig = crate::io::config::parse_toml(text).map_err(|e| CrankError::Config(e.to_string()))?;
        c.validate()?;
        Ok(c)
    }

    /// Reads, parses and validates a configuration file; messages name the file.
    pub fn load(path: &Path) -> Result<Self, CrankError> {
        let text = std::fs::read_to_string(path).map_err(|reason| CrankError::Io { path: path.into(), reason })?;
        Self::from_toml_str(&text).map_err(|e| CrankError::Config(format!("{}: {e}", path.display())))
    }

    /// Checks every figure; the message names the offending key.
    pub fn validate(&self) -> Result<(), CrankError> {
        for (table, bar) in [("crank", &self.crank), ("rod", &self.rod)] {
            positive(&format!("{table}.mass"), bar.mass)?;
            positive(&format!("{table}.length"), bar.length)?;
            positive(&format!("{table}.inertia"), bar.inertia)?;
        }
        positive("slider.mass", self.slider.mass)?;
        if self.rod.length <= self.crank.length {
            return Err(CrankError::Config(format!(
                "rod.length = {} must exceed crank.length = {}: a shorter rod cannot follow a full turn of the crank",
                self.rod.length, self.crank.length
            )));
        }
        let g = self.world.gravity;
        if !(g.is_finite() && g >= 0.0) {
            return Err(CrankError::Config(format!("world.gravity = {g} must be a non-negative number")));
        }
        if !self.release.crank_angle_deg.is_finite() {
            return Err(CrankError::Config("release.crank_angle_deg must be a finite number".into()));
        }
        let c = &self.contact;
        if !(c.restitution > 0.0 && c.restitution <= 1.0) {
            return Err(CrankError::Config(format!("contact.restitution = {} must be in (0, 1]", c.restitution)));
        }
        positive("contact.young", c.young)?;
        if !(c.poisson >= 0.0 && c.poisson < 0.5) {
            return Err(CrankError::Config(format!("contact.poisson = {} must be in [0, 0.5)", c.poisson)));
        }
        positive("contact.journal_radius", c.journal_radius)?;
        for (name, v) in [
            ("contact.journal_radius_A", c.journal_radius_a),
            ("contact.journal_radius_B", c.journal_radius_b),
            ("contact.journal_radius_C", c.journal_radius_c),
        ] {
            if let Some(v) = v {
                positive(name, v)?;
            }
        }
        positive("contact.min_impact_velocity", c.min_impact_velocity)?;
        let s = &self.sensor;
        if !(s.noise_std.is_finite() && s.noise_std >= 0.0) {
            return Err(CrankError::Config(format!(
                "sensor.noise_std = {} must be a non-negative number",
                s.noise_std
            )));
        }
        positive("sensor.sample_rate", s.sample_rate)?;
        let i = &self.integrator;
        positive("integrator.step", i.step)?;
        positive("integrator.max_step", i.max_step)?;
        if !(i.tolerance > 0.0 && i.tolerance <= 1e-2) {
            return Err(CrankError::Config(format!("integrator.tolerance = {} must be in (0, 0.01]", i.tolerance)));
        }
        self.timeline.validate().map_err(CrankError::Config)
    }
}
