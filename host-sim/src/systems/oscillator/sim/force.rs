//! The excitation: a harmonic force at a known frequency whose amplitude and phase follow a
//! schedule, plus optional constant extra harmonics.

use serde::Deserialize;
use std::f64::consts::PI;

/// One change of the force: from `t` on, amplitude and/or phase move to new values over the
/// force's `transition_s`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceChange {
    /// When the change starts, s.
    pub t: f64,
    /// New amplitude, N (unchanged if absent).
    #[serde(default)]
    pub amplitude_n: Option<f64>,
    /// New phase, degrees (unchanged if absent). Interpolated literally: 350° → 10° turns back
    /// through 180°, so write 370° for the short way.
    #[serde(default)]
    pub phase_deg: Option<f64>,
}

/// A constant extra excitation at a multiple of the drive frequency (e.g. `multiple = 2` for the
/// second harmonic of misalignment). The estimator does not model it: it is there to test what
/// the residuals show when the model is incomplete.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExtraHarmonic {
    /// Frequency as a multiple of the drive frequency Ω.
    pub multiple: f64,
    /// Amplitude, N.
    pub amplitude_n: f64,
    /// Phase, degrees.
    #[serde(default)]
    pub phase_deg: f64,
    /// When it begins, s (0: from the start): a rub or a loosening that starts mid-run. It
    /// fades in over the force's `transition_s` as the main harmonic's changes do.
    #[serde(default)]
    pub start_s: f64,
}

impl ExtraHarmonic {
    /// A harmonic at `multiple` × the drive, present from the start.
    pub fn new(multiple: f64, amplitude_n: f64, phase_deg: f64) -> Self {
        Self { multiple, amplitude_n, phase_deg, start_s: 0.0 }
    }

    /// Its force at `t` for a drive of `drive_rad_s`, N, faded in over `transition_s` after
    /// `start_s`.
    ///
    /// ```
    /// use edgekf_sim::systems::oscillator::sim::ExtraHarmonic;
    /// let rub = ExtraHarmonic { start_s: 2.0, ..ExtraHarmonic::new(2.0, 0.5, 0.0) };
    /// assert_eq!(rub.force(10.0, 1.9, 0.2), 0.0);
    /// assert_eq!(rub.force(10.0, 3.0, 0.2), 0.5 * (60.0f64).cos());
    /// ```
    pub fn force(&self, drive_rad_s: f64, t: f64, transition_s: f64) -> f64 {
        let s = t - self.start_s;
        let w = if self.start_s <= 0.0 || s >= transition_s {
            1.0
        } else if s < 0.0 {
            0.0
        } else {
            0.5 * (1.0 - (PI * s / transition_s).cos())
        };
        w * self.amplitude_n * (self.multiple * drive_rad_s * t + self.phase_deg.to_radians()).cos()
    }
}

/// The force on the mode: `F(t) = A(t) cos(Ω t + φ(t)) + Σ extra`.
///
/// `A` and `φ` are piecewise constant; at each [`ForceChange`] they move to their new values along
/// a raised cosine `w = (1 − cos(π s / T)) / 2`, `s` the time since the change, `T` =
/// `transition_s`. A real machine never steps its unbalance instantly, and a smooth transition
/// keeps the force continuous with a continuous derivative, so the RK4 reference stays accurate
/// through it.
///
/// ```
/// use edgekf_sim::systems::oscillator::sim::ForceConfig;
/// let f = ForceConfig::default(); // 5 N at 30°, stepping to 3 N at 6 s over 0.2 s
/// assert_eq!(f.amplitude_phase(5.0).0, 5.0);
/// assert!((f.amplitude_phase(6.1).0 - 4.0).abs() < 1e-12); // half-way through the transition
/// assert_eq!(f.amplitude_phase(7.0).0, 3.0);
/// ```
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ForceConfig {
    /// Frequency of the force (running speed), rad/s.
    pub drive_rad_s: f64,
    /// Initial amplitude, N.
    pub amplitude_n: f64,
    /// Initial phase, degrees.
    pub phase_deg: f64,
    /// Duration of each change, s (0 for a step).
    pub transition_s: f64,
    /// Changes, in increasing time, at least `transition_s` apart. Empty when omitted in TOML.
    #[serde(default)]
    pub changes: Vec<ForceChange>,
    /// Extra harmonics. Empty when omitted in TOML.
    #[serde(default)]
    pub extra: Vec<ExtraHarmonic>,
}

impl Default for ForceConfig {
    /// 5 N at 30° and 87.96 rad/s (14 Hz), stepping to 3 N at 6 s over 0.2 s.
    fn default() -> Self {
        Self {
            drive_rad_s: 87.96,
            amplitude_n: 5.0,
            phase_deg: 30.0,
            transition_s: 0.2,
            changes: vec![ForceChange { t: 6.0, amplitude_n: Some(3.0), phase_deg: None }],
            extra: vec![],
        }
    }
}

impl ForceConfig {
    /// A constant force `amplitude_n cos(Ω t + phase)`.
    pub fn constant(drive_rad_s: f64, amplitude_n: f64, phase_deg: f64) -> Self {
        Self { drive_rad_s, amplitude_n, phase_deg, transition_s: 0.0, changes: vec![], extra: vec![] }
    }

    /// Amplitude (N) and phase (rad) of the main harmonic at time `t`.
    pub fn amplitude_phase(&self, t: f64) -> (f64, f64) {
        let (mut a, mut p) = (self.amplitude_n, self.phase_deg);
        for c in &self.changes {
            if t < c.t {
                break;
            }
            let (a1, p1) = (c.amplitude_n.unwrap_or(a), c.phase_deg.unwrap_or(p));
            let s = t - c.t;
            if s < self.transition_s {
                let w = 0.5 * (1.0 - (PI * s / self.transition_s).cos());
                return (a + (a1 - a) * w, (p + (p1 - p) * w).to_radians());
            }
            (a, p) = (a1, p1);
        }
        (a, p.to_radians())
    }

    /// The main harmonic alone, N: what the estimator is built to recover.
    pub fn main_force(&self, t: f64) -> f64 {
        let (a, p) = self.amplitude_phase(t);
        a * (self.drive_rad_s * t + p).cos()
    }

    /// The total force, N: main harmonic plus the extras.
    pub fn force(&self, t: f64) -> f64 {
        let extra: f64 = self.extra.iter().map(|e| e.force(self.drive_rad_s, t, self.transition_s)).sum();
        self.main_force(t) + extra
    }

    /// Checks that every figure is finite and the changes are ordered and far enough apart.
    pub fn validate(&self) -> Result<(), String> {
        let finite = [self.drive_rad_s, self.amplitude_n, self.phase_deg, self.transition_s];
        if finite.iter().any(|v| !v.is_finite()) {
            return Err("force: drive_rad_s, amplitude_n, phase_deg and transition_s must be finite".into());
        }
        if self.drive_rad_s <= 0.0 {
            return Err(format!("force.drive_rad_s = {} must be positive", self.drive_rad_s));
        }
        if self.transition_s < 0.0 {
            return Err(format!("force.transition_s = {} must not be negative", self.transition_s));
        }
        let mut last: Option<f64> = None;
        for (i, c) in self.changes.iter().enumerate() {
            let vals = [Some(c.t), c.amplitude_n, c.phase_deg];
            if vals.iter().flatten().any(|v| !v.is_finite()) {
                return Err(format!("force.changes[{i}]: values must be finite"));
            }
            if let Some(prev) = last {
                if c.t < prev + self.transition_s || c.t <= prev {
                    return Err(format!(
                        "force.changes[{i}] at t = {} s starts before the previous change (t = {prev} s) has \
                         finished its {} s transition",
                        c.t, self.transition_s
                    ));
                }
            }
            last = Some(c.t);
        }
        for (i, e) in self.extra.iter().enumerate() {
            if ![e.multiple, e.amplitude_n, e.phase_deg, e.start_s].iter().all(|v| v.is_finite()) {
                return Err(format!("force.extra[{i}]: values must be finite"));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transition_is_smooth_and_ends_on_target() {
        let mut f = ForceConfig::default();
        f.changes[0].phase_deg = Some(90.0);
        let (a0, p0) = f.amplitude_phase(6.0);
        assert_eq!((a0, p0), (5.0, 30f64.to_radians()));
        // Quarter-way: w = (1 − cos(π/4))/2 = 0.1464.
        let (a, p) = f.amplitude_phase(6.05);
        let w = 0.5 * (1.0 - (PI / 4.0).cos());
        assert!((a - (5.0 - 2.0 * w)).abs() < 1e-12);
        assert!((p - (30.0 + 60.0 * w).to_radians()).abs() < 1e-12);
        let (a, p) = f.amplitude_phase(6.2);
        assert_eq!(a, 3.0);
        assert!((p - 90f64.to_radians()).abs() < 1e-15);
        // Continuous: no jump over the whole transition at 0.1 ms resolution.
        let mut prev = f.amplitude_phase(5.99).0;
        for k in 0..3000 {
            let a = f.amplitude_phase(5.99 + k as f64 * 1e-4).0;
            assert!((a - prev).abs() < 2.0 * PI / 2.0 / 0.2 * 1e-4 + 1e-12);
            prev = a;
        }
    }

    #[test]
    fn a_change_may_leave_amplitude_or_phase_unchanged() {
        let f = ForceConfig {
            changes: vec![
                ForceChange { t: 1.0, amplitude_n: None, phase_deg: Some(-45.0) },
                ForceChange { t: 2.0, amplitude_n: Some(7.0), phase_deg: None },
            ],
            ..ForceConfig::constant(50.0, 2.0, 0.0)
        };
        assert_eq!(f.amplitude_phase(1.5), (2.0, (-45f64).to_radians()));
        assert_eq!(f.amplitude_phase(3.0), (7.0, (-45f64).to_radians()));
    }

    #[test]
    fn extras_add_to_the_main_force() {
        let f = ForceConfig { extra: vec![ExtraHarmonic::new(2.0, 0.5, 0.0)], ..ForceConfig::constant(10.0, 1.0, 0.0) };
        let t = 0.3;
        assert!((f.force(t) - ((10.0 * t).cos() + 0.5 * (20.0 * t).cos())).abs() < 1e-15);
        assert!((f.main_force(t) - (10.0 * t).cos()).abs() < 1e-15);
    }

    #[test]
    fn overlapping_changes_are_refused() {
        let mut f = ForceConfig::default();
        f.changes.push(ForceChange { t: 6.1, amplitude_n: Some(1.0), phase_deg: None });
        assert!(f.validate().unwrap_err().contains("changes[1]"));
        f.changes[1].t = 6.2;
        assert!(f.validate().is_ok());
        f.drive_rad_s = -1.0;
        assert!(f.validate().is_err());
    }
}
