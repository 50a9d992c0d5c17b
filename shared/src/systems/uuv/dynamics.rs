//! The estimator's vehicle model: Prestero's component equations with Euler angles, one
//! constant mass matrix inverted once, and a midpoint step.
//!
//! The rigid-body terms are written out for a centre of gravity straight below the origin
//! (`x_g = y_g = 0`), the hydrodynamic terms take the velocity relative to the water, the
//! rigid-body terms the velocity over ground. What the host's reference simulator does and this
//! model does not: quaternions, four RK4 steps per sample, and the added mass's share of the
//! current's apparent acceleration in a turning frame (`M_A (ω × v_c)`, a few mm/s² in a turn
//! across a 0.2 m/s current, nothing in straight flight).

use super::settings::VELOCITY;
use super::vehicle::Vehicle;
use crate::Real;
use nalgebra::{SMatrix, SVector};

/// Body velocity `[u v w p q r]` (m/s, rad/s).
pub type Nu<T> = SVector<T, 6>;

/// What drives the vehicle during one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drive<T> {
    /// Main thruster speed, rpm (signed).
    pub n_t: T,
    /// Vertical thruster speed, rpm (signed; positive pushes down).
    pub n_v: T,
    /// Rudder, rad.
    pub rudder: T,
    /// Elevator (stern planes), rad.
    pub elevator: T,
    /// Main thruster health factor.
    pub k_t: T,
    /// Vertical thruster health factor.
    pub k_v: T,
    /// Ocean current over ground, north and east, m/s (horizontal).
    pub current: [T; 2],
}

/// Sines and cosines of the Euler angles.
#[derive(Debug, Clone, Copy)]
pub struct Attitude<T> {
    /// `sin φ`, `cos φ`.
    pub roll: (T, T),
    /// `sin θ`, `cos θ` (`cos θ` kept away from zero).
    pub pitch: (T, T),
    /// `sin ψ`, `cos ψ`.
    pub yaw: (T, T),
}

impl<T: Real> Attitude<T> {
    /// From roll, pitch and yaw, rad.
    pub fn new(phi: T, theta: T, psi: T) -> Self {
        use crate::trig::sin_cos;
        let (st, ct) = sin_cos(theta);
        Self { roll: sin_cos(phi), pitch: (st, ct.max(T::of_f64(0.05))), yaw: sin_cos(psi) }
    }

    /// Body to earth (north, east, down): `R = Rz(ψ) Ry(θ) Rx(φ)`.
    pub fn to_earth(&self) -> SMatrix<T, 3, 3> {
        let ((sf, cf), (st, ct), (sp, cp)) = (self.roll, self.pitch, self.yaw);
        SMatrix::<T, 3, 3>::new(
            cp * ct,
            cp * st * sf - sp * cf,
            cp * st * cf + sp * sf,
            sp * ct,
            sp * st * sf + cp * cf,
            sp * st * cf - cp * sf,
            -st,
            ct * sf,
            ct * cf,
        )
    }

    /// Euler-angle rates from body rates.
    pub fn angle_rates(&self, p: T, q: T, r: T) -> [T; 3] {
        let ((sf, cf), (st, ct)) = (self.roll, self.pitch);
        let turn = q * sf + r * cf;
        [p + turn * st / ct, q * cf - r * sf, turn / ct]
    }
}

/// The reduced model: constants in the filter's precision and the inverse mass matrix.
///
/// ```
/// use edgekf::systems::uuv::{Attitude, Drive, ReducedDynamics, Vehicle};
/// use nalgebra::SVector;
/// let d = ReducedDynamics::<f64>::new(&Vehicle::default()).unwrap();
/// let drive = Drive { n_t: 1500.0, n_v: 0.0, rudder: 0.0, elevator: 0.0, k_t: 1.0, k_v: 1.0, current: [0.0; 2] };
/// let level = Attitude::new(0.0, 0.0, 0.0);
/// // At rest, the propeller accelerates the vehicle forward.
/// let a = d.accelerations(&level, &SVector::zeros(), &drive);
/// assert!(a[0] > 0.1 && a[0] < 0.15);
/// ```
#[derive(Debug, Clone)]
pub struct ReducedDynamics<T: Real> {
    c: Coefficients<T>,
    m_inv: SMatrix<T, 6, 6>,
}

/// The vehicle's constants in `T`.
#[derive(Debug, Clone, Copy)]
struct Coefficients<T> {
    m: T,
    g: T,
    w: T,
    b: T,
    zg: T,
    ixx: T,
    iyy: T,
    izz: T,
    h: [T; 45],
    kt: T,
    kq: T,
    kv: T,
}

/// Indices into `Hydro::as_array`.
mod ix {
    pub const X_UU: usize = 0;
    pub const X_WQ: usize = 2;
    pub const X_QQ: usize = 3;
    pub const X_VR: usize = 4;
    pub const X_RR: usize = 5;
    pub const Y_VV: usize = 6;
    pub const Y_RR: usize = 7;
    pub const Y_UV: usize = 8;
    pub const Y_UR: usize = 11;
    pub const Y_WP: usize = 12;
    pub const Y_PQ: usize = 13;
    pub const Y_UUDR: usize = 14;
    pub const Z_WW: usize = 15;
    pub const Z_QQ: usize = 16;
    pub const Z_UW: usize = 17;
    pub const Z_UQ: usize = 20;
    pub const Z_VP: usize = 21;
    pub const Z_RP: usize = 22;
    pub const Z_UUDS: usize = 23;
    pub const K_PP: usize = 24;
    pub const K_P: usize = 25;
    pub const M_WW: usize = 27;
    pub const M_QQ: usize = 28;
    pub const M_UW: usize = 29;
    pub const M_UQ: usize = 32;
    pub const M_VP: usize = 33;
    pub const M_RP: usize = 34;
    pub const M_UUDS: usize = 35;
    pub const N_VV: usize = 36;
    pub const N_RR: usize = 37;
    pub const N_UV: usize = 38;
    pub const N_UR: usize = 41;
    pub const N_WP: usize = 42;
    pub const N_PQ: usize = 43;
    pub const N_UUDR: usize = 44;
}

/// The seven hydrodynamic products that one pair of the equations of motion shares (sway and
/// yaw, or heave and pitch): six of two velocities, and the control surface's `u_r·u_r·δ`.
type Products<T> = ([[T; 2]; 6], [T; 3]);

/// `start + c₀·a₀·b₀ + … + c₅·a₅·b₅ + c₆·u_r·u_r·δ`: one equation's coefficients `c` on its
/// pair's products `p`, multiplied and added left to right as the equation written out (the
/// same operations in the same order, so the same bits and the same instructions).
#[inline(always)]
fn hydrodynamic<T: Real>(start: T, c: [T; 7], p: &Products<T>) -> T {
    let [c0, c1, c2, c3, c4, c5, c6] = c;
    let ([[a0, b0], [a1, b1], [a2, b2], [a3, b3], [a4, b4], [a5, b5]], [u0, u1, d]) = *p;
    start + c0 * a0 * b0 + c1 * a1 * b1 + c2 * a2 * b2 + c3 * a3 * b3 + c4 * a4 * b4 + c5 * a5 * b5 + c6 * u0 * u1 * d
}

impl<T: Real> ReducedDynamics<T> {
    /// The model of `vehicle`; `None` if its constants fail [`Vehicle::check`] or its mass
    /// matrix is singular.
    pub fn new(vehicle: &Vehicle) -> Option<Self> {
        vehicle.check().ok()?;
        let m_inv = crate::linalg::solve(&Self::mass_matrix(vehicle), &SMatrix::<f64, 6, 6>::identity())?;
        let h = vehicle.hydro.as_array();
        let a = &vehicle.actuators;
        let t = T::of_f64;
        Some(Self {
            c: Coefficients {
                m: t(vehicle.mass()),
                g: t(vehicle.gravity),
                w: t(vehicle.weight),
                b: t(vehicle.buoyancy),
                zg: t(vehicle.z_g),
                ixx: t(vehicle.i_xx),
                iyy: t(vehicle.i_yy),
                izz: t(vehicle.i_zz),
                h: h.map(t),
                kt: t(a.main_thrust),
                kq: t(a.main_torque),
                kv: t(a.vertical_thrust),
            },
            m_inv: m_inv.map(t),
        })
    }

    /// Rigid-body plus added mass, `[u̇ v̇ ẇ ṗ q̇ ṙ]` coefficients of Prestero's six equations.
    fn mass_matrix(v: &Vehicle) -> SMatrix<f64, 6, 6> {
        let (m, zg, h) = (v.mass(), v.z_g, &v.hydro);
        let mut mm = SMatrix::<f64, 6, 6>::zeros();
        mm[(0, 0)] = m - h.x_udot;
        mm[(0, 4)] = m * zg;
        mm[(1, 1)] = m - h.y_vdot;
        mm[(1, 3)] = -m * zg;
        mm[(1, 5)] = -h.y_rdot;
        mm[(2, 2)] = m - h.z_wdot;
        mm[(2, 4)] = -h.z_qdot;
        mm[(3, 1)] = -m * zg;
        mm[(3, 3)] = v.i_xx - h.k_pdot;
        mm[(4, 0)] = m * zg;
        mm[(4, 2)] = -h.m_wdot;
        mm[(4, 4)] = v.i_yy - h.m_qdot;
        mm[(5, 1)] = -h.n_vdot;
        mm[(5, 5)] = v.i_zz - h.n_rdot;
        mm
    }

    /// Straight and level speed through the water at main thruster speed `n_t` (thrust against
    /// `X_u|u|` alone), m/s: a first guess when no velocity is measured.
    pub fn cruise_speed(&self, n_t: f64) -> f64 {
        let thrust = self.c.kt.as_f64() * n_t * n_t.abs();
        let drag = -self.c.h[ix::X_UU].as_f64();
        if drag > 0.0 && thrust.is_finite() {
            thrust.signum() * libm::sqrt(thrust.abs() / drag)
        } else {
            0.0
        }
    }

    /// Gravitational acceleration, m/s².
    pub fn gravity(&self) -> T {
        self.c.g
    }

    /// `ν̇` at attitude `att`, body velocity `nu` (over ground) and `drive`.
    pub fn accelerations(&self, att: &Attitude<T>, nu: &Nu<T>, drive: &Drive<T>) -> Nu<T> {
        use ix::*;
        let c = &self.c;
        let h = &c.h;
        let (u, v, w, p, q, r) = (nu[0], nu[1], nu[2], nu[3], nu[4], nu[5]);
        // Velocity through the water: the current seen in body axes taken off.
        let earth = att.to_earth();
        let cur = earth.transpose() * SVector::<T, 3>::new(drive.current[0], drive.current[1], T::zero());
        let (ur, vr, wr) = (u - cur[0], v - cur[1], w - cur[2]);
        let ((sf, cf), (st, ct)) = (att.roll, att.pitch);
        let wb = c.w - c.b;
        let (dr, ds) = (drive.rudder, drive.elevator);
        let main = drive.k_t * drive.n_t * drive.n_t.abs();
        let vert = drive.k_v * c.kv * drive.n_v * drive.n_v.abs();
        let x = -wb * st
            + h[X_UU] * ur * ur.abs()
            + h[X_WQ] * wr * q
            + h[X_QQ] * q * q
            + h[X_VR] * vr * r
            + h[X_RR] * r * r
            + c.kt * main
            - c.m * (w * q - v * r + c.zg * p * r);
        // Sway and yaw share their seven hydrodynamic products, heave and pitch theirs.
        let lateral = ([[vr, vr.abs()], [r, r.abs()], [ur, r], [wr, p], [p, q], [ur, vr]], [ur, ur, dr]);
        let vertical = ([[wr, wr.abs()], [q, q.abs()], [ur, q], [vr, p], [r, p], [ur, wr]], [ur, ur, ds]);
        let y = hydrodynamic(wb * ct * sf, [h[Y_VV], h[Y_RR], h[Y_UR], h[Y_WP], h[Y_PQ], h[Y_UV], h[Y_UUDR]], &lateral)
            - c.m * (u * r - w * p + c.zg * q * r);
        let z =
            hydrodynamic(wb * ct * cf, [h[Z_WW], h[Z_QQ], h[Z_UQ], h[Z_VP], h[Z_RP], h[Z_UW], h[Z_UUDS]], &vertical)
                + vert
                - c.m * (v * p - u * q - c.zg * (p * p + q * q));
        let k = -c.zg * c.w * ct * sf + h[K_PP] * p * p.abs() + h[K_P] * p + c.kq * main - (c.izz - c.iyy) * q * r
            + c.m * c.zg * (u * r - w * p);
        let mm = hydrodynamic(
            -c.zg * c.w * st,
            [h[M_WW], h[M_QQ], h[M_UQ], h[M_VP], h[M_RP], h[M_UW], h[M_UUDS]],
            &vertical,
        ) - (c.ixx - c.izz) * r * p
            - c.m * c.zg * (w * q - v * r);
        // −0 is the exact identity of `+`: the sum starts at the first product, as written out.
        let n = hydrodynamic(-T::zero(), [h[N_VV], h[N_RR], h[N_UR], h[N_WP], h[N_PQ], h[N_UV], h[N_UUDR]], &lateral)
            - (c.iyy - c.ixx) * p * q;
        self.m_inv * Nu::<T>::from([x, y, z, k, mm, n])
    }

    /// What an accelerometer at the origin reads, body axes, m/s²: the acceleration over
    /// ground minus gravity (a level vehicle at rest reads `[0, 0, −g]`).
    pub fn specific_force(&self, att: &Attitude<T>, nu: &Nu<T>, nu_dot: &Nu<T>) -> [T; 3] {
        let (u, v, w, p, q, r) = (nu[0], nu[1], nu[2], nu[3], nu[4], nu[5]);
        let ((sf, cf), (st, ct)) = (att.roll, att.pitch);
        let g = self.c.g;
        [
            nu_dot[0] + q * w - r * v + g * st,
            nu_dot[1] + r * u - p * w - g * ct * sf,
            nu_dot[2] + p * v - q * u - g * ct * cf,
        ]
    }
}

/// The filters' view of the model: the ten vehicle states `[z φ θ ψ u v w p q r]` first in a
/// state vector of `N`, the rest (health factors, biases, current) random walks that act
/// through the [`Drive`] the caller reads from the state.
impl<T: Real> ReducedDynamics<T> {
    /// Rates of the ten vehicle states of `x` under `drive`.
    pub fn state_rates<const N: usize>(&self, x: &SVector<T, N>, drive: &Drive<T>) -> [T; 10] {
        let att = Attitude::new(x[1], x[2], x[3]);
        let nu: Nu<T> = x.fixed_rows::<6>(VELOCITY).into_owned();
        let a = self.accelerations(&att, &nu, drive);
        let down = att.to_earth().fixed_rows::<1>(2) * nu.fixed_rows::<3>(0);
        let e = att.angle_rates(nu[3], nu[4], nu[5]);
        [down[0], e[0], e[1], e[2], a[0], a[1], a[2], a[3], a[4], a[5]]
    }

    /// One midpoint step of `x`'s vehicle states over `dt`, the drive read from the state at
    /// each stage; the other states are left as they are.
    pub fn midpoint_step<const N: usize>(
        &self,
        x: &SVector<T, N>,
        dt: T,
        drive: impl Fn(&SVector<T, N>) -> Drive<T>,
    ) -> SVector<T, N> {
        let half = dt * T::of_f64(0.5);
        let k1 = self.state_rates(x, &drive(x));
        let mut mid = *x;
        for (i, d) in k1.iter().enumerate() {
            mid[i] += half * *d;
        }
        let k2 = self.state_rates(&mid, &drive(&mid));
        let mut next = *x;
        for (i, d) in k2.iter().enumerate() {
            next[i] += dt * *d;
        }
        next
    }

    /// What a bias-free IMU at the origin reads in state `x` under `drive`: specific force
    /// (m/s²) and rates (rad/s), body axes.
    pub fn imu<const N: usize>(&self, x: &SVector<T, N>, drive: &Drive<T>) -> SVector<T, 6> {
        let att = Attitude::new(x[1], x[2], x[3]);
        let nu: Nu<T> = x.fixed_rows::<6>(VELOCITY).into_owned();
        let a = self.accelerations(&att, &nu, drive);
        let f = self.specific_force(&att, &nu, &a);
        SVector::<T, 6>::from([f[0], f[1], f[2], nu[3], nu[4], nu[5]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drive(n_t: f64) -> Drive<f64> {
        Drive { n_t, n_v: 0.0, rudder: 0.0, elevator: 0.0, k_t: 1.0, k_v: 1.0, current: [0.0; 2] }
    }

    #[test]
    fn level_at_rest_reads_minus_g_and_rises_by_the_net_buoyancy() {
        let v = Vehicle::default();
        let d = ReducedDynamics::<f64>::new(&v).unwrap();
        let att = Attitude::new(0.0, 0.0, 0.0);
        let a = d.accelerations(&att, &Nu::zeros(), &drive(0.0));
        // 7 N up on m − Z_ẇ = 30.48 + 35.5 kg; the pitch couplings (Z_q̇, M_ẇ) move it 0.7 %.
        let expected = -(v.buoyancy - v.weight) / (v.mass() - v.hydro.z_wdot);
        assert!((a[2] - expected).abs() < 1e-2 * expected.abs(), "{} vs {expected}", a[2]);
        let f = d.specific_force(&att, &Nu::zeros(), &Nu::zeros());
        assert_eq!(f, [0.0, 0.0, -9.81]);
    }

    #[test]
    fn surge_balance_is_thrust_against_quadratic_drag() {
        let v = Vehicle::default();
        let d = ReducedDynamics::<f64>::new(&v).unwrap();
        let att = Attitude::new(0.0, 0.0, 0.0);
        let u = (3.86 / 1.62f64).sqrt();
        let nu = Nu::from([u, 0.0, 0.0, 0.0, 0.0, 0.0]);
        let a = d.accelerations(&att, &nu, &drive(1500.0));
        // Balanced but for the net buoyancy's heave reaching surge through z_g (m z_g q̇).
        assert!(a[0].abs() < 1e-3, "{}", a[0]);
        // A head current of 0.2 m/s adds drag: the vehicle slows.
        let head = Drive { current: [-0.2, 0.0], ..drive(1500.0) };
        assert!(d.accelerations(&att, &nu, &head)[0] < -0.02);
    }

    #[test]
    fn earth_rotation_is_orthonormal() {
        let r = Attitude::new(0.1f64, -0.2, 2.5).to_earth();
        assert!((r * r.transpose() - SMatrix::<f64, 3, 3>::identity()).norm() < 1e-12);
    }
}
