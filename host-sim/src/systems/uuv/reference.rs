//! Reference 6-DOF vehicle model, written independently of the estimator's
//! (`edgekf::systems::uuv::ReducedDynamics`): the rigid body in Fossen's vector form
//! (`M_RB ν̇ + C_RB(ν) ν`, general centre of gravity, Fossen 2011 Theorem 3.2), hydrostatics as
//! the weight and buoyancy vectors rotated into the body, the hydrodynamic derivatives as a
//! table of terms, the added mass acting on the acceleration relative to the water (so a
//! current seen from a turning body costs `M_A (ω × v_c)`), attitude as a unit quaternion, and
//! classical RK4 at [`IntegratorConfig::step`](super::config::IntegratorConfig).
//!
//! Its numbers are Prestero's REMUS 100 set (see [`edgekf::systems::uuv::Vehicle`]); the
//! thesis's check, 1.51 m/s at 1500 rpm with about −5.3° of roll, is a test of this module
//! (the coefficient set gives 1.54 m/s in straight flight, thrust against `X_u|u|` alone).

use edgekf::systems::uuv::{Hydro, Vehicle};
use nalgebra::{Matrix3, Matrix6, Quaternion, SVector, UnitQuaternion, Vector3, Vector6};

/// The reference state: position north, east, down (m), attitude quaternion `[w x y z]`
/// (body to earth), body velocity over ground `[u v w p q r]`.
pub type RefState = SVector<f64, 13>;

/// Indices into [`RefState`].
pub mod at {
    /// North position.
    pub const POSITION: usize = 0;
    /// Quaternion `w` (then `x y z`).
    pub const QUATERNION: usize = 3;
    /// `u` (then `v w p q r`).
    pub const VELOCITY: usize = 7;
}

/// What acts on the vehicle during an integration step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Forcing {
    /// Main thruster, rpm.
    pub n_t: f64,
    /// Vertical thruster, rpm.
    pub n_v: f64,
    /// Rudder, rad.
    pub rudder: f64,
    /// Elevator, rad.
    pub elevator: f64,
    /// Main thruster health.
    pub k_t: f64,
    /// Vertical thruster health.
    pub k_v: f64,
    /// Current over ground, north and east, m/s.
    pub current: [f64; 2],
    /// Its rate of change, m/s².
    pub current_rate: [f64; 2],
}

/// Which products of the relative velocity a hydrodynamic derivative multiplies.
#[derive(Debug, Clone, Copy)]
enum Factor {
    /// `a |a|`.
    Abs(usize),
    /// `a`.
    Lin(usize),
    /// `a b`.
    Prod(usize, usize),
    /// `u² δ`: rudder (0) or elevator (1).
    Fin(usize),
}

const U: usize = 0;
const V: usize = 1;
const W: usize = 2;
const P: usize = 3;
const Q: usize = 4;
const R: usize = 5;

type Coefficient = fn(&Hydro) -> f64;

/// Prestero's hydrodynamic terms: (degree of freedom, coefficient, factor).
const TERMS: [(usize, Coefficient, Factor); 35] = [
    (0, |h| h.x_uu, Factor::Abs(U)),
    (0, |h| h.x_wq, Factor::Prod(W, Q)),
    (0, |h| h.x_qq, Factor::Prod(Q, Q)),
    (0, |h| h.x_vr, Factor::Prod(V, R)),
    (0, |h| h.x_rr, Factor::Prod(R, R)),
    (1, |h| h.y_vv, Factor::Abs(V)),
    (1, |h| h.y_rr, Factor::Abs(R)),
    (1, |h| h.y_ur, Factor::Prod(U, R)),
    (1, |h| h.y_wp, Factor::Prod(W, P)),
    (1, |h| h.y_pq, Factor::Prod(P, Q)),
    (1, |h| h.y_uv, Factor::Prod(U, V)),
    (1, |h| h.y_uudr, Factor::Fin(0)),
    (2, |h| h.z_ww, Factor::Abs(W)),
    (2, |h| h.z_qq, Factor::Abs(Q)),
    (2, |h| h.z_uq, Factor::Prod(U, Q)),
    (2, |h| h.z_vp, Factor::Prod(V, P)),
    (2, |h| h.z_rp, Factor::Prod(R, P)),
    (2, |h| h.z_uw, Factor::Prod(U, W)),
    (2, |h| h.z_uuds, Factor::Fin(1)),
    (3, |h| h.k_pp, Factor::Abs(P)),
    (3, |h| h.k_p, Factor::Lin(P)),
    (4, |h| h.m_ww, Factor::Abs(W)),
    (4, |h| h.m_qq, Factor::Abs(Q)),
    (4, |h| h.m_uq, Factor::Prod(U, Q)),
    (4, |h| h.m_vp, Factor::Prod(V, P)),
    (4, |h| h.m_rp, Factor::Prod(R, P)),
    (4, |h| h.m_uw, Factor::Prod(U, W)),
    (4, |h| h.m_uuds, Factor::Fin(1)),
    (5, |h| h.n_vv, Factor::Abs(V)),
    (5, |h| h.n_rr, Factor::Abs(R)),
    (5, |h| h.n_ur, Factor::Prod(U, R)),
    (5, |h| h.n_wp, Factor::Prod(W, P)),
    (5, |h| h.n_pq, Factor::Prod(P, Q)),
    (5, |h| h.n_uv, Factor::Prod(U, V)),
    (5, |h| h.n_uudr, Factor::Fin(0)),
];

/// The reference vehicle.
///
/// ```
/// use edgekf_sim::systems::uuv::reference::{Forcing, ReferenceVehicle};
/// use edgekf::systems::uuv::Vehicle;
/// let v = ReferenceVehicle::new(&Vehicle::default()).unwrap();
/// let x = ReferenceVehicle::level(10.0, 0.0, 1.5);
/// let f = Forcing { n_t: 1500.0, n_v: 0.0, rudder: 0.0, elevator: 0.0, k_t: 1.0, k_v: 1.0,
///                   current: [0.0; 2], current_rate: [0.0; 2] };
/// let next = v.rk4(&x, &f, 0.005);
/// assert!(next[7] > 1.5); // 1.5 m/s is below the 1500 rpm cruise: it speeds up
/// ```
#[derive(Debug, Clone)]
pub struct ReferenceVehicle {
    v: Vehicle,
    r_g: Vector3<f64>,
    inertia: Matrix3<f64>,
    added: Matrix6<f64>,
    mass_inv: Matrix6<f64>,
}

fn skew(a: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

impl ReferenceVehicle {
    /// The model of `v`; `None` if its mass matrix is singular or a constant fails
    /// [`Vehicle::check`].
    pub fn new(v: &Vehicle) -> Option<Self> {
        v.check().ok()?;
        let m = v.mass();
        let r_g = Vector3::new(0.0, 0.0, v.z_g);
        let inertia = Matrix3::from_diagonal(&Vector3::new(v.i_xx, v.i_yy, v.i_zz));
        let mut rigid = Matrix6::zeros();
        rigid.fixed_view_mut::<3, 3>(0, 0).copy_from(&(Matrix3::identity() * m));
        rigid.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-skew(&r_g) * m));
        rigid.fixed_view_mut::<3, 3>(3, 0).copy_from(&(skew(&r_g) * m));
        rigid.fixed_view_mut::<3, 3>(3, 3).copy_from(&inertia);
        let h = &v.hydro;
        let mut added = Matrix6::zeros();
        for (i, j, c) in [
            (U, U, h.x_udot),
            (V, V, h.y_vdot),
            (V, R, h.y_rdot),
            (W, W, h.z_wdot),
            (W, Q, h.z_qdot),
            (P, P, h.k_pdot),
            (Q, W, h.m_wdot),
            (Q, Q, h.m_qdot),
            (R, V, h.n_vdot),
            (R, R, h.n_rdot),
        ] {
            added[(i, j)] = -c;
        }
        let mass_inv = (rigid + added).try_inverse()?;
        Some(Self { v: *v, r_g, inertia, added, mass_inv })
    }

    /// Level at depth `z` (m), heading `psi` (rad), surging at `u` (m/s).
    pub fn level(z: f64, psi: f64, u: f64) -> RefState {
        let q = UnitQuaternion::from_euler_angles(0.0, 0.0, psi);
        let mut x = RefState::zeros();
        x[2] = z;
        x[at::QUATERNION] = q.w;
        x[at::QUATERNION + 1] = q.i;
        x[at::QUATERNION + 2] = q.j;
        x[at::QUATERNION + 3] = q.k;
        x[at::VELOCITY] = u;
        x
    }

    /// The attitude of `x`.
    pub fn attitude(x: &RefState) -> UnitQuaternion<f64> {
        let q = at::QUATERNION;
        UnitQuaternion::from_quaternion(Quaternion::new(x[q], x[q + 1], x[q + 2], x[q + 3]))
    }

    /// Roll, pitch and yaw of `x`, rad (`R = Rz(ψ) Ry(θ) Rx(φ)`).
    pub fn euler(x: &RefState) -> [f64; 3] {
        let (phi, theta, psi) = Self::attitude(x).euler_angles();
        [phi, theta, psi]
    }

    /// `ν̇` of `x` under `f`.
    pub fn accelerations(&self, x: &RefState, f: &Forcing) -> Vector6<f64> {
        let rot = Self::attitude(x).to_rotation_matrix();
        let nu = x.fixed_rows::<6>(at::VELOCITY).into_owned();
        let lin = nu.fixed_rows::<3>(0).into_owned();
        let omega = nu.fixed_rows::<3>(3).into_owned();
        let m = self.v.mass();
        // The current in body axes and its rate as seen from the turning body.
        let c = Vector3::new(f.current[0], f.current[1], 0.0);
        let c_body = rot.inverse() * c;
        let c_dot_body =
            -omega.cross(&c_body) + rot.inverse() * Vector3::new(f.current_rate[0], f.current_rate[1], 0.0);
        let mut rel = nu;
        rel.fixed_rows_mut::<3>(0).copy_from(&(lin - c_body));
        // Hydrodynamic derivatives.
        let fins = [f.rudder, f.elevator];
        let mut tau = Vector6::zeros();
        for (dof, coefficient, factor) in TERMS {
            let value = match factor {
                Factor::Abs(a) => rel[a] * rel[a].abs(),
                Factor::Lin(a) => rel[a],
                Factor::Prod(a, b) => rel[a] * rel[b],
                Factor::Fin(k) => rel[U] * rel[U] * fins[k],
            };
            tau[dof] += coefficient(&self.v.hydro) * value;
        }
        // Weight at r_g and buoyancy at the origin, both vertical in the earth frame.
        let down = rot.inverse() * Vector3::z();
        let weight = down * self.v.weight;
        let buoyancy = -down * self.v.buoyancy;
        let moment = self.r_g.cross(&weight);
        for i in 0..3 {
            tau[i] += weight[i] + buoyancy[i];
            tau[3 + i] += moment[i];
        }
        // Thrusters.
        let a = &self.v.actuators;
        let main = f.k_t * f.n_t * f.n_t.abs();
        tau[0] += a.main_thrust * main;
        tau[3] += a.main_torque * main;
        tau[2] += f.k_v * a.vertical_thrust * f.n_v * f.n_v.abs();
        // Rigid-body Coriolis and centripetal terms, C_RB(ν) ν.
        let coriolis_lin = (omega.cross(&lin) + omega.cross(&omega.cross(&self.r_g))) * m;
        let coriolis_ang = self.r_g.cross(&omega.cross(&lin)) * m + omega.cross(&(self.inertia * omega));
        for i in 0..3 {
            tau[i] -= coriolis_lin[i];
            tau[3 + i] -= coriolis_ang[i];
        }
        // Added mass on the relative acceleration: M_A (ν̇ − ν̇_c).
        let mut nu_c_dot = Vector6::zeros();
        nu_c_dot.fixed_rows_mut::<3>(0).copy_from(&c_dot_body);
        tau += self.added * nu_c_dot;
        self.mass_inv * tau
    }

    /// `ẋ` of `x` under `f`.
    pub fn derivative(&self, x: &RefState, f: &Forcing) -> RefState {
        let att = Self::attitude(x);
        let nu = x.fixed_rows::<6>(at::VELOCITY);
        let lin = Vector3::new(nu[0], nu[1], nu[2]);
        let omega = Quaternion::new(0.0, nu[3], nu[4], nu[5]);
        let q = at::QUATERNION;
        let raw = Quaternion::new(x[q], x[q + 1], x[q + 2], x[q + 3]);
        let q_dot = raw * omega * 0.5;
        let mut d = RefState::zeros();
        d.fixed_rows_mut::<3>(at::POSITION).copy_from(&(att * lin));
        d[q] = q_dot.w;
        d[q + 1] = q_dot.i;
        d[q + 2] = q_dot.j;
        d[q + 3] = q_dot.k;
        d.fixed_rows_mut::<6>(at::VELOCITY).copy_from(&self.accelerations(x, f));
        d
    }

    /// One classical RK4 step of `h` seconds (the forcing held), quaternion renormalised.
    pub fn rk4(&self, x: &RefState, f: &Forcing, h: f64) -> RefState {
        let k1 = self.derivative(x, f);
        let k2 = self.derivative(&(x + k1 * (h / 2.0)), f);
        let k3 = self.derivative(&(x + k2 * (h / 2.0)), f);
        let k4 = self.derivative(&(x + k3 * h), f);
        let mut next = x + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
        let q = at::QUATERNION;
        let norm = next.fixed_rows::<4>(q).norm();
        next.fixed_rows_mut::<4>(q).unscale_mut(norm);
        next
    }

    /// What an accelerometer at the origin reads at `x` under `f`, body axes, m/s².
    pub fn specific_force(&self, x: &RefState, f: &Forcing) -> Vector3<f64> {
        let a = self.accelerations(x, f);
        let nu = x.fixed_rows::<6>(at::VELOCITY);
        let lin = Vector3::new(nu[0], nu[1], nu[2]);
        let omega = Vector3::new(nu[3], nu[4], nu[5]);
        let gravity = Self::attitude(x).inverse() * Vector3::new(0.0, 0.0, self.v.gravity);
        Vector3::new(a[0], a[1], a[2]) + omega.cross(&lin) - gravity
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use edgekf::systems::uuv::{Attitude, Drive, Nu, ReducedDynamics};

    fn forcing(n_t: f64) -> Forcing {
        Forcing {
            n_t,
            n_v: 0.0,
            rudder: 0.0,
            elevator: 0.0,
            k_t: 1.0,
            k_v: 1.0,
            current: [0.1, -0.2],
            current_rate: [0.0; 2],
        }
    }

    /// The two formulations agree on the accelerations at an arbitrary state in still water,
    /// and differ in a current only by the added mass's `ω × v_c` (the reference's alone).
    #[test]
    fn vector_form_agrees_with_the_estimators_component_form() {
        for (current, tolerance) in [([0.0, 0.0], 1e-12), ([0.1, -0.2], 5e-3)] {
            agree(current, tolerance);
        }
    }

    fn agree(current: [f64; 2], tolerance: f64) {
        let v = Vehicle::default();
        let reference = ReferenceVehicle::new(&v).unwrap();
        let reduced = ReducedDynamics::<f64>::new(&v).unwrap();
        let (phi, theta, psi) = (0.1, -0.05, 0.7);
        let q = UnitQuaternion::from_euler_angles(phi, theta, psi);
        let mut x = RefState::zeros();
        x[at::QUATERNION] = q.w;
        x[at::QUATERNION + 1] = q.i;
        x[at::QUATERNION + 2] = q.j;
        x[at::QUATERNION + 3] = q.k;
        let nu = [1.4, 0.05, -0.03, 0.02, -0.01, 0.04];
        for (i, n) in nu.iter().enumerate() {
            x[at::VELOCITY + i] = *n;
        }
        let mut f = forcing(1500.0);
        f.current = current;
        f.rudder = 0.05;
        f.elevator = -0.03;
        f.n_v = 1200.0;
        let a_ref = reference.accelerations(&x, &f);
        let drive = Drive {
            n_t: f.n_t,
            n_v: f.n_v,
            rudder: f.rudder,
            elevator: f.elevator,
            k_t: 1.0,
            k_v: 1.0,
            current: f.current,
        };
        let a_red = reduced.accelerations(&Attitude::new(phi, theta, psi), &Nu::from(nu), &drive);
        for i in 0..6 {
            let d = (a_ref[i] - a_red[i]).abs();
            assert!(d < tolerance * (1.0 + a_ref[i].abs()), "{i}: {} vs {}", a_ref[i], a_red[i]);
            if tolerance > 1e-9 && i == 0 {
                assert!(d > 1e-7, "the current's apparent acceleration is missing from the reference");
            }
        }
    }

    /// Prestero's check: steady speed and roll at 1500 rpm in still water, flown by the
    /// autopilots (depth held by the tunnel thruster, so the vehicle flies level).
    #[test]
    fn steady_flight_at_1500_rpm_is_the_thesis_s() {
        use crate::systems::uuv::{simulate, Scenario, SimOptions, UuvConfig};
        let mut config = UuvConfig::default();
        config.current.speed = [0.0, 0.0];
        config.current.variation = 0.0;
        let rec = simulate(&config, &SimOptions { scenario: Scenario::Healthy, duration: 20.0, seed: 3 }, &mut |_| {})
            .unwrap();
        let mean = |name: &str| {
            let c = rec.column(name).unwrap();
            c.iter().sum::<f64>() / c.len() as f64
        };
        let (u, phi) = (mean("truth_u"), mean("truth_phi").to_degrees());
        assert!((u - 1.51).abs() < 0.03 * 1.51, "u = {u}");
        assert!((phi + 5.3).abs() < 0.2, "roll = {phi}°");
    }
}
