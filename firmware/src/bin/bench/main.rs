//! Per-step instruction counts of the filters on the Cortex-M4F, under QEMU.
//!
//! Each kernel runs a few warm-up steps, then exactly one step between the markers
//! `bench_start` and `bench_end`; a QEMU TCG plugin (`xtask/qemu-plugin/insn_section.c`) counts
//! the instructions executed between them, and `cargo xtask bench` pairs the counts with the
//! `bench <label>` lines this image prints. Instruction counts are not cycles (flash wait
//! states and multi-cycle FPU operations come on top) but they are exact and repeatable, so
//! they serve as the regression metric.
//!
//! Models are dense and pseudo-random (fixed seed): the cost of these filters does not depend
//! on the values, only on the sizes.

#![no_std]
#![no_main]

use cortex_m_rt::entry;
use edgekf::filter::{KalmanFilter, MerweSigmaPoints, SteadyState, SteadyStateFilter, UnscentedKalmanFilter};
use edgekf::models::synthetic::{dense_model, CubicModel, Lcg};
use edgekf::systems::oscillator::{HarmonicForceEstimator, HarmonicForceParams};
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
    // Any gain costs the same; solving a 24-state Riccati equation in software f64 would only
    // slow the benchmark down.
    let ss = SteadyState {
        predicted: SMatrix::identity(),
        filtered: SMatrix::identity(),
        gain: SMatrix::from_fn(|_, _| 0.01 * rng.next()),
        innovation: SMatrix::identity(),
        iterations: 0,
    };
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

/// The rotor node's per-sample step with its disk and force outputs, in both phases: the
/// filter with its start-up term of rank 12 (`rotor_node_step`), the sample that drops the
/// term (`rotor_node_switch`), and the steady-state step the node runs from 0.5 s on
/// (`rotor_node_steady`); the same for the accelerometer node's 28 states (`rotor_accel_*`).
fn rotor() {
    use edgekf_firmware::systems::rotor::accel::AccelEstimator;
    use edgekf_firmware::systems::rotor::RotorEstimator;
    // Displacement-like readings for the probes, acceleration-like ones for the accelerometers.
    rotor_phases(RotorEstimator::new(), ["rotor_node_step", "rotor_node_switch", "rotor_node_steady"], 1e-6);
    rotor_phases(AccelEstimator::accel(), ["rotor_accel_step", "rotor_accel_switch", "rotor_accel_steady"], 1e-2);
}

/// [`rotor`]'s three steps of one estimator, readings of size `scale`.
fn rotor_phases<const N: usize, const R: usize>(
    mut est: edgekf_firmware::systems::rotor::RotorEstimator<N, R>,
    labels: [&str; 3],
    scale: f32,
) {
    use edgekf_firmware::systems::rotor::STEADY_AFTER;
    let [step, switch, steady] = labels;
    let y = |k: u32| Some([scale * k as f32, -0.5 * scale * k as f32, 2.0 * scale, 0.25 * scale * k as f32]);
    let mut k = 0;
    while k < 3 {
        est.step(y(k));
        k += 1;
    }
    // Measures one step; `steady`: whether the steady-state filter must be in use after it.
    let measured =
        |est: &mut edgekf_firmware::systems::rotor::RotorEstimator<N, R>, label: &str, k: u32, steady: bool| {
            bench_start();
            core::hint::black_box(est.step(core::hint::black_box(y(k))));
            bench_end();
            if est.is_steady() != steady {
                defmt::error!("bench {=str}: steady-state filter in use: {=bool}", label, est.is_steady());
                exit(1)
            }
            defmt::info!(
                "bench {=str} n={=usize} m={=usize} resets={=u32}",
                label,
                N,
                4usize,
                est.health().covariance_resets
            );
        };
    measured(&mut est, step, k, false);
    k += 1;
    while k < STEADY_AFTER {
        est.step(y(k));
        k += 1;
    }
    measured(&mut est, switch, k, true);
    k += 1;
    for _ in 0..3 {
        est.step(y(k));
        k += 1;
    }
    measured(&mut est, steady, k, true);
}

/// The slider-crank clearance estimator (`edgekf_firmware::crank`, 0.25 s windows at 10 kHz):
/// an ordinary sample (`crank_sample`: sums, differences, high-pass), the sample that closes a
/// window (`crank_window_end`: the exact median of 2 499 `|Δα|` by four radix passes, the
/// impact pass, ten window statistics, the model on the running features), and a whole window
/// (`crank_window`, 2 500 samples, including about 10 instructions per sample to synthesise the
/// input), whose count / 2 500 is the average per sample.
fn crank() {
    use edgekf_firmware::systems::crank::{Storage, WINDOW};
    // Noise-like values from a multiplicative hash, and an impact every 97 samples.
    let alpha = |k: u32| {
        let noise = (k.wrapping_mul(2_654_435_761) >> 20) as f32 - 2048.0;
        if k % 97 == 0 {
            noise + 30_000.0
        } else {
            noise
        }
    };
    let mut storage: Storage = [0.0; WINDOW - 1];
    let mut node = crank_node(&mut storage);
    let mut k = 0u32;
    let window = WINDOW as u32;
    // One whole window, then into the second one for an ordinary sample, then its last sample.
    bench_start();
    while k < window {
        core::hint::black_box(node.step(core::hint::black_box(Some(alpha(k)))));
        k += 1;
    }
    bench_end();
    defmt::info!("bench crank_window n={=usize} m={=usize} windows={=u32}", WINDOW, 1usize, node.windows());
    while k < window + 1000 {
        node.step(Some(alpha(k)));
        k += 1;
    }
    measured_crank_step(&mut node, alpha(k));
    defmt::info!("bench crank_sample n={=usize} m={=usize} windows={=u32}", WINDOW, 1usize, node.windows());
    k += 1;
    while k < 2 * window - 1 {
        node.step(Some(alpha(k)));
        k += 1;
    }
    let report = measured_crank_step(&mut node, alpha(k));
    if report.is_none() || node.windows() != 2 {
        defmt::error!("bench crank: the measured sample did not close the second window");
        exit(1)
    }
    defmt::info!("bench crank_window_end n={=usize} m={=usize} windows={=u32}", WINDOW, 1usize, node.windows());
}

/// The crank node on `storage`, or the bench ends with an error.
fn crank_node(
    storage: &mut edgekf_firmware::systems::crank::Storage,
) -> edgekf_firmware::systems::crank::CrankNode<'_> {
    match edgekf_firmware::systems::crank::CrankNode::new(storage) {
        Ok(node) => node,
        Err(_) => {
            defmt::error!("bench crank: no estimator");
            exit(1)
        }
    }
}

/// One step of `node` on `x`, its instructions counted.
fn measured_crank_step(
    node: &mut edgekf_firmware::systems::crank::CrankNode<'_>,
    x: f32,
) -> Option<edgekf_firmware::systems::crank::WindowReport> {
    bench_start();
    let report = core::hint::black_box(node.step(core::hint::black_box(Some(x))));
    bench_end();
    report
}

/// A sample while the release detector still looks for the first contact
/// (`crank_release_sample`: an ordinary sample plus the running quadratic fit, its 3 × 3 solve
/// and the threshold test). Only the samples before the first contact pay it, at most the first
/// 0.1 s of a recording.
fn crank_release() {
    use edgekf_firmware::systems::crank::{Storage, WINDOW};
    // Small noise-like values about a slow ramp: no contact.
    let alpha = |k: u32| ((k.wrapping_mul(2_654_435_761) >> 24) as f32 - 128.0) * 0.04 - 27.0 - 0.01 * k as f32;
    let mut storage: Storage = [0.0; WINDOW - 1];
    let mut node = crank_node(&mut storage);
    for k in 0..60 {
        node.step(Some(alpha(k)));
    }
    measured_crank_step(&mut node, alpha(60));
    if node.release_contact().is_some() {
        defmt::error!("bench crank: the release detector fired on a smooth ramp");
        exit(1)
    }
    defmt::info!("bench crank_release_sample n={=usize} m={=usize} windows={=u32}", WINDOW, 1usize, node.windows());
}

/// The ADXL355 source's poll on the virtual ADXL355, without the estimator: `adxl_poll`, an
/// ordinary poll (the status read with the IDs, the 16-sample FIFO burst, screening and
/// conversion); `adxl_poll_stall`, one that finds the FIFO empty although samples are due (a
/// dropped period: plus the configuration read-back); `adxl_poll_reset`, the poll after a
/// reset (plus the re-initialisation and 16 bridged samples). The virtual device's register
/// emulation is in the counts, as the I²C driver's would be on the board.
fn adxl_poll() {
    use edgekf_firmware::adxl355::{Adxl355, I2cInterface};
    use edgekf_firmware::node::{Health, Recorded, SampleSource};
    use edgekf_firmware::source::{Adxl355Settings, Adxl355Source};
    use edgekf_firmware::virtual_adxl355::{FeedSample, SliceFeed, VirtualAdxl355};
    let mut feed = [FeedSample::new([0.0, 0.0, 9.8]); 96];
    for (k, s) in feed.iter_mut().enumerate() {
        let x = k as f32;
        s.accel = [0.5 * x - 20.0, 3.0 - 0.25 * x, 9.8 + 0.01 * x];
    }
    // Periods 0–2 ordinary, 3 dropped, 4 reset at its first sample, 5 ordinary.
    for s in feed.get_mut(48..64).into_iter().flatten() {
        s.dropped = true;
    }
    if let Some(s) = feed.get_mut(64) {
        s.reset = true;
    }
    let sensor = Adxl355::new_i2c(VirtualAdxl355::new(SliceFeed::new(&feed)), 0x1D);
    let mut health = Health::default();
    let Ok(mut source) = Adxl355Source::start(sensor, Adxl355Settings::default(), &mut health) else {
        defmt::error!("bench adxl_poll: the virtual part did not start");
        exit(1)
    };
    type Source<'a> = Adxl355Source<I2cInterface<VirtualAdxl355<SliceFeed<'a>>>>;
    // One period passes and the source reads it, counted if `label` says what it is.
    fn poll(source: &mut Source<'_>, health: &mut Health, label: Option<&str>) {
        source.advance();
        if label.is_some() {
            bench_start();
        }
        let read = source.read(health, |s| {
            core::hint::black_box(s);
        });
        if let Some(label) = label {
            bench_end();
            defmt::info!("bench {=str} n={=usize} m={=usize} read={=u16}", label, 16usize, 1usize, read);
        }
    }
    poll(&mut source, &mut health, None);
    poll(&mut source, &mut health, None);
    poll(&mut source, &mut health, Some("adxl_poll"));
    poll(&mut source, &mut health, Some("adxl_poll_stall"));
    poll(&mut source, &mut health, Some("adxl_poll_reset"));
    if (health.config_checks, health.resets, health.bridged) != (2, 1, 32) {
        defmt::error!("bench adxl_poll: not the polls meant: {}", health);
        exit(1)
    }
}

fn harmonic() {
    let Ok(mut est) = HarmonicForceEstimator::<f32>::new(&HarmonicForceParams::default()) else {
        defmt::error!("bench harmonic: no estimator");
        exit(1)
    };
    for k in 0..3 {
        est.step(Some(k as f32 * 0.1));
    }
    bench_start();
    core::hint::black_box(est.step(core::hint::black_box(Some(0.25))));
    bench_end();
    defmt::info!(
        "bench harmonic_step n={=usize} m={=usize} resets={=u32}",
        4usize,
        1usize,
        est.counters().filter.covariance_resets
    );
}

/// The underwater vehicle's 20-state joint UKF and detector (`edgekf_firmware::systems::uuv`)
/// at 50 Hz: a sample with the IMU, depth and heading (`uuv_step`: predict and two updates),
/// and one with a DVL reading too (`uuv_step_dvl`, one sample in ten). Steady level flight at
/// 1500 rpm, so the CUSUM stays quiet.
fn uuv() {
    use edgekf_firmware::systems::uuv::{estimator, UuvNode, STATES};
    let Ok(mut est) = estimator() else {
        defmt::error!("bench uuv: no estimator");
        exit(1)
    };
    let mut node = UuvNode::new(&mut est);
    let row = |k: u32| {
        let dvl = if k % 10 == 0 { [1.54, 0.0, 0.0] } else { [f32::NAN; 3] };
        Some([0.0, -0.9, -9.77, 0.0, 0.0, 0.0, 10.0, 0.785, dvl[0], dvl[1], dvl[2], 1500.0, 1670.0, 0.0, 0.0])
    };
    let mut k = 0;
    while k < 21 {
        node.step(row(k));
        k += 1;
    }
    for (label, at) in [("uuv_step", 21), ("uuv_step_dvl", 30)] {
        while k < at {
            node.step(row(k));
            k += 1;
        }
        bench_start();
        core::hint::black_box(node.step(core::hint::black_box(row(k))));
        bench_end();
        k += 1;
        defmt::info!(
            "bench {=str} n={=usize} m={=usize} resets={=u32}",
            label,
            STATES,
            6usize,
            node.estimator().health().covariance_resets
        );
    }
}

/// The boom's model-based filter and the paper's method side by side
/// (`edgekf_firmware::systems::boom`) at 100 Hz: a sample at a fixed length and angle
/// (`boom_step`), and one that re-reduces the boom (`boom_rereduce`: three Rayleigh–Ritz
/// reductions in `f64`, once per 0.5 m of telescoping or 0.1 rad of luffing).
fn boom() {
    use edgekf::systems::boom::STATES;
    use edgekf_firmware::systems::boom::{estimators, BoomNode};
    let Ok((mut model, mut paper)) = estimators() else {
        defmt::error!("bench boom: no estimator");
        exit(1)
    };
    let mut node = BoomNode::new(&mut model, &mut paper);
    // At rest at 30 m, then a sample telescoped 0.6 m further in.
    let row = |length: f32| Some([0.002, 0.5, length, 0.0]);
    for _ in 0..20 {
        node.step(row(30.0));
    }
    for (label, length) in [("boom_step", 30.0), ("boom_rereduce", 29.4)] {
        bench_start();
        core::hint::black_box(node.step(core::hint::black_box(row(length))));
        bench_end();
        defmt::info!(
            "bench {=str} n={=usize} m={=usize} resets={=u32}",
            label,
            STATES,
            2usize,
            node.model().health().covariance_resets
        );
    }
}

#[entry]
fn main() -> ! {
    let mut rng = Lcg(0xEDC0_FFEE);
    harmonic();
    adxl_poll();
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
    rotor();
    crank();
    crank_release();
    uuv();
    boom();
    defmt::info!("done");
    exit(0)
}

edgekf_firmware::semihost_fault_handlers!("edgekf-bench");
