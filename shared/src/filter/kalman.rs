use crate::linalg::{column, mul_tr, mul_tr_add};
use crate::Real;
use nalgebra::{SMatrix, SVector};

/// A discrete linear time-invariant model `x' = A x + w`, `y = C x + v` with
/// `w ~ N(0, Q)`, `v ~ N(0, R)`.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearModel<T: Real, const N: usize, const M: usize> {
    /// State transition `A` (N × N).
    pub a: SMatrix<T, N, N>,
    /// Measurement matrix `C` (M × N).
    pub c: SMatrix<T, M, N>,
    /// Process-noise covariance `Q` (N × N).
    pub q: SMatrix<T, N, N>,
    /// Measurement-noise covariance `R` (M × M).
    pub r: SMatrix<T, M, M>,
}

impl<T: Real, const N: usize, const M: usize> LinearModel<T, N, M> {
    /// Converts an `f64` model (as built on the host or at start-up) to another precision.
    pub fn cast<U: Real>(&self) -> LinearModel<U, N, M> {
        let f = |v: T| U::of_f64(v.as_f64());
        LinearModel { a: self.a.map(f), c: self.c.map(f), q: self.q.map(f), r: self.r.map(f) }
    }
}

/// The innovation of one measurement update: what the model could not predict.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Innovation<T: Real, const M: usize> {
    /// `y − C x⁻`.
    pub residual: SVector<T, M>,
    /// Its predicted covariance `S = C P⁻ Cᵀ + R`.
    pub s: SMatrix<T, M, M>,
    /// Normalised innovation squared `rᵀ S⁻¹ r`; χ²(M) distributed when the filter is consistent.
    pub nis: T,
}

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
}

/// What a sequential (scalar-by-scalar) update used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SequentialInnovation<T: Real, const M: usize> {
    /// `y − C x⁻`, against the prediction before the first scalar update.
    pub residual: SVector<T, M>,
    /// Sum of the scalar NIS values; equals `rᵀ S⁻¹ r` of the joint update.
    pub nis: T,
}

/// Linear Kalman filter with `N` states and `M` measurements.
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
pub struct KalmanFilter<T: Real, const N: usize, const M: usize> {
    model: LinearModel<T, N, M>,
    /// `Aᵀ` and `Cᵀ`, kept so that every product below is a dot product of contiguous columns
    /// (nalgebra stores column-major): on the Cortex-M4 that halves the instruction count.
    at: SMatrix<T, N, N>,
    ct: SMatrix<T, N, M>,
    x: SVector<T, N>,
    p: SMatrix<T, N, N>,
    x_reset: SVector<T, N>,
    p_reset: SMatrix<T, N, N>,
    health: FilterHealth,
}

impl<T: Real, const N: usize, const M: usize> KalmanFilter<T, N, M> {
    /// A filter starting at `x0` with covariance `p0`; `x0, p0` are also the reset values the
    /// covariance guard falls back to.
    pub fn new(model: LinearModel<T, N, M>, x0: SVector<T, N>, p0: SMatrix<T, N, N>) -> Self {
        let (at, ct) = (model.a.transpose(), model.c.transpose());
        Self { model, at, ct, x: x0, p: p0, x_reset: x0, p_reset: p0, health: FilterHealth::default() }
    }

    /// The model in use.
    pub fn model(&self) -> &LinearModel<T, N, M> {
        &self.model
    }

    /// Current state estimate.
    pub fn state(&self) -> &SVector<T, N> {
        &self.x
    }

    /// Current state covariance.
    pub fn covariance(&self) -> &SMatrix<T, N, N> {
        &self.p
    }

    /// Repair counters since construction.
    pub fn health(&self) -> FilterHealth {
        self.health
    }

    /// Time update `x = A x`, `P = A P Aᵀ + Q`.
    ///
    /// `U = P Aᵀ` then `P⁻ = A U + Q` on the upper triangle only, mirrored: `1.5 N³`
    /// multiply-adds instead of `2 N³`, and P comes out exactly symmetric.
    pub fn predict(&mut self) {
        self.x = self.model.a * self.x;
        // U = P Aᵀ = Pᵀ Aᵀ (P symmetric), then P⁻ = A U + Q = (Aᵀ)ᵀ U + Q on the upper triangle.
        let mut u = SMatrix::<T, N, N>::zeros();
        mul_tr(&self.p, &self.at, &mut u, false);
        self.p = self.model.q;
        mul_tr_add(&self.at, &u, &mut self.p, true);
        self.mirror_upper();
        self.guard();
    }

    /// Copies the upper triangle of P onto the lower one.
    fn mirror_upper(&mut self) {
        // Copies through the column slices: no index check is left (no panic path).
        let cols = &mut self.p.data.0;
        for j in 0..N {
            for i in 0..j {
                if let Some(v) = cols.get(j).and_then(|c| c.get(i)).copied() {
                    if let Some(d) = cols.get_mut(i).and_then(|c| c.get_mut(j)) {
                        *d = v;
                    }
                }
            }
        }
    }

    /// Innovation of `y` against the current prediction, without changing the filter.
    ///
    /// Returns `None` if `S` is not positive definite.
    pub fn innovation(&self, y: &SVector<T, M>) -> Option<Innovation<T, M>> {
        let residual = y - self.model.c * self.x;
        let s = self.model.c * self.p * self.model.c.transpose() + self.model.r;
        let chol = s.cholesky()?;
        let white = chol.l().solve_lower_triangular(&residual)?;
        Some(Innovation { residual, s, nis: white.norm_squared() })
    }

    /// Measurement update with `y`. Returns the innovation it used.
    ///
    /// A non-finite `y` or a non-positive-definite `S` leaves the filter unchanged, is counted
    /// in [`FilterHealth::refused_updates`] and is returned as an error.
    pub fn update(&mut self, y: &SVector<T, M>) -> Result<Innovation<T, M>, FilterError> {
        if y.iter().any(|v| !v.is_finite()) {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::NonFiniteMeasurement);
        }
        let residual = y - self.model.c * self.x;
        // P Cᵀ (N × M) and S = C P Cᵀ + R, as dot products of contiguous columns.
        let mut pct = SMatrix::<T, N, M>::zeros();
        mul_tr(&self.p, &self.ct, &mut pct, false);
        let mut cpct = SMatrix::<T, M, M>::zeros();
        mul_tr(&self.ct, &pct, &mut cpct, false);
        let s = self.model.r + (cpct + cpct.transpose()) * T::of_f64(0.5);
        let Some(chol) = s.cholesky() else {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::InnovationCovariance);
        };
        // K = P Cᵀ S⁻¹, computed as (S⁻¹ C P)ᵀ since S and P are symmetric.
        let gain = chol.solve(&pct.transpose()).transpose();
        let nis = chol.l().solve_lower_triangular(&residual).map(|w| w.norm_squared()).unwrap_or_else(T::zero);
        self.x += gain * residual;
        // Joseph form, expanded: (I − KC) P (I − KC)ᵀ + K R Kᵀ = P − K (PCᵀ)ᵀ − PCᵀ Kᵀ + (K S) Kᵀ.
        // The same first-order insensitivity to rounding in K (the K-terms cancel at the
        // optimum), at O(N² M) instead of O(N³); the upper triangle is computed and mirrored.
        let ks = gain * s;
        for m in 0..M {
            let (kc, gc, pc) = (column(&ks, m), column(&gain, m), column(&pct, m));
            for j in 0..N {
                let (g_j, p_j) = (gc[j], pc[j]);
                let upper = &mut self.p.as_mut_slice()[j * N..j * N + j + 1];
                for (((v, k), g), p) in upper.iter_mut().zip(kc).zip(gc).zip(pc) {
                    *v += *k * g_j - *g * p_j - *p * g_j;
                }
            }
        }
        self.mirror_upper();
        self.guard();
        Ok(Innovation { residual, s, nis })
    }

    /// Measurement update one channel at a time, for a diagonal `R`: `M` scalar updates of
    /// `O(N²)` each instead of a Cholesky of `S` and an `O(N³)` Joseph product, with no
    /// matrix inverse at all. Each scalar step uses the Joseph form written as rank-one
    /// corrections, `P − k φᵀ − φ kᵀ + s k kᵀ` with `φ = P hᵀ`, `s = h φ + r`, `k = φ / s`,
    /// which keeps its first-order insensitivity to rounding in the gain.
    ///
    /// Gives the same result as [`KalmanFilter::update`] up to rounding. A non-finite `y`, a
    /// non-diagonal `R` or a non-positive `s` leaves the filter unchanged and is counted.
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
    pub fn update_sequential(&mut self, y: &SVector<T, M>) -> Result<SequentialInnovation<T, M>, FilterError> {
        if y.iter().any(|v| !v.is_finite()) {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::NonFiniteMeasurement);
        }
        let r = &self.model.r;
        // Off-diagonal entries, column by column from the storage (no indexing, no panic path).
        if r.data.0.iter().enumerate().any(|(j, col)| col.iter().enumerate().any(|(i, v)| i != j && *v != T::zero())) {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::CorrelatedNoise);
        }
        let residual = y - self.model.c * self.x;
        let (mut x, mut p) = (self.x, self.p);
        let mut nis = T::zero();
        for i in 0..M {
            let h = self.model.c.row(i);
            let phi = p * h.transpose();
            let s = (h * phi)[(0, 0)] + r[(i, i)];
            if !s.is_finite() || s <= T::zero() {
                self.health.refused_updates = self.health.refused_updates.saturating_add(1);
                return Err(FilterError::InnovationCovariance);
            }
            let e = y[i] - (h * x)[(0, 0)];
            let k = phi / s;
            x += k * e;
            for a in 0..N {
                for b in a..N {
                    let v = p[(a, b)] - k[a] * phi[b] - phi[a] * k[b] + s * k[a] * k[b];
                    p[(a, b)] = v;
                    p[(b, a)] = v;
                }
            }
            nis += e * e / s;
        }
        self.x = x;
        self.p = p;
        self.guard();
        Ok(SequentialInnovation { residual, nis })
    }

    /// Resets a broken covariance (non-finite, or a non-positive diagonal) or state. The
    /// updates above produce an exactly symmetric `P` by construction.
    fn guard(&mut self) {
        // One sum instead of N² finiteness tests: NaN and ±∞ (and ∞ − ∞) all make it
        // non-finite. (It also trips if finite entries sum past the type's range, a covariance
        // that is broken in practice anyway.)
        let sum = self.p.iter().fold(T::zero(), |s, v| s + *v) + self.x.iter().fold(T::zero(), |s, v| s + *v);
        // A finite sum means no NaN anywhere, so a plain comparison suffices for the diagonal.
        let broken = !sum.is_finite() || (0..N).any(|i| self.p[(i, i)] <= T::zero());
        if broken {
            self.health.covariance_resets = self.health.covariance_resets.saturating_add(1);
            self.p = self.p_reset;
            if self.x.iter().any(|v| !v.is_finite()) {
                self.x = self.x_reset;
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
}
