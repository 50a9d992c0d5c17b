//! The state of the slider-crank: everything needed to continue a simulation from an instant.
//!
//! The independent coordinates are always the same seven numbers, whatever joints have
//! clearance: the crank angle `θ` and, for each joint A, B, C, the eccentricity `e` of its
//! journal centre relative to its bearing centre (m). An ideal joint's eccentricity is zero and
//! stays zero (it is not integrated), so one `State` layout serves every mechanism, and a state
//! can be carried from one clearance set to another (see
//! [`Mechanism::transfer_state`](super::Mechanism::transfer_state)).
//!
//! Who is journal and who is bearing (it only fixes the sign of `e`):
//! * A: journal on the crank, bearing in the ground (at the origin);
//! * B: journal (crank pin) on the crank, bearing (big end) on the rod;
//! * C: journal (wrist pin) on the slider, bearing (small end) on the rod.

use super::Joint;

/// Number of independent coordinates: `θ` and three 2-D eccentricities.
pub const DOF: usize = 7;

/// Index of the crank angle in [`State::z`].
pub const CRANK_ANGLE: usize = 0;

/// Index of the x component of `joint`'s eccentricity in [`State::z`] (y is the next one).
pub const fn eccentricity_index(joint: Joint) -> usize {
    1 + 2 * joint.index()
}

/// Position, velocity and contact memory of the mechanism at time `t`.
///
/// ```
/// use edgekf_sim::systems::crank::{CrankConfig, Joint, Mechanism};
/// let m = Mechanism::new(&CrankConfig::default(), [Some(0.25e-3), None, None]).unwrap();
/// let s = m.release_state();
/// assert_eq!(s.crank_angle(), 30f64.to_radians());
/// assert_eq!(s.crank_rate(), 0.0);
/// assert_eq!(s.eccentricity(Joint::A), [0.0, 0.0]); // journal centred, at rest
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    /// Time, s.
    pub t: f64,
    /// Coordinates: `[θ (rad, unwrapped), e_A.x, e_A.y, e_B.x, e_B.y, e_C.x, e_C.y]` (m).
    pub z: [f64; DOF],
    /// Their rates (rad/s, m/s).
    pub zd: [f64; DOF],
    /// Per joint A, B, C: `Some(δ̇⁻)` while a contact is in progress, with the indentation rate
    /// at its start (m/s) that scales the hysteresis damping; `None` when apart.
    pub impact_velocity: [Option<f64>; 3],
    /// Energy dissipated by contact damping since the start of the run that produced this
    /// state, J (a diagnostic: mechanical energy + dissipated stays constant).
    pub dissipated: f64,
}

impl State {
    /// Crank angle `θ`, rad, from the guide direction, counter-clockwise (not wrapped).
    pub fn crank_angle(&self) -> f64 {
        self.z[CRANK_ANGLE]
    }

    /// Crank angular velocity, rad/s.
    pub fn crank_rate(&self) -> f64 {
        self.zd[CRANK_ANGLE]
    }

    /// Journal centre minus bearing centre at `joint`, m (zero for an ideal joint).
    pub fn eccentricity(&self, joint: Joint) -> [f64; 2] {
        let i = eccentricity_index(joint);
        [self.z[i], self.z[i + 1]]
    }

    /// Rate of [`State::eccentricity`], m/s.
    pub fn eccentricity_rate(&self, joint: Joint) -> [f64; 2] {
        let i = eccentricity_index(joint);
        [self.zd[i], self.zd[i + 1]]
    }

    /// Sets the eccentricity of `joint` and its rate.
    pub fn set_eccentricity(&mut self, joint: Joint, e: [f64; 2], rate: [f64; 2]) {
        let i = eccentricity_index(joint);
        self.z[i..i + 2].copy_from_slice(&e);
        self.zd[i..i + 2].copy_from_slice(&rate);
    }

    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        self.t.is_finite()
            && self.z.iter().chain(&self.zd).all(|v| v.is_finite())
            && self.impact_velocity.iter().flatten().all(|v| v.is_finite())
            && self.dissipated.is_finite()
    }
}
