//! Steady unbalance response: the harmonic solution at the running speed.
//!
//! With `f(t) = Re(F̂ e^{iΩt})` the steady response is `q(t) = Re(Q̂ e^{iΩt})` with
//! `(K − Ω² M + iΩ (C + Ω G)) Q̂ = F̂`, one complex dense solve. This is independent of the
//! time-domain simulation (which integrates the first-order system from rest), so the two
//! agreeing once the start-up transient has decayed checks both.

use super::assembly::RotorModel;
use super::config::Direction;
use super::{dof, RotorError};
use faer::linalg::solvers::Solve;
use faer::{c64, Mat};

/// Complex amplitudes of the steady unbalance response at one speed.
#[derive(Debug, Clone, PartialEq)]
pub struct UnbalanceResponse {
    /// Speed Ω, rad/s.
    pub speed: f64,
    /// Complex amplitude of every DOF: `q_i(t) = Re(q[i] e^{iΩt}) = |q[i]| cos(Ωt + arg q[i])`.
    pub q: Vec<c64>,
}

impl UnbalanceResponse {
    /// Complex amplitude of node `node` in `direction`, m.
    pub fn at(&self, node: usize, direction: Direction) -> c64 {
        self.q[dof(node, direction.dof())]
    }

    /// Amplitude (zero to peak) of node `node` in `direction`, m.
    pub fn amplitude(&self, node: usize, direction: Direction) -> f64 {
        self.at(node, direction).norm()
    }

    /// Phase of node `node` in `direction`: `x(t) = A cos(Ωt + phase)`, degrees.
    pub fn phase_deg(&self, node: usize, direction: Direction) -> f64 {
        self.at(node, direction).arg().to_degrees()
    }

    /// Semi-major axis of the orbit of a node, m.
    pub fn major_axis(&self, node: usize) -> f64 {
        let (u, v) = (self.q[dof(node, 0)], self.q[dof(node, 1)]);
        // For x = Re(u e^{iθ}), y = Re(v e^{iθ}): a² = (|u|²+|v|²)/2 + |u²+v²|/2.
        ((u.norm_sqr() + v.norm_sqr()) / 2.0 + (u * u + v * v).norm() / 2.0).sqrt()
    }

    /// Every DOF at time `t`, m or rad.
    pub fn at_time(&self, t: f64) -> Vec<f64> {
        let e = c64::from_polar(1.0, self.speed * t);
        self.q.iter().map(|q| (q * e).re).collect()
    }
}

impl RotorModel {
    /// Steady response to the configured unbalances at `speed` (rad/s).
    ///
    /// ```
    /// use edgekf_sim::systems::rotor::{Direction, RotorConfig, RotorModel};
    /// let cfg = RotorConfig::from_toml_str(include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml"))).unwrap();
    /// let model = RotorModel::from_config(&cfg).unwrap();
    /// let r = model.unbalance_response(87.96).unwrap();
    /// // Tens of micrometres at the disk, a fraction of that next to a bearing.
    /// assert!(r.amplitude(12, Direction::X) > 1e-5 && r.amplitude(12, Direction::X) < 1e-4);
    /// assert!(r.amplitude(5, Direction::X) < r.amplitude(12, Direction::X) / 5.0);
    /// ```
    pub fn unbalance_response(&self, speed: f64) -> Result<UnbalanceResponse, RotorError> {
        if !speed.is_finite() {
            return Err(RotorError::Invalid(format!("speed = {speed} rad/s must be finite")));
        }
        let s = self.matrices();
        let n = s.n();
        let z = Mat::<c64>::from_fn(n, n, |i, j| {
            c64::new(s.k[(i, j)] - speed * speed * s.m[(i, j)], speed * (s.c[(i, j)] + speed * s.g[(i, j)]))
        });
        let f = self.unbalance_phasor(speed);
        let rhs = Mat::<c64>::from_fn(n, 1, |i, _| f[i]);
        let q = z.partial_piv_lu().solve(&rhs);
        let q: Vec<c64> = (0..n).map(|i| q[(i, 0)]).collect();
        if q.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
            return Err(RotorError::Numerical(format!(
                "unbalance response at {speed} rad/s: the dynamic stiffness is singular (undamped resonance or an unsupported rotor)"
            )));
        }
        Ok(UnbalanceResponse { speed, q })
    }
}
