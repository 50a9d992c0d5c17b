//! The contact law of a revolute clearance joint: a journal of radius `R` inside a bearing of
//! radius `R + c`, pushed back by the Lankarani–Nikravesh force when it indents the bearing.
//!
//! With `e` the journal centre relative to the bearing centre, the indentation is
//! `δ = |e| − c` and the force on the journal acts along `−e/|e|` (frictionless, so through both
//! centres) with magnitude
//!
//! ```text
//! F = K δ^1.5 · (1 + 3 (1 − cᵣ²) / 4 · δ̇ / δ̇⁻)      for δ > 0, clamped at F ≥ 0
//! ```
//!
//! (Lankarani & Nikravesh 1990): Hertz's elastic term and a hysteresis damping that dissipates,
//! in one impact, the kinetic energy lost with restitution `cᵣ`; `δ̇⁻` is the indentation rate
//! at the start of the contact. Both terms vanish with `δ`, so the force is continuous when a
//! contact starts and ends: there is no jump for an integrator to trip over. The clamp stops the
//! damping from pulling the journal back in at the end of a contact (no adhesion); it only
//! removes force while the journal separates, so energy still cannot increase.
//!
//! Stiffness (Flores et al. 2004, the journal-bearing use of Hertz's conformal cylinders):
//! `K = 4 / (3 (σ_b + σ_j)) · √(R_b R_j / (R_b − R_j))`, `σ = (1 − ν²)/E`. It grows as the
//! clearance shrinks (`K ∝ c^−½`), which is why a tiny clearance needs a small step.
//!
//! ```
//! use edgekf_sim::systems::crank::contact::{hertz_stiffness, ContactLaw};
//! // Paper steel, 10 mm journal, 0.25 mm clearance.
//! let k = hertz_stiffness(207e9, 0.3, 0.010, 0.01025);
//! assert!((k / 9.71e10 - 1.0).abs() < 1e-3); // N/m^1.5
//! let law = ContactLaw::new(0.25e-3, 0.010, 207e9, 0.3, 0.9, 1e-3).unwrap();
//! // No force outside contact, and none at first touch.
//! assert_eq!(law.force(-1e-6, 0.1, Some(0.1)).total, 0.0);
//! assert_eq!(law.force(0.0, 0.1, Some(0.1)).total, 0.0);
//! // Compressing at the impact speed: elastic force times 1 + 0.1425.
//! let f = law.force(1e-6, 0.1, Some(0.1));
//! assert!((f.total / f.elastic - 1.1425).abs() < 1e-12);
//! ```

use super::error::CrankError;

/// Exponent of the Hertz force law for these contacts.
pub const HERTZ_EXPONENT: f64 = 1.5;

/// Hertz stiffness `K` of a journal of radius `journal_radius` in a bearing of radius
/// `bearing_radius` (both of the same material), N/m^1.5.
pub fn hertz_stiffness(young: f64, poisson: f64, journal_radius: f64, bearing_radius: f64) -> f64 {
    let sigma = (1.0 - poisson * poisson) / young;
    let conformity = (bearing_radius * journal_radius / (bearing_radius - journal_radius)).sqrt();
    4.0 / (3.0 * 2.0 * sigma) * conformity
}

/// The contact law of one clearance joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactLaw {
    /// Radial clearance `c` (bearing radius minus journal radius), m.
    pub clearance: f64,
    /// Journal radius, m.
    pub journal_radius: f64,
    /// Hertz stiffness `K`, N/m^1.5.
    pub stiffness: f64,
    /// Coefficient of restitution.
    pub restitution: f64,
    /// Floor on the impact velocity, m/s (see
    /// [`ContactConfig::min_impact_velocity`](super::config::ContactConfig::min_impact_velocity)).
    pub min_impact_velocity: f64,
    /// `3 (1 − cᵣ²) / 4`.
    hysteresis: f64,
}

/// The force of a contact at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactForce {
    /// Force pushing the journal back towards the bearing centre, N (≥ 0).
    pub total: f64,
    /// Its elastic (Hertz) part `K δ^1.5`, N.
    pub elastic: f64,
}

impl ContactForce {
    /// Power dissipated by the contact at indentation rate `rate`, W (≥ 0): the force's
    /// non-conservative part times the rate.
    pub fn dissipation(&self, rate: f64) -> f64 {
        (self.total - self.elastic) * rate
    }
}

impl ContactLaw {
    /// The law of a joint with radial clearance `clearance` and journal radius `journal_radius`
    /// (m), material `young` (Pa) / `poisson`, restitution in (0, 1] and the impact-velocity
    /// floor (m/s).
    pub fn new(
        clearance: f64,
        journal_radius: f64,
        young: f64,
        poisson: f64,
        restitution: f64,
        min_impact_velocity: f64,
    ) -> Result<Self, CrankError> {
        if !(clearance.is_finite() && clearance > 0.0) {
            return Err(CrankError::Config(format!("clearance = {clearance} m must be positive")));
        }
        if !(journal_radius.is_finite() && journal_radius > clearance) {
            return Err(CrankError::Config(format!(
                "journal radius = {journal_radius} m must be positive and larger than the clearance {clearance} m"
            )));
        }
        let stiffness = hertz_stiffness(young, poisson, journal_radius, journal_radius + clearance);
        if !(stiffness.is_finite() && stiffness > 0.0) {
            return Err(CrankError::Config(format!("contact stiffness {stiffness} is not a positive number")));
        }
        if !(restitution > 0.0 && restitution <= 1.0) {
            return Err(CrankError::Config(format!("restitution = {restitution} must be in (0, 1]")));
        }
        if !(min_impact_velocity.is_finite() && min_impact_velocity > 0.0) {
            return Err(CrankError::Config(format!("min_impact_velocity = {min_impact_velocity} must be positive")));
        }
        Ok(Self {
            clearance,
            journal_radius,
            stiffness,
            restitution,
            min_impact_velocity,
            hysteresis: 0.75 * (1.0 - restitution * restitution),
        })
    }

    /// The force at indentation `penetration` (m, negative when apart) and indentation rate
    /// `rate` (m/s), for a contact that started at speed `impact_velocity` (`None`: no contact
    /// in progress, no force).
    pub fn force(&self, penetration: f64, rate: f64, impact_velocity: Option<f64>) -> ContactForce {
        match impact_velocity {
            Some(v0) if penetration > 0.0 => {
                let elastic = self.stiffness * penetration * penetration.sqrt();
                let v0 = v0.max(self.min_impact_velocity);
                let total = (elastic * (1.0 + self.hysteresis * rate / v0)).max(0.0);
                ContactForce { total, elastic }
            }
            _ => ContactForce::default(),
        }
    }

    /// The impact velocity to remember for a contact starting at indentation rate `rate`.
    pub fn impact_velocity(&self, rate: f64) -> f64 {
        rate.max(self.min_impact_velocity)
    }

    /// Elastic energy stored at indentation `penetration`, J: `K δ^2.5 / 2.5`.
    pub fn potential(&self, penetration: f64) -> f64 {
        if penetration > 0.0 {
            self.stiffness * penetration * penetration * penetration.sqrt() / (HERTZ_EXPONENT + 1.0)
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mass dropped on a Hertz–LN wall rebounds with about the restitution asked for: the
    /// hysteresis term is what sets the energy lost per impact.
    #[test]
    fn single_impact_restitution() {
        let law = ContactLaw::new(0.25e-3, 0.010, 207e9, 0.3, 0.9, 1e-6).unwrap();
        let m = 0.3;
        for v_in in [0.01, 0.1, 1.0] {
            let (mut x, mut v, h) = (0.0_f64, v_in, 1e-9);
            let mut t = 0.0;
            // x is the indentation; the contact starts at x = 0 with rate v_in.
            loop {
                let f = law.force(x, v, Some(v_in)).total;
                v -= h * f / m;
                x += h * v;
                t += h;
                if x <= 0.0 || t > 1e-2 {
                    break;
                }
            }
            let e = -v / v_in;
            // Lankarani–Nikravesh is derived for restitution near 1; at 0.9 it is within 2 %.
            assert!((e - 0.9).abs() < 0.02, "v_in {v_in}: restitution {e}");
        }
    }

    #[test]
    fn damping_never_pulls() {
        let law = ContactLaw::new(1e-4, 0.01, 207e9, 0.3, 0.5, 1e-3).unwrap();
        let f = law.force(1e-6, -10.0, Some(1e-3));
        assert_eq!(f.total, 0.0);
        assert!(f.dissipation(-10.0) > 0.0);
        assert!(law.force(1e-6, 0.5, Some(0.5)).dissipation(0.5) > 0.0);
    }

    #[test]
    fn bad_parameters_are_refused() {
        assert!(ContactLaw::new(0.0, 0.01, 207e9, 0.3, 0.9, 1e-3).is_err());
        assert!(ContactLaw::new(0.02, 0.01, 207e9, 0.3, 0.9, 1e-3).is_err());
        assert!(ContactLaw::new(1e-4, 0.01, 207e9, 0.3, 0.0, 1e-3).is_err());
        assert!(ContactLaw::new(1e-4, 0.01, f64::NAN, 0.3, 0.9, 1e-3).is_err());
        assert!(ContactLaw::new(1e-4, 0.01, 207e9, 0.3, 0.9, 0.0).is_err());
    }
}
