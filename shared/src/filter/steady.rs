use super::kalman::{FilterAllocator, GenericLinearModel};
use crate::linalg::solve;
use crate::Real;
use nalgebra::{Const, DefaultAllocator, Dim, OMatrix, OVector, SMatrix, SVector};

/// Why a steady-state gain could not be computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RiccatiError {
    /// The Riccati recursion did not settle within the iteration budget (an unobservable
    /// unstable mode, or a budget too small for a very slow filter).
    NotConverged,
    /// The innovation covariance was singular or a value was not finite.
    Singular,
    /// The shapes of the model, gain or state disagree (possible only with dynamic sizes).
    SizeMismatch,
}

/// The steady state of a linear Kalman filter: the solution of the discrete algebraic Riccati
/// equation for the predicted covariance, with its gain and innovation covariance; for any
/// nalgebra dimensions ([`SteadyState`] fixed, [`DSteadyState`] dynamic).
#[derive(Debug, Clone, PartialEq)]
pub struct GenericSteadyState<N: Dim, M: Dim>
where
    DefaultAllocator: FilterAllocator<N, M>,
{
    /// Predicted (a-priori) covariance `P⁻`.
    pub predicted: OMatrix<f64, N, N>,
    /// Filtered (a-posteriori) covariance `P⁺`.
    pub filtered: OMatrix<f64, N, N>,
    /// Gain `K = P⁻ Cᵀ S⁻¹`.
    pub gain: OMatrix<f64, N, M>,
    /// Innovation covariance `S = C P⁻ Cᵀ + R`.
    pub innovation: OMatrix<f64, M, M>,
    /// Riccati iterations it took.
    pub iterations: u32,
}

/// The steady state of a filter with sizes fixed at compile time.
pub type SteadyState<const N: usize, const M: usize> = GenericSteadyState<Const<N>, Const<M>>;

/// The steady state of a filter with sizes known at run time (host, `alloc` feature).
#[cfg(feature = "alloc")]
pub type DSteadyState = GenericSteadyState<nalgebra::Dyn, nalgebra::Dyn>;

impl<const N: usize, const M: usize> Copy for SteadyState<N, M> {}

/// Solves the filter's discrete algebraic Riccati equation by iterating the covariance
/// recursion in `f64` (Joseph form) from `P = Q` until the gain changes by less than `tol`
/// relative, or `max_iter` is reached. Any nalgebra dimensions; a dynamic model whose shapes
/// disagree is [`RiccatiError::SizeMismatch`].
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
pub fn solve_riccati<N: Dim, M: Dim>(
    model: &GenericLinearModel<f64, N, M>,
    tol: f64,
    max_iter: u32,
) -> Result<GenericSteadyState<N, M>, RiccatiError>
where
    DefaultAllocator: FilterAllocator<N, M>,
{
    if !model.sizes_agree() {
        return Err(RiccatiError::SizeMismatch);
    }
    let (a, c, q, r) = (&model.a, &model.c, &model.q, &model.r);
    let (n, _) = a.shape_generic();
    let (m, _) = r.shape_generic();
    let eye = OMatrix::<f64, N, N>::identity_generic(n, n);
    let mut filtered = q.clone();
    let mut prev_gain = OMatrix::<f64, N, M>::zeros_generic(n, m);
    for it in 1..=max_iter {
        let predicted = a * &filtered * a.transpose() + q;
        let pct = &predicted * c.transpose();
        let s = c * &pct + r;
        let gain = solve(&s, &pct.transpose()).ok_or(RiccatiError::Singular)?.transpose();
        let i_kc = &eye - &gain * c;
        let next = &i_kc * &predicted * i_kc.transpose() + &gain * r * gain.transpose();
        let next = (&next + next.transpose()) * 0.5;
        if next.iter().any(|v| !v.is_finite()) {
            return Err(RiccatiError::Singular);
        }
        // Both the gain and the covariance must settle: an unobservable unstable mode leaves
        // the gain fixed while its variance grows without bound.
        let gain_change = (&gain - &prev_gain).abs().max() / gain.abs().max().max(f64::MIN_POSITIVE);
        let cov_change = (&next - &filtered).abs().max() / next.abs().max().max(f64::MIN_POSITIVE);
        prev_gain = gain;
        filtered = next;
        if it > 1 && gain_change <= tol && cov_change <= tol {
            return Ok(GenericSteadyState { predicted, filtered, gain: prev_gain, innovation: s, iterations: it });
        }
    }
    Err(RiccatiError::NotConverged)
}

/// A Kalman filter frozen at its steady state: `x = A x`, `x += K (y − C x)`. The cheapest
/// per-sample cost there is (no covariance arithmetic), and numerically trivial in `f32`, where
/// a full covariance recursion on a stiff model can lose positive definiteness. Any nalgebra
/// dimensions ([`SteadyStateFilter`] fixed, [`DSteadyStateFilter`] dynamic).
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
pub struct GenericSteadyStateFilter<T: Real, N: Dim, M: Dim>
where
    DefaultAllocator: FilterAllocator<N, M>,
{
    /// The model's `A` and `C`: all the filter keeps of it, the gain being fixed.
    a: OMatrix<T, N, N>,
    c: OMatrix<T, M, N>,
    /// The steady-state gain `K` and `S⁻¹` (for the innovations' NIS), computed once.
    gain: OMatrix<T, N, M>,
    s_inv: OMatrix<T, M, M>,
    /// The state, and the start it returns to when it stops being finite ([`Self::resets`]).
    x: OVector<T, N>,
    x0: OVector<T, N>,
    resets: u32,
}

/// A steady-state filter with sizes fixed at compile time (the chip's).
pub type SteadyStateFilter<T, const N: usize, const M: usize> = GenericSteadyStateFilter<T, Const<N>, Const<M>>;

/// A steady-state filter with sizes known at run time (host, `alloc` feature).
#[cfg(feature = "alloc")]
pub type DSteadyStateFilter<T> = GenericSteadyStateFilter<T, nalgebra::Dyn, nalgebra::Dyn>;

impl<T: Real, const N: usize, const M: usize> SteadyStateFilter<T, N, M> {
    /// Builds the filter from `A`, `C` and `K` already in precision `T`, and `S` in `f64`
    /// (inverted here, in `f64`, then rounded to `T`). Gives the same bits as
    /// [`GenericSteadyStateFilter::from_gain`] on `A`, `C`, `K` rounded with [`Real::of_f64`],
    /// without an `f64` model: a 20-state `f64` `A` and `Q` are 6.4 KB of stack on a chip that
    /// only needs the `f32` `A` (for example one built straight from exported constants).
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
}

impl<T: Real, N: Dim, M: Dim> GenericSteadyStateFilter<T, N, M>
where
    DefaultAllocator: FilterAllocator<N, M>,
{
    /// Solves the Riccati equation (tolerance 1e-12, at most 100 000 iterations) and keeps the
    /// gain in precision `T`.
    pub fn new(model: &GenericLinearModel<f64, N, M>, x0: OVector<T, N>) -> Result<Self, RiccatiError> {
        let ss = solve_riccati(model, 1e-12, 100_000)?;
        Self::from_steady_state(model, &ss, x0)
    }

    /// Builds the filter from an already computed steady state (for example one solved on the
    /// host and compiled in as constants).
    pub fn from_steady_state(
        model: &GenericLinearModel<f64, N, M>,
        ss: &GenericSteadyState<N, M>,
        x0: OVector<T, N>,
    ) -> Result<Self, RiccatiError> {
        Self::from_gain(model, &ss.gain, &ss.innovation, x0)
    }

    /// Builds the filter from a gain `K` and innovation covariance `S` alone (what
    /// [`crate::export::write_steady_state`] writes); shapes that do not fit the model are
    /// [`RiccatiError::SizeMismatch`].
    pub fn from_gain(
        model: &GenericLinearModel<f64, N, M>,
        gain: &OMatrix<f64, N, M>,
        innovation: &OMatrix<f64, M, M>,
        x0: OVector<T, N>,
    ) -> Result<Self, RiccatiError> {
        let (n, m) = (model.states(), model.measurements());
        if !model.sizes_agree() || gain.shape() != (n, m) || innovation.shape() != (m, m) || x0.nrows() != n {
            return Err(RiccatiError::SizeMismatch);
        }
        let cast = |v: f64| T::of_f64(v);
        let (mdim, _) = innovation.shape_generic();
        let eye = OMatrix::<f64, M, M>::identity_generic(mdim, mdim);
        let s_inv = solve(innovation, &eye).ok_or(RiccatiError::Singular)?;
        Ok(Self {
            a: model.a.map(cast),
            c: model.c.map(cast),
            gain: gain.map(cast),
            s_inv: s_inv.map(cast),
            x: x0.clone(),
            x0,
            resets: 0,
        })
    }

    /// Time update `x = A x`.
    pub fn predict(&mut self) {
        self.x = &self.a * &self.x;
        self.guard();
    }

    /// Measurement update; returns the residual and its NIS. A non-finite `y` (or one of the
    /// wrong length) is not used (returns `None`).
    pub fn update(&mut self, y: &OVector<T, M>) -> Option<(OVector<T, M>, T)> {
        if y.nrows() != self.c.nrows() || y.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let r = y - &self.c * &self.x;
        let nis = (r.transpose() * &self.s_inv * &r)[(0, 0)];
        self.x += &self.gain * &r;
        self.guard();
        Some((r, nis))
    }

    /// Residual and NIS of `y` without updating (`None` for a `y` of the wrong length).
    pub fn innovation(&self, y: &OVector<T, M>) -> Option<(OVector<T, M>, T)> {
        if y.nrows() != self.c.nrows() {
            return None;
        }
        let r = y - &self.c * &self.x;
        let nis = (r.transpose() * &self.s_inv * &r)[(0, 0)];
        Some((r, nis))
    }

    fn guard(&mut self) {
        if self.x.iter().any(|v| !v.is_finite()) {
            self.x.copy_from(&self.x0);
            self.resets = self.resets.saturating_add(1);
        }
    }

    /// Current state.
    pub fn state(&self) -> &OVector<T, N> {
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
    use crate::filter::{KalmanFilter, LinearModel};
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
