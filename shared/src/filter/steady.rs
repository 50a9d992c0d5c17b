use super::kalman::LinearModel;
use crate::linalg::solve;
use crate::Real;
use nalgebra::{SMatrix, SVector};

/// Why a steady-state gain could not be computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RiccatiError {
    /// The Riccati recursion did not settle within the iteration budget (an unobservable
    /// unstable mode, or a budget too small for a very slow filter).
    NotConverged,
    /// The innovation covariance was singular or a value was not finite.
    Singular,
}

/// The steady state of a linear Kalman filter: the solution of the discrete algebraic Riccati
/// equation for the predicted covariance, with its gain and innovation covariance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteadyState<const N: usize, const M: usize> {
    /// Predicted (a-priori) covariance `P⁻`.
    pub predicted: SMatrix<f64, N, N>,
    /// Filtered (a-posteriori) covariance `P⁺`.
    pub filtered: SMatrix<f64, N, N>,
    /// Gain `K = P⁻ Cᵀ S⁻¹`.
    pub gain: SMatrix<f64, N, M>,
    /// Innovation covariance `S = C P⁻ Cᵀ + R`.
    pub innovation: SMatrix<f64, M, M>,
    /// Riccati iterations it took.
    pub iterations: u32,
}

/// Solves the filter's discrete algebraic Riccati equation by iterating the covariance
/// recursion in `f64` (Joseph form) from `P = Q` until the gain changes by less than `tol`
/// relative, or `max_iter` is reached.
///
/// Uses only arithmetic and comparisons, so the chip (at start-up, in software `f64`) and the
/// host compute the same bits.
///
/// ```
/// use edgekf::filter::{solve_riccati, LinearModel};
/// use nalgebra::Matrix1;
/// // Random walk q = 1 seen with r = 1: P⁻ = (1 + √5)/2, the golden ratio.
/// let m = LinearModel { a: Matrix1::new(1.0), c: Matrix1::new(1.0), q: Matrix1::new(1.0), r: Matrix1::new(1.0) };
/// let ss = solve_riccati(&m, 1e-14, 10_000).unwrap();
/// assert!((ss.predicted[(0, 0)] - 1.618033988749895).abs() < 1e-12);
/// ```
// Out of line for the same reason as `expm`: start-up temporaries must not stay in `main`'s frame.
#[inline(never)]
pub fn solve_riccati<const N: usize, const M: usize>(
    model: &LinearModel<f64, N, M>,
    tol: f64,
    max_iter: u32,
) -> Result<SteadyState<N, M>, RiccatiError> {
    let (a, c, q, r) = (&model.a, &model.c, &model.q, &model.r);
    let eye = SMatrix::<f64, N, N>::identity();
    let mut filtered = *q;
    let mut prev_gain = SMatrix::<f64, N, M>::zeros();
    for it in 1..=max_iter {
        let predicted = a * filtered * a.transpose() + q;
        let pct = predicted * c.transpose();
        let s = c * pct + r;
        let gain = solve(&s, &pct.transpose()).ok_or(RiccatiError::Singular)?.transpose();
        let i_kc = eye - gain * c;
        let next = i_kc * predicted * i_kc.transpose() + gain * r * gain.transpose();
        let next = (next + next.transpose()) * 0.5;
        if next.iter().any(|v| !v.is_finite()) {
            return Err(RiccatiError::Singular);
        }
        // Both the gain and the covariance must settle: an unobservable unstable mode leaves
        // the gain fixed while its variance grows without bound.
        let gain_change = (gain - prev_gain).abs().max() / gain.abs().max().max(f64::MIN_POSITIVE);
        let cov_change = (next - filtered).abs().max() / next.abs().max().max(f64::MIN_POSITIVE);
        prev_gain = gain;
        filtered = next;
        if it > 1 && gain_change <= tol && cov_change <= tol {
            return Ok(SteadyState { predicted, filtered, gain, innovation: s, iterations: it });
        }
    }
    Err(RiccatiError::NotConverged)
}

/// A Kalman filter frozen at its steady state: `x = A x`, `x += K (y − C x)`. The cheapest
/// per-sample cost there is (no covariance arithmetic), and numerically trivial in `f32`, where
/// a full covariance recursion on a stiff model can lose positive definiteness.
///
/// The gain is optimal once the time-varying filter would have converged; after a gap in the
/// data it re-converges at the steady-state rate rather than faster.
///
/// ```
/// use edgekf::filter::{LinearModel, SteadyStateFilter};
/// use nalgebra::{Matrix1, Vector1};
/// let m = LinearModel { a: Matrix1::new(1.0), c: Matrix1::new(1.0), q: Matrix1::new(1e-4), r: Matrix1::new(1.0) };
/// let mut f = SteadyStateFilter::<f32, 1, 1>::new(&m, Vector1::zeros()).unwrap();
/// for _ in 0..2000 { f.predict(); f.update(&Vector1::new(3.0)); }
/// assert!((f.state()[0] - 3.0).abs() < 1e-3);
/// ```
#[derive(Debug, Clone)]
pub struct SteadyStateFilter<T: Real, const N: usize, const M: usize> {
    a: SMatrix<T, N, N>,
    c: SMatrix<T, M, N>,
    gain: SMatrix<T, N, M>,
    s_inv: SMatrix<T, M, M>,
    x: SVector<T, N>,
    x0: SVector<T, N>,
    resets: u32,
}

impl<T: Real, const N: usize, const M: usize> SteadyStateFilter<T, N, M> {
    /// Solves the Riccati equation (tolerance 1e-12, at most 100 000 iterations) and keeps the
    /// gain in precision `T`.
    pub fn new(model: &LinearModel<f64, N, M>, x0: SVector<T, N>) -> Result<Self, RiccatiError> {
        let ss = solve_riccati(model, 1e-12, 100_000)?;
        Self::from_steady_state(model, &ss, x0)
    }

    /// Builds the filter from an already computed steady state (for example one solved on the
    /// host and compiled in as constants).
    pub fn from_steady_state(
        model: &LinearModel<f64, N, M>,
        ss: &SteadyState<N, M>,
        x0: SVector<T, N>,
    ) -> Result<Self, RiccatiError> {
        Self::from_gain(model, &ss.gain, &ss.innovation, x0)
    }

    /// Builds the filter from a gain `K` and innovation covariance `S` alone (what
    /// [`crate::export::write_steady_state`] writes).
    pub fn from_gain(
        model: &LinearModel<f64, N, M>,
        gain: &SMatrix<f64, N, M>,
        innovation: &SMatrix<f64, M, M>,
        x0: SVector<T, N>,
    ) -> Result<Self, RiccatiError> {
        let cast = |v: f64| T::of_f64(v);
        Self::from_parts(&model.a.map(cast), &model.c.map(cast), &gain.map(cast), innovation, x0)
    }

    /// Builds the filter from `A`, `C` and `K` already in precision `T`, and `S` in `f64`
    /// (inverted here, in `f64`, then rounded to `T`). Gives the same bits as
    /// [`SteadyStateFilter::from_gain`] on `A`, `C`, `K` rounded with [`Real::of_f64`], without
    /// an `f64` model: a 20-state `f64` `A` and `Q` are 6.4 KB of stack on a chip that only
    /// needs the `f32` `A` (for example one built straight from exported constants).
    ///
    /// ```
    /// use edgekf::filter::SteadyStateFilter;
    /// use nalgebra::{Matrix1, Vector1};
    /// let (a, c, k) = (Matrix1::new(1.0f32), Matrix1::new(1.0f32), Matrix1::new(0.5f32));
    /// let mut f = SteadyStateFilter::from_parts(&a, &c, &k, &Matrix1::new(4.0), Vector1::zeros()).unwrap();
    /// let (r, nis) = f.update(&Vector1::new(2.0)).unwrap();
    /// assert_eq!((r[0], nis, f.state()[0]), (2.0, 1.0, 1.0)); // NIS = 2²/4
    /// ```
    pub fn from_parts(
        a: &SMatrix<T, N, N>,
        c: &SMatrix<T, M, N>,
        gain: &SMatrix<T, N, M>,
        innovation: &SMatrix<f64, M, M>,
        x0: SVector<T, N>,
    ) -> Result<Self, RiccatiError> {
        let s_inv = solve(innovation, &SMatrix::<f64, M, M>::identity()).ok_or(RiccatiError::Singular)?;
        Ok(Self { a: *a, c: *c, gain: *gain, s_inv: s_inv.map(T::of_f64), x: x0, x0, resets: 0 })
    }

    /// Time update `x = A x`.
    pub fn predict(&mut self) {
        self.x = self.a * self.x;
        self.guard();
    }

    /// Measurement update; returns the residual and its NIS. A non-finite `y` is not used
    /// (returns `None`).
    pub fn update(&mut self, y: &SVector<T, M>) -> Option<(SVector<T, M>, T)> {
        if y.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let r = y - self.c * self.x;
        let nis = (r.transpose() * self.s_inv * r)[(0, 0)];
        self.x += self.gain * r;
        self.guard();
        Some((r, nis))
    }

    /// Residual and NIS of `y` without updating.
    pub fn innovation(&self, y: &SVector<T, M>) -> (SVector<T, M>, T) {
        let r = y - self.c * self.x;
        (r, (r.transpose() * self.s_inv * r)[(0, 0)])
    }

    fn guard(&mut self) {
        if self.x.iter().any(|v| !v.is_finite()) {
            self.x = self.x0;
            self.resets = self.resets.saturating_add(1);
        }
    }

    /// Current state.
    pub fn state(&self) -> &SVector<T, N> {
        &self.x
    }

    /// Times a non-finite state was reset to the initial state.
    pub fn resets(&self) -> u32 {
        self.resets
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filter::KalmanFilter;
    use nalgebra::{Matrix1, Matrix2, RowVector2, Vector1, Vector2};

    #[test]
    fn steady_state_matches_the_converged_time_varying_filter() {
        let dt = 0.01;
        let model = LinearModel {
            a: Matrix2::new(1.0, dt, 0.0, 0.98),
            c: RowVector2::new(1.0, 0.0),
            q: Matrix2::new(1e-6, 0.0, 0.0, 1e-4),
            r: Matrix1::new(1e-2),
        };
        let ss = solve_riccati(&model, 1e-13, 100_000).unwrap();
        let mut kf = KalmanFilter::new(model.clone(), Vector2::zeros(), Matrix2::identity());
        for _ in 0..20_000 {
            kf.predict();
            kf.update(&Vector1::new(0.0)).unwrap();
        }
        assert!((kf.covariance() - ss.filtered).abs().max() < 1e-12 * ss.filtered.abs().max() * 1e3);
        // DARE residual: P⁻ = A P⁺ Aᵀ + Q.
        let resid = model.a * ss.filtered * model.a.transpose() + model.q - ss.predicted;
        assert!(resid.abs().max() < 1e-12 * ss.predicted.abs().max());
    }

    #[test]
    fn unobservable_unstable_mode_does_not_converge() {
        let model = LinearModel {
            a: Matrix2::new(1.1, 0.0, 0.0, 0.5),
            c: RowVector2::new(0.0, 1.0),
            q: Matrix2::identity(),
            r: Matrix1::new(1.0),
        };
        assert_eq!(solve_riccati(&model, 1e-12, 2_000).unwrap_err(), RiccatiError::NotConverged);
    }
}
