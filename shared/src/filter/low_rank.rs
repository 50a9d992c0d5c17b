//! The exact Kalman filter of a time-invariant model whose prior is its steady state plus a
//! term of low rank, at the steady-state filter's cost plus `O(N² R)` a sample instead of the
//! `O(N³)` covariance recursion.
//!
//! Why it is exact: write the predicted covariance as `P = P̄ + D`, `P̄` the Riccati solution
//! and `K̄` its gain. Then `D` evolves as `D ← Ā (D − D Cᵀ S⁻¹ C D) Āᵀ` with
//! `Ā = A (I − K̄ C)` and `S = S̄ + C D Cᵀ`, so `D = U M Uᵀ` keeps its rank: `U ← Ā U` and
//! `M ← M − M Gᵀ S⁻¹ G M` with `G = C U`. The gain applied to the innovation `e` is
//! `(P̄ Cᵀ + U M Gᵀ) S⁻¹ e`. `M` may be indefinite: a prior tighter than the steady state in
//! some directions (a rotor known to start at rest) and wider in others (its unknown forces).
//! A node starting from such a prior gets the time-varying filter's fast start at the cost of
//! a steady one plus `O(N² R)`.

use super::kalman::{FilterError, FilterHealth, LinearModel};
use super::steady::SteadyState;
use crate::linalg::{cholesky, mul_tr, mul_tr_add, solve, solve_lower, symmetric_eigen};
use crate::Real;
use nalgebra::{SMatrix, SVector};

/// What a [`LowRankKalmanFilter`] is built from: the model, its steady state and the prior's
/// deviation from that steady state as `U₀ U₀ᵀ`. Computed once in `f64`
/// ([`LowRankDesign::from_prior`]), on the host for a chip that compiles it in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LowRankDesign<T: Real, const N: usize, const M: usize, const R: usize> {
    /// State transition `A`.
    pub a: SMatrix<T, N, N>,
    /// Measurement matrix `C`.
    pub c: SMatrix<T, M, N>,
    /// The steady state's closed loop `Ā = A (I − K̄ C)`, which carries the deviation.
    pub closed: SMatrix<T, N, N>,
    /// `P̄ Cᵀ` of the steady (predicted) covariance `P̄`.
    pub pct: SMatrix<T, N, M>,
    /// The steady innovation covariance `S̄ = C P̄ Cᵀ + R`.
    pub s: SMatrix<T, M, M>,
    /// Its inverse, taken in `f64` (for the steady-state filter once the deviation is dropped).
    pub s_inv: SMatrix<T, M, M>,
    /// The prior's deviation from `P̄`: `P₀ ≈ P̄ + U₀ diag(signs) U₀ᵀ`.
    pub u0: SMatrix<T, N, R>,
    /// `+1` or `−1` for each column of `U₀` (`0` for an unused one).
    pub signs: SVector<T, R>,
}

/// How well `P̄ + U₀ diag(signs) U₀ᵀ` stands for the prior it was fitted to: the deviation's
/// eigenvalues relative to `P̄` kept (largest magnitude first) and the largest magnitude left
/// out (see [`LowRankDesign::from_prior`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LowRankFit<const R: usize> {
    /// The eigenvalues of `P₀ − P̄` relative to `P̄` that `U₀` keeps.
    pub kept: SVector<f64, R>,
    /// The largest magnitude among those it leaves out.
    pub dropped: f64,
}

impl<const N: usize, const M: usize, const R: usize> LowRankDesign<f64, N, M, R> {
    /// The design for `model` started with predicted covariance `p0`. The deviation
    /// `p0 − P̄` is measured against `P̄` itself (the generalised eigenproblem
    /// `(p0 − P̄) v = λ P̄ v`, taken after scaling every state to unit steady variance so that
    /// states of very different sizes keep their digits): `U₀` holds the `R` directions of
    /// largest `|λ|`, and `signs` their signs. A left-out `λ` of 0.1 is a prior 10 % off `P̄` in
    /// its direction. `None` if `S̄` or `P̄` is not positive definite.
    ///
    /// ```
    /// use edgekf::filter::{solve_riccati, LinearModel, LowRankDesign};
    /// use nalgebra::{Matrix2, Matrix1x2};
    /// // A position–velocity model seen in position; the prior is wide on the velocity only.
    /// let model = LinearModel {
    ///     a: Matrix2::new(1.0, 0.01, 0.0, 1.0),
    ///     c: Matrix1x2::new(1.0, 0.0),
    ///     q: Matrix2::new(1e-8, 0.0, 0.0, 1e-6),
    ///     r: nalgebra::Matrix1::new(1e-4),
    /// };
    /// let ss = solve_riccati(&model, 1e-13, 100_000).unwrap();
    /// let p0 = ss.predicted + Matrix2::new(0.0, 0.0, 0.0, 4.0);
    /// let (design, fit) = LowRankDesign::<f64, 2, 1, 1>::from_prior(&model, &ss, &p0).unwrap();
    /// assert!(fit.kept[0] > 0.0 && fit.dropped < 1e-9 && design.signs[0] == 1.0);
    /// let d = design.u0 * design.u0.transpose();
    /// assert!((d - Matrix2::new(0.0, 0.0, 0.0, 4.0)).abs().max() < 1e-12);
    /// ```
    pub fn from_prior(
        model: &LinearModel<f64, N, M>,
        ss: &SteadyState<N, M>,
        p0: &SMatrix<f64, N, N>,
    ) -> Option<(Self, LowRankFit<R>)> {
        let s_inv = solve(&ss.innovation, &SMatrix::<f64, M, M>::identity())?;
        let closed = model.a * (SMatrix::<f64, N, N>::identity() - ss.gain * model.c);
        // P̄ = S Ps S with S = diag(√P̄ᵢᵢ), Ps = L Lᵀ; the deviation whitened: L⁻¹ S⁻¹ D S⁻¹ L⁻ᵀ.
        let steady = &ss.predicted;
        let scale = SVector::<f64, N>::from_fn(|i, _| steady.get((i, i)).map_or(0.0, |v| libm::sqrt(*v)));
        if !scale.iter().all(|v| *v > 0.0 && v.is_finite()) {
            return None;
        }
        let scaled = |m: &SMatrix<f64, N, N>| SMatrix::<f64, N, N>::from_fn(|i, j| m[(i, j)] / (scale[i] * scale[j]));
        let l = cholesky(&scaled(steady))?;
        let x = solve_lower(&l, &scaled(&(p0 - steady)));
        let white = solve_lower(&l, &x.transpose()).transpose();
        let (values, vectors) = symmetric_eigen(&((white + white.transpose()) * 0.5));
        // Back from the whitened coordinates: v ↦ S L v.
        let back = SMatrix::<f64, N, N>::from_diagonal(&scale) * l * vectors;
        // Indices by decreasing magnitude.
        let mut order: [usize; N] = core::array::from_fn(|i| i);
        let magnitude = |i: &usize| values.get(*i).map_or(0.0, |v| v.abs());
        order.sort_unstable_by(|a, b| magnitude(b).total_cmp(&magnitude(a)));
        let (mut u0, mut signs) = (SMatrix::<f64, N, R>::zeros(), SVector::<f64, R>::zeros());
        let mut kept = SVector::<f64, R>::zeros();
        let mut dropped = 0.0f64;
        for (k, idx) in order.iter().enumerate() {
            let value = values.get(*idx).copied().unwrap_or(0.0);
            if k >= R {
                dropped = dropped.max(value.abs());
                continue;
            }
            if let (Some(v), Some(sign)) = (kept.get_mut(k), signs.get_mut(k)) {
                *v = value;
                *sign = if value > 0.0 {
                    1.0
                } else if value < 0.0 {
                    -1.0
                } else {
                    0.0
                };
            }
            let root = libm::sqrt(value.abs());
            for i in 0..N {
                if let (Some(u), Some(e)) = (u0.get_mut((i, k)), back.get((i, *idx))) {
                    *u = e * root;
                }
            }
        }
        let pct = ss.predicted * model.c.transpose();
        let design = Self { a: model.a, c: model.c, closed, pct, s: ss.innovation, s_inv, u0, signs };
        Some((design, LowRankFit { kept, dropped }))
    }
}

/// A linear Kalman filter whose covariance is its steady state plus a term of rank `R` (see
/// the module's doc): exact for a prior `P̄ + U₀ diag(signs) U₀ᵀ`, and once [`retire`](Self::retire)d the
/// steady-state filter itself.
///
/// A missing sample ([`predict`](Self::predict) without an update) carries the deviation by `A`
/// alone: the steady part's growth over the gap is left out, as the steady-state filter leaves
/// it out.
///
/// ```
/// use edgekf::filter::{solve_riccati, KalmanFilter, LinearModel, LowRankDesign, LowRankKalmanFilter};
/// use nalgebra::{Matrix1, Matrix1x2, Matrix2, Vector1, Vector2};
/// let model = LinearModel {
///     a: Matrix2::new(1.0, 0.01, 0.0, 1.0),
///     c: Matrix1x2::new(1.0, 0.0),
///     q: Matrix2::new(1e-8, 0.0, 0.0, 1e-6),
///     r: Matrix1::new(1e-4),
/// };
/// let ss = solve_riccati(&model, 1e-13, 100_000).unwrap();
/// let p0 = ss.predicted + Matrix2::new(0.0, 0.0, 0.0, 4.0);
/// let (design, _) = LowRankDesign::<f64, 2, 1, 1>::from_prior(&model, &ss, &p0).unwrap();
/// let mut fast = LowRankKalmanFilter::new(&design, Vector2::zeros());
/// let mut full = KalmanFilter::new(model, Vector2::zeros(), p0);
/// for k in 0..50 {
///     let y = Vector1::new(0.02 * k as f64); // moving at 2 m/s
///     fast.update(&y).unwrap();
///     full.update(&y).unwrap();
///     fast.predict();
///     full.predict();
/// }
/// assert!((fast.state() - full.state()).abs().max() < 1e-9);
/// ```
#[derive(Debug, Clone)]
pub struct LowRankKalmanFilter<T: Real, const N: usize, const M: usize, const R: usize> {
    /// `Aᵀ`, `Āᵀ`, `Cᵀ`: every product below is a dot product of contiguous columns.
    at: SMatrix<T, N, N>,
    closed_t: SMatrix<T, N, N>,
    ct: SMatrix<T, N, M>,
    pct_t: SMatrix<T, M, N>,
    s: SMatrix<T, M, M>,
    s_inv: SMatrix<T, M, M>,
    x: SVector<T, N>,
    x0: SVector<T, N>,
    u: SMatrix<T, N, R>,
    /// `M` of the deviation `U M Uᵀ`.
    m: SMatrix<T, R, R>,
    /// Whether the deviation is still carried (false once retired or after a repair).
    live: bool,
    /// Whether the last step was an update (the deviation then moves by `Ā`, else by `A`).
    updated: bool,
    health: FilterHealth,
}

impl<T: Real, const N: usize, const M: usize, const R: usize> LowRankKalmanFilter<T, N, M, R> {
    /// The filter of `design`, starting at `x0` with the prior `P̄ + U₀ diag(signs) U₀ᵀ`.
    pub fn new(design: &LowRankDesign<T, N, M, R>, x0: SVector<T, N>) -> Self {
        Self {
            at: design.a.transpose(),
            closed_t: design.closed.transpose(),
            ct: design.c.transpose(),
            pct_t: design.pct.transpose(),
            s: design.s,
            s_inv: design.s_inv,
            x: x0,
            x0,
            u: design.u0,
            m: SMatrix::from_diagonal(&design.signs),
            live: true,
            updated: false,
            health: FilterHealth::default(),
        }
    }

    /// Current state estimate.
    pub fn state(&self) -> &SVector<T, N> {
        &self.x
    }

    /// Repair counters since construction.
    pub fn health(&self) -> FilterHealth {
        self.health
    }

    /// Whether the low-rank deviation is still carried (false: the steady-state filter).
    pub fn is_live(&self) -> bool {
        self.live
    }

    /// Drops the deviation: from now on the steady-state filter, at its cost. For a deviation
    /// that has decayed below what it changes.
    pub fn retire(&mut self) {
        self.live = false;
    }

    /// The predicted covariance `P̄ + U M Uᵀ`, given `P̄` (for checks; the filter never forms it).
    pub fn covariance(&self, steady: &SMatrix<T, N, N>) -> SMatrix<T, N, N> {
        if self.live {
            steady + self.u * self.m * self.u.transpose()
        } else {
            *steady
        }
    }

    /// Time update `x = A x`, and the deviation's `U ← Ā U` (after an update) or `U ← A U`.
    pub fn predict(&mut self) {
        let mut x = SVector::<T, N>::zeros();
        mul_tr(&self.at, &self.x, &mut x, false);
        self.x = x;
        if self.live {
            let mut u = SMatrix::<T, N, R>::zeros();
            mul_tr(if self.updated { &self.closed_t } else { &self.at }, &self.u, &mut u, false);
            self.u = u;
        }
        self.updated = false;
        if self.x.iter().any(|v| !v.is_finite()) {
            self.reset();
        }
    }

    /// Measurement update with `y`; returns the residual `y − C x` and its NIS. A non-finite
    /// `y`, or an `S` that is not positive definite, leaves the filter unchanged, is counted in
    /// [`FilterHealth::refused_updates`] and is returned as an error.
    pub fn update(&mut self, y: &SVector<T, M>) -> Result<(SVector<T, M>, T), FilterError> {
        if y.iter().any(|v| !v.is_finite()) {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::NonFiniteMeasurement);
        }
        // Gᵀ = Uᵀ Cᵀ. A non-finite `U` shows in `G` (NaN · 0 is NaN), so `U` itself is never
        // scanned: the deviation is dropped, and the state reset, before the update.
        let mut gt = SMatrix::<T, R, M>::zeros();
        if self.live {
            mul_tr(&self.u, &self.ct, &mut gt, false);
            // A NaN or an infinity anywhere makes the sum non-finite.
            if !gt.iter().fold(T::zero(), |sum, v| sum + *v).is_finite() {
                self.reset();
            }
        }
        let mut cx = SVector::<T, M>::zeros();
        mul_tr(&self.ct, &self.x, &mut cx, false);
        let e = y - cx;
        if !self.live {
            let w = self.s_inv * e;
            mul_tr_add(&self.pct_t, &w, &mut self.x, false);
            self.updated = true;
            return Ok((e, e.dot(&w)));
        }
        // Every product below is `aᵀ b` on contiguous columns (`M` is symmetric): G M and
        // S = S̄ + (G M) Gᵀ.
        let (mut gm, mut gmg) = (SMatrix::<T, M, R>::zeros(), SMatrix::zeros());
        mul_tr(&gt, &self.m, &mut gm, false);
        mul_tr(&gm.transpose(), &gt, &mut gmg, false);
        let s = self.s + (gmg + gmg.transpose()) * T::of_f64(0.5);
        // S = L Lᵀ; with L⁻¹ (4 columns of a triangular solve) everything else is a product.
        let Some(l) = cholesky(&s) else {
            self.health.refused_updates = self.health.refused_updates.saturating_add(1);
            return Err(FilterError::InnovationCovariance);
        };
        let l_inv = solve_lower(&l, &SMatrix::<T, M, M>::identity());
        let l_inv_t = l_inv.transpose();
        // z = L⁻¹ e (NIS = |z|²), w = L⁻ᵀ z = S⁻¹ e, H = L⁻¹ (G M).
        let (mut z, mut w, mut h) = (SVector::<T, M>::zeros(), SVector::<T, M>::zeros(), SMatrix::<T, M, R>::zeros());
        mul_tr(&l_inv_t, &e, &mut z, false);
        mul_tr(&l_inv, &z, &mut w, false);
        mul_tr(&l_inv_t, &gm, &mut h, false);
        // x += (P̄ Cᵀ + U M Gᵀ) S⁻¹ e.
        let mut v = SVector::<T, R>::zeros();
        mul_tr_add(&self.pct_t, &w, &mut self.x, false);
        mul_tr(&gm, &w, &mut v, false);
        let (x, u) = (&mut self.x.data.0[0], &self.u.data.0);
        for (uk, vk) in u.iter().zip(&v.data.0[0]) {
            for (xi, ui) in x.iter_mut().zip(uk) {
                *xi += *ui * *vk;
            }
        }
        // M ← M − (G M)ᵀ S⁻¹ (G M) = M − Hᵀ H. Every element of Hᵀ H is summed in the same
        // order whichever triangle it is in, so M stays exactly symmetric.
        let mut correction = SMatrix::<T, R, R>::zeros();
        mul_tr(&h, &h, &mut correction, false);
        for (mij, cij) in self.m.as_mut_slice().iter_mut().zip(correction.as_slice()) {
            *mij -= *cij;
        }
        self.updated = true;
        Ok((e, z.dot(&z)))
    }

    /// A broken state or deviation: back to the initial state, as the steady-state filter.
    /// (`S` not positive definite refuses the update instead: the deviation is kept.)
    fn reset(&mut self) {
        self.x = self.x0;
        self.live = false;
        self.health.covariance_resets = self.health.covariance_resets.saturating_add(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filter::{solve_riccati, KalmanFilter};
    use nalgebra::Vector2;

    /// Two lightly damped oscillators, the position of each measured, with an unknown force
    /// on each (random walks): the rotor node's structure in small.
    fn model() -> LinearModel<f64, 6, 2> {
        let dt = 1e-3;
        let mut a = SMatrix::<f64, 6, 6>::identity();
        for (k, w) in [40.0f64, 130.0].iter().enumerate() {
            let (p, v) = (2 * k, 2 * k + 1);
            a[(p, v)] = dt;
            a[(v, p)] = -w * w * dt;
            a[(v, v)] = 1.0 - 0.02 * w * dt;
            a[(v, 4 + k)] = dt;
        }
        let mut c = SMatrix::<f64, 2, 6>::zeros();
        c[(0, 0)] = 1.0;
        c[(1, 2)] = 1.0;
        let mut q = SMatrix::<f64, 6, 6>::from_diagonal_element(1e-14);
        q[(4, 4)] = 1e-4;
        q[(5, 5)] = 1e-4;
        LinearModel { a, c, q, r: SMatrix::<f64, 2, 2>::identity() * 1e-10 }
    }

    fn measurements(k: usize) -> Vector2<f64> {
        let t = k as f64 * 1e-3;
        Vector2::new(1e-4 * (40.0 * t).sin() + 3e-6 * (k as f64 * 0.7).cos(), -5e-5 * (130.0 * t).cos())
    }

    /// Runs the filter of `design` beside the dense `full` over `steps` steps of
    /// [`measurements`]: every NIS within 1e-6 and every state within `tol` of the largest state
    /// component, with no repair. Returns both filters.
    fn follow<const R: usize>(
        design: &LowRankDesign<f64, 6, 2, R>,
        mut full: KalmanFilter<f64, 6, 2>,
        tol: f64,
        steps: usize,
    ) -> (LowRankKalmanFilter<f64, 6, 2, R>, KalmanFilter<f64, 6, 2>) {
        let mut fast = LowRankKalmanFilter::new(design, SVector::zeros());
        for k in 0..steps {
            let y = measurements(k);
            let (_, nis_fast) = fast.update(&y).unwrap();
            let nis_full = full.update(&y).unwrap().nis;
            assert!((nis_fast - nis_full).abs() <= 1e-6 * nis_full.max(1.0), "{k}: {nis_fast} {nis_full}");
            fast.predict();
            full.predict();
            let scale = full.state().abs().max().max(1e-12);
            let (a, b) = (fast.state(), full.state());
            assert!((a - b).abs().max() <= tol * scale, "{k}: {a} {b}");
        }
        assert_eq!(fast.health(), FilterHealth::default());
        (fast, full)
    }

    /// With a prior exactly `P̄ + U₀ U₀ᵀ`, the filter is the dense Kalman filter: states and
    /// covariance agree over 2 000 steps (a bug in the deviation's recursion would not).
    #[test]
    fn equals_the_dense_filter_for_a_prior_of_rank_r() {
        let m = model();
        let ss = solve_riccati(&m, 1e-13, 200_000).unwrap();
        let mut p0 = ss.predicted;
        p0[(4, 4)] += 100.0;
        p0[(5, 5)] += 25.0;
        p0[(4, 5)] += 10.0;
        p0[(5, 4)] += 10.0;
        let (design, fit) = LowRankDesign::<f64, 6, 2, 2>::from_prior(&m, &ss, &p0).unwrap();
        assert!(fit.dropped < 1e-9 * fit.kept.max(), "{fit:?}");
        // While the deviation is large, the covariances agree too.
        let (fast, full) = follow(&design, KalmanFilter::new(m.clone(), SVector::zeros(), p0), 1e-7, 6);
        let (p_fast, p_full) = (fast.covariance(&ss.predicted), full.covariance());
        assert!((p_fast - p_full).abs().max() <= 1e-8 * p_full.abs().max(), "{p_fast} {p_full}");
        follow(&design, KalmanFilter::new(m, SVector::zeros(), p0), 1e-7, 2000);
        // The start-up matters: the steady-state filter alone is far off early on.
        let mut steady = LowRankKalmanFilter::new(&design, SVector::zeros());
        steady.retire();
        let mut fast = LowRankKalmanFilter::new(&design, SVector::zeros());
        for k in 0..30 {
            steady.update(&measurements(k)).unwrap();
            fast.update(&measurements(k)).unwrap();
            steady.predict();
            fast.predict();
        }
        assert!((steady.state()[4] - fast.state()[4]).abs() > 1e-3 * fast.state()[4].abs());
    }

    /// A prior tighter than the steady state on the oscillators (known to start at rest) and
    /// wider on the forces: an indefinite deviation, of full rank here, and the filter is the
    /// dense one.
    #[test]
    fn an_indefinite_deviation_is_carried_exactly() {
        let m = model();
        let ss = solve_riccati(&m, 1e-13, 200_000).unwrap();
        let mut p0 = SMatrix::<f64, 6, 6>::from_diagonal_element(1e-14);
        p0[(4, 4)] = 100.0;
        p0[(5, 5)] = 100.0;
        let (design, fit) = LowRankDesign::<f64, 6, 2, 6>::from_prior(&m, &ss, &p0).unwrap();
        assert!(fit.kept.iter().any(|v| *v < 0.0) && fit.dropped == 0.0, "{fit:?}");
        follow(&design, KalmanFilter::new(m, SVector::zeros(), p0), 1e-6, 2000);
    }

    /// Retired, it is the steady-state filter: `x += K̄ e` with `K̄ = P̄ Cᵀ S̄⁻¹`.
    #[test]
    fn retired_it_is_the_steady_state_filter() {
        let m = model();
        let ss = solve_riccati(&m, 1e-13, 200_000).unwrap();
        let (design, _) = LowRankDesign::<f64, 6, 2, 2>::from_prior(&m, &ss, &(ss.predicted * 2.0)).unwrap();
        let mut f = LowRankKalmanFilter::new(&design, SVector::zeros());
        f.retire();
        let mut x = SVector::<f64, 6>::zeros();
        for k in 0..200 {
            let y = measurements(k);
            f.update(&y).unwrap();
            x += ss.gain * (y - m.c * x);
            f.predict();
            x = m.a * x;
        }
        assert!((f.state() - x).abs().max() <= 1e-9 * x.abs().max(), "{} {x}", f.state());
    }

    /// Bad measurements are refused and counted; a missing sample is a prediction; in `f32`
    /// the filter follows the `f64` one.
    #[test]
    fn refuses_bad_input_and_runs_in_f32() {
        let m = model();
        let ss = solve_riccati(&m, 1e-13, 200_000).unwrap();
        let mut p0 = ss.predicted;
        p0[(4, 4)] += 100.0;
        p0[(5, 5)] += 100.0;
        let (design, _) = LowRankDesign::<f64, 6, 2, 2>::from_prior(&m, &ss, &p0).unwrap();
        let cast = LowRankDesign::<f32, 6, 2, 2> {
            a: design.a.cast(),
            c: design.c.cast(),
            closed: design.closed.cast(),
            pct: design.pct.cast(),
            s: design.s.cast(),
            s_inv: design.s_inv.cast(),
            u0: design.u0.cast(),
            signs: design.signs.cast(),
        };
        let mut f64f = LowRankKalmanFilter::new(&design, SVector::zeros());
        let mut f32f = LowRankKalmanFilter::new(&cast, SVector::zeros());
        assert_eq!(f32f.update(&Vector2::new(f32::NAN, 0.0)), Err(FilterError::NonFiniteMeasurement));
        assert_eq!(f32f.health().refused_updates, 1);
        for k in 0..3000 {
            let y = measurements(k);
            if k % 97 != 13 {
                f64f.update(&y).unwrap();
                f32f.update(&y.cast()).unwrap();
            }
            f64f.predict();
            f32f.predict();
        }
        let (a, b) = (f64f.state(), f32f.state().cast::<f64>());
        // The forces, estimated from displacements of 1e-4 m, agree to a few parts in 10⁴.
        assert!((a - b).abs().max() <= 1e-3 * a.abs().max(), "{a} {b}");
        assert_eq!(f32f.health().covariance_resets, 0);
    }
}
