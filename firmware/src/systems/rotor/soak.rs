//! The soaks of the rotor nodes' AKFs, from the probes and from the accelerometers: each with
//! its start-up term throughout, and as the node runs it (the start-up term, then the
//! steady-state gain).

use super::accel::{self, RotorAccelImage, ACCEL_DESIGN, ACCEL_STATES};
use super::{constants as probes, RotorEstimator, RotorImage, DESIGN, STATES, STEADY_AFTER};
use crate::hil::HilImage;
use crate::soak::engine::{psd_root, swing, Blocks, Drift, Noise, SoakFrame, SoakRow};
use edgekf::export::matrix;
use nalgebra::SVector;

/// Steps per block of statistics.
const BLOCK: u32 = 10_000;

/// Its rows.
pub const SOAKS: &[SoakRow] = &[ROTOR_START_UP, ROTOR_NODE, ROTOR_ACCEL_START_UP, ROTOR_ACCEL_NODE];

/// The rotor's AKF with its start-up term throughout.
pub const ROTOR_START_UP: SoakRow = SoakRow {
    name: "rotor_start_up",
    system: "rotor",
    image: Some(RotorImage::NAME),
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
    image: Some(RotorAccelImage::NAME),
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
