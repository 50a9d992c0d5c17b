pub use super::dims::{FilterAllocator, FilterDim};
use crate::Real;
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, Dim, OMatrix, OVector, SMatrix, SVector};

/// A discrete linear time-invariant model `x' = A x + w`, `y = C x + v` with
/// `w ~ N(0, Q)`, `v ~ N(0, R)`, for any nalgebra dimensions; [`LinearModel`] is its fixed-size
/// form (the chip's), [`DLinearModel`] the dynamic one (the host's, `alloc`).
#[derive(Debug, Clone, PartialEq)]
pub struct GenericLinearModel<T: Real, N: Dim, M: Dim>
where
    DefaultAllocator: FilterAllocator<N, M>,
{
    /// State transition `A` (N × N).
    pub a: OMatrix<T, N, N>,
    /// Measurement matrix `C` (M × N).
    pub c: OMatrix<T, M, N>,
    /// Process-noise covariance `Q` (N × N).
    pub q: OMatrix<T, N, N>,
    /// Measurement-noise covariance `R` (M × M).
    pub r: OMatrix<T, M, M>,
}

/// A linear model with `N` states and `M` measurements fixed at compile time.
pub type LinearModel<T, const N: usize, const M: usize> = GenericLinearModel<T, Const<N>, Const<M>>;

/// A linear model with sizes known at run time (host, `alloc` feature).
#[cfg(feature = "alloc")]
pub type DLinearModel<T> = GenericLinearModel<T, nalgebra::Dyn, nalgebra::Dyn>;

impl<T: Real, N: Dim, M: Dim> GenericLinearModel<T, N, M>
where
    DefaultAllocator: FilterAllocator<N, M>,
{
    /// Converts an `f64` model (as built on the host or at start-up) to another precision.
    pub fn cast<U: Real>(&self) -> GenericLinearModel<U, N, M> {
        let f = |v: T| U::of_f64(v.as_f64());
        GenericLinearModel { a: self.a.map(f), c: self.c.map(f), q: self.q.map(f), r: self.r.map(f) }
    }

    /// Whether the four matrices have the shapes of one model (`A`, `Q` square, `C` as wide as
    /// `A`, `R` as tall as `C`). Always true for fixed sizes; a dynamic model is checked by
    /// every constructor so that a wrong shape is an error, not a panic.
    ///
    /// ```
    /// # #[cfg(feature = "alloc")] {
    /// use edgekf::filter::DLinearModel;
    /// use nalgebra::DMatrix;
    /// let m = DLinearModel { a: DMatrix::<f64>::identity(2, 2), c: DMatrix::zeros(1, 2), q: DMatrix::zeros(2, 2), r: DMatrix::zeros(1, 1) };
    /// assert!(m.sizes_agree());
    /// assert!(!DLinearModel { c: DMatrix::zeros(1, 3), ..m }.sizes_agree());
    /// # }
    /// ```
    pub fn sizes_agree(&self) -> bool {
        let (n, m) = (self.a.nrows(), self.c.nrows());
        self.a.ncols() == n && self.c.ncols() == n && self.q.shape() == (n, n) && self.r.shape() == (m, m)
    }

    /// Number of states `N`.
    pub fn states(&self) -> usize {
        self.a.nrows()
    }

    /// Number of measurements `M`.
    pub fn measurements(&self) -> usize {
        self.c.nrows()
    }
}

/// The innovation of one measurement update: what the model could not predict.
#[derive(Debug, Clone, PartialEq)]
pub struct GenericInnovation<T: Real, M: Dim>
where
    DefaultAllocator: Allocator<M> + Allocator<M, M>,
{
    /// `y − C x⁻`.
    pub residual: OVector<T, M>,
    /// Its predicted covariance `S = C P⁻ Cᵀ + R`.
    pub s: OMatrix<T, M, M>,
    /// Normalised innovation squared `rᵀ S⁻¹ r`; χ²(M) distributed when the filter is consistent.
    pub nis: T,
}

/// The innovation of a filter with `M` measurements fixed at compile time.
pub type Innovation<T, const M: usize> = GenericInnovation<T, Const<M>>;

impl<T: Real, const M: usize> Copy for GenericInnovation<T, Const<M>> {}

/// Counters of everything the filter had to repair or refuse. All zero in a healthy run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FilterHealth {
    /// Times the covariance (or state) became non-finite or lost its positive diagonal and was
    /// reset to the stated initial covariance.
    pub covariance_resets: u32,
    /// Updates refused because the innovation covariance was not positive definite or the
    /// measurement was not finite.
    pub refused_updates: u32,
}

/// Why a measurement update was not applied. The filter state is unchanged in every case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FilterError {
    /// The measurement held NaN or infinity.
    NonFiniteMeasurement,
    /// `S = C P Cᵀ + R` could not be factorised (not positive definite).
    InnovationCovariance,
    /// A sequential update was asked for with a non-diagonal `R`.
    CorrelatedNoise,
    /// The shapes of the model, state, covariance or measurement disagree (possible only with
    /// dynamic sizes).
    SizeMismatch,
}

/// What a sequential (scalar-by-scalar) update used.
#[derive(Debug, Clone, PartialEq)]
pub struct GenericSequentialInnovation<T: Real, M: Dim>
where
    DefaultAllocator: Allocator<M>,
{
    /// `y − C x⁻`, against the prediction before the first scalar update.
    pub residual: OVector<T, M>,
    /// Sum of the scalar NIS values; equals `rᵀ S⁻¹ r` of the joint update.
    pub nis: T,
    /// Each scalar update's innovation `eᵢ`, against the state the earlier scalars left (the
    /// first is `residual`'s).
    pub scalar: OVector<T, M>,
    /// Its variance `sᵢ`: `Σ ln sᵢ = ln det S` and `Σ eᵢ² / sᵢ` is [`nis`](Self::nis), so the
    /// two give the log-likelihood.
    pub variance: OVector<T, M>,
}

/// What a sequential update used, `M` fixed at compile time.
pub type SequentialInnovation<T, const M: usize> = GenericSequentialInnovation<T, Const<M>>;

impl<T: Real, const M: usize> Copy for GenericSequentialInnovation<T, Const<M>> {}

/// Linear Kalman filter with `N` states and `M` measurements, for any nalgebra dimensions:
/// [`KalmanFilter`] (sizes fixed at compile time) on the chip, [`DKalmanFilter`] (sizes known at
/// run time, `alloc` feature) on the host. One implementation: the host runs a model of any size
/// with the chip's algorithm, and a fixed size gives the same result either way.
///
/// Covariance update in Joseph form `P = (I − K C) P (I − K C)ᵀ + K R Kᵀ`, which stays symmetric
/// positive semi-definite under round-off far better than `(I − K C) P`, followed by explicit
/// symmetrisation; the gain comes from a Cholesky solve, never an explicit inverse.
///
/// ```
/// use edgekf::filter::{KalmanFilter, LinearModel};
/// use nalgebra::{Matrix1, Vector1};
/// // A constant observed in noise: the estimate converges to the mean of the data.
/// let model = LinearModel { a: Matrix1::new(1.0f64), c: Matrix1::new(1.0), q: Matrix1::new(0.0), r: Matrix1::new(1.0) };
/// let mut kf = KalmanFilter::new(model, Vector1::new(0.0), Matrix1::new(1e6));
/// for y in [1.0, 3.0, 2.0] {
///     kf.predict();
///     kf.update(&Vector1::new(y)).unwrap();
/// }
/// assert!((kf.state()[0] - 2.0).abs() < 1e-5);
/// ```
#[derive(Debug, Clone)]
pub struct GenericKalmanFilter<T: Real, N: FilterDim<M>, M: Dim>
where
    DefaultAllocator: FilterAllocator<N, M>,
{
    model: GenericLinearModel<T, N, M>,
    /// `Aᵀ` and `Cᵀ`, kept so that every product below is a dot product of contiguous columns
    /// (nalgebra stores column-major): on the Cortex-M4 that halves the instruction count.
    at: OMatrix<T, N, N>,
    ct: OMatrix<T, N, M>,
    x: OVector<T, N>,
    p: OMatrix<T, N, N>,
    x_reset: OVector<T, N>,
    p_reset: OMatrix<T, N, N>,
    health: FilterHealth,
}

/// A Kalman filter with `N` states and `M` measurements fixed at compile time (the chip's).
pub type KalmanFilter<T, const N: usize, const M: usize> = GenericKalmanFilter<T, Const<N>, Const<M>>;

/// A Kalman filter with sizes known at run time (host, `alloc` feature).
///
/// ```
/// use edgekf::filter::{DKalmanFilter, DLinearModel};
/// use nalgebra::{DMatrix, DVector};
/// let model = DLinearModel {
///     a: DMatrix::identity(1, 1),
///     c: DMatrix::identity(1, 1),
///     q: DMatrix::zeros(1, 1),
///     r: DMatrix::from_element(1, 1, 1.0f64),
/// };
/// let mut kf = DKalmanFilter::try_new(model, DVector::zeros(1), DMatrix::from_element(1, 1, 1e6)).unwrap();
/// for y in [1.0, 3.0, 2.0] {
///     kf.predict();
///     kf.update(&DVector::from_element(1, y)).unwrap();
/// }
/// assert!((kf.state()[0] - 2.0).abs() < 1e-5);
/// // A measurement of the wrong length is refused, not a panic.
/// assert!(kf.update(&DVector::zeros(2)).is_err());
/// ```
#[cfg(feature = "alloc")]
pub type DKalmanFilter<T> = GenericKalmanFilter<T, nalgebra::Dyn, nalgebra::Dyn>;

impl<T: Real, const N: usize, const M: usize> KalmanFilter<T, N, M> {
    /// A filter starting at `x0` with covariance `p0`; `x0, p0` are also the reset values the
    /// covariance guard falls back to. (Fixed sizes cannot disagree; for dynamic ones see
    /// [`GenericKalmanFilter::try_new`].)
    pub fn new(model: LinearModel<T, N, M>, x0: SVector<T, N>, p0: SMatrix<T, N, N>) -> Self {
        let (at, ct) = (model.a.transpose(), model.c.transpose());
        Self { model, at, ct, x: x0, p: p0, x_reset: x0, p_reset: p0, health: FilterHealth::default() }
    }
}

impl<T: Real, N: FilterDim<M>, M: Dim> GenericKalmanFilter<T, N, M>
where
    DefaultAllocator: FilterAllocator<N, M>,
{
    /// Like [`KalmanFilter::new`], for any sizes: [`FilterError::SizeMismatch`] if the model,
    /// `x0` and `p0` do not fit together.
    pub fn try_new(
        model: GenericLinearModel<T, N, M>,
        x0: OVector<T, N>,
        p0: OMatrix<T, N, N>,
    ) -> Result<Self, FilterError> {
        let n = model.states();
        if !model.sizes_agree() || x0.nrows() != n || p0.shape() != (n, n) {
            return Err(FilterError::SizeMismatch);
        }
        let (at, ct) = (model.a.transpose(), model.c.transpose());
        let (x_reset, p_reset) = (x0.clone(), p0.clone());
        Ok(Self { model, at, ct, x: x0, p: p0, x_reset, p_reset, health: FilterHealth::default() })
    }

    /// The model in use.
    pub fn model(&self) -> &GenericLinearModel<T, N, M> {
        &self.model
    }

    /// Current state estimate.
    pub fn state(&self) -> &OVector<T, N> {
        &self.x
    }

    /// Current state covariance.
    pub fn covariance(&self) -> &OMatrix<T, N, N> {
        &self.p
    }

    /// Repair counters since construction.
    pub fn health(&self) -> FilterHealth {
        self.health
    }

    /// Replaces the model for the steps that follow, keeping the state and covariance: a
    /// time-varying system (a boom that telescopes, a drive that saturates) re-linearised at
    /// each step. A model whose sizes do not fit the filter's is refused.
    ///
    /// ```
    /// use edgekf::filter::{KalmanFilter, LinearModel};
    /// use nalgebra::{Matrix1, Vector1};
    /// let m = |a: f64| LinearModel { a: Matrix1::new(a), c: Matrix1::new(1.0), q: Matrix1::new(0.0), r: Matrix1::new(1.0) };
    /// let mut kf = KalmanFilter::new(m(1.0), Vector1::new(1.0), Matrix1::new(1.0));
    /// kf.set_model(m(2.0)).unwrap();
    /// kf.predict();
    /// assert_eq!((kf.state()[0], kf.covariance()[(0, 0)]), (2.0, 4.0));
    /// ```
    pub fn set_model(&mut self, model: GenericLinearModel<T, N, M>) -> Result<(), FilterError> {
        if !model.sizes_agree() || model.states() != self.x.nrows() || model.measurements() != self.ct.ncols() {
            return Err(FilterError::SizeMismatch);
        }
        self.at = model.a.transpose();
        self.ct = model.c.transpose();
        self.model = model;
        Ok(())
    }

    /// Adds `dx` to the state: a known input's effect `B u`, after [`predict`](Self::predict)'s
    /// `A x`. A non-finite `dx` (or one of the wrong length) is refused and counted.
    pub fn shift(&mut self, dx: &OVector<T, N>) -> Result<(), FilterError> {
        if dx.nrows() != self.x.nrows() || dx.iter().any(|v| !v.is_finite()) {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::NonFiniteMeasurement);
        }
        self.x += dx;
        Ok(())
    }

    /// Time update `x = A x`, `P = A P Aᵀ + Q`.
    ///
    /// `U = P Aᵀ` then `P⁻ = A U + Q` on the upper triangle only, mirrored: `1.5 N³`
    /// multiply-adds instead of `2 N³`, and P comes out exactly symmetric.
    pub fn predict(&mut self) {
        self.x = &self.model.a * &self.x;
        // U = P Aᵀ = Pᵀ Aᵀ (P symmetric), then P⁻ = A U + Q = (Aᵀ)ᵀ U + Q on the upper triangle.
        let (n, _) = self.p.shape_generic();
        let mut u = OMatrix::<T, N, N>::zeros_generic(n, n);
        N::mul_tr_nn(&self.p, &self.at, &mut u, false, false);
        self.p.copy_from(&self.model.q);
        N::mul_tr_nn(&self.at, &u, &mut self.p, true, true);
        self.mirror_upper();
        self.guard();
    }

    /// Copies the upper triangle of P onto the lower one.
    fn mirror_upper(&mut self) {
        // Through `get` and `get_mut`: no index check is left (no panic path).
        for j in 0..self.p.ncols() {
            for i in 0..j {
                if let Some(v) = self.p.get((i, j)).copied() {
                    if let Some(d) = self.p.get_mut((j, i)) {
                        *d = v;
                    }
                }
            }
        }
    }

    /// Innovation of `y` against the current prediction, without changing the filter.
    ///
    /// Returns `None` if `S` is not positive definite (or `y` has the wrong length).
    pub fn innovation(&self, y: &OVector<T, M>) -> Option<GenericInnovation<T, M>> {
        if y.nrows() != self.model.measurements() {
            return None;
        }
        let residual = y - &self.model.c * &self.x;
        let s = &self.model.c * &self.p * self.model.c.transpose() + &self.model.r;
        let chol = s.clone().cholesky()?;
        let white = chol.l().solve_lower_triangular(&residual)?;
        Some(GenericInnovation { residual, s, nis: white.norm_squared() })
    }

    /// Measurement update with `y`. Returns the innovation it used.
    ///
    /// A non-finite `y` (or one of the wrong length) or a non-positive-definite `S` leaves the
    /// filter unchanged, is counted in [`FilterHealth::refused_updates`] and is returned as an
    /// error.
    pub fn update(&mut self, y: &OVector<T, M>) -> Result<GenericInnovation<T, M>, FilterError> {
        if y.nrows() != self.model.measurements() {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::SizeMismatch);
        }
        if y.iter().any(|v| !v.is_finite()) {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::NonFiniteMeasurement);
        }
        let residual = y - &self.model.c * &self.x;
        // P Cᵀ (N × M) and S = C P Cᵀ + R, as dot products of contiguous columns.
        let (n, m) = self.ct.shape_generic();
        let mut pct = OMatrix::<T, N, M>::zeros_generic(n, m);
        N::mul_tr_nm(&self.p, &self.ct, &mut pct);
        let mut cpct = OMatrix::<T, M, M>::zeros_generic(m, m);
        N::mul_tr_mm(&self.ct, &pct, &mut cpct);
        let s = &self.model.r + (&cpct + cpct.transpose()) * T::of_f64(0.5);
        let Some(chol) = s.clone().cholesky() else {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::InnovationCovariance);
        };
        // K = P Cᵀ S⁻¹, computed as (S⁻¹ C P)ᵀ since S and P are symmetric.
        let gain = chol.solve(&pct.transpose()).transpose();
        let nis = chol.l().solve_lower_triangular(&residual).map(|w| w.norm_squared()).unwrap_or_else(T::zero);
        self.x += &gain * &residual;
        // Joseph form, expanded: (I − KC) P (I − KC)ᵀ + K R Kᵀ = P − K (PCᵀ)ᵀ − PCᵀ Kᵀ + (K S) Kᵀ.
        // The same first-order insensitivity to rounding in K (the K-terms cancel at the
        // optimum), at O(N² M) instead of O(N³); the upper triangle is computed and mirrored.
        let ks = &gain * &s;
        let rows = n.value();
        let (kss, gs, ps) = (ks.as_slice(), gain.as_slice(), pct.as_slice());
        let p = self.p.as_mut_slice();
        for col in 0..m.value() {
            let range = col * rows..(col + 1) * rows;
            let (Some(kc), Some(gc), Some(pc)) = (kss.get(range.clone()), gs.get(range.clone()), ps.get(range)) else {
                break;
            };
            for j in 0..rows {
                let (g_j, p_j) = (gc[j], pc[j]);
                let upper = &mut p[j * rows..j * rows + j + 1];
                for (((v, k), g), pv) in upper.iter_mut().zip(kc).zip(gc).zip(pc) {
                    *v += *k * g_j - *g * p_j - *pv * g_j;
                }
            }
        }
        self.mirror_upper();
        self.guard();
        Ok(GenericInnovation { residual, s, nis })
    }

    /// Measurement update one channel at a time, for a diagonal `R`: `M` scalar updates of
    /// `O(N²)` each instead of a Cholesky of `S` and an `O(N³)` Joseph product, with no
    /// matrix inverse at all. Each scalar step uses the Joseph form written as rank-one
    /// corrections, `P − k φᵀ − φ kᵀ + s k kᵀ` with `φ = P hᵀ`, `s = h φ + r`, `k = φ / s`,
    /// which keeps its first-order insensitivity to rounding in the gain.
    ///
    /// Gives the same result as [`GenericKalmanFilter::update`] up to rounding. A non-finite `y`
    /// (or one of the wrong length), a non-diagonal `R` or a non-positive `s` leaves the filter
    /// unchanged and is counted.
    ///
    /// ```
    /// use edgekf::filter::{KalmanFilter, LinearModel};
    /// use nalgebra::{Matrix2, Vector2};
    /// let m = LinearModel { a: Matrix2::identity(), c: Matrix2::identity(), q: Matrix2::zeros(), r: Matrix2::identity() };
    /// let mut a = KalmanFilter::new(m.clone(), Vector2::zeros(), Matrix2::new(2.0, 0.5, 0.5, 1.0));
    /// let mut b = a.clone();
    /// a.update(&Vector2::new(1.0, -1.0)).unwrap();
    /// b.update_sequential(&Vector2::new(1.0, -1.0)).unwrap();
    /// assert!((a.state() - b.state()).abs().max() < 1e-15);
    /// assert!((a.covariance() - b.covariance()).abs().max() < 1e-15);
    /// ```
    pub fn update_sequential(&mut self, y: &OVector<T, M>) -> Result<GenericSequentialInnovation<T, M>, FilterError> {
        let m = self.model.measurements();
        if y.nrows() != m {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::SizeMismatch);
        }
        if y.iter().any(|v| !v.is_finite()) {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::NonFiniteMeasurement);
        }
        let r = &self.model.r;
        // Off-diagonal entries through `get` (no index check, no panic path).
        if (0..m).any(|i| (0..m).any(|j| i != j && r.get((i, j)).is_some_and(|v| *v != T::zero()))) {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::CorrelatedNoise);
        }
        let residual = y - &self.model.c * &self.x;
        let (mut x, mut p) = (self.x.clone(), self.p.clone());
        let n = x.nrows();
        let mut nis = T::zero();
        let (mut scalar, mut variance) = (residual.clone(), residual.clone());
        for i in 0..m {
            let h = self.model.c.row(i);
            let phi = &p * h.transpose();
            let s = (h * &phi)[(0, 0)] + r[(i, i)];
            if !s.is_finite() || s <= T::zero() {
                self.health.refused_updates = self.health.refused_updates.saturating_add(1);
                return Err(FilterError::InnovationCovariance);
            }
            let e = y[i] - (h * &x)[(0, 0)];
            let k = &phi / s;
            x += &k * e;
            for a in 0..n {
                for b in a..n {
                    let v = p[(a, b)] - k[a] * phi[b] - phi[a] * k[b] + s * k[a] * k[b];
                    p[(a, b)] = v;
                    p[(b, a)] = v;
                }
            }
            nis += e * e / s;
            if let (Some(ei), Some(si)) = (scalar.get_mut(i), variance.get_mut(i)) {
                (*ei, *si) = (e, s);
            }
        }
        self.x = x;
        self.p = p;
        self.guard();
        Ok(GenericSequentialInnovation { residual, nis, scalar, variance })
    }

    /// Resets a broken covariance (non-finite, or a non-positive diagonal) or state. The
    /// updates above produce an exactly symmetric `P` by construction.
    fn guard(&mut self) {
        // One sum instead of N² finiteness tests: NaN and ±∞ (and ∞ − ∞) all make it
        // non-finite. (It also trips if finite entries sum past the type's range, a covariance
        // that is broken in practice anyway.)
        let sum = self.p.iter().fold(T::zero(), |s, v| s + *v) + self.x.iter().fold(T::zero(), |s, v| s + *v);
        // A finite sum means no NaN anywhere, so a plain comparison suffices for the diagonal.
        let broken = !sum.is_finite() || (0..self.p.nrows()).any(|i| self.p[(i, i)] <= T::zero());
        if broken {
            self.health.covariance_resets = self.health.covariance_resets.saturating_add(1);
            self.p.copy_from(&self.p_reset);
            if self.x.iter().any(|v| !v.is_finite()) {
                self.x.copy_from(&self.x_reset);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix1, Matrix2, RowVector2, Vector1, Vector2};

    fn cv_model() -> LinearModel<f64, 2, 1> {
        let dt = 0.1;
        LinearModel {
            a: Matrix2::new(1.0, dt, 0.0, 1.0),
            c: RowVector2::new(1.0, 0.0),
            q: Matrix2::new(dt.powi(3) / 3.0, dt * dt / 2.0, dt * dt / 2.0, dt) * 0.01,
            r: Matrix1::new(0.25),
        }
    }

    #[test]
    fn tracks_a_ramp() {
        let mut kf = KalmanFilter::new(cv_model(), Vector2::zeros(), Matrix2::identity() * 100.0);
        for k in 0..200 {
            kf.predict();
            kf.update(&Vector1::new(0.1 * k as f64 * 2.0)).unwrap();
        }
        // slope 2 per second
        assert!((kf.state()[1] - 2.0).abs() < 1e-3, "{}", kf.state());
        assert_eq!(kf.health(), FilterHealth::default());
    }

    #[test]
    fn joseph_update_matches_information_form() {
        // One update from a known prior: P⁺⁻¹ = P⁻⁻¹ + Cᵀ R⁻¹ C.
        let model = cv_model();
        let p0 = Matrix2::new(2.0, 0.3, 0.3, 1.0);
        let mut kf = KalmanFilter::new(model.clone(), Vector2::new(1.0, -1.0), p0);
        let inn = kf.update(&Vector1::new(2.0)).unwrap();
        let info = p0.try_inverse().unwrap() + model.c.transpose() * model.r.try_inverse().unwrap() * model.c;
        let p_expected = info.try_inverse().unwrap();
        assert!((kf.covariance() - p_expected).abs().max() < 1e-12);
        assert!((inn.residual[0] - 1.0).abs() < 1e-15);
        assert!((inn.nis - 1.0 / 2.25).abs() < 1e-12);
    }

    #[test]
    fn sequential_update_equals_the_joint_update() {
        use nalgebra::{Matrix3, Matrix3x2, Vector3};
        let model = LinearModel {
            a: Matrix3::identity(),
            c: Matrix3x2::new(1.0f64, 0.2, -0.5, 1.0, 0.3, 0.7).transpose(),
            q: Matrix3::zeros(),
            r: Matrix2::new(0.3, 0.0, 0.0, 0.8),
        };
        let p0 = Matrix3::new(2.0, 0.3, -0.1, 0.3, 1.5, 0.2, -0.1, 0.2, 0.9);
        let mut joint = KalmanFilter::new(model.clone(), Vector3::new(0.1, 0.2, 0.3), p0);
        let mut seq = joint.clone();
        let y = Vector2::new(1.0, -2.0);
        let a = joint.update(&y).unwrap();
        let b = seq.update_sequential(&y).unwrap();
        assert!((joint.state() - seq.state()).abs().max() < 1e-14);
        assert!((joint.covariance() - seq.covariance()).abs().max() < 1e-14);
        assert!((a.nis - b.nis).abs() < 1e-13 && a.residual == b.residual);
        let mut correlated = model.clone();
        correlated.r[(0, 1)] = 0.1;
        correlated.r[(1, 0)] = 0.1;
        let mut kf = KalmanFilter::new(correlated, Vector3::zeros(), p0);
        assert_eq!(kf.update_sequential(&y).unwrap_err(), FilterError::CorrelatedNoise);
    }

    #[test]
    fn nan_measurement_is_refused_and_counted() {
        let mut kf = KalmanFilter::new(cv_model(), Vector2::zeros(), Matrix2::identity());
        let before = *kf.state();
        assert_eq!(kf.update(&Vector1::new(f64::NAN)), Err(FilterError::NonFiniteMeasurement));
        assert_eq!(*kf.state(), before);
        assert_eq!(kf.health().refused_updates, 1);
    }

    #[test]
    fn broken_covariance_is_reset_and_counted() {
        let mut model = cv_model();
        model.q[(0, 0)] = f64::NAN;
        let p0 = Matrix2::identity() * 3.0;
        let mut kf = KalmanFilter::new(model, Vector2::zeros(), p0);
        kf.predict();
        assert_eq!(kf.health().covariance_resets, 1);
        assert_eq!(*kf.covariance(), p0);
    }

    /// One filter, two builds: with dynamic sizes it computes what it computes with fixed ones.
    /// (At these sizes nalgebra's products take the same path for both, so the bits agree.)
    #[cfg(feature = "alloc")]
    #[test]
    fn dynamic_sizes_run_the_fixed_size_filter() {
        use crate::filter::{solve_riccati, DKalmanFilter, DLinearModel, DSteadyStateFilter, SteadyStateFilter};
        use nalgebra::{DMatrix, DVector, Matrix3, Matrix3x2};
        let dt = 0.01;
        let fixed = LinearModel {
            a: Matrix3::new(1.0, dt, 0.0, -0.4 * dt, 0.99, dt, 0.0, 0.0, 1.0),
            c: Matrix3x2::new(1.0, 0.0, 0.0, 1.0, 0.0, 0.5).transpose(),
            q: Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-6, 1e-4, 1e-3)),
            r: Matrix2::new(0.04, 0.0, 0.0, 0.09),
        };
        let d = |m: &[f64], r: usize, c: usize| DMatrix::from_column_slice(r, c, m);
        let dynamic = DLinearModel {
            a: d(fixed.a.as_slice(), 3, 3),
            c: d(fixed.c.as_slice(), 2, 3),
            q: d(fixed.q.as_slice(), 3, 3),
            r: d(fixed.r.as_slice(), 2, 2),
        };
        let p0 = Matrix3::identity() * 2.0;
        let mut kf = KalmanFilter::new(fixed.clone(), nalgebra::Vector3::zeros(), p0);
        let mut dkf = DKalmanFilter::try_new(dynamic.clone(), DVector::zeros(3), d(p0.as_slice(), 3, 3)).unwrap();
        for k in 0..300 {
            let y = Vector2::new((0.1 * k as f64).sin(), (0.07 * k as f64).cos());
            kf.predict();
            dkf.predict();
            let (a, b) = if k % 3 == 0 {
                let (a, b) = (
                    kf.update_sequential(&y).unwrap(),
                    dkf.update_sequential(&DVector::from_column_slice(y.as_slice())).unwrap(),
                );
                (a.residual.as_slice().to_vec(), b.residual.as_slice().to_vec())
            } else {
                let (a, b) = (kf.update(&y).unwrap(), dkf.update(&DVector::from_column_slice(y.as_slice())).unwrap());
                assert_eq!(a.nis.to_bits(), b.nis.to_bits());
                (a.residual.as_slice().to_vec(), b.residual.as_slice().to_vec())
            };
            assert_eq!(a, b, "step {k}");
        }
        assert_eq!(kf.covariance().as_slice(), dkf.covariance().as_slice());
        assert_eq!(kf.state().as_slice(), dkf.state().as_slice());

        let (ss, dss) =
            (solve_riccati(&fixed, 1e-12, 100_000).unwrap(), solve_riccati(&dynamic, 1e-12, 100_000).unwrap());
        assert_eq!((ss.gain.as_slice(), ss.iterations), (dss.gain.as_slice(), dss.iterations));
        let mut f = SteadyStateFilter::<f32, 3, 2>::from_steady_state(&fixed, &ss, nalgebra::Vector3::zeros()).unwrap();
        let mut df = DSteadyStateFilter::<f32>::from_steady_state(&dynamic, &dss, DVector::zeros(3)).unwrap();
        let y = Vector2::new(0.5f32, -0.25);
        f.predict();
        df.predict();
        let (a, b) = (f.update(&y).unwrap(), df.update(&DVector::from_column_slice(y.as_slice())).unwrap());
        assert_eq!((a.0.as_slice(), a.1), (b.0.as_slice(), b.1));
    }

    /// A dynamic model, state or measurement whose shape does not fit is an error, never a panic.
    #[cfg(feature = "alloc")]
    #[test]
    fn dynamic_shapes_that_disagree_are_refused() {
        use crate::filter::{solve_riccati, DKalmanFilter, DLinearModel, DSteadyStateFilter, RiccatiError};
        use nalgebra::{DMatrix, DVector};
        let good = DLinearModel {
            a: DMatrix::<f64>::identity(2, 2) * 0.5,
            c: DMatrix::from_element(1, 2, 1.0),
            q: DMatrix::identity(2, 2),
            r: DMatrix::identity(1, 1),
        };
        let wide_c = DLinearModel { c: DMatrix::from_element(1, 3, 1.0), ..good.clone() };
        let p0 = DMatrix::identity(2, 2);
        assert_eq!(
            DKalmanFilter::try_new(wide_c.clone(), DVector::zeros(2), p0.clone()).unwrap_err(),
            FilterError::SizeMismatch
        );
        assert_eq!(
            DKalmanFilter::try_new(good.clone(), DVector::zeros(3), p0.clone()).unwrap_err(),
            FilterError::SizeMismatch
        );
        assert_eq!(
            DKalmanFilter::try_new(good.clone(), DVector::zeros(2), DMatrix::identity(2, 3)).unwrap_err(),
            FilterError::SizeMismatch
        );
        let mut kf = DKalmanFilter::try_new(good.clone(), DVector::zeros(2), p0).unwrap();
        assert_eq!(kf.update(&DVector::zeros(2)).unwrap_err(), FilterError::SizeMismatch);
        assert_eq!(kf.update_sequential(&DVector::zeros(0)).unwrap_err(), FilterError::SizeMismatch);
        assert!(kf.innovation(&DVector::zeros(3)).is_none());
        assert_eq!(kf.health().refused_updates, 2);
        assert_eq!(solve_riccati(&wide_c, 1e-12, 10).unwrap_err(), RiccatiError::SizeMismatch);
        let ss = solve_riccati(&good, 1e-12, 10_000).unwrap();
        let bad_x0 = DSteadyStateFilter::<f64>::from_steady_state(&good, &ss, DVector::zeros(1));
        assert_eq!(bad_x0.unwrap_err(), RiccatiError::SizeMismatch);
        let mut f = DSteadyStateFilter::<f64>::from_steady_state(&good, &ss, DVector::zeros(2)).unwrap();
        assert!(f.update(&DVector::zeros(2)).is_none() && f.innovation(&DVector::zeros(2)).is_none());
    }
}
