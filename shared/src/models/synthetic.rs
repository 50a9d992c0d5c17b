//! Deterministic synthetic systems for benchmarks and tests: the cost of a filter step depends
//! only on the sizes, so the chip benchmark (`firmware/src/bin/bench`) and the host benchmark
//! (`shared/benches/filters.rs`) run these same models, and their figures compare.

use crate::filter::{LinearModel, SteadyState, UkfModel};
use nalgebra::{SMatrix, SVector};

/// A tiny linear congruential generator: numbers in [−1, 1), identical on every platform.
///
/// ```
/// use edgekf::models::synthetic::Lcg;
/// let mut a = Lcg(1);
/// let mut b = Lcg(1);
/// assert_eq!(a.next(), b.next());
/// assert!((-1.0..1.0).contains(&a.next()));
/// ```
#[derive(Debug, Clone)]
pub struct Lcg(pub u32);

impl Lcg {
    /// The next number in [−1, 1).
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (self.0 >> 8) as f64 / (1u32 << 23) as f64 - 1.0
    }
}

/// A dense stable model: `A` with entries in [−1, 1) scaled to Frobenius norm 0.9 (so its
/// spectral radius is below 0.9), dense `C`, `Q = B Bᵀ + 0.01 I`, `R = 0.5 I`.
///
/// ```
/// use edgekf::models::synthetic::{dense_model, Lcg};
/// let m = dense_model::<24, 4>(&mut Lcg(3));
/// assert!((m.a.norm() - 0.9).abs() < 1e-12);
/// ```
pub fn dense_model<const N: usize, const M: usize>(rng: &mut Lcg) -> LinearModel<f64, N, M> {
    let a = SMatrix::<f64, N, N>::from_fn(|_, _| rng.next());
    let b = SMatrix::<f64, N, N>::from_fn(|_, _| 0.3 * rng.next());
    LinearModel {
        a: a * (0.9 / a.norm()),
        c: SMatrix::from_fn(|_, _| rng.next()),
        q: b * b.transpose() + SMatrix::identity() * 0.01,
        r: SMatrix::identity() * 0.5,
    }
}

/// A steady state for the steady-state filter's benchmarks: identity covariances and a gain
/// with entries in [−0.01, 0.01). Any gain costs the same per step, and solving a 24-state
/// Riccati equation (in software `f64` on the chip) would only slow the benchmarks down.
///
/// ```
/// use edgekf::filter::SteadyStateFilter;
/// use edgekf::models::synthetic::{dense_model, some_steady_state, Lcg};
/// use nalgebra::SVector;
/// let mut rng = Lcg(11);
/// let model = dense_model::<6, 2>(&mut rng);
/// let ss = some_steady_state::<6, 2>(&mut rng);
/// assert!(ss.gain.amax() < 0.01);
/// assert!(SteadyStateFilter::<f32, 6, 2>::from_steady_state(&model, &ss, SVector::zeros()).is_ok());
/// ```
pub fn some_steady_state<const N: usize, const M: usize>(rng: &mut Lcg) -> SteadyState<N, M> {
    SteadyState {
        predicted: SMatrix::identity(),
        filtered: SMatrix::identity(),
        gain: SMatrix::from_fn(|_, _| 0.01 * rng.next()),
        innovation: SMatrix::identity(),
        iterations: 0,
    }
}

/// A nonlinear model for the UKF benchmarks: dense linear dynamics with cubic damping,
/// `f(x) = A x − 0.01 x³`, and quadratic sensors, `h(x) = C x + 0.05 (C x)²`.
#[derive(Debug, Clone)]
pub struct CubicModel<const N: usize, const M: usize> {
    /// Linear part of the dynamics.
    pub a: SMatrix<f32, N, N>,
    /// Linear part of the sensors.
    pub c: SMatrix<f32, M, N>,
}

impl<const N: usize, const M: usize> UkfModel<f32, N, M> for CubicModel<N, M> {
    fn f(&self, x: &SVector<f32, N>) -> SVector<f32, N> {
        self.a * x - x.map(|v| 0.01 * v * v * v)
    }
    fn h(&self, x: &SVector<f32, N>) -> SVector<f32, M> {
        let y = self.c * x;
        y + y.map(|v| 0.05 * v * v)
    }
}
