//! Host timings of one filter step (`cargo bench -p edgekf`). The chip's figures are
//! instruction counts under QEMU: `cargo xtask bench`.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use edgekf::filter::{KalmanFilter, LinearModel, SteadyState, SteadyStateFilter};
use edgekf::models::harmonic::{HarmonicForceEstimator, HarmonicForceParams};
use edgekf::Real;
use nalgebra::{SMatrix, SVector};

/// Deterministic pseudo-random numbers in [−1, 1).
struct Lcg(u32);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (self.0 >> 8) as f64 / (1u32 << 23) as f64 - 1.0
    }
}

fn dense_model<const N: usize, const M: usize>(rng: &mut Lcg) -> LinearModel<f64, N, M> {
    let a = SMatrix::<f64, N, N>::from_fn(|_, _| rng.next());
    let b = SMatrix::<f64, N, N>::from_fn(|_, _| 0.3 * rng.next());
    LinearModel {
        a: a * (0.9 / a.norm()),
        c: SMatrix::from_fn(|_, _| rng.next()),
        q: b * b.transpose() + SMatrix::identity() * 0.01,
        r: SMatrix::identity() * 0.5,
    }
}

fn kalman<T: Real, const N: usize, const M: usize>(c: &mut Criterion, name: &str) {
    let mut rng = Lcg(7);
    let mut kf = KalmanFilter::<T, N, M>::new(dense_model::<N, M>(&mut rng).cast(), SVector::zeros(), SMatrix::identity());
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
    let ss = SteadyState {
        predicted: SMatrix::identity(),
        filtered: SMatrix::identity(),
        gain: SMatrix::from_fn(|_, _| 0.01 * rng.next()),
        innovation: SMatrix::identity(),
        iterations: 0,
    };
    let mut f = SteadyStateFilter::<f32, N, M>::from_steady_state(&model, &ss, SVector::zeros()).expect("filter");
    let y = SVector::<f32, M>::from_fn(|_, _| rng.next() as f32);
    c.bench_function(&format!("f32 steady-state step n={N} m={M}"), |b| {
        b.iter(|| {
            f.predict();
            black_box(f.update(black_box(&y)))
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
}

criterion_group!(benches, all);
criterion_main!(benches);
