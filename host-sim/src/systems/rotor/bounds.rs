//! What the model allows an effect to be (`[bounds]` of the rotor's configuration): a fit that
//! lands at or beyond a bound is not an estimate of that effect but the effect standing in for
//! something the library lacks, so the engine refuses it with
//! [`OUTSIDE`](crate::residual_loop::OUTSIDE) instead of keeping it (the rotor gives the engine
//! each effect's [`limit`](crate::residual_loop::Fitting::limit) from here).
//!
//! The defaults (the README's table) are wide enough for any real fault and narrow enough to
//! refuse what the CWRU records once drew out of the loop: a disk mass ×1.95, Young's modulus
//! ×0.33, 30–64 N forces at kHz, a negative sensor delay.

use serde::Deserialize;

/// `[bounds]`: the physical range of each effect kind.
///
/// ```
/// use edgekf_sim::systems::rotor::bounds::Bounds;
/// let b: Bounds = toml::from_str("parameter = 0.5\ndelay = 1e-3").unwrap();
/// assert_eq!(b.factor_range(), (0.5, 1.5));
/// assert_eq!(b.delay_s(12_000.0), 1e-3);
/// assert_eq!(Bounds::default().delay_s(10_000.0), 5e-4); // five samples
/// assert_eq!(Bounds::default().force_n(30.0), 30.0); // the default: the given weight
/// assert_eq!(Bounds::default().mass_kg(10.0), 3.0); // the default: 0.3 of the machine's mass
/// assert!(toml::from_str::<Bounds>("force = -1").unwrap().validate().is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Bounds {
    /// A `parameter` effect's factor stays within `1 ± parameter` (default 0.3).
    pub parameter: f64,
    /// The largest force an effect may carry, N (default: the machine's weight).
    pub force: Option<f64>,
    /// The longest sensor delay, s (default: five samples). Never negative: a sensor cannot
    /// read the future.
    pub delay: Option<f64>,
    /// The longest first-order sensor lag (time constant), s (default 1 s).
    pub lag: f64,
    /// The largest point mass an effect may add, kg (default: `parameter` times the machine's
    /// mass, as a factor on it would add).
    pub mass: Option<f64>,
}

impl Default for Bounds {
    fn default() -> Self {
        Self { parameter: 0.3, force: None, delay: None, lag: 1.0, mass: None }
    }
}

impl Bounds {
    /// Checks the values: `parameter` in (0, 1), the rest positive and finite.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.parameter > 0.0 && self.parameter < 1.0) {
            return Err(format!("bounds.parameter = {} must be in (0, 1) (a factor within 1 ± it)", self.parameter));
        }
        let named = [
            ("bounds.force", self.force),
            ("bounds.delay", self.delay),
            ("bounds.lag", Some(self.lag)),
            ("bounds.mass", self.mass),
        ];
        for (name, v) in named {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0) {
                    return Err(format!("{name} = {v} must be positive and finite"));
                }
            }
        }
        Ok(())
    }

    /// The factors a `parameter` effect may take: `(1 − parameter, 1 + parameter)`.
    pub fn factor_range(&self) -> (f64, f64) {
        (1.0 - self.parameter, 1.0 + self.parameter)
    }

    /// The longest delay, s, at `sample_rate` Hz.
    pub fn delay_s(&self, sample_rate: f64) -> f64 {
        self.delay.unwrap_or(5.0 / sample_rate)
    }

    /// The largest force, N, for a machine weighing `weight_n`.
    pub fn force_n(&self, weight_n: f64) -> f64 {
        self.force.unwrap_or(weight_n)
    }

    /// The largest point mass, kg, for a machine of `mass_kg`.
    pub fn mass_kg(&self, mass_kg: f64) -> f64 {
        self.mass.unwrap_or(self.parameter * mass_kg)
    }
}
