//! Per-step instruction counts of the filters on the Cortex-M4F, under QEMU.
//!
//! Each kernel runs a few warm-up steps, then exactly one step between the markers
//! `bench_start` and `bench_end`; a QEMU TCG plugin (`xtask/qemu-plugin/insn_section.c`) counts
//! the instructions executed between them, and `cargo xtask bench` pairs the counts with the
//! `bench <label>` lines this image prints. Instruction counts are not cycles (flash wait
//! states and multi-cycle FPU operations come on top) but they are exact and repeatable, so
//! they serve as the regression metric.
//!
//! The shared core's kernels are here: their models are dense and pseudo-random (fixed seed),
//! since the cost of these filters does not depend on the values, only on the sizes. Each
//! system's kernels (its node's steps on its own model) are in its folder,
//! `edgekf_firmware::systems::<name>::bench`, and run through the manifest.

#![no_std]
#![no_main]

use cortex_m_rt::entry;
use edgekf::filter::{KalmanFilter, MerweSigmaPoints, SteadyStateFilter, UnscentedKalmanFilter};
use edgekf::models::synthetic::{dense_model, some_steady_state, CubicModel, Lcg};
use edgekf_firmware::semihost::exit;
use nalgebra::{SMatrix, SVector};

/// Marks the start of the measured section.
#[no_mangle]
#[inline(never)]
pub extern "C" fn bench_start() {
    // SAFETY: an empty asm block; it only keeps the function from being merged or removed.
    unsafe { core::arch::asm!("") }
}

/// Marks the end of the measured section (a different body, so it gets its own address).
#[no_mangle]
#[inline(never)]
pub extern "C" fn bench_end() {
    // SAFETY: a single `nop`.
    unsafe { core::arch::asm!("nop") }
}

fn measurement<const M: usize>(rng: &mut Lcg) -> SVector<f32, M> {
    SVector::from_fn(|_, _| rng.next() as f32)
}

fn kalman<const N: usize, const M: usize>(label: &str, sequential: bool, rng: &mut Lcg) {
    let mut kf = KalmanFilter::<f32, N, M>::new(dense_model::<N, M>(rng).cast(), SVector::zeros(), SMatrix::identity());
    let step = |kf: &mut KalmanFilter<f32, N, M>, y: &SVector<f32, M>| {
        kf.predict();
        if sequential {
            core::hint::black_box(kf.update_sequential(core::hint::black_box(y)).is_ok());
        } else {
            core::hint::black_box(kf.update(core::hint::black_box(y)).is_ok());
        }
    };
    for _ in 0..3 {
        step(&mut kf, &measurement(rng));
    }
    let y = measurement(rng);
    bench_start();
    step(&mut kf, &y);
    bench_end();
    defmt::info!("bench {=str} n={=usize} m={=usize} resets={=u32}", label, N, M, kf.health().covariance_resets);
}

fn predict_only<const N: usize, const M: usize>(rng: &mut Lcg) {
    let mut kf = KalmanFilter::<f32, N, M>::new(dense_model::<N, M>(rng).cast(), SVector::zeros(), SMatrix::identity());
    kf.predict();
    bench_start();
    kf.predict();
    bench_end();
    defmt::info!("bench kalman_predict n={=usize} m={=usize} resets={=u32}", N, M, kf.health().covariance_resets);
}

fn steady<const N: usize, const M: usize>(label: &str, rng: &mut Lcg) {
    let model = dense_model::<N, M>(rng);
    let ss = some_steady_state::<N, M>(rng);
    let Ok(mut f) = SteadyStateFilter::<f32, N, M>::from_steady_state(&model, &ss, SVector::zeros()) else {
        defmt::error!("bench {=str}: no filter", label);
        exit(1)
    };
    let y = measurement::<M>(rng);
    f.predict();
    f.update(&y);
    bench_start();
    f.predict();
    core::hint::black_box(f.update(core::hint::black_box(&y)));
    bench_end();
    defmt::info!("bench {=str} n={=usize} m={=usize} resets={=u32}", label, N, M, f.resets());
}

fn ukf<const N: usize, const M: usize>(rng: &mut Lcg) {
    let lin = dense_model::<N, M>(rng).cast::<f32>();
    let model = CubicModel { a: lin.a, c: lin.c };
    let points = MerweSigmaPoints { alpha: 0.5f32, beta: 2.0, kappa: 0.0 };
    let Ok(mut f) = UnscentedKalmanFilter::new(points, lin.q, lin.r, SVector::zeros(), SMatrix::identity()) else {
        defmt::error!("bench ukf: no filter");
        exit(1)
    };
    for _ in 0..3 {
        f.predict(&model);
        core::hint::black_box(f.update(&model, &measurement(rng)).is_ok());
    }
    let y = measurement::<M>(rng);
    bench_start();
    f.predict(&model);
    core::hint::black_box(f.update(&model, core::hint::black_box(&y)).is_ok());
    bench_end();
    defmt::info!("bench ukf n={=usize} m={=usize} resets={=u32}", N, M, f.health().covariance_resets);
}

/// The markers the systems' kernels call ([`edgekf_firmware::bench::Markers`]).
struct Marks;

impl edgekf_firmware::bench::Markers for Marks {
    #[inline(always)]
    fn start() {
        bench_start();
    }

    #[inline(always)]
    fn end() {
        bench_end();
    }
}

#[entry]
fn main() -> ! {
    let mut rng = Lcg(0xEDC0_FFEE);
    steady::<4, 1>("steady_state", &mut rng);
    steady::<24, 4>("steady_state", &mut rng);
    kalman::<4, 4>("kalman_joseph", false, &mut rng);
    kalman::<12, 4>("kalman_joseph", false, &mut rng);
    kalman::<24, 4>("kalman_joseph", false, &mut rng);
    predict_only::<24, 4>(&mut rng);
    kalman::<4, 4>("kalman_sequential", true, &mut rng);
    kalman::<12, 4>("kalman_sequential", true, &mut rng);
    kalman::<24, 4>("kalman_sequential", true, &mut rng);
    ukf::<14, 4>(&mut rng);
    // Every system's kernels, in the manifest's order.
    edgekf_firmware::systems::bench::<Marks>();
    defmt::info!("done");
    exit(0)
}

edgekf_firmware::semihost_fault_handlers!("edgekf-bench");
