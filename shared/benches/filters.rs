//! Host timings of one filter step (`cargo bench -p edgekf`). The chip's figures are
//! instruction counts under QEMU: `cargo xtask bench`.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use edgekf::filter::{KalmanFilter, MerweSigmaPoints, SteadyStateFilter, UnscentedKalmanFilter};
use edgekf::models::synthetic::{dense_model, some_steady_state, CubicModel, Lcg};
use edgekf::systems::oscillator::{HarmonicForceEstimator, HarmonicForceParams};
use edgekf::Real;
use nalgebra::{SMatrix, SVector};

fn kalman<T: Real, const N: usize, const M: usize>(c: &mut Criterion, name: &str) {
    let mut rng = Lcg(7);
    let mut kf =
        KalmanFilter::<T, N, M>::new(dense_model::<N, M>(&mut rng).cast(), SVector::zeros(), SMatrix::identity());
    let y = SVector::<T, M>::from_fn(|_, _| T::of_f64(rng.next()));
    c.bench_function(&format!("{name} kalman predict+update n={N} m={M}"), |b| {
        b.iter(|| {
            kf.predict();
            black_box(kf.update(black_box(&y)).is_ok())
        })
    });
}

fn steady<const N: usize, const M: usize>(c: &mut Criterion) {
    let mut rng = Lcg(11);
    let model = dense_model::<N, M>(&mut rng);
    let ss = some_steady_state::<N, M>(&mut rng);
    let mut f = SteadyStateFilter::<f32, N, M>::from_steady_state(&model, &ss, SVector::zeros()).expect("filter");
    let y = SVector::<f32, M>::from_fn(|_, _| rng.next() as f32);
    c.bench_function(&format!("f32 steady-state step n={N} m={M}"), |b| {
        b.iter(|| {
            f.predict();
            black_box(f.update(black_box(&y)))
        })
    });
}

fn ukf(c: &mut Criterion) {
    let mut rng = Lcg(13);
    let lin = dense_model::<14, 4>(&mut rng).cast::<f32>();
    let model = CubicModel { a: lin.a, c: lin.c };
    let points = MerweSigmaPoints { alpha: 0.5f32, beta: 2.0, kappa: 0.0 };
    let mut f = UnscentedKalmanFilter::new(points, lin.q, lin.r, SVector::zeros(), SMatrix::identity()).expect("ukf");
    let y = SVector::<f32, 4>::from_fn(|_, _| rng.next() as f32);
    c.bench_function("f32 ukf predict+update n=14 m=4", |b| {
        b.iter(|| {
            f.predict(&model);
            black_box(f.update(&model, black_box(&y)).is_ok())
        })
    });
}

fn all(c: &mut Criterion) {
    let mut est = HarmonicForceEstimator::<f32>::new(&HarmonicForceParams::default()).expect("estimator");
    c.bench_function("f32 harmonic-force estimator step", |b| b.iter(|| black_box(est.step(black_box(Some(0.25))))));
    steady::<4, 1>(c);
    steady::<24, 4>(c);
    kalman::<f32, 4, 4>(c, "f32");
    kalman::<f32, 12, 4>(c, "f32");
    kalman::<f32, 24, 4>(c, "f32");
    kalman::<f64, 24, 4>(c, "f64");
    ukf(c);
}

criterion_group!(benches, all);
criterion_main!(benches);
