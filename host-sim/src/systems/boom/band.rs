//! Cholesky factorisation of the finite-element boom's banded matrices. A Hermite beam couples
//! each node's two DOFs to its neighbours' only, so every matrix of [`beam`] has half-bandwidth
//! [`HALF_BAND`]: factorising within the band costs `n·b²` instead of `n³/6`, which is what lets
//! the reference integrate 60 elements every sub-step.
//!
//! [`beam`]: super::beam

use nalgebra::{DMatrix, DVector};

/// Half-bandwidth of the boom's matrices: DOF `i` couples to `i ± 3` at most.
pub const HALF_BAND: usize = 3;

/// The lower Cholesky factor of a symmetric positive definite matrix with half-bandwidth
/// [`HALF_BAND`], stored as rows of the band (`l[i][k]` is `L[i][i − HALF_BAND + k]`).
#[derive(Debug, Clone)]
pub struct BandCholesky {
    l: Vec<[f64; HALF_BAND + 1]>,
}

impl BandCholesky {
    /// Factorises the band of `a` (entries outside it are ignored); `None` if `a` is not positive
    /// definite.
    ///
    /// ```
    /// use edgekf_sim::systems::boom::band::BandCholesky;
    /// use nalgebra::{DMatrix, DVector};
    /// // A tridiagonal [2 −1; −1 2 −1; …] and its dense solve.
    /// let a = DMatrix::from_fn(6, 6, |i, j| if i == j { 2.0 } else if i.abs_diff(j) == 1 { -1.0 } else { 0.0 });
    /// let b = DVector::from_fn(6, |i, _| i as f64);
    /// let x = BandCholesky::new(&a).unwrap().solve(&b);
    /// assert!((a.cholesky().unwrap().solve(&b) - x).norm() < 1e-12);
    /// ```
    pub fn new(a: &DMatrix<f64>) -> Option<Self> {
        let n = a.nrows();
        let mut l = vec![[0.0; HALF_BAND + 1]; n];
        // `at(l, i, j)` is L[i][j] for j in i − HALF_BAND ..= i.
        let at = |l: &[[f64; HALF_BAND + 1]], i: usize, j: usize| l[i][HALF_BAND + j - i];
        for i in 0..n {
            let first = i.saturating_sub(HALF_BAND);
            for j in first..=i {
                let mut s = a[(i, j)];
                for k in first.max(j.saturating_sub(HALF_BAND))..j {
                    s -= at(&l, i, k) * at(&l, j, k);
                }
                let v = if i == j {
                    if s.is_nan() || s <= 0.0 {
                        return None;
                    }
                    s.sqrt()
                } else {
                    s / at(&l, j, j)
                };
                l[i][HALF_BAND + j - i] = v;
            }
        }
        Some(Self { l })
    }

    /// Solves `A x = b`.
    pub fn solve(&self, b: &DVector<f64>) -> DVector<f64> {
        let n = self.l.len();
        let mut y = b.clone();
        for i in 0..n {
            let first = i.saturating_sub(HALF_BAND);
            let mut s = y[i];
            for k in first..i {
                s -= self.l[i][HALF_BAND + k - i] * y[k];
            }
            y[i] = s / self.l[i][HALF_BAND];
        }
        for i in (0..n).rev() {
            let mut s = y[i];
            for k in i + 1..(i + HALF_BAND + 1).min(n) {
                s -= self.l[k][HALF_BAND + i - k] * y[k];
            }
            y[i] = s / self.l[i][HALF_BAND];
        }
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::systems::boom::beam::assemble;
    use crate::systems::boom::config::BoomConfig;

    #[test]
    fn it_solves_the_boom_s_stiffness_as_the_dense_cholesky_does() {
        let c = BoomConfig::default();
        let b = assemble(&c, 24.0);
        // The band holds every non-zero.
        for i in 0..b.dofs() {
            for j in 0..b.dofs() {
                if i.abs_diff(j) > HALF_BAND {
                    assert_eq!((b.k[(i, j)], b.m[(i, j)], b.kg[(i, j)]), (0.0, 0.0, 0.0), "({i}, {j})");
                }
            }
        }
        let f = DVector::from_fn(b.dofs(), |i, _| (i as f64 * 0.7).sin());
        let dense = b.k.clone().cholesky().unwrap().solve(&f);
        let band = BandCholesky::new(&b.k).unwrap().solve(&f);
        assert!((&dense - &band).norm() <= 1e-12 * dense.norm(), "{}", (&dense - &band).norm());
        // Not positive definite: refused, not NaN.
        assert!(BandCholesky::new(&(-&b.k)).is_none());
    }
}
