//! Numerical soak: the filters the node runs, in `f32` as on the chip, for many steps on data
//! whose parameters drift slowly (the force's amplitude, the mode's frequency, the unbalance).
//! Each must stay finite, keep its covariance positive definite and symmetric (at most one
//! covariance reset per 10⁶ steps), refuse no update, stay consistent (NIS) and keep tracking
//! the truth, block after block.
//!
//! `cargo test -p edgekf-tests --test soak` is the short soak CI runs (10⁶ steps of each
//! filter); `EDGEKF_LONG=1 cargo test --release -p
//! edgekf-tests --test soak -- --nocapture` runs 10⁷ steps of each and prints the figures the
//! README gives.
//!
//! The truth is simulated in `f64` from the filters' own models (exact discretisations) with
//! the drift added, so what is tested is the `f32` arithmetic over a long run, not a model
//! error.

use edgekf::export::matrix;
use edgekf::filter::{JointModel, MerweSigmaPoints, ParametricModel, UnscentedKalmanFilter};
use edgekf::linalg::van_loan;
use edgekf::models::synthetic::Lcg;
use edgekf::systems::oscillator::{GainMode, HarmonicForceEstimator, HarmonicForceParams};
use edgekf_firmware::systems::rotor::{RotorEstimator, STATES};
use nalgebra::{Matrix1, Matrix2, SMatrix, SVector, Vector1, Vector2};
use std::f64::consts::TAU;

/// The rotor node's compiled-in model, as the firmware includes it.
#[allow(dead_code)]
mod constants {
    include!("../../firmware/src/generated/rotor.rs");
}

/// Steps of a soak: 10⁷ with `EDGEKF_LONG=1`, `short` otherwise.
fn steps(short: u64) -> u64 {
    if std::env::var_os("EDGEKF_LONG").is_some() {
        10_000_000
    } else {
        short
    }
}

/// Samples per block the statistics are taken over.
const BLOCK: u64 = 10_000;

/// A zero-mean uniform number of unit variance (`Lcg` is uniform on [−1, 1)).
fn unit(rng: &mut Lcg) -> f64 {
    3f64.sqrt() * rng.next()
}

/// What a soak saw, block by block.
#[derive(Debug, Default)]
struct Soak {
    steps: u64,
    /// The largest block mean of the NIS (per measurement).
    worst_nis: f64,
    /// The largest block RMS error against the truth, relative to the truth's RMS.
    worst_error: f64,
    covariance_resets: u32,
    refused_updates: u32,
}

impl Soak {
    /// Checks the soak's limits and prints its figures.
    fn check(&self, name: &str, nis_limit: f64, error_limit: f64) {
        println!(
            "soak {name}: {} steps in f32, worst block NIS mean {:.3}, worst block error {:.2} % of the truth, \
             {} covariance resets, {} refused updates",
            self.steps,
            self.worst_nis,
            100.0 * self.worst_error,
            self.covariance_resets,
            self.refused_updates
        );
        assert!(u64::from(self.covariance_resets) <= self.steps / 1_000_000, "{name}: {self:?}");
        assert_eq!(self.refused_updates, 0, "{name}: {self:?}");
        assert!(self.worst_nis.is_finite() && self.worst_nis < nis_limit, "{name}: {self:?}");
        assert!(self.worst_error.is_finite() && self.worst_error < error_limit, "{name}: {self:?}");
    }
}

/// One block's running sums.
#[derive(Default)]
struct Block {
    nis: f64,
    err2: f64,
    truth2: f64,
    n: u64,
}

impl Block {
    fn push(&mut self, nis: f64, err2: f64, truth2: f64) {
        (self.nis, self.err2, self.truth2, self.n) =
            (self.nis + nis, self.err2 + err2, self.truth2 + truth2, self.n + 1);
    }

    /// Folds a full block into `soak` (the first block, the start-up transient, is left out).
    fn close(&mut self, soak: &mut Soak, k: u64, measurements: f64) {
        if k >= BLOCK {
            let n = self.n.max(1) as f64;
            soak.worst_nis = soak.worst_nis.max(self.nis / n / measurements);
            soak.worst_error = soak.worst_error.max((self.err2 / self.truth2.max(1e-300)).sqrt());
        }
        *self = Block::default();
    }
}

/// The harmonic-force estimator in `f32` over a 20 Hz mode driven at 14 Hz by a force whose
/// amplitude swings between 0.5 and 1.5 N over 10 minutes, while the mode's true frequency
/// drifts by ±0.3 % over 20 minutes (the truth re-discretised every block); the accelerometer
/// reads it with the ADXL355's noise. With `check_covariance`, the time-varying filter's
/// covariance is checked symmetric and positive definite (in `f64`) at every block's end.
fn soak_oscillator(gain: GainMode, n: u64) -> Soak {
    let p = HarmonicForceParams { gain, ..HarmonicForceParams::default() };
    let mut est = HarmonicForceEstimator::<f32>::new(&p).unwrap();
    assert_eq!(est.kalman().is_some(), gain == GainMode::TimeVarying, "the filter of the gain mode asked for");
    let fs = p.sample_rate_hz;
    let truth_at = |k: u64| {
        let t = k as f64 / fs;
        let hz = p.natural_freq_hz * (1.0 + 0.003 * (TAU * t / 1200.0).sin());
        HarmonicForceParams { natural_freq_hz: hz, ..p }.discrete_model().unwrap()
    };
    let amplitude = |k: u64| 1.0 + 0.5 * (TAU * k as f64 / fs / 600.0).sin();
    let mut m = truth_at(0);
    let q =
        m.q.cholesky()
            .map(|c| c.l())
            .unwrap_or_else(|| SMatrix::<f64, 4, 4>::from_diagonal(&m.q.diagonal().map(f64::sqrt)));
    let mut x = SVector::<f64, 4>::new(0.0, 0.0, 1.0, 0.0);
    let mut rng = Lcg(0x50A4_0001);
    let (mut soak, mut block) = (Soak { steps: n, ..Soak::default() }, Block::default());
    let sd = p.accel_noise_std;
    for k in 0..n {
        // The force phasor turns with the model; its size follows the schedule (per unit mass).
        let size = x.fixed_rows::<2>(2).norm().max(1e-12);
        let want = amplitude(k) / p.modal_mass_kg;
        x[2] *= want / size;
        x[3] *= want / size;
        let y = (m.c * x)[0] + sd * unit(&mut rng);
        let s = est.step(Some(y as f32));
        let nis = f64::from(s.nis.expect("every sample is present"));
        let truth = amplitude(k);
        let e = f64::from(s.force_amplitude) - truth;
        assert!(s.force_amplitude.is_finite() && s.displacement.is_finite(), "sample {k}: {s:?}");
        block.push(nis, e * e, truth * truth);
        let w = q * SVector::<f64, 4>::from_fn(|_, _| unit(&mut rng));
        x = m.a * x + SVector::<f64, 4>::new(0.0, w[1], 0.0, 0.0);
        if (k + 1) % BLOCK == 0 {
            block.close(&mut soak, k, 1.0);
            if let Some(kf) = est.kalman() {
                let pm = kf.covariance().map(f64::from);
                let asym = (pm - pm.transpose()).abs().max() / pm.abs().max();
                assert!(asym <= 1e-5, "sample {k}: covariance asymmetry {asym:.2e}");
                assert!(pm.cholesky().is_some(), "sample {k}: covariance not positive definite");
            }
            m = truth_at(k + 1);
        }
    }
    let c = est.counters();
    (soak.covariance_resets, soak.refused_updates) = (c.filter.covariance_resets, c.filter.refused_updates);
    soak
}

/// The rotor node's estimator in `f32` (`switch_at`: when it drops its start-up term for the
/// steady-state gain alone, `None` to carry the term throughout) on the paper rotor's reduced model: process noise
/// from the model's `Q`, 1 µm probe noise, and unbalance forces whose sizes swing by ±50 % over
/// 10 and 7 minutes while they turn with the shaft.
fn soak_rotor(switch_at: Option<u32>, n: u64) -> Soak {
    use constants::*;
    let (a, c, disk) = (matrix(&ROTOR_A), matrix(&ROTOR_C), matrix(&ROTOR_DISK));
    // Q is positive semi-definite: its square root by eigen-decomposition.
    let eig = matrix(&ROTOR_Q).symmetric_eigen();
    let q_root =
        eig.eigenvectors * SMatrix::<f64, STATES, STATES>::from_diagonal(&eig.eigenvalues.map(|v| v.max(0.0).sqrt()));
    let r_sd: [f64; 4] = std::array::from_fn(|i| ROTOR_R[i][i].sqrt());
    let mut est = RotorEstimator::with_switch_at(switch_at);
    let mut x = SVector::<f64, STATES>::zeros();
    x[16] = 2.0;
    x[19] = 1.5;
    let base = [(16, 2.0, 600.0), (18, 1.5, 420.0)];
    let mut rng = Lcg(0x50A4_0002);
    let (mut soak, mut block) = (Soak { steps: n, ..Soak::default() }, Block::default());
    for k in 0..n {
        let t = k as f64 / 1000.0;
        for (s, size, period) in base {
            let now = x.fixed_rows::<2>(s).norm().max(1e-12);
            let want = size * (1.0 + 0.5 * (TAU * t / period).sin());
            x[s] *= want / now;
            x[s + 1] *= want / now;
        }
        let y = c * x;
        let reading: [f32; 4] = std::array::from_fn(|i| (y[i] + r_sd[i] * unit(&mut rng)) as f32);
        let r = est.step(Some(reading));
        let d = disk * x;
        assert!(r.disk.iter().chain(&r.force).all(|v| v.is_finite()) && r.nis.is_finite(), "sample {k}: {r:?}");
        let err2: f64 = (0..4).map(|i| (f64::from(r.disk[i]) - d[i]).powi(2)).sum();
        block.push(f64::from(r.nis), err2, d.norm_squared());
        x = a * x + q_root * SVector::<f64, STATES>::from_fn(|_, _| unit(&mut rng));
        if (k + 1) % BLOCK == 0 {
            block.close(&mut soak, k, 4.0);
        }
    }
    let h = est.health();
    (soak.covariance_resets, soak.refused_updates) = (h.covariance_resets, h.refused_updates);
    soak
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
/// and recovering): the truth is discretised exactly at the current `k` every block. The
/// error is that of the stiffness estimate.
fn soak_joint_ukf(n: u64) -> Soak {
    let (dt, zeta, k0) = (0.01, 0.05, (TAU * 1.5f64).powi(2));
    let c = 2.0 * zeta * k0.sqrt();
    let (accel_psd, meas_std) = (100.0, 0.05);
    let k_at = |k: u64| k0 * (1.0 + 0.1 * (TAU * k as f64 * dt / 20_000.0).sin());
    let truth = |k_true: f64| {
        let (a, q) =
            van_loan::<f64, 2, 4>(&Matrix2::new(0.0, 1.0, -k_true, -c), &Matrix2::new(0.0, 0.0, 0.0, accel_psd), dt)
                .unwrap();
        (a, q.cholesky().unwrap().unpack())
    };
    let model = JointModel::<_, 2, 1, 3>::new(Mode { dt: dt as f32, damping: c as f32 });
    let qx = Matrix2::new(dt * dt * dt / 3.0, dt * dt / 2.0, dt * dt / 2.0, dt) * accel_psd;
    // k may drift by about 0.3 s⁻² per 100 s (its true rate is up to 0.28).
    let q = model.block_diag(&qx.map(|v| v as f32), &Matrix1::new(1e-5f32));
    let p0 = model.block_diag(&Matrix2::new(1.0f32, 0.0, 0.0, 100.0), &Matrix1::new(900.0f32));
    let z0 = model.stack(&Vector2::zeros(), &Vector1::new(60.0f32));
    let r = Matrix1::new((meas_std * meas_std) as f32);
    let points = MerweSigmaPoints { alpha: 0.5f32, beta: 2.0, kappa: 0.0 };
    let mut ukf = UnscentedKalmanFilter::new(points, q, r, z0, p0).unwrap();
    let mut rng = Lcg(0x50A4_0003);
    let (mut a, mut q_chol) = truth(k_at(0));
    let mut x = Vector2::new(0.5, 0.0);
    let (mut soak, mut block) = (Soak { steps: n, ..Soak::default() }, Block::default());
    for k in 0..n {
        x = a * x + q_chol * Vector2::new(unit(&mut rng), unit(&mut rng));
        let y = x[0] + meas_std * unit(&mut rng);
        ukf.predict(&model);
        let inn = ukf.update(&model, &Vector1::new(y as f32)).expect("every update is taken");
        let est = model.parameters(&ukf);
        assert!(ukf.state().iter().all(|v| v.is_finite()) && est.std[0] > 0.0, "sample {k}: {est:?}");
        // The stiffness is only seen over many cycles: the first 10 minutes are its start-up.
        if k >= 60_000 {
            let e = f64::from(est.mean[0]) - k_at(k);
            block.push(f64::from(inn.nis), e * e, k_at(k).powi(2));
        }
        if (k + 1) % BLOCK == 0 {
            if block.n > 0 {
                block.close(&mut soak, k, 1.0);
            }
            let pm = ukf.covariance().map(f64::from);
            assert!(pm.cholesky().is_some(), "sample {k}: covariance not positive definite");
            (a, q_chol) = truth(k_at(k + 1));
        }
    }
    let h = ukf.health();
    (soak.covariance_resets, soak.refused_updates) = (h.covariance_resets, h.refused_updates);
    soak
}

#[test]
fn the_joint_ukf_stays_sound() {
    soak_joint_ukf(steps(1_000_000)).check("joint UKF (stiffness)", 1.3, 0.05);
}

#[test]
fn the_oscillator_time_varying_filter_stays_sound() {
    soak_oscillator(GainMode::TimeVarying, steps(1_000_000)).check("oscillator, time-varying KF", 1.3, 0.05);
}

#[test]
fn the_oscillator_steady_state_filter_stays_sound() {
    soak_oscillator(GainMode::SteadyState, steps(1_000_000)).check("oscillator, steady-state", 1.3, 0.05);
}

#[test]
fn the_rotor_node_stays_sound() {
    soak_rotor(Some(edgekf_firmware::systems::rotor::STEADY_AFTER), steps(1_000_000)).check(
        "rotor AKF, node",
        1.3,
        0.05,
    );
}

#[test]
fn the_rotor_filter_with_its_start_up_term_throughout_stays_sound() {
    soak_rotor(None, steps(1_000_000)).check("rotor AKF, start-up term throughout", 1.3, 0.05);
}
