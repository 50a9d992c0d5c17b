//! The rotor configuration file (TOML): shaft, disks, point masses, bearings, unbalances,
//! sensors and operating point, with every unit in SI except `phase_deg`.
//!
//! Normative keys (what the rotor paper gives) are required; every other key has the default
//! documented on its field. Unknown keys are refused, so a typo cannot silently fall back to a
//! default. Numbers are checked after parsing ([`RotorConfig::validate`]) and every message names
//! the offending entry, e.g. `disk[1].node = 40 is out of range: the shaft has nodes 0..=37`.
//!
//! ```
//! use edgekf_sim::systems::rotor::RotorConfig;
//! let cfg = RotorConfig::from_toml_str(r#"
//!     [shaft]
//!     length = 1.0
//!     elements = 10
//!     diameter = 0.02
//!     young = 2.1e11
//!     density = 7850.0
//!     poisson = 0.3
//!     [[bearing]]
//!     node = 0
//!     kxx = 1e8
//!     kyy = 1e8
//!     [[bearing]]
//!     node = 10
//!     kxx = 1e8
//!     kyy = 1e8
//! "#).unwrap();
//! assert_eq!(cfg.n_nodes(), 11);
//! assert_eq!(cfg.operation.sample_rate, 1000.0); // default
//! let err = RotorConfig::from_toml_str("[shaft]\nlenght = 1.0\n").unwrap_err();
//! assert!(err.to_string().contains("unknown field `lenght`"), "{err}");
//! ```

mod check;
mod sensor;

pub use self::sensor::{AccelerometerConfig, Direction, SensorConfig, SensorKind};
use super::bearing_geometry::BearingGeometry;
use super::RotorError;
use serde::Deserialize;
use std::path::Path;

/// Most shaft elements a model may have: the matrices are dense, and the eigen decomposition of
/// the 8·(elements+1) state matrix costs its size cubed (500 elements: a 4008² matrix, ~1 min).
pub const MAX_ELEMENTS: usize = 500;

/// A whole rotor and how it is run and measured.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotorConfig {
    /// The shaft (`[shaft]`).
    pub shaft: ShaftConfig,
    /// Rigid disks (`[[disk]]`).
    #[serde(default, rename = "disk")]
    pub disks: Vec<DiskConfig>,
    /// Point masses (`[[mass]]`), e.g. a coupling.
    #[serde(default, rename = "mass")]
    pub masses: Vec<PointMassConfig>,
    /// Linear bearings (`[[bearing]]`).
    #[serde(default, rename = "bearing")]
    pub bearings: Vec<BearingConfig>,
    /// Unbalances (`[[unbalance]]`).
    #[serde(default, rename = "unbalance")]
    pub unbalances: Vec<UnbalanceConfig>,
    /// Sensors (`[[sensor]]`), in the order of the data file's channels.
    #[serde(default, rename = "sensor")]
    pub sensors: Vec<SensorConfig>,
    /// Operating point (`[operation]`); default: standstill, 1 kHz.
    #[serde(default)]
    pub operation: OperationConfig,
    /// Noise levels of the virtual-sensing filter for this machine (`[filter]`); default: the
    /// built-in tuning's.
    #[serde(default)]
    pub filter: FilterConfig,
    /// How gaps in a recording's time column are bridged (`[timeline]`).
    #[serde(default)]
    pub timeline: crate::io::timeline::TimelineOptions,
    /// What the residual loop allows an effect to be (`[bounds]`; the force's default is the
    /// rotor's [`weight`](RotorConfig::weight)).
    #[serde(default)]
    pub bounds: crate::systems::rotor::bounds::Bounds,
    /// How the report grades the housings' vibration (`[severity]`); default: velocity only.
    #[serde(default)]
    pub severity: SeverityConfig,
}

/// The machine's class for the vibration zones (`[severity] machine_class = "group2_rigid"`;
/// also `group2_flexible`, `group1_rigid`, `group1_flexible` of ISO 20816-3, and
/// `class1_small` for machines up to 15 kW). Without it the report gives the
/// housings' vibration velocity and no zone: the zone's boundaries depend on the class.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SeverityConfig {
    /// The class, if known.
    pub machine_class: Option<crate::diagnostics::severity::MachineClass>,
}

/// The virtual-sensing filter's noise levels for a machine (`[filter]`), e.g. from `edgekf
/// rotor tune` on a healthy recording. They are declared, not fitted by the residual loop: a
/// filter whose noise is fitted to the data it diagnoses absorbs what it should reveal.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FilterConfig {
    /// Spectral density of unmodelled modal acceleration, (m/s²)² kg / s (modal units).
    pub modal_psd: Option<f64>,
    /// Spectral density of the force states' random walk, N²/s.
    pub force_psd: Option<f64>,
}

/// The shaft: one material, one or more uniform sections laid end to end from z = 0.
///
/// In TOML either one uniform shaft (`length`, `elements`, `diameter`, optional
/// `inner_diameter`) or a list `[[shaft.section]]` of `{length, elements, diameter,
/// inner_diameter}`; not both.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(try_from = "ShaftToml")]
pub struct ShaftConfig {
    /// Uniform sections from z = 0 on; node numbering runs through them without gaps.
    pub sections: Vec<ShaftSection>,
    /// Young's modulus E, Pa.
    pub young: f64,
    /// Density ρ, kg/m³.
    pub density: f64,
    /// Poisson's ratio ν; the shear modulus is `E / (2 (1 + ν))`.
    pub poisson: f64,
    /// Shear coefficient κ; default (`None`): Cowper's for the section (as ROSS).
    pub shear_factor: Option<f64>,
    /// Include shear deformation (Timoshenko); default true. False gives Rayleigh beams.
    pub shear_deformation: bool,
    /// Include the rotary inertia of the cross-section; default true.
    pub rotary_inertia: bool,
    /// Include the shaft's gyroscopic matrix; default true.
    pub gyroscopic: bool,
    /// Rayleigh damping of the shaft elements, `C_e = α M_e + β K_e`: α in 1/s; default 0.
    /// Applied as stationary damping (no rotating-damping circulatory terms), as in ROSS.
    pub damping_alpha: f64,
    /// Rayleigh damping β in s; default 0.
    pub damping_beta: f64,
}

/// One uniform section of the shaft.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShaftSection {
    /// Length, m.
    pub length: f64,
    /// Number of equal elements.
    pub elements: usize,
    /// Outer diameter, m.
    pub diameter: f64,
    /// Inner diameter, m; default 0 (solid).
    #[serde(default)]
    pub inner_diameter: f64,
}

/// The shaft as written in TOML (uniform keys or sections), before it is normalised.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ShaftToml {
    length: Option<f64>,
    elements: Option<usize>,
    diameter: Option<f64>,
    inner_diameter: Option<f64>,
    #[serde(default, rename = "section")]
    sections: Vec<ShaftSection>,
    young: f64,
    density: f64,
    poisson: f64,
    shear_factor: Option<f64>,
    #[serde(default = "yes")]
    shear_deformation: bool,
    #[serde(default = "yes")]
    rotary_inertia: bool,
    #[serde(default = "yes")]
    gyroscopic: bool,
    #[serde(default)]
    damping_alpha: f64,
    #[serde(default)]
    damping_beta: f64,
}

fn yes() -> bool {
    true
}

impl TryFrom<ShaftToml> for ShaftConfig {
    type Error = String;

    fn try_from(s: ShaftToml) -> Result<Self, String> {
        let uniform = [s.length.is_some(), s.elements.is_some(), s.diameter.is_some(), s.inner_diameter.is_some()];
        let sections = if s.sections.is_empty() {
            match (s.length, s.elements, s.diameter) {
                (Some(length), Some(elements), Some(diameter)) => {
                    vec![ShaftSection { length, elements, diameter, inner_diameter: s.inner_diameter.unwrap_or(0.0) }]
                }
                _ => {
                    let missing: Vec<&str> = [("length", s.length.is_none()), ("elements", s.elements.is_none())]
                        .into_iter()
                        .chain([("diameter", s.diameter.is_none())])
                        .filter(|(_, m)| *m)
                        .map(|(n, _)| n)
                        .collect();
                    return Err(format!(
                        "shaft: missing {} (give length, elements and diameter, or a list of [[shaft.section]])",
                        missing.join(", ")
                    ));
                }
            }
        } else if uniform.iter().any(|&u| u) {
            return Err("shaft: give either length/elements/diameter or [[shaft.section]], not both".into());
        } else {
            s.sections
        };
        Ok(Self {
            sections,
            young: s.young,
            density: s.density,
            poisson: s.poisson,
            shear_factor: s.shear_factor,
            shear_deformation: s.shear_deformation,
            rotary_inertia: s.rotary_inertia,
            gyroscopic: s.gyroscopic,
            damping_alpha: s.damping_alpha,
            damping_beta: s.damping_beta,
        })
    }
}

impl ShaftConfig {
    /// A uniform solid shaft with the defaults (Timoshenko, Cowper's κ, no damping).
    pub fn uniform(length: f64, elements: usize, diameter: f64, young: f64, density: f64, poisson: f64) -> Self {
        Self {
            sections: vec![ShaftSection { length, elements, diameter, inner_diameter: 0.0 }],
            young,
            density,
            poisson,
            shear_factor: None,
            shear_deformation: true,
            rotary_inertia: true,
            gyroscopic: true,
            damping_alpha: 0.0,
            damping_beta: 0.0,
        }
    }

    /// Number of elements over all sections.
    pub fn elements(&self) -> usize {
        self.sections.iter().map(|s| s.elements).sum()
    }

    /// Total length, m.
    pub fn length(&self) -> f64 {
        self.sections.iter().map(|s| s.length).sum()
    }
}

/// A rigid disk on a node: a solid disk of the given mass, diameter and width, unless its
/// inertias are given.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiskConfig {
    /// Node index.
    pub node: usize,
    /// Mass, kg.
    pub mass: f64,
    /// Outer diameter, m.
    pub diameter: f64,
    /// Axial width, m.
    pub width: f64,
    /// Polar moment of inertia, kg·m²; default `m D²/8`.
    pub ip: Option<f64>,
    /// Diametral moment of inertia, kg·m²; default `m D²/16 + m w²/12`.
    pub id: Option<f64>,
}

/// A point mass with optional inertias on a node (`[[mass]] node, mass, ip, id`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointMassConfig {
    /// Node index.
    pub node: usize,
    /// Mass, kg.
    pub mass: f64,
    /// Polar moment of inertia, kg·m²; default 0.
    #[serde(default)]
    pub ip: f64,
    /// Diametral moment of inertia, kg·m²; default 0.
    #[serde(default)]
    pub id: f64,
}

/// A linear bearing on a node. The force on the shaft is `−K [x, y]ᵀ − C [ẋ, ẏ]ᵀ` with
/// `K = [[kxx, kxy], [kyx, kyy]]`, `C = [[cxx, cxy], [cyx, cyy]]`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BearingConfig {
    /// Node index.
    pub node: usize,
    /// Direct stiffness in x, N/m.
    pub kxx: f64,
    /// Direct stiffness in y, N/m.
    pub kyy: f64,
    /// Cross stiffness (force in x per y displacement), N/m; default 0.
    #[serde(default)]
    pub kxy: f64,
    /// Cross stiffness (force in y per x displacement), N/m; default 0.
    #[serde(default)]
    pub kyx: f64,
    /// Direct damping in x, N·s/m; default 0.
    #[serde(default)]
    pub cxx: f64,
    /// Direct damping in y, N·s/m; default 0.
    #[serde(default)]
    pub cyy: f64,
    /// Cross damping, N·s/m; default 0.
    #[serde(default)]
    pub cxy: f64,
    /// Cross damping, N·s/m; default 0.
    #[serde(default)]
    pub cyx: f64,
    /// Rolling-element geometry, if the bearing is one (used to name defect lines in the
    /// residual loop); default none.
    #[serde(default)]
    pub geometry: Option<BearingGeometry>,
}

/// An unbalance `U = m e` at a node: `F_x = U Ω² cos(Ωt + φ)`, `F_y = U Ω² sin(Ωt + φ)`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UnbalanceConfig {
    /// Node index.
    pub node: usize,
    /// `m e`, kg·m.
    pub magnitude: f64,
    /// Phase φ, degrees; default 0.
    #[serde(default)]
    pub phase_deg: f64,
}

/// The operating point.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OperationConfig {
    /// Rotor speed Ω, rad/s (positive: rotation from x toward y); default 0.
    pub speed: f64,
    /// Output sample rate, Hz; default 1000.
    pub sample_rate: f64,
}

impl Default for OperationConfig {
    fn default() -> Self {
        Self { speed: 0.0, sample_rate: 1000.0 }
    }
}

impl RotorConfig {
    /// Parses and validates a configuration.
    pub fn from_toml_str(text: &str) -> Result<Self, RotorError> {
        let cfg: RotorConfig = crate::io::config::parse_toml(text)
            .map_err(|e| RotorError::Config { origin: None, message: e.to_string() })?;
        cfg.validate()?;
        cfg.timeline.validate().map_err(|message| RotorError::Config { origin: None, message })?;
        cfg.bounds.validate().map_err(|message| RotorError::Config { origin: None, message })?;
        Ok(cfg)
    }

    /// The rotor's weight, N: its [`mass`](RotorConfig::mass) under standard gravity (the
    /// default bound of a force the residual loop may add).
    pub fn weight(&self) -> f64 {
        9.80665 * self.mass()
    }

    /// The rotor's mass, kg: shaft, disks and point masses (the default bound of a point mass
    /// the residual loop may add is a share of it).
    pub fn mass(&self) -> f64 {
        let shaft: f64 = self
            .shaft
            .sections
            .iter()
            .map(|s| std::f64::consts::FRAC_PI_4 * (s.diameter.powi(2) - s.inner_diameter.powi(2)) * s.length)
            .sum::<f64>()
            * self.shaft.density;
        let disks: f64 = self.disks.iter().map(|d| d.mass).sum();
        let masses: f64 = self.masses.iter().map(|m| m.mass).sum();
        shaft + disks + masses
    }

    /// Reads, parses and validates a configuration file; errors name the file.
    pub fn load(path: &Path) -> Result<Self, RotorError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| RotorError::Io { path: path.to_owned(), reason: e.to_string() })?;
        Self::from_toml_str(&text).map_err(|e| e.in_file(path))
    }

    /// Number of nodes: elements + 1, numbered 0.. from z = 0.
    pub fn n_nodes(&self) -> usize {
        self.shaft.elements() + 1
    }

    /// Nodes that carry an unbalance, in configuration order (the `truth_f<k>_*` columns).
    pub fn unbalance_nodes(&self) -> Vec<usize> {
        self.unbalances.iter().map(|u| u.node).collect()
    }

    /// Checks every figure; the message names the offending entry.
    pub fn validate(&self) -> Result<(), RotorError> {
        self.check().map_err(|message| RotorError::Config { origin: None, message })
    }
}
