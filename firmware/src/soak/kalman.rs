//! The soaks of the Kalman filters: the oscillator's harmonic-force filter (time-varying and
//! steady-state), the rotor nodes' AKFs, from the probes and from the accelerometers (each with
//! its start-up term throughout, and as the node runs it), and a joint UKF of a mode's state
//! and stiffness.

use super::{psd_root, swing, Blocks, Drift, Noise, SoakFrame, SoakRow};
use crate::systems::rotor::accel::{self, ACCEL_DESIGN, ACCEL_STATES};
use crate::systems::rotor::{constants as probes, RotorEstimator, DESIGN, STATES, STEADY_AFTER};
use edgekf::export::matrix;
use edgekf::filter::{JointModel, MerweSigmaPoints, ParametricModel, UnscentedKalmanFilter};
use edgekf::linalg::van_loan;
use edgekf::systems::oscillator::{GainMode, HarmonicForceEstimator, HarmonicForceParams};
use nalgebra::{Matrix1, Matrix2, SVector, Vector1, Vector2, Vector4};

/// Steps per block of statistics.
const BLOCK: u32 = 10_000;

/// A soak that could not start: every step counted non-finite, so that it fails its check.
pub(super) fn not_started(steps: u32) -> SoakFrame {
    SoakFrame { steps, non_finite: steps.max(1), ..SoakFrame::default() }
}

/// The harmonic-force estimator, time-varying gain.
pub const OSCILLATOR_VARYING: SoakRow = SoakRow {
    name: "oscillator_varying",
    system: "oscillator",
    image: Some("edgekf-qemu"),
    what: "harmonic-force KF, time-varying (oscillator)",
    drift: "force 0.5–1.5 N over 10 min, mode frequency ±0.3 % over 20 min",
    error_of: "force amplitude",
    host_steps: 1_000_000,
    qemu_steps: 30_000,
    qemu_long_steps: 1_500_000,
    nis_limit: Some(1.3),
    error_limit: 0.05,
    run: |n| oscillator(GainMode::TimeVarying, n),
};

/// The harmonic-force estimator as the oscillator node runs it, steady-state gain.
pub const OSCILLATOR_STEADY: SoakRow = SoakRow {
    name: "oscillator_steady",
    what: "harmonic-force, steady-state gain (oscillator node)",
    qemu_long_steps: 2_000_000,
    run: |n| oscillator(GainMode::SteadyState, n),
    ..OSCILLATOR_VARYING
};

/// The rotor's AKF with its start-up term throughout.
pub const ROTOR_START_UP: SoakRow = SoakRow {
    name: "rotor_start_up",
    system: "rotor",
    image: Some("edgekf-rotor-qemu"),
    what: "rotor AKF with its start-up term throughout (20 states, 4 probes)",
    drift: "unbalance sizes ±50 % over 10 and 7 min",
    error_of: "disk displacements",
    host_steps: 1_000_000,
    qemu_steps: 20_000,
    qemu_long_steps: 200_000,
    nis_limit: Some(1.3),
    error_limit: 0.05,
    run: |n| rotor(RotorEstimator::from_design(&DESIGN, None), &PROBES, n),
};

/// The rotor node: the start-up term, then the steady-state gain alone from 0.5 s.
pub const ROTOR_NODE: SoakRow = SoakRow {
    name: "rotor_node",
    what: "rotor node (start-up term, steady-state gain from 0.5 s)",
    qemu_long_steps: 1_000_000,
    run: |n| rotor(RotorEstimator::from_design(&DESIGN, Some(STEADY_AFTER)), &PROBES, n),
    ..ROTOR_START_UP
};

/// The accelerometer rotor's AKF with its start-up term throughout (`edgekf-rotor-accel-qemu`).
pub const ROTOR_ACCEL_START_UP: SoakRow = SoakRow {
    name: "rotor_accel_start_up",
    image: Some("edgekf-rotor-accel-qemu"),
    what: "rotor AKF from accelerometers with its start-up term throughout (28 states)",
    // About 85 000 instructions a step with the truth's: 10¹⁰ in 120 000 steps.
    qemu_long_steps: 120_000,
    run: |n| rotor(RotorEstimator::from_design(&ACCEL_DESIGN, None), &ACCELEROMETERS, n),
    ..ROTOR_START_UP
};

/// The accelerometer rotor node: the start-up term, then the steady-state gain from 0.5 s.
pub const ROTOR_ACCEL_NODE: SoakRow = SoakRow {
    name: "rotor_accel_node",
    what: "accelerometer rotor node (start-up term, steady-state gain from 0.5 s)",
    // The unbalance's whole 10-minute swing, as for the probes' node (39 000 instructions a step).
    qemu_long_steps: 1_000_000,
    run: |n| rotor(RotorEstimator::from_design(&ACCEL_DESIGN, Some(STEADY_AFTER)), &ACCELEROMETERS, n),
    ..ROTOR_ACCEL_START_UP
};

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

/// The harmonic-force estimator in `f32` over a 20 Hz mode driven at 14 Hz by a force whose
/// amplitude swings between 0.5 and 1.5 N over 10 minutes, while the mode's true frequency
/// drifts by ±0.3 % over 20 minutes (the truth re-discretised every block); the accelerometer
/// reads it with the ADXL355's noise. The time-varying filter's covariance is checked at every
/// block's end.
#[inline(never)]
pub fn oscillator(gain: GainMode, n: u32) -> SoakFrame {
    let p = HarmonicForceParams { gain, ..HarmonicForceParams::default() };
    let Ok(mut est) = HarmonicForceEstimator::<f32>::new(&p) else { return not_started(n) };
    let fs = p.sample_rate_hz;
    let truth_at = |k: u32| {
        let t = f64::from(k) / fs;
        let hz = p.natural_freq_hz * swing(t, 0.003, 1200.0);
        let m = HarmonicForceParams { natural_freq_hz: hz, ..p }.discrete_model().ok()?;
        Some((m.a.cast::<f32>(), m.c.cast::<f32>(), psd_root(&m.q).cast::<f32>()))
    };
    let Some((mut a, mut c, mut q)) = truth_at(0) else { return not_started(n) };
    let mass = p.modal_mass_kg as f32;
    let sd = p.accel_noise_std as f32;
    let mut amplitude = Drift::new(1.0 / fs);
    let mut x = Vector4::<f32>::new(0.0, 0.0, 1.0 / mass, 0.0);
    let mut noise = Noise(0x50A4_0001);
    let mut blocks = Blocks::new(n, 1.0);
    for k in 0..n {
        // The force phasor turns with the model; its size follows the schedule (per unit mass).
        let truth = amplitude.at(k, |t| swing(t, 0.5, 600.0));
        let size = libm::sqrtf(x[2] * x[2] + x[3] * x[3]).max(1e-12);
        let scale = truth / mass / size;
        x[2] *= scale;
        x[3] *= scale;
        let y = (c * x)[0] + sd * noise.unit();
        let s = est.step(Some(y));
        let nis = s.nis.unwrap_or(f32::NAN);
        if !(s.force_amplitude.is_finite() && s.displacement.is_finite() && nis.is_finite()) {
            blocks.non_finite();
        }
        let e = f64::from(s.force_amplitude) - f64::from(truth);
        blocks.push(nis, e * e, f64::from(truth) * f64::from(truth));
        let w = q * noise.vector::<4>();
        x = a * x + Vector4::new(0.0, w[1], 0.0, 0.0);
        if (k + 1) % BLOCK == 0 {
            blocks.close();
            if let Some(kf) = est.kalman() {
                blocks.covariance(kf.covariance());
            }
            if let Some(m) = truth_at(k + 1) {
                (a, c, q) = m;
            }
        }
    }
    blocks.finish(est.counters().filter)
}

/// The exported constants of a rotor model that its soak's truth is simulated from.
pub struct RotorTruth<const N: usize> {
    a: &'static [[f64; N]; N],
    c: &'static [[f64; N]; 4],
    q: &'static [[f64; N]; N],
    r: &'static [[f64; 4]; 4],
    disk: &'static [[f64; N]; 4],
}

/// The probes' model (`generated/rotor.rs`).
pub const PROBES: RotorTruth<STATES> = RotorTruth {
    a: &probes::ROTOR_A,
    c: &probes::ROTOR_C,
    q: &probes::ROTOR_Q,
    r: &probes::ROTOR_R,
    disk: &probes::ROTOR_DISK,
};

/// The accelerometers' model (`generated/rotor_accel.rs`).
pub const ACCELEROMETERS: RotorTruth<ACCEL_STATES> = RotorTruth {
    a: &accel::constants::ROTOR_A,
    c: &accel::constants::ROTOR_C,
    q: &accel::constants::ROTOR_Q,
    r: &accel::constants::ROTOR_R,
    disk: &accel::constants::ROTOR_DISK,
};

/// A rotor node's estimator `est` in `f32` (with its start-up term throughout, or dropping it
/// at 0.5 s as the node does) on its own exported model `truth`: process noise from the
/// model's `Q`, sensor noise from its `R` (1 µm on the probes, the ADXL355's on the
/// accelerometers), and unbalance forces whose sizes swing by ±50 % over 10 and 7 minutes
/// while they turn with the shaft (states 16–19 in both models: the modes come first, the
/// accelerometers' low-pass last).
#[inline(never)]
pub fn rotor<const N: usize, const R: usize>(
    mut est: RotorEstimator<N, R>,
    truth: &RotorTruth<N>,
    n: u32,
) -> SoakFrame {
    let a = matrix(truth.a).cast::<f32>();
    let c = matrix(truth.c).cast::<f32>();
    let disk = matrix(truth.disk).cast::<f32>();
    let q = psd_root(&matrix(truth.q)).cast::<f32>();
    let r_sd: [f32; 4] = core::array::from_fn(|i| {
        let v = truth.r.get(i).and_then(|row| row.get(i)).copied().unwrap_or(0.0);
        libm::sqrt(v) as f32
    });
    let mut x = SVector::<f32, N>::zeros();
    x[16] = 2.0;
    x[19] = 1.5;
    let mut sizes = [(16, 2.0, 600.0, Drift::new(1e-3)), (18, 1.5, 420.0, Drift::new(1e-3))];
    let mut noise = Noise(0x50A4_0002);
    let mut blocks = Blocks::new(n, 4.0);
    for k in 0..n {
        for (s, size, period, drift) in &mut sizes {
            let want = *size * drift.at(k, |t| swing(t, 0.5, *period));
            let (i, j) = (*s, *s + 1);
            let (xi, xj) = (x.get(i).copied().unwrap_or(0.0), x.get(j).copied().unwrap_or(0.0));
            let scale = want / libm::sqrtf(xi * xi + xj * xj).max(1e-12);
            if let Some(v) = x.get_mut(i) {
                *v *= scale;
            }
            if let Some(v) = x.get_mut(j) {
                *v *= scale;
            }
        }
        let y = c * x;
        let reading: [f32; 4] = core::array::from_fn(|i| y[i] + r_sd[i] * noise.unit());
        let r = est.step(Some(reading));
        if !(r.disk.iter().chain(&r.force).all(|v| v.is_finite()) && r.nis.is_finite()) {
            blocks.non_finite();
        }
        let d = disk * x;
        let err2: f64 = (0..4)
            .map(|i| {
                let e = f64::from(r.disk[i]) - f64::from(d[i]);
                e * e
            })
            .sum();
        let truth2: f64 = d.iter().map(|v| f64::from(*v) * f64::from(*v)).sum();
        blocks.push(r.nis, err2, truth2);
        x = a * x + q * noise.vector::<N>();
        if (k + 1) % BLOCK == 0 {
            blocks.close();
        }
    }
    blocks.finish(est.health())
}

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
