//! The soak of the shared core's joint UKF on a mode's state and stiffness: no node runs it as
//! such (its row's system is `"core"`, not a system of [`crate::systems`]).

use super::engine::{not_started, psd_root, swing, Blocks, Drift, Noise, SoakFrame, SoakRow};
use edgekf::filter::{JointModel, MerweSigmaPoints, ParametricModel, UnscentedKalmanFilter};
use edgekf::linalg::van_loan;
use nalgebra::{Matrix1, Matrix2, Vector1, Vector2};

/// Steps per block of statistics.
const BLOCK: u32 = 10_000;

/// Its row.
pub const SOAKS: &[SoakRow] = &[JOINT_UKF];

/// The joint UKF of a mode's state and stiffness (the shared core's UKF; no node runs it as
/// such).
pub const JOINT_UKF: SoakRow = SoakRow {
    name: "joint_ukf",
    system: "core",
    image: None,
    what: "joint UKF (a mode's stiffness)",
    drift: "stiffness ±10 % over 5.5 h",
    error_of: "stiffness",
    host_steps: 1_000_000,
    qemu_steps: 80_000,
    qemu_long_steps: 1_000_000,
    nis_limit: Some(1.3),
    error_limit: 0.05,
    run: joint_ukf,
};

/// A damped mode `ẍ = −k x − c ẋ + w` whose stiffness (per unit mass) `k` the joint UKF
/// estimates with its state, one RK4 step per sample.
struct Mode {
    dt: f32,
    damping: f32,
}

impl ParametricModel<f32, 2, 1, 1> for Mode {
    fn f(&self, x: &Vector2<f32>, p: &Vector1<f32>) -> Vector2<f32> {
        let (k, c, dt) = (p[0], self.damping, self.dt);
        let deriv = |s: &Vector2<f32>| Vector2::new(s[1], -k * s[0] - c * s[1]);
        let k1 = deriv(x);
        let k2 = deriv(&(x + k1 * (0.5 * dt)));
        let k3 = deriv(&(x + k2 * (0.5 * dt)));
        let k4 = deriv(&(x + k3 * dt));
        x + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0)
    }

    fn h(&self, x: &Vector2<f32>, _p: &Vector1<f32>) -> Vector1<f32> {
        Vector1::new(x[0])
    }
}

/// The joint UKF in `f32` on a 1.5 Hz mode (ζ = 5 %) under white random acceleration, read at
/// 100 Hz with 5 cm noise, whose true stiffness drifts by ±10 % over 5.5 hours (a part wearing
/// and recovering): the truth is discretised exactly (in `f64`) at the current stiffness every
/// block. The error is that of the stiffness estimate, from 10 minutes on (the stiffness is
/// only seen over many cycles).
#[inline(never)]
pub fn joint_ukf(n: u32) -> SoakFrame {
    let (dt, zeta, k0) = (0.01, 0.05, (core::f64::consts::TAU * 1.5f64) * (core::f64::consts::TAU * 1.5f64));
    let c = 2.0 * zeta * libm::sqrt(k0);
    let (accel_psd, meas_std) = (100.0, 0.05f32);
    let k_at = |k: u32| k0 * swing(f64::from(k) * dt, 0.1, 20_000.0);
    let truth = |k_true: f64| {
        let (a, q) =
            van_loan::<f64, 2, 4>(&Matrix2::new(0.0, 1.0, -k_true, -c), &Matrix2::new(0.0, 0.0, 0.0, accel_psd), dt)
                .ok()?;
        Some((a.cast::<f32>(), psd_root(&q).cast::<f32>()))
    };
    let model = JointModel::<_, 2, 1, 3>::new(Mode { dt: dt as f32, damping: c as f32 });
    let qx = Matrix2::new(dt * dt * dt / 3.0, dt * dt / 2.0, dt * dt / 2.0, dt) * accel_psd;
    // k may drift by about 0.3 s⁻² per 100 s (its true rate is up to 0.28).
    let q = model.block_diag(&qx.map(|v| v as f32), &Matrix1::new(1e-5f32));
    let p0 = model.block_diag(&Matrix2::new(1.0f32, 0.0, 0.0, 100.0), &Matrix1::new(900.0f32));
    let z0 = model.stack(&Vector2::zeros(), &Vector1::new(60.0f32));
    let r = Matrix1::new(meas_std * meas_std);
    let points = MerweSigmaPoints { alpha: 0.5f32, beta: 2.0, kappa: 0.0 };
    let (Ok(mut ukf), Some((mut a, mut q_root))) = (UnscentedKalmanFilter::new(points, q, r, z0, p0), truth(k_at(0)))
    else {
        return not_started(n);
    };
    let mut stiffness = Drift::new(dt);
    let mut noise = Noise(0x50A4_0003);
    let mut x = Vector2::<f32>::new(0.5, 0.0);
    let mut blocks = Blocks::new(n, 1.0);
    for k in 0..n {
        x = a * x + q_root * noise.vector::<2>();
        let y = x[0] + meas_std * noise.unit();
        ukf.predict(&model);
        let nis = ukf.update(&model, &Vector1::new(y)).map_or(f32::NAN, |inn| inn.nis);
        let est = model.parameters(&ukf);
        if !(ukf.state().iter().all(|v| v.is_finite()) && est.std[0] > 0.0 && nis.is_finite()) {
            blocks.non_finite();
        }
        if k >= 60_000 {
            let truth_k = stiffness.at(k, |t| k0 * swing(t, 0.1, 20_000.0));
            let e = f64::from(est.mean[0]) - f64::from(truth_k);
            blocks.push(nis, e * e, f64::from(truth_k) * f64::from(truth_k));
        }
        if (k + 1) % BLOCK == 0 {
            if k >= 60_000 {
                blocks.close();
            }
            blocks.covariance(ukf.covariance());
            if let Some(m) = truth(k_at(k + 1)) {
                (a, q_root) = m;
            }
        }
    }
    blocks.finish(ukf.health())
}
