//! The structural family: a declared component parameter off by a factor, and a point mass the
//! configuration does not declare. Both change the configuration itself, and the rotor is
//! reduced anew from it ([`apply_parameters`]).

use super::Effect;
use crate::systems::rotor::config::PointMassConfig;
use crate::systems::rotor::RotorConfig;
use anyhow::{anyhow, bail, Result};

/// A component of the rotor whose declared parameter may be wrong.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Parameter {
    /// Mass of disk `i` (configuration order); its inertias scale with it.
    DiskMass(usize),
    /// Young's modulus of the shaft (its bending stiffness).
    ShaftYoung,
    /// Density of the shaft (its mass).
    ShaftDensity,
    /// Direct stiffness `kxx` of bearing `i`.
    BearingKxx(usize),
    /// Direct stiffness `kyy` of bearing `i`.
    BearingKyy(usize),
    /// Direct damping `cxx` of bearing `i`.
    BearingCxx(usize),
    /// Direct damping `cyy` of bearing `i`.
    BearingCyy(usize),
}

impl Parameter {
    /// Every parameter of `cfg` the library can correct (damping only where it is declared
    /// non-zero: a factor on zero means nothing).
    pub fn all(cfg: &RotorConfig) -> Vec<Parameter> {
        let mut out: Vec<Parameter> = (0..cfg.disks.len()).map(Parameter::DiskMass).collect();
        out.extend([Parameter::ShaftYoung, Parameter::ShaftDensity]);
        for (i, b) in cfg.bearings.iter().enumerate() {
            out.extend([Parameter::BearingKxx(i), Parameter::BearingKyy(i)]);
            if b.cxx > 0.0 {
                out.push(Parameter::BearingCxx(i));
            }
            if b.cyy > 0.0 {
                out.push(Parameter::BearingCyy(i));
            }
        }
        out
    }

    /// The parameter's name in the report (`mass`, `young`, `kxx`, …).
    pub fn name(self) -> &'static str {
        match self {
            Parameter::DiskMass(_) => "mass",
            Parameter::ShaftYoung => "young",
            Parameter::ShaftDensity => "density",
            Parameter::BearingKxx(_) => "kxx",
            Parameter::BearingKyy(_) => "kyy",
            Parameter::BearingCxx(_) => "cxx",
            Parameter::BearingCyy(_) => "cyy",
        }
    }

    /// The component, as the report names it (`disk 12`, `shaft`, `bearing 4`: by node).
    pub fn component(self, cfg: &RotorConfig) -> String {
        let node = |n: Option<usize>| n.map_or("?".to_string(), |n| n.to_string());
        match self {
            Parameter::DiskMass(i) => format!("disk {}", node(cfg.disks.get(i).map(|d| d.node))),
            Parameter::ShaftYoung | Parameter::ShaftDensity => "shaft".to_string(),
            Parameter::BearingKxx(i)
            | Parameter::BearingKyy(i)
            | Parameter::BearingCxx(i)
            | Parameter::BearingCyy(i) => {
                format!("bearing {}", node(cfg.bearings.get(i).map(|b| b.node)))
            }
        }
    }

    /// The configuration's keys that [`apply`](Self::apply) multiplies, as key paths of
    /// [`config_edit`](crate::io::config_edit) (a disk's declared inertias follow its mass).
    ///
    /// ```
    /// use edgekf_sim::systems::rotor::loop_system::effects::Parameter;
    /// use edgekf_sim::systems::rotor::RotorConfig;
    /// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml"));
    /// let cfg = RotorConfig::from_toml_str(text).unwrap();
    /// assert_eq!(Parameter::DiskMass(0).keys(&cfg), vec!["disk[node=12].mass".to_string()]);
    /// assert_eq!(Parameter::BearingKyy(1).keys(&cfg), vec!["bearing[node=33].kyy".to_string()]);
    /// ```
    pub fn keys(self, cfg: &RotorConfig) -> Vec<String> {
        let bearing = |i: usize, key: &str| cfg.bearings.get(i).map(|b| format!("bearing[node={}].{key}", b.node));
        match self {
            Parameter::DiskMass(i) => cfg.disks.get(i).map_or_else(Vec::new, |d| {
                let declared = [("mass", Some(d.mass)), ("ip", d.ip), ("id", d.id)];
                declared
                    .iter()
                    .filter(|(_, v)| v.is_some())
                    .map(|(k, _)| format!("disk[node={}].{k}", d.node))
                    .collect()
            }),
            Parameter::ShaftYoung => vec!["shaft.young".into()],
            Parameter::ShaftDensity => vec!["shaft.density".into()],
            Parameter::BearingKxx(i) => bearing(i, "kxx").into_iter().collect(),
            Parameter::BearingKyy(i) => bearing(i, "kyy").into_iter().collect(),
            Parameter::BearingCxx(i) => bearing(i, "cxx").into_iter().collect(),
            Parameter::BearingCyy(i) => bearing(i, "cyy").into_iter().collect(),
        }
    }

    /// Multiplies the parameter in `cfg` by `factor`.
    pub fn apply(self, cfg: &mut RotorConfig, factor: f64) -> Result<()> {
        if !(factor.is_finite() && factor > 0.0) {
            bail!("a parameter factor must be positive and finite, not {factor}");
        }
        let missing = || anyhow!("the configuration has no component for {self:?}");
        match self {
            Parameter::DiskMass(i) => {
                let d = cfg.disks.get_mut(i).ok_or_else(missing)?;
                // The inertias follow the mass (a solid disk's are proportional to it; declared
                // ones are scaled alike).
                d.mass *= factor;
                d.ip = d.ip.map(|v| v * factor);
                d.id = d.id.map(|v| v * factor);
            }
            Parameter::ShaftYoung => cfg.shaft.young *= factor,
            Parameter::ShaftDensity => cfg.shaft.density *= factor,
            Parameter::BearingKxx(i) => cfg.bearings.get_mut(i).ok_or_else(missing)?.kxx *= factor,
            Parameter::BearingKyy(i) => cfg.bearings.get_mut(i).ok_or_else(missing)?.kyy *= factor,
            Parameter::BearingCxx(i) => cfg.bearings.get_mut(i).ok_or_else(missing)?.cxx *= factor,
            Parameter::BearingCyy(i) => cfg.bearings.get_mut(i).ok_or_else(missing)?.cyy *= factor,
        }
        Ok(())
    }
}

/// The configuration with the effects of `effects` that change it applied: a `Parameter`'s
/// factor and a `PointMass`'s mass (their scalar is the log of either).
pub fn apply_parameters(cfg: &RotorConfig, effects: &[(Effect, f64)]) -> Result<RotorConfig> {
    let mut out = cfg.clone();
    for &(e, theta) in effects {
        match e {
            Effect::Parameter(p) => p.apply(&mut out, theta.exp())?,
            Effect::PointMass { node } => {
                let mass = theta.exp();
                if !(mass.is_finite() && mass > 0.0) {
                    bail!("a point mass must be positive and finite, not {mass} kg");
                }
                out.masses.push(PointMassConfig { node, mass, ip: 0.0, id: 0.0 });
            }
            _ => {}
        }
    }
    Ok(out)
}
