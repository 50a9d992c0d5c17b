//! Unscented Kalman filter with Van der Merwe's scaled sigma points.
//!
//! The arithmetic follows filterpy's `UnscentedKalmanFilter` with `MerweScaledSigmaPoints` step
//! for step (same weights, same sigma-point order, sigma points of the update redrawn from the
//! predicted mean and covariance), so a host run in `f64` can be checked against it element by
//! element; `shared/tests/filterpy.rs` does that.

use super::kalman::{FilterError, FilterHealth, Innovation};
use super::sigma::{MerweSigmaPoints, SigmaWeights, UkfError};
use crate::Real;
use nalgebra::{SMatrix, SVector};

/// A nonlinear discrete model `x' = f(x) + w`, `y = h(x) + v` with `w ~ N(0, Q)`,
/// `v ~ N(0, R)`; the noise covariances live in the filter.
///
/// `f` and `h` are called `2N + 1` times per predict and per update, at sigma points that may lie
/// outside the physical domain (a negative clearance, a health factor above one): clamp inside
/// the model where that matters. They must not panic; a non-finite result is caught by the filter
/// (see [`UnscentedKalmanFilter`]). For the chip and the
/// host to compute the same bits, write them with `+ − × ÷`, `sqrt` and comparisons only (or
/// call `libm` explicitly, accepting that its results may differ in the last bit between
/// platforms).
///
/// ```
/// use edgekf::filter::UkfModel;
/// use nalgebra::{Vector1, Vector2};
/// /// A falling body with drag, position measured.
/// struct Fall { dt: f64 }
/// impl UkfModel<f64, 2, 1> for Fall {
///     fn f(&self, x: &Vector2<f64>) -> Vector2<f64> {
///         let v = x[1] + self.dt * (-9.81 + 0.1 * x[1] * x[1]);
///         Vector2::new(x[0] + self.dt * v, v)
///     }
///     fn h(&self, x: &Vector2<f64>) -> Vector1<f64> {
///         Vector1::new(x[0])
///     }
/// }
/// let m = Fall { dt: 0.01 };
/// assert!(m.f(&Vector2::new(10.0, 0.0))[1] < 0.0);
/// ```
pub trait UkfModel<T: Real, const N: usize, const M: usize> {
    /// Process model: the state one step later, without noise.
    fn f(&self, x: &SVector<T, N>) -> SVector<T, N>;
    /// Measurement model: the noise-free measurement of state `x`.
    fn h(&self, x: &SVector<T, N>) -> SVector<T, M>;
}

/// A further measurement of a [`UkfModel`]'s state, `y = h(x) + v`, applied with
/// [`UnscentedKalmanFilter::update_with`]; same rules for `h` as [`UkfModel::h`].
pub trait UkfMeasurement<T: Real, const N: usize, const K: usize> {
    /// The noise-free measurement of state `x`.
    fn h(&self, x: &SVector<T, N>) -> SVector<T, K>;
}

/// A model's own measurement as a [`UkfMeasurement`].
struct ModelMeasurement<'a, F>(&'a F);

impl<T: Real, const N: usize, const M: usize, F: UkfModel<T, N, M>> UkfMeasurement<T, N, M>
    for ModelMeasurement<'_, F>
{
    fn h(&self, x: &SVector<T, N>) -> SVector<T, M> {
        self.0.h(x)
    }
}

/// Lower Cholesky factor of `spread · P` into `l`; `false` unless the lower triangle and the
/// factor are finite and the factor's diagonal is positive (`P` is symmetric wherever this is
/// called on a filter's covariance: the guard symmetrises it first).
fn sigma_factor<T: Real, const N: usize>(p: &SMatrix<T, N, N>, spread: T, l: &mut SMatrix<T, N, N>) -> bool {
    // The factor checks every pivot and entry as it forms them, which covers the (symmetric)
    // input: no separate passes over the matrix. In place: see `cholesky_scaled_into`.
    crate::linalg::cholesky_scaled_into(p, spread, l)
}

/// The sigma-point factor of a filter's start into `sqrt`, or why there is none: `x0` not
/// finite, `p0` not finite or not positive definite.
fn start_factor<T: Real, const N: usize>(
    weights: &SigmaWeights<T>,
    x0: &SVector<T, N>,
    p0: &SMatrix<T, N, N>,
    sqrt: &mut SMatrix<T, N, N>,
) -> Result<(), UkfError> {
    if x0.iter().any(|v| !v.is_finite()) || !sigma_factor(p0, weights.spread, sqrt) {
        return Err(UkfError::InitialCovariance);
    }
    Ok(())
}

/// Weighted mean and covariance of the `2N + 1` images of the sigma points, given as the centre
/// image `ψ₀` and the images of the `+` and `−` points (columns of `plus`, `minus`).
///
/// Summed about the centre image instead of as `Σ Wmᵢ ψᵢ`: with `eᵢ = ψᵢ − ψ₀`,
///
/// ```text
/// m = Σᵢ₌₁ W eᵢ,   mean = ψ₀ + m,   cov = Σᵢ₌₁ W eᵢ eᵢᵀ + (β − α²) m mᵀ
/// ```
///
/// which equals filterpy's `Σ Wmᵢ ψᵢ`, `Σ Wcᵢ (ψᵢ − mean)(…)ᵀ` exactly for the Merwe weights
/// (`Wm₀ + 2n W = 1`, `Wc₀ + 2n W − 2 = β − α²`). Unlike the direct sums it has no terms of size
/// `|Wm₀| |ψ|` to cancel (the deviations `eᵢ` of nearby points are formed exactly, and the weight
/// sum is one by construction, not by rounding), and for `β ≥ α²` every term is positive
/// semi-definite. What remains is the rounding of the images `ψᵢ` themselves, amplified by about
/// `|Wm₀|` (see [`MerweSigmaPoints`]). Rank-one terms are formed as `(e eᵀ) · w`, which is exactly
/// symmetric.
///
/// In place, for the stack of a small target (a 20-state `f32` filter's `plus` and `minus` are
/// 1.6 KB each): the images become their deviations `eᵢ`, the covariance is written to `cov`,
/// and `m` is returned (the mean is `ψ₀ + m`; the update takes `eᵢ − m` for the cross-covariance).
fn moments<T: Real, const K: usize, const N: usize>(
    w: &SigmaWeights<T>,
    center: &SVector<T, K>,
    plus: &mut SMatrix<T, K, N>,
    minus: &mut SMatrix<T, K, N>,
    cov: &mut SMatrix<T, K, K>,
) -> SVector<T, K> {
    // Element by element: the same subtraction without nalgebra's shape assertion.
    for mut col in plus.column_iter_mut().chain(minus.column_iter_mut()) {
        for (e, c) in col.iter_mut().zip(center.iter()) {
            *e -= *c;
        }
    }
    // The columns from the storage: `column_iter`'s per-column assertion would be a panic path
    // (the no-panic proof); the arithmetic is the same.
    let columns = || plus.data.0.iter().chain(minus.data.0.iter());
    let mut m = SVector::<T, K>::zeros();
    for e in columns() {
        m += SVector::<T, K>::from(*e) * w.side;
    }
    // `cov = (m mᵀ) · (β − α²)`, element by element as nalgebra forms the expression.
    for (col, mj) in cov.data.0.iter_mut().zip(m.iter()) {
        for (x, mi) in col.iter_mut().zip(m.iter()) {
            *x = (*mi * *mj) * w.cov_shift;
        }
    }
    // `cov += (e eᵀ) · W` for every deviation, fused into one pass over the columns' storage:
    // the same products in the same order as the matrix expression (so the same bits, exactly
    // symmetric), without its two temporaries per point (the chip's hot loop).
    for e in columns() {
        add_outer(cov, e, e, w.side);
    }
    m
}

/// `acc += (a bᵀ) · w`, element by element as nalgebra forms `(a * b.transpose()) * w`.
fn add_outer<T: Real, const R: usize, const C: usize>(acc: &mut SMatrix<T, R, C>, a: &[T; R], b: &[T; C], w: T) {
    for (col, bj) in acc.data.0.iter_mut().zip(b.iter()) {
        for (x, ai) in col.iter_mut().zip(a.iter()) {
            *x += (*ai * *bj) * w;
        }
    }
}

/// `p −= wᵀ w` in place, each entry's sum in the order nalgebra's product forms it (first term,
/// then each next one added): the same bits as `p -= w.transpose() * w` without its `N × N`
/// temporary and the transposed copy.
fn sub_gram<T: Real, const K: usize, const N: usize>(p: &mut SMatrix<T, N, N>, w: &SMatrix<T, K, N>) {
    for (p_col, wj) in p.data.0.iter_mut().zip(w.data.0.iter()) {
        for (x, wi) in p_col.iter_mut().zip(w.data.0.iter()) {
            let mut terms = wi.iter().zip(wj.iter()).map(|(a, b)| *a * *b);
            if let Some(first) = terms.next() {
                *x -= terms.fold(first, |sum, t| sum + t);
            }
        }
    }
}

/// Unscented Kalman filter with `N` states and `M` measurements.
///
/// The plain (covariance, not square-root) form, step for step as filterpy computes it:
///
/// * predict: sigma points of `(x, P)`, through `f`, weighted mean and covariance, `+ Q`;
/// * update: sigma points redrawn from the predicted `(x⁻, P⁻)`, through `h`, predicted
///   measurement `ẑ`, `S = Pzz + R`, cross-covariance `Pxz`, `K = Pxz S⁻¹`, `x = x⁻ + K (y − ẑ)`,
///   `P = P⁻ − K S Kᵀ`.
///
/// The weighted sums are evaluated about the centre image (`mean = ψ₀ + Σ W (ψᵢ − ψ₀)`,
/// `cov = Σ W eᵢ eᵢᵀ + (β − α²) m mᵀ` with `eᵢ = ψᵢ − ψ₀`, `m = Σ W eᵢ`), which is algebraically
/// the same as filterpy's `Σ Wcᵢ (ψᵢ − mean)(…)ᵀ` but has no `±1/α²`-weighted terms to cancel.
/// In `f64` the two agree to about 1e-12 for a moderate α; at α = 1e-3 both sit at the rounding
/// floor `|Wm₀|·ε ≈ 2e-10` from the exact result (`shared/tests/filterpy.rs` checks edgekf
/// against filterpy and against a 60-digit reference).
///
/// Robustness, and why not a square-root filter:
///
/// * the centred sums are positive semi-definite by construction whenever `β ≥ α²` (every
///   standard choice): only positive weights `W` and `β − α²` appear, so the predicted `P⁻` and
///   `S` cannot lose definiteness however negative `Wc₀` is; only the update subtraction can;
/// * `K S Kᵀ` is formed as `W Wᵀ` with `W = Pxz L⁻ᵀ` (`S = L Lᵀ`): exactly symmetric, no inverse;
/// * the covariance guard runs after every predict and update. It symmetrises `P` and computes
///   the Cholesky factor of `(n + λ) P`, which is exactly the factor the next step needs for its
///   sigma points, so the check costs nothing extra. If `x` or `P` is not finite or the factor
///   does not exist, the filter counts a [`FilterHealth::covariance_resets`] and restarts its
///   covariance from the stated `P₀` (and its state from `x₀` if the state is not finite); every
///   step therefore starts from a positive definite `P`.
///
/// A square-root UKF (QR plus Cholesky up/downdates) was not chosen: with the Merwe weights
/// `Wc₀ < 0` for `α < 1`, so its square-root form needs a Cholesky *downdate*, which fails where
/// the direct sums lose definiteness; the centred sums remove that failure mode instead, at the
/// plain filter's cost (one `N × N` Cholesky per step) and with filterpy's arithmetic still
/// available for verification.
///
/// A measurement update that cannot be applied (non-finite measurement, `S` not positive
/// definite) leaves the filter unchanged, is counted in [`FilterHealth::refused_updates`] and
/// returns an error; `f` or `h` returning NaN is caught by the guard (predict) or by `S`
/// (update).
///
/// ```
/// use edgekf::filter::{MerweSigmaPoints, UkfModel, UnscentedKalmanFilter};
/// use nalgebra::{Matrix1, Matrix2, Vector1, Vector2};
/// /// A constant seen through a cubic sensor.
/// struct Model;
/// impl UkfModel<f32, 2, 1> for Model {
///     fn f(&self, x: &Vector2<f32>) -> Vector2<f32> { *x }
///     fn h(&self, x: &Vector2<f32>) -> Vector1<f32> { Vector1::new(x[0] + 0.1 * x[0] * x[0] * x[0]) }
/// }
/// let points = MerweSigmaPoints { alpha: 0.5, beta: 2.0, kappa: 1.0 };
/// let q = Matrix2::identity() * 1e-6;
/// let r = Matrix1::new(0.01);
/// let mut ukf = UnscentedKalmanFilter::new(points, q, r, Vector2::zeros(), Matrix2::identity()).unwrap();
/// for _ in 0..50 {
///     ukf.predict(&Model);
///     ukf.update(&Model, &Vector1::new(1.1)).unwrap(); // h(1, ·) = 1.1
/// }
/// assert!((ukf.state()[0] - 1.0).abs() < 0.01);
/// assert_eq!(ukf.health().covariance_resets, 0);
/// ```
#[derive(Debug, Clone)]
pub struct UnscentedKalmanFilter<T: Real, const N: usize, const M: usize> {
    /// Process-noise covariance `Q`, added after every predict. May be changed between steps
    /// (for example to retune a parameter random walk); a non-finite value is caught by the
    /// covariance guard.
    pub q: SMatrix<T, N, N>,
    /// Measurement-noise covariance `R`. May be changed between steps; one that makes `S`
    /// indefinite makes updates refused, not wrong.
    pub r: SMatrix<T, M, M>,
    weights: SigmaWeights<T>,
    x: SVector<T, N>,
    p: SMatrix<T, N, N>,
    /// Lower Cholesky factor of `spread · p`; always valid between steps.
    sqrt: SMatrix<T, N, N>,
    x_reset: SVector<T, N>,
    /// `P₀`. Its factor is not kept but formed again on a reset (the same bits as in `new`): a
    /// reset is rare, and the filter is moved by value and lives on a small target's stack.
    p_reset: SMatrix<T, N, N>,
    health: FilterHealth,
}

impl<T: Real, const N: usize, const M: usize> UnscentedKalmanFilter<T, N, M> {
    /// A filter starting at `x0` with covariance `p0`, which are also the values the covariance
    /// guard resets to.
    ///
    /// Fails if the sigma-point parameters give no real spread, or if `x0` or `p0` is not finite
    /// or `p0` not positive definite (a reset target must itself be valid).
    pub fn new(
        points: MerweSigmaPoints<T>,
        q: SMatrix<T, N, N>,
        r: SMatrix<T, M, M>,
        x0: SVector<T, N>,
        p0: SMatrix<T, N, N>,
    ) -> Result<Self, UkfError> {
        let weights = points.weights::<N>()?;
        let mut sqrt = SMatrix::<T, N, N>::zeros();
        start_factor(&weights, &x0, &p0, &mut sqrt)?;
        let health = FilterHealth::default();
        Ok(Self { q, r, weights, x: x0, p: p0, sqrt, x_reset: x0, p_reset: p0, health })
    }

    /// [`new`](Self::new), built in `slot` in place (the same filter, the same failures, and
    /// `slot` unchanged on one): `new` returns the filter by value, 6.6 KB at 20 `f32` states,
    /// which a caller that stores it meets as a copy or two on its stack. A node that starts
    /// its filter at its first sample, inside its loop, keeps the loop's stack down with this.
    ///
    /// ```
    /// use edgekf::filter::{MerweSigmaPoints, UnscentedKalmanFilter};
    /// use nalgebra::{Matrix1, Matrix2, Vector2};
    /// let points = MerweSigmaPoints { alpha: 0.5, beta: 2.0, kappa: 1.0 };
    /// let (q, r, x0, p0) = (Matrix2::zeros(), Matrix1::new(1.0), Vector2::new(1.0, 2.0), Matrix2::identity());
    /// let mut slot = None;
    /// let ukf = UnscentedKalmanFilter::<f64, 2, 1>::new_in(&mut slot, points, &q, &r, &x0, &p0).unwrap();
    /// assert_eq!(ukf.state()[1], 2.0);
    /// assert!(UnscentedKalmanFilter::new_in(&mut slot, points, &q, &r, &x0, &Matrix2::zeros()).is_err());
    /// assert_eq!(slot.unwrap().state()[1], 2.0);
    /// ```
    pub fn new_in<'a>(
        slot: &'a mut Option<Self>,
        points: MerweSigmaPoints<T>,
        q: &SMatrix<T, N, N>,
        r: &SMatrix<T, M, M>,
        x0: &SVector<T, N>,
        p0: &SMatrix<T, N, N>,
    ) -> Result<&'a mut Self, UkfError> {
        let weights = points.weights::<N>()?;
        let mut sqrt = SMatrix::<T, N, N>::zeros();
        start_factor(&weights, x0, p0, &mut sqrt)?;
        let (zero, zeros) = (SVector::zeros(), SMatrix::zeros());
        let health = FilterHealth::default();
        // Zeros first (a fill of `slot`, no temporary: a filter literal would be built on the
        // stack and copied), then each field copied in.
        let f = slot.insert(Self {
            q: zeros,
            r: SMatrix::zeros(),
            weights,
            x: zero,
            p: zeros,
            sqrt: zeros,
            x_reset: zero,
            p_reset: zeros,
            health,
        });
        f.q = *q;
        f.r = *r;
        f.x = *x0;
        f.p = *p0;
        f.sqrt = sqrt;
        f.x_reset = *x0;
        f.p_reset = *p0;
        Ok(f)
    }

    /// Current state estimate.
    pub fn state(&self) -> &SVector<T, N> {
        &self.x
    }

    /// Current state covariance (symmetric positive definite between steps).
    pub fn covariance(&self) -> &SMatrix<T, N, N> {
        &self.p
    }

    /// Repair counters since construction.
    pub fn health(&self) -> FilterHealth {
        self.health
    }

    /// The sigma-point weights in use.
    pub fn weights(&self) -> &SigmaWeights<T> {
        &self.weights
    }

    /// Time update through `model.f`: `x⁻ = Σ Wmᵢ f(χᵢ)`, `P⁻ = Σ Wcᵢ (f(χᵢ) − x⁻)(…)ᵀ + Q`.
    #[inline(never)] // see `update_with`
    pub fn predict<F: UkfModel<T, N, M>>(&mut self, model: &F) {
        let center = model.f(&self.x);
        let mut plus = SMatrix::<T, N, N>::zeros();
        let mut minus = SMatrix::<T, N, N>::zeros();
        for (k, l) in self.sqrt.column_iter().enumerate() {
            plus.set_column(k, &model.f(&(self.x + l)));
            minus.set_column(k, &model.f(&(self.x - l)));
        }
        let m = moments(&self.weights, &center, &mut plus, &mut minus, &mut self.p);
        self.x = center + m;
        self.p += self.q;
        self.guard();
    }

    /// Measurement update with `y` through `model.h`. Returns the innovation `y − ẑ`, its
    /// covariance `S` and NIS.
    ///
    /// A non-finite `y`, or an `S` that is not positive definite (including `h` returning NaN),
    /// leaves the filter unchanged, is counted in [`FilterHealth::refused_updates`] and is returned
    /// as an error.
    pub fn update<F: UkfModel<T, N, M>>(
        &mut self,
        model: &F,
        y: &SVector<T, M>,
    ) -> Result<Innovation<T, M>, FilterError> {
        let r = self.r;
        self.update_with(&ModelMeasurement(model), y, &r)
    }

    /// Measurement update with another set of `K` measurements, `y = h(x) + v` with
    /// `v ~ N(0, r)`: for sensors slower than the filter's step (a 5 Hz velocity log beside a
    /// 50 Hz IMU) or groups of channels that may be missing on their own. Same guards and counts
    /// as [`update`](Self::update).
    ///
    /// ```
    /// use edgekf::filter::{MerweSigmaPoints, UkfMeasurement, UkfModel, UnscentedKalmanFilter};
    /// use nalgebra::{Matrix1, Matrix2, Vector1, Vector2};
    /// /// Position and velocity; position measured every step.
    /// struct Track;
    /// impl UkfModel<f64, 2, 1> for Track {
    ///     fn f(&self, x: &Vector2<f64>) -> Vector2<f64> { Vector2::new(x[0] + 0.1 * x[1], x[1]) }
    ///     fn h(&self, x: &Vector2<f64>) -> Vector1<f64> { Vector1::new(x[0]) }
    /// }
    /// /// A velocity log, now and then.
    /// struct Log;
    /// impl UkfMeasurement<f64, 2, 1> for Log {
    ///     fn h(&self, x: &Vector2<f64>) -> Vector1<f64> { Vector1::new(x[1]) }
    /// }
    /// let points = MerweSigmaPoints { alpha: 0.5, beta: 2.0, kappa: 1.0 };
    /// let mut ukf = UnscentedKalmanFilter::new(points, Matrix2::identity() * 1e-9, Matrix1::new(1e-4),
    ///     Vector2::zeros(), Matrix2::identity()).unwrap();
    /// ukf.update_with(&Log, &Vector1::new(2.0), &Matrix1::new(1e-6)).unwrap();
    /// assert!((ukf.state()[1] - 2.0).abs() < 1e-3);
    /// ```
    // Not inlined, nor is `predict`: each keeps its sigma-point matrices in its own frame, so a
    // caller's predict and several updates in a row take the largest of them, not their sum.
    #[inline(never)]
    pub fn update_with<const K: usize, H: UkfMeasurement<T, N, K>>(
        &mut self,
        model: &H,
        y: &SVector<T, K>,
        r: &SMatrix<T, K, K>,
    ) -> Result<Innovation<T, K>, FilterError> {
        if y.iter().any(|v| !v.is_finite()) {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::NonFiniteMeasurement);
        }
        let x = self.x;
        let center = model.h(&x);
        let mut plus = SMatrix::<T, K, N>::zeros();
        let mut minus = SMatrix::<T, K, N>::zeros();
        for (k, l) in self.sqrt.column_iter().enumerate() {
            plus.set_column(k, &model.h(&(x + l)));
            minus.set_column(k, &model.h(&(x - l)));
        }
        let mut s = SMatrix::<T, K, K>::zeros();
        let m = moments(&self.weights, &center, &mut plus, &mut minus, &mut s);
        let z_pred = center + m;
        s += r;
        // `Pzx = Pxzᵀ`, accumulated transposed (the same products: the solve below takes it so).
        // The centre point's state deviation is exactly zero: it adds nothing. The other points'
        // deviations `(x ± l) − x` (as filterpy forms them, not `± l`) are formed again here
        // rather than kept from the loop above: two `N × N` matrices fewer on the stack.
        let mut pzx = SMatrix::<T, K, N>::zeros();
        let side = self.weights.side;
        let mut add = |point: SVector<T, N>, dz: &mut [T; K]| {
            for (e, mi) in dz.iter_mut().zip(m.iter()) {
                *e -= *mi;
            }
            let [dx] = &(point - x).data.0;
            add_outer(&mut pzx, dz, dx, side);
        };
        for (l, dz) in self.sqrt.data.0.iter().zip(plus.data.0.iter_mut()) {
            add(x + SVector::<T, N>::from(*l), dz);
        }
        for (l, dz) in self.sqrt.data.0.iter().zip(minus.data.0.iter_mut()) {
            add(x - SVector::<T, N>::from(*l), dz);
        }
        let residual = y - z_pred;
        let refuse = |health: &mut FilterHealth| {
            health.refused_updates = health.refused_updates.saturating_add(1);
            Err(FilterError::InnovationCovariance)
        };
        if s.iter().any(|v| !v.is_finite()) || pzx.iter().any(|v| !v.is_finite()) {
            return refuse(&mut self.health);
        }
        let Some(l) = crate::linalg::cholesky(&s) else {
            return refuse(&mut self.health);
        };
        // K = Pxz S⁻¹ = (L⁻ᵀ L⁻¹ Pxzᵀ)ᵀ;  K S Kᵀ = W Wᵀ with Wᵀ = L⁻¹ Pxzᵀ.
        let wt = crate::linalg::solve_lower(&l, &pzx);
        let white = crate::linalg::solve_lower(&l, &residual);
        let gain = crate::linalg::solve_lower_transposed(&l, &wt).transpose();
        if wt.iter().chain(white.iter()).any(|v| !v.is_finite()) {
            return refuse(&mut self.health);
        }
        self.x = x + gain * residual;
        sub_gram(&mut self.p, &wt);
        self.guard();
        Ok(Innovation { residual, s, nis: white.norm_squared() })
    }

    /// Replaces the state's covariance with `p` (a change-point detector reopening a parameter
    /// it had settled), through the same guard as every step: a `p` that is not positive
    /// definite resets to `P₀` and is counted.
    pub fn set_covariance(&mut self, p: SMatrix<T, N, N>) {
        self.edit_covariance(|q| *q = p);
    }

    /// Changes the state's covariance in place through `edit`, then the same guard as
    /// [`set_covariance`](Self::set_covariance): for changing a few entries without a copy of
    /// the whole matrix (1.6 KB of stack for 20 `f32` states).
    ///
    /// ```
    /// use edgekf::filter::{MerweSigmaPoints, UnscentedKalmanFilter};
    /// use nalgebra::{Matrix1, Matrix2, Vector2};
    /// let points = MerweSigmaPoints { alpha: 0.5, beta: 2.0, kappa: 1.0 };
    /// let mut ukf = UnscentedKalmanFilter::<f64, 2, 1>::new(points, Matrix2::zeros(), Matrix1::new(1.0),
    ///     Vector2::zeros(), Matrix2::identity()).unwrap();
    /// ukf.edit_covariance(|p| p[(1, 1)] = 4.0);
    /// assert_eq!(ukf.covariance()[(1, 1)], 4.0);
    /// ukf.edit_covariance(|p| p[(0, 0)] = -1.0); // not positive definite: reset to P₀
    /// assert_eq!((*ukf.covariance(), ukf.health().covariance_resets), (Matrix2::identity(), 1));
    /// ```
    pub fn edit_covariance(&mut self, edit: impl FnOnce(&mut SMatrix<T, N, N>)) {
        edit(&mut self.p);
        self.guard();
    }

    /// Symmetrises `P`, refreshes the sigma-point factor, and resets what is broken (see the
    /// type's documentation).
    fn guard(&mut self) {
        let half = T::of_f64(0.5);
        // `P ← (P + Pᵀ)/2` in place: each pair averaged once, the same bits as the expression.
        for j in 0..N {
            for i in j + 1..N {
                if let (Some(&a), Some(&b)) = (self.p.get((i, j)), self.p.get((j, i))) {
                    let v = (a + b) * half;
                    for e in [(i, j), (j, i)] {
                        if let Some(x) = self.p.get_mut(e) {
                            *x = v;
                        }
                    }
                }
            }
        }
        let state_ok = self.x.iter().all(|v| v.is_finite());
        // Factored in place: a failed factor leaves a partial one, which the reset replaces.
        if !(sigma_factor(&self.p, self.weights.spread, &mut self.sqrt) && state_ok) {
            self.health.covariance_resets = self.health.covariance_resets.saturating_add(1);
            self.p = self.p_reset;
            // `new` factored this same `P₀`, so this cannot fail.
            let _ = sigma_factor(&self.p, self.weights.spread, &mut self.sqrt);
            if !state_ok {
                self.x = self.x_reset;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix1, Matrix2, RowVector2, Vector1, Vector2};

    struct Linear {
        a: Matrix2<f64>,
        c: RowVector2<f64>,
    }

    impl UkfModel<f64, 2, 1> for Linear {
        fn f(&self, x: &Vector2<f64>) -> Vector2<f64> {
            self.a * x
        }
        fn h(&self, x: &Vector2<f64>) -> Vector1<f64> {
            self.c * x
        }
    }

    fn cv() -> (Linear, crate::filter::LinearModel<f64, 2, 1>) {
        let dt = 0.1;
        let a = Matrix2::new(1.0, dt, 0.0, 1.0);
        let c = RowVector2::new(1.0, 0.0);
        let q = Matrix2::new(dt * dt * dt / 3.0, dt * dt / 2.0, dt * dt / 2.0, dt) * 0.01;
        (Linear { a, c }, crate::filter::LinearModel { a, c, q, r: Matrix1::new(0.25) })
    }

    #[test]
    fn linear_model_reproduces_the_kalman_filter() {
        // The unscented transform is exact for linear models, for any α, β, κ.
        let (m, lin) = cv();
        let p0 = Matrix2::new(2.0, 0.3, 0.3, 1.0);
        let x0 = Vector2::new(1.0, -1.0);
        for (alpha, kappa) in [(1e-3, 0.0), (0.5, 1.0), (1.0, 0.0)] {
            let points = MerweSigmaPoints { alpha, beta: 2.0, kappa };
            let mut ukf = UnscentedKalmanFilter::new(points, lin.q, lin.r, x0, p0).unwrap();
            let mut kf = crate::filter::KalmanFilter::new(lin.clone(), x0, p0);
            for k in 0..100 {
                let y = Vector1::new(0.3 * k as f64 + if k % 2 == 0 { 0.2 } else { -0.2 });
                ukf.predict(&m);
                kf.predict();
                let iu = ukf.update(&m, &y).unwrap();
                let ik = kf.update(&y).unwrap();
                let tol = if alpha < 1e-2 { 1e-6 } else { 1e-10 };
                assert!((ukf.state() - kf.state()).abs().max() < tol, "α={alpha} k={k}");
                assert!((ukf.covariance() - kf.covariance()).abs().max() < tol, "α={alpha} k={k}");
                assert!((iu.nis - ik.nis).abs() < tol * 10.0);
            }
            assert_eq!(ukf.health(), FilterHealth::default());
        }
    }

    #[test]
    fn weights_match_filterpy_definition() {
        let w = MerweSigmaPoints { alpha: 1e-3f64, beta: 2.0, kappa: 0.0 }.weights::<3>().unwrap();
        let lambda = 1e-6 * 3.0 - 3.0;
        assert_eq!(w.mean_center, lambda / (3.0 + lambda));
        assert_eq!(w.cov_center, lambda / (3.0 + lambda) + (1.0 - 1e-6 + 2.0));
        assert_eq!(w.side, 0.5 / (3.0 + lambda));
        let sum = w.mean_center + 6.0 * w.side;
        assert!((sum - 1.0).abs() < 1e-9);
    }

    #[test]
    fn invalid_parameters_are_errors() {
        let (_, lin) = cv();
        let x0 = Vector2::zeros();
        let bad_points = [(0.0, 0.0), (-1.0, 0.0), (f64::NAN, 0.0), (1.0, -2.0), (1.0, f64::INFINITY)];
        for (alpha, kappa) in bad_points {
            let points = MerweSigmaPoints { alpha, beta: 2.0, kappa };
            let r = UnscentedKalmanFilter::new(points, lin.q, lin.r, x0, Matrix2::identity());
            assert_eq!(r.err(), Some(UkfError::SigmaPoints), "α={alpha} κ={kappa}");
        }
        let points = MerweSigmaPoints { alpha: 1.0, beta: 2.0, kappa: 0.0 };
        for p0 in [Matrix2::zeros(), Matrix2::new(1.0, 2.0, 2.0, 1.0), Matrix2::identity() * f64::NAN] {
            let r = UnscentedKalmanFilter::new(points, lin.q, lin.r, x0, p0);
            assert_eq!(r.err(), Some(UkfError::InitialCovariance));
        }
        let r = UnscentedKalmanFilter::new(points, lin.q, lin.r, Vector2::new(f64::NAN, 0.0), Matrix2::identity());
        assert_eq!(r.err(), Some(UkfError::InitialCovariance));
    }

    #[test]
    fn nan_measurement_is_refused_and_counted() {
        let (m, lin) = cv();
        let points = MerweSigmaPoints { alpha: 1.0, beta: 2.0, kappa: 0.0 };
        let mut ukf = UnscentedKalmanFilter::new(points, lin.q, lin.r, Vector2::zeros(), Matrix2::identity()).unwrap();
        let (x, p) = (*ukf.state(), *ukf.covariance());
        assert_eq!(ukf.update(&m, &Vector1::new(f64::INFINITY)), Err(FilterError::NonFiniteMeasurement));
        ukf.r = Matrix1::new(-10.0);
        assert_eq!(ukf.update(&m, &Vector1::new(1.0)), Err(FilterError::InnovationCovariance));
        assert_eq!((*ukf.state(), *ukf.covariance()), (x, p));
        assert_eq!(ukf.health().refused_updates, 2);
    }

    /// A model whose `f` goes NaN past a threshold, and whose `h` does on demand.
    struct Fragile;
    impl UkfModel<f64, 2, 1> for Fragile {
        fn f(&self, x: &Vector2<f64>) -> Vector2<f64> {
            if x[0] > 4.3 {
                Vector2::new(f64::NAN, 0.0)
            } else {
                x * 2.0
            }
        }
        fn h(&self, x: &Vector2<f64>) -> Vector1<f64> {
            Vector1::new(if x[1] > 100.0 { f64::NAN } else { x[0] })
        }
    }

    #[test]
    fn non_finite_model_output_resets_and_is_counted() {
        let points = MerweSigmaPoints { alpha: 1.0, beta: 2.0, kappa: 0.0 };
        let x0 = Vector2::new(1.0, 0.0);
        let p0 = Matrix2::identity() * 0.01;
        let mut ukf = UnscentedKalmanFilter::new(points, Matrix2::zeros(), Matrix1::new(1.0), x0, p0).unwrap();
        ukf.predict(&Fragile); // x = 2
        ukf.predict(&Fragile); // x = 4
        assert_eq!(ukf.health().covariance_resets, 0);
        ukf.predict(&Fragile); // a sigma point passes 4.3: NaN state
        assert_eq!(ukf.health().covariance_resets, 1);
        assert_eq!((*ukf.state(), *ukf.covariance()), (x0, p0));
        // h NaN on a sigma point → S not finite → refused, state unchanged.
        let mut ukf = UnscentedKalmanFilter::new(points, Matrix2::zeros(), Matrix1::new(1.0), x0, p0 * 1e6).unwrap();
        assert_eq!(ukf.update(&Fragile, &Vector1::new(0.0)), Err(FilterError::InnovationCovariance));
        assert_eq!(ukf.health().refused_updates, 1);
        assert!(ukf.state().iter().chain(ukf.covariance().iter()).all(|v| v.is_finite()));
    }

    #[test]
    fn indefinite_covariance_is_reset_and_counted() {
        let (m, lin) = cv();
        let points = MerweSigmaPoints { alpha: 1.0, beta: 2.0, kappa: 0.0 };
        let p0 = Matrix2::identity();
        let mut ukf = UnscentedKalmanFilter::new(points, lin.q, lin.r, Vector2::zeros(), p0).unwrap();
        ukf.q = Matrix2::new(0.0, 0.0, 0.0, -1e3); // an indefinite Q
        ukf.predict(&m);
        assert_eq!(ukf.health().covariance_resets, 1);
        assert_eq!(*ukf.covariance(), p0);
        ukf.q = lin.q;
        ukf.predict(&m);
        assert!(ukf.update(&m, &Vector1::new(0.5)).is_ok());
        assert_eq!(ukf.health().covariance_resets, 1);
    }
}
