//! A vehicle's constants: mass and inertia, hydrodynamic derivatives, thrusters and fins, in
//! Prestero's notation and SI units, body origin at the centre of buoyancy (x forward, y
//! starboard, z down).
//!
//! The defaults are the REMUS 100 set of Prestero's thesis ("Verification of a six-degree of
//! freedom simulation model for the REMUS autonomous underwater vehicle", MIT/WHOI 2001,
//! Appendix B with the field corrections), plus two things REMUS lacks and this project adds:
//! a linear roll damping `k_p` (his fins give the roll mode almost none, so a thrust step would
//! ring it for minutes) and a vertical tunnel thruster at the centre of buoyancy.

/// Hydrodynamic derivatives. Quadratic drag terms are written `x_uu` for `X_u|u|`; `dot`
/// marks an added mass (`x_udot` is `X_u̇`); `uudr` and `uuds` are the fin terms `u²δr` and
/// `u²δs`. The cross terms (`x_wq`, `y_ur`, …) are Prestero's combined added-mass, body-lift
/// and fin-lift coefficients, so the Munk moments are in them.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
#[allow(missing_docs)] // each field is the coefficient its name spells, see the type's doc
pub struct Hydro {
    pub x_uu: f64,
    pub x_udot: f64,
    pub x_wq: f64,
    pub x_qq: f64,
    pub x_vr: f64,
    pub x_rr: f64,
    pub y_vv: f64,
    pub y_rr: f64,
    pub y_uv: f64,
    pub y_vdot: f64,
    pub y_rdot: f64,
    pub y_ur: f64,
    pub y_wp: f64,
    pub y_pq: f64,
    pub y_uudr: f64,
    pub z_ww: f64,
    pub z_qq: f64,
    pub z_uw: f64,
    pub z_wdot: f64,
    pub z_qdot: f64,
    pub z_uq: f64,
    pub z_vp: f64,
    pub z_rp: f64,
    pub z_uuds: f64,
    pub k_pp: f64,
    /// Linear roll damping, N·m·s/rad: not in Prestero's set (see the module doc).
    pub k_p: f64,
    pub k_pdot: f64,
    pub m_ww: f64,
    pub m_qq: f64,
    pub m_uw: f64,
    pub m_wdot: f64,
    pub m_qdot: f64,
    pub m_uq: f64,
    pub m_vp: f64,
    pub m_rp: f64,
    pub m_uuds: f64,
    pub n_vv: f64,
    pub n_rr: f64,
    pub n_uv: f64,
    pub n_vdot: f64,
    pub n_rdot: f64,
    pub n_ur: f64,
    pub n_wp: f64,
    pub n_pq: f64,
    pub n_uudr: f64,
}

impl Default for Hydro {
    /// REMUS 100 (Prestero 2001, Appendix B) with `k_p = −0.5` N·m·s/rad.
    fn default() -> Self {
        Self {
            x_uu: -1.62,
            x_udot: -0.93,
            x_wq: -35.5,
            x_qq: -1.93,
            x_vr: 35.5,
            x_rr: -1.93,
            y_vv: -131.0,
            y_rr: 0.632,
            y_uv: -28.6,
            y_vdot: -35.5,
            y_rdot: 1.93,
            y_ur: 5.22,
            y_wp: 35.5,
            y_pq: 1.93,
            y_uudr: 9.64,
            z_ww: -131.0,
            z_qq: -0.632,
            z_uw: -28.6,
            z_wdot: -35.5,
            z_qdot: -1.93,
            z_uq: -5.22,
            z_vp: -35.5,
            z_rp: 1.93,
            z_uuds: -9.64,
            k_pp: -0.130,
            k_p: -0.5,
            k_pdot: -0.0704,
            m_ww: 3.18,
            m_qq: -188.0,
            m_uw: 24.0,
            m_wdot: -1.93,
            m_qdot: -4.88,
            m_uq: -2.00,
            m_vp: -1.93,
            m_rp: 4.86,
            m_uuds: -6.15,
            n_vv: -3.18,
            n_rr: -94.0,
            n_uv: -24.0,
            n_vdot: 1.93,
            n_rdot: -4.88,
            n_ur: -2.00,
            n_wp: -1.93,
            n_pq: -4.86,
            n_uudr: -6.15,
        }
    }
}

/// Thrusters and fins. A thruster's force is `k · K · n|n|` with `k` its health factor
/// (1 healthy, 0 dead) and `n` its speed in rpm.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct Actuators {
    /// Main thruster's thrust coefficient `K_T`, N/rpm² (3.86 N at 1500 rpm).
    pub main_thrust: f64,
    /// Main thruster's roll torque coefficient `K_Q`, N·m/rpm² (−0.543 N·m at 1500 rpm).
    pub main_torque: f64,
    /// Vertical tunnel thruster's coefficient `K_V`, N/rpm², along +z body (down) at the
    /// centre of buoyancy.
    pub vertical_thrust: f64,
    /// Vertical thruster's speed limit, rpm (either direction).
    pub vertical_max_rpm: f64,
    /// Main thruster's speed limit, rpm.
    pub main_max_rpm: f64,
    /// Rudder and elevator limit, rad.
    pub fin_max: f64,
}

impl Default for Actuators {
    /// REMUS 100's propeller, the added tunnel thruster, fins ±13.6°.
    fn default() -> Self {
        Self {
            main_thrust: 3.86 / (1500.0 * 1500.0),
            main_torque: -0.543 / (1500.0 * 1500.0),
            vertical_thrust: 2.5e-6,
            vertical_max_rpm: 3000.0,
            main_max_rpm: 2000.0,
            fin_max: 13.6 * core::f64::consts::PI / 180.0,
        }
    }
}

/// Mass, inertia, hydrostatics, hydrodynamics and actuators of one vehicle.
///
/// ```
/// use edgekf::systems::uuv::Vehicle;
/// let remus = Vehicle::default();
/// assert!((remus.mass() - 299.0 / 9.81).abs() < 1e-12);
/// // The thesis's steady roll: the propeller's torque against the weight's lever z_g.
/// let roll = (remus.actuators.main_torque * 1500.0 * 1500.0 / (remus.z_g * remus.weight)).asin();
/// assert!((roll.to_degrees() + 5.3).abs() < 0.1);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct Vehicle {
    /// Weight `W`, N.
    pub weight: f64,
    /// Buoyancy `B`, N (above `W`: the vehicle floats up when idle).
    pub buoyancy: f64,
    /// Gravitational acceleration, m/s².
    pub gravity: f64,
    /// Centre of gravity below the centre of buoyancy, m (x_g = y_g = 0).
    pub z_g: f64,
    /// Roll inertia about the origin, kg·m².
    pub i_xx: f64,
    /// Pitch inertia about the origin, kg·m².
    pub i_yy: f64,
    /// Yaw inertia about the origin, kg·m².
    pub i_zz: f64,
    /// Hydrodynamic derivatives.
    pub hydro: Hydro,
    /// Thrusters and fins.
    pub actuators: Actuators,
}

impl Default for Vehicle {
    /// REMUS 100.
    fn default() -> Self {
        Self {
            weight: 299.0,
            buoyancy: 306.0,
            gravity: 9.81,
            z_g: 0.0196,
            i_xx: 0.177,
            i_yy: 3.45,
            i_zz: 3.45,
            hydro: Hydro::default(),
            actuators: Actuators::default(),
        }
    }
}

impl Vehicle {
    /// Mass `W / g`, kg.
    pub fn mass(&self) -> f64 {
        self.weight / self.gravity
    }

    /// The first constant that cannot describe a vehicle (not finite, a non-positive mass,
    /// inertia or limit, an added mass that is not one), as a sentence.
    pub fn check(&self) -> Result<(), &'static str> {
        let h = &self.hydro;
        let a = &self.actuators;
        let all = [
            self.weight,
            self.buoyancy,
            self.gravity,
            self.z_g,
            self.i_xx,
            self.i_yy,
            self.i_zz,
            a.main_thrust,
            a.main_torque,
            a.vertical_thrust,
            a.vertical_max_rpm,
            a.main_max_rpm,
            a.fin_max,
        ];
        if all.iter().any(|v| !v.is_finite()) || h.as_array().iter().any(|v| !v.is_finite()) {
            return Err("a vehicle constant is not a finite number");
        }
        if self.weight <= 0.0 || self.buoyancy <= 0.0 || self.gravity <= 0.0 {
            return Err("weight, buoyancy and gravity must be positive");
        }
        if self.i_xx <= 0.0 || self.i_yy <= 0.0 || self.i_zz <= 0.0 {
            return Err("the inertias must be positive");
        }
        if h.x_udot > 0.0 || h.y_vdot > 0.0 || h.z_wdot > 0.0 || h.k_pdot > 0.0 || h.m_qdot > 0.0 || h.n_rdot > 0.0 {
            return Err("added masses (x_udot, y_vdot, z_wdot, k_pdot, m_qdot, n_rdot) must be zero or negative");
        }
        if a.vertical_max_rpm <= 0.0 || a.main_max_rpm <= 0.0 || a.fin_max <= 0.0 {
            return Err("actuator limits must be positive");
        }
        Ok(())
    }
}

impl Hydro {
    /// Every coefficient, in the field order (for checks that treat them alike).
    pub fn as_array(&self) -> [f64; 45] {
        [
            self.x_uu,
            self.x_udot,
            self.x_wq,
            self.x_qq,
            self.x_vr,
            self.x_rr,
            self.y_vv,
            self.y_rr,
            self.y_uv,
            self.y_vdot,
            self.y_rdot,
            self.y_ur,
            self.y_wp,
            self.y_pq,
            self.y_uudr,
            self.z_ww,
            self.z_qq,
            self.z_uw,
            self.z_wdot,
            self.z_qdot,
            self.z_uq,
            self.z_vp,
            self.z_rp,
            self.z_uuds,
            self.k_pp,
            self.k_p,
            self.k_pdot,
            self.m_ww,
            self.m_qq,
            self.m_uw,
            self.m_wdot,
            self.m_qdot,
            self.m_uq,
            self.m_vp,
            self.m_rp,
            self.m_uuds,
            self.n_vv,
            self.n_rr,
            self.n_uv,
            self.n_vdot,
            self.n_rdot,
            self.n_ur,
            self.n_wp,
            self.n_pq,
            self.n_uudr,
        ]
    }
}
