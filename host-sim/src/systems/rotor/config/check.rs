//! The rotor configuration's checks after parsing: every figure in range, every node on the
//! shaft, every sensor's channel unique; each message names the offending entry.

use super::{RotorConfig, SensorKind, MAX_ELEMENTS};
use std::fmt;

/// A list entry that failed validation, for messages like `disk[1].mass = -2 must be …`.
struct At<'a>(&'a str, usize);

impl fmt::Display for At<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}[{}]", self.0, self.1)
    }
}

fn positive(what: impl fmt::Display, v: f64) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("{what} = {v} must be positive"))
    }
}

fn non_negative(what: impl fmt::Display, v: f64) -> Result<(), String> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(format!("{what} = {v} must be zero or positive"))
    }
}

fn finite(what: impl fmt::Display, v: f64) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("{what} = {v} must be a finite number"))
    }
}

impl RotorConfig {
    /// Every check, in the file's order.
    pub(super) fn check(&self) -> Result<(), String> {
        self.check_shaft()?;
        self.check_parts()?;
        for (name, v) in [("filter.modal_psd", self.filter.modal_psd), ("filter.force_psd", self.filter.force_psd)] {
            if let Some(v) = v {
                positive(name, v)?;
            }
        }
        let op = &self.operation;
        finite("operation.speed", op.speed)?;
        positive("operation.sample_rate", op.sample_rate)?;
        self.check_sensors()
    }

    fn check_shaft(&self) -> Result<(), String> {
        let sh = &self.shaft;
        if sh.sections.is_empty() {
            return Err("shaft: no sections".into());
        }
        for (i, s) in sh.sections.iter().enumerate() {
            let at = |f: &str| format!("shaft.section[{i}].{f}");
            positive(at("length"), s.length)?;
            positive(at("diameter"), s.diameter)?;
            non_negative(at("inner_diameter"), s.inner_diameter)?;
            if s.inner_diameter >= s.diameter {
                return Err(format!(
                    "{} = {} must be smaller than the diameter {}",
                    at("inner_diameter"),
                    s.inner_diameter,
                    s.diameter
                ));
            }
            if s.elements == 0 {
                return Err(format!("{} must be at least 1", at("elements")));
            }
        }
        if sh.elements() > MAX_ELEMENTS {
            return Err(format!(
                "shaft: {} elements; at most {MAX_ELEMENTS} are supported (dense matrices)",
                sh.elements()
            ));
        }
        positive("shaft.young", sh.young)?;
        positive("shaft.density", sh.density)?;
        if !(sh.poisson > -1.0 && sh.poisson < 0.5) {
            return Err(format!("shaft.poisson = {} must be in (-1, 0.5)", sh.poisson));
        }
        if let Some(k) = sh.shear_factor {
            positive("shaft.shear_factor", k)?;
        }
        non_negative("shaft.damping_alpha", sh.damping_alpha)?;
        non_negative("shaft.damping_beta", sh.damping_beta)?;

        Ok(())
    }

    /// An error unless `n` is a node of the shaft.
    fn node(&self, what: &At, n: usize) -> Result<(), String> {
        let last = self.n_nodes() - 1;
        if n > last {
            Err(format!("{what}.node = {n} is out of range: the shaft has nodes 0..={last}"))
        } else {
            Ok(())
        }
    }

    /// Disks, point masses, bearings and unbalances.
    fn check_parts(&self) -> Result<(), String> {
        let node = |what: &At, n: usize| self.node(what, n);
        for (i, d) in self.disks.iter().enumerate() {
            let at = At("disk", i);
            node(&at, d.node)?;
            positive(format!("{at}.mass"), d.mass)?;
            positive(format!("{at}.diameter"), d.diameter)?;
            non_negative(format!("{at}.width"), d.width)?;
            if let Some(ip) = d.ip {
                non_negative(format!("{at}.ip"), ip)?;
            }
            if let Some(id) = d.id {
                non_negative(format!("{at}.id"), id)?;
            }
        }
        for (i, m) in self.masses.iter().enumerate() {
            let at = At("mass", i);
            node(&at, m.node)?;
            non_negative(format!("{at}.mass"), m.mass)?;
            non_negative(format!("{at}.ip"), m.ip)?;
            non_negative(format!("{at}.id"), m.id)?;
        }
        for (i, b) in self.bearings.iter().enumerate() {
            let at = At("bearing", i);
            node(&at, b.node)?;
            for (name, v) in [("kxx", b.kxx), ("kyy", b.kyy), ("kxy", b.kxy), ("kyx", b.kyx)] {
                finite(format!("{at}.{name}"), v)?;
            }
            for (name, v) in [("cxx", b.cxx), ("cyy", b.cyy), ("cxy", b.cxy), ("cyx", b.cyx)] {
                finite(format!("{at}.{name}"), v)?;
            }
            non_negative(format!("{at}.kxx"), b.kxx)?;
            non_negative(format!("{at}.kyy"), b.kyy)?;
            non_negative(format!("{at}.cxx"), b.cxx)?;
            non_negative(format!("{at}.cyy"), b.cyy)?;
            if let Some(g) = &b.geometry {
                g.validate().map_err(|e| format!("{at}.geometry: {e}"))?;
            }
        }
        for (i, u) in self.unbalances.iter().enumerate() {
            let at = At("unbalance", i);
            node(&at, u.node)?;
            non_negative(format!("{at}.magnitude"), u.magnitude)?;
            finite(format!("{at}.phase_deg"), u.phase_deg)?;
        }
        Ok(())
    }

    fn check_sensors(&self) -> Result<(), String> {
        let node = |what: &At, n: usize| self.node(what, n);
        let mut names = std::collections::HashSet::new();
        for (i, s) in self.sensors.iter().enumerate() {
            let at = At("sensor", i);
            node(&at, s.node)?;
            match s.kind {
                SensorKind::Displacement { noise_std } => non_negative(format!("{at}.noise_std"), noise_std)?,
                SensorKind::Acceleration(a) => {
                    non_negative(format!("{at}.noise_density"), a.noise_density)?;
                    if let Some(f) = a.lowpass_hz {
                        positive(format!("{at}.lowpass_hz"), f)?;
                    }
                    if a.lowpass_order > 8 {
                        return Err(format!("{at}.lowpass_order = {} must be 0 (no filter) … 8", a.lowpass_order));
                    }
                    if let Some(v) = a.sensitivity {
                        finite(format!("{at}.sensitivity"), v)?;
                        if v == 0.0 {
                            return Err(format!("{at}.sensitivity must not be 0"));
                        }
                    }
                    finite(format!("{at}.offset"), a.offset)?;
                }
            }
            if !names.insert(s.channel_name()) {
                return Err(format!(
                    "{at}: a second sensor named `{}` (same node, direction and kind)",
                    s.channel_name()
                ));
            }
        }
        Ok(())
    }
}
