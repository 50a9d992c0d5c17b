//! A real square matrix in real modal form, `A = W Λ W⁻¹`: a 1×1 block per real eigenvalue, a
//! 2×2 rotation–scaling block per complex pair. The one builder of such a basis (issue #33): the
//! rotor simulator's free response ([`super::free_response`], `e^{ΛΔt}` per block in closed
//! form) and the residual loop's filter (`residual_loop::modal_form`, an `O(n²)` covariance step)
//! both stand on it and differ only in how ill-conditioned a basis they accept.
//!
//! Why these steps:
//! * balanced first (`D⁻¹ A D`, powers of two, exact): states that mix metres, metres per second
//!   and newtons give unit eigenvectors of the unbalanced matrix far from orthogonal;
//! * a repeated eigenvalue (two channels' equal low-passes, a harmonic force's x and y) is
//!   spanned anew by inverse iteration, because the solver's vectors for it may be near-parallel;
//! * the basis is accepted only if it is well-conditioned (`‖W‖₁ ‖W⁻¹‖₁`, the caller's limit)
//!   and reproduces `A` (`A W = W Λ` to rounding). A defective eigenvalue (a Jordan block, such
//!   as a free rotor's rigid-body modes or a double integrator) has no basis of eigenvectors and
//!   is refused: the caller keeps its dense product. (Rounding may instead split it into a
//!   complex pair `α ± iβ` with β ~ 1e-9, whose 2×2 block is then the Jordan block itself on a
//!   well-conditioned basis: exact, and kept.)

use super::{balance, norm1};
use faer::linalg::solvers::{DenseSolveCore, PartialPivLu, Solve};
use faer::{c64, Mat, MatRef};
use std::cmp::Ordering;

/// `A W = W Λ` must hold to this accuracy relative to `‖A‖_F` (unit columns, balanced).
const MAX_RESIDUAL: f64 = 1e-11;
/// Eigenvalues this close (relative to the largest) are one repeated eigenvalue.
const SAME: f64 = 1e-9;
/// Inverse iteration's shift from a repeated eigenvalue (relative to the largest).
const SHIFT: f64 = 1e-10;

/// One diagonal block of `Λ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Block {
    /// A real eigenvalue `λ`, on one column.
    Real(f64),
    /// A complex pair `α ± iβ` on the columns `[Re v / |Re v|, Im v / |Im v|]`, with
    /// `r = |Im v| / |Re v|`: `A [P Q] = [P Q] [[α, β/r], [−β r, α]]`.
    Pair {
        /// `α`.
        re: f64,
        /// `β > 0`.
        im: f64,
        /// `|Im v| / |Re v|`.
        r: f64,
    },
}

impl Block {
    /// Its number of columns.
    pub fn size(&self) -> usize {
        match self {
            Block::Real(_) => 1,
            Block::Pair { .. } => 2,
        }
    }

    /// Its entries, row by row (`size()²` of them, the rest zero).
    pub fn matrix(&self) -> [f64; 4] {
        match *self {
            Block::Real(l) => [l, 0.0, 0.0, 0.0],
            Block::Pair { re, im, r } => [re, im / r, -im * r, re],
        }
    }
}

/// `A = W Λ W⁻¹` with `W = D W_b`: `W_b` the basis of the balanced matrix (unit columns).
#[derive(Debug, Clone)]
pub struct ModalBasis {
    /// `W_b`, the balanced basis.
    balanced: Mat<f64>,
    /// `W_b`'s factors, for `W⁻¹ z` without an explicit inverse.
    lu: PartialPivLu<f64>,
    /// The balancing `D`.
    d: Vec<f64>,
    /// The diagonal blocks of `Λ`, in column order.
    pub blocks: Vec<Block>,
}

impl ModalBasis {
    /// The real modal basis of `a`, or `None` where `a` has no eigenbasis whose condition
    /// (`‖W_b‖₁ ‖W_b⁻¹‖₁`, estimated) is at most `max_condition`.
    ///
    /// ```
    /// use edgekf_sim::linalg::modal_basis::{Block, ModalBasis};
    /// // A damped oscillator (ω = 10 rad/s, ζ = 0.1) beside a decay.
    /// let a = faer::mat![[0.0, 1.0, 0.0], [-100.0, -2.0, 0.0], [0.0, 1.0, -3.0]];
    /// let basis = ModalBasis::of(a.as_ref(), 1e6).unwrap();
    /// let sizes: Vec<usize> = basis.blocks.iter().map(Block::size).collect();
    /// assert_eq!(sizes.iter().sum::<usize>(), 3);
    /// // `W Λ W⁻¹` is `a` again.
    /// let rebuilt = basis.w() * basis.block_matrix() * basis.w_inv();
    /// assert!((rebuilt - a).norm_l2() < 1e-12);
    /// // A Jordan block (λ = 0 twice, one eigenvector) has none.
    /// assert!(ModalBasis::of(faer::mat![[0.0, 1.0], [0.0, 0.0]].as_ref(), 1e6).is_none());
    /// ```
    pub fn of(a: MatRef<'_, f64>, max_condition: f64) -> Option<Self> {
        let n = a.nrows();
        if n == 0 || a.ncols() != n || !super::all_finite(a) {
            return None;
        }
        let mut ab = a.to_owned();
        let d = balance(&mut ab);
        let evd = ab.eigen().ok()?;
        let mut values: Vec<c64> = evd.S().column_vector().iter().copied().collect();
        let mut u = evd.U().to_owned();
        // Repeated eigenvalues (those above the real axis, and real ones) spanned anew.
        let scale = values.iter().map(|l| l.norm()).fold(0.0, f64::max);
        let mut seen = vec![false; n];
        for k in 0..n {
            if seen[k] || values[k].im < 0.0 {
                continue;
            }
            let cluster: Vec<usize> =
                (k..n).filter(|&j| values[j].im >= 0.0 && (values[j] - values[k]).norm() <= SAME * scale).collect();
            cluster.iter().for_each(|&j| seen[j] = true);
            if cluster.len() > 1 {
                let (basis, lambda) = eigenspace(ab.as_ref(), values[k], cluster.len(), scale)?;
                for (c, &j) in cluster.iter().enumerate() {
                    u.col_mut(j).copy_from(basis.col(c));
                    values[j] = lambda;
                }
            }
        }
        let (balanced, blocks) = real_columns(u.as_ref(), &values)?;
        let lu = balanced.partial_piv_lu();
        let condition = norm1(balanced.as_ref()) * inverse_norm1(&lu, n);
        if condition.is_nan() || condition > max_condition {
            return None;
        }
        let basis = Self { balanced, lu, d, blocks };
        // `A W = W Λ` to rounding: the basis and the blocks describe `A`.
        let mut residual = super::mul(ab.as_ref(), basis.balanced.as_ref());
        let mut at = 0;
        for block in &basis.blocks {
            let (lambda, size) = (block.matrix(), block.size());
            for c in 0..size {
                for r in 0..size {
                    let l = lambda[r * size + c];
                    let w = basis.balanced.col(at + r);
                    residual.col_mut(at + c).iter_mut().zip(w.iter()).for_each(|(x, v)| *x -= v * l);
                }
            }
            at += size;
        }
        let residual = residual.norm_l2();
        if residual.is_nan() || residual > MAX_RESIDUAL * ab.norm_l2() {
            return None;
        }
        Some(basis)
    }

    /// `W = D W_b`, in the matrix's own coordinates.
    pub fn w(&self) -> Mat<f64> {
        Mat::from_fn(self.d.len(), self.d.len(), |i, j| self.balanced[(i, j)] * self.d[i])
    }

    /// `W⁻¹ = W_b⁻¹ D⁻¹`, explicit (for callers that transform many vectors and covariances).
    pub fn w_inv(&self) -> Mat<f64> {
        let inverse = self.lu.inverse();
        Mat::from_fn(self.d.len(), self.d.len(), |i, j| inverse[(i, j)] / self.d[j])
    }

    /// `W⁻¹ z` by `W_b`'s factors.
    ///
    /// # Panics
    /// If `z` is not as long as the matrix is wide (a caller's error).
    pub fn solve(&self, z: &[f64]) -> Vec<f64> {
        assert_eq!(z.len(), self.d.len(), "modal basis: {} states, a vector of {}", self.d.len(), z.len());
        let scaled = Mat::<f64>::from_fn(z.len(), 1, |i, _| z[i] / self.d[i]);
        self.lu.solve(scaled).col(0).iter().copied().collect()
    }

    /// `Λ` as a dense matrix.
    pub fn block_matrix(&self) -> Mat<f64> {
        let n = self.d.len();
        let mut lambda = Mat::zeros(n, n);
        let mut at = 0;
        for block in &self.blocks {
            let (m, size) = (block.matrix(), block.size());
            for k in 0..size * size {
                lambda[(at + k / size, at + k % size)] = m[k];
            }
            at += size;
        }
        lambda
    }
}

/// The real basis from complex eigenvectors `u` (columns) and their eigenvalues: a unit column
/// per real eigenvalue, `Re v / |Re v|` and `Im v / |Im v|` per pair (the one above the real
/// axis; the conjugate below only counted). `None` if a vector is zero or the pairs do not match.
fn real_columns(u: MatRef<'_, c64>, values: &[c64]) -> Option<(Mat<f64>, Vec<Block>)> {
    let n = u.nrows();
    let mut w = Mat::<f64>::zeros(n, n);
    let mut blocks = Vec::with_capacity(n);
    let (mut column, mut above, mut below) = (0, 0usize, 0usize);
    for (k, l) in values.iter().enumerate() {
        let size = if l.im > 0.0 { 2 } else { 1 };
        if l.im < 0.0 {
            below += 1;
            continue;
        } else if column + size > n {
            return None;
        }
        let norm_re = (0..n).map(|i| u[(i, k)].re.powi(2)).sum::<f64>().sqrt();
        let norm_im = (0..n).map(|i| u[(i, k)].im.powi(2)).sum::<f64>().sqrt();
        if norm_re.partial_cmp(&0.0) != Some(Ordering::Greater)
            || (size == 2 && norm_im.partial_cmp(&0.0) != Some(Ordering::Greater))
        {
            return None;
        }
        for i in 0..n {
            w[(i, column)] = u[(i, k)].re / norm_re;
            if size == 2 {
                w[(i, column + 1)] = u[(i, k)].im / norm_im;
            }
        }
        if size == 1 {
            blocks.push(Block::Real(l.re));
        } else {
            blocks.push(Block::Pair { re: l.re, im: l.im, r: norm_im / norm_re });
            above += 1;
        }
        column += size;
    }
    (column == n && above == below).then_some((w, blocks))
}

/// `m` orthonormal vectors spanning the eigenspace of `f` at `lambda`, by two steps of inverse
/// iteration from `m` independent starts, and the eigenvalue as their Rayleigh quotient (the
/// solver splits a repeated eigenvalue by more than rounding). Vectors that are not
/// eigenvectors (a Jordan block's eigenspace is smaller) fail the caller's residual check.
fn eigenspace(f: MatRef<'_, f64>, lambda: c64, m: usize, scale: f64) -> Option<(Mat<c64>, c64)> {
    let n = f.nrows();
    let sigma = lambda + c64::new(SHIFT * scale, 0.0);
    let shifted = Mat::<c64>::from_fn(n, n, |i, j| c64::new(f[(i, j)], 0.0) - if i == j { sigma } else { c64::ZERO });
    let lu = shifted.partial_piv_lu();
    // Independent starts: pseudo-random entries in [−1, 1) (a 64-bit LCG).
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    let mut x = Mat::<c64>::from_fn(n, m, |_, _| {
        seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        c64::new((seed >> 11) as f64 / (1u64 << 52) as f64 - 1.0, 0.0)
    });
    for _ in 0..2 {
        x = lu.solve(&x);
        // Modified Gram–Schmidt, twice.
        for _ in 0..2 {
            for j in 0..m {
                for i in 0..j {
                    let p: c64 = (0..n).map(|r| x[(r, i)].conj() * x[(r, j)]).sum();
                    for r in 0..n {
                        let v = x[(r, i)];
                        x[(r, j)] -= p * v;
                    }
                }
                let norm = (0..n).map(|r| x[(r, j)].norm_sqr()).sum::<f64>().sqrt();
                if !(norm > 0.0 && norm.is_finite()) {
                    return None;
                }
                (0..n).for_each(|r| x[(r, j)] /= norm);
            }
        }
    }
    // `trace(Xᴴ F X) / m`.
    let fx = Mat::<c64>::from_fn(n, m, |i, j| (0..n).map(|k| x[(k, j)] * f[(i, k)]).sum());
    let quotient: c64 =
        (0..m).map(|j| (0..n).map(|r| x[(r, j)].conj() * fx[(r, j)]).sum::<c64>()).sum::<c64>() / m as f64;
    Some((x, quotient))
}

/// An estimate of `‖W⁻¹‖₁` from `W`'s factors (Hager's method, as LAPACK's `lacon`): a few
/// solves instead of the inverse, and a lower bound within a small factor of the true norm.
fn inverse_norm1(lu: &PartialPivLu<f64>, n: usize) -> f64 {
    let mut x = Mat::<f64>::from_fn(n, 1, |_, _| 1.0 / n as f64);
    let mut estimate = 0.0;
    for _ in 0..5 {
        let y = lu.solve(&x);
        estimate = norm1(y.as_ref());
        if !estimate.is_finite() {
            return f64::INFINITY;
        }
        let signs = Mat::<f64>::from_fn(n, 1, |i, _| if y[(i, 0)] >= 0.0 { 1.0 } else { -1.0 });
        let z = lu.solve_transpose(&signs);
        let (j, largest) = (0..n).map(|i| (i, z[(i, 0)].abs())).fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a });
        let zx: f64 = (0..n).map(|i| z[(i, 0)] * x[(i, 0)]).sum();
        if largest <= zx {
            break;
        }
        x = Mat::<f64>::from_fn(n, 1, |i, _| f64::from(u8::from(i == j)));
    }
    estimate
}

#[cfg(test)]
mod tests;
