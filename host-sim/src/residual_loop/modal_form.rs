//! The transition in real modal form, `Φ = W B W⁻¹` with `B` block diagonal: a 1×1 block per
//! real eigenvalue, a 2×2 rotation–scaling block per complex pair, one block for the whole
//! invariant subspace of a repeated eigenvalue. In those coordinates the filter's covariance
//! step `B P Bᵀ` costs `O(n²)` instead of the `O(n³)` of a dense product, which is most of the
//! loop's time: a reduced model with undamped effect states (an unbalance, a harmonic force)
//! never reaches a steady gain, so every sample takes a covariance step.
//!
//! The basis is [`crate::linalg::modal_basis`]'s, the one builder of a real modal form: a
//! transition whose eigenvectors are close to parallel (or that has none, a Jordan block) has no
//! well-conditioned `W`; [`ModalForm::of`] then returns `None` and the filter keeps the dense
//! product.

use crate::linalg::modal_basis::ModalBasis;
use faer::Mat;
use nalgebra::{DMatrix, DVector};

/// `W` may amplify rounding by at most this much (`‖W‖₁ ‖W⁻¹‖₁`, unit columns, balanced).
/// Tighter than the free response's 1e7: the filter carries every segment's covariances
/// through both `W` and `W⁻¹` (`W⁻¹ P W⁻ᵀ`, `W P Wᵀ`), where the condition enters squared, and
/// a dense product is always there to fall back on (a reduced model has tens of states, not
/// hundreds).
const MAX_CONDITION: f64 = 1e6;

/// One diagonal block of `B`: its first row, its size (1 or 2) and its entries, row by row.
#[derive(Debug, Clone, PartialEq)]
struct Block {
    at: usize,
    size: usize,
    b: [f64; 4],
}

/// `Φ = W B W⁻¹` with `B` block diagonal.
#[derive(Debug, Clone)]
pub struct ModalForm {
    /// The modal basis `W` (columns of unit length before balancing is undone).
    pub w: DMatrix<f64>,
    /// `W⁻¹`.
    pub w_inv: DMatrix<f64>,
    blocks: Vec<Block>,
}

impl ModalForm {
    /// The modal form of `phi`, or `None` if it has no well-conditioned one.
    ///
    /// ```
    /// use edgekf_sim::residual_loop::modal_form::ModalForm;
    /// use nalgebra::{DMatrix, DVector};
    /// // A damped rotation and a decay: two blocks.
    /// let (c, s) = (0.99 * 0.3f64.cos(), 0.99 * 0.3f64.sin());
    /// let phi = DMatrix::from_row_slice(3, 3, &[c, -s, 0.1, s, c, 0.0, 0.0, 0.0, 0.5]);
    /// let form = ModalForm::of(&phi).unwrap();
    /// let mut z = &form.w_inv * DVector::from_row_slice(&[1.0, 2.0, 3.0]);
    /// form.step(&mut z);
    /// let x = &form.w * z; // Φ x, through the blocks
    /// assert!((x - &phi * DVector::from_row_slice(&[1.0, 2.0, 3.0])).norm() < 1e-12);
    /// ```
    pub fn of(phi: &DMatrix<f64>) -> Option<Self> {
        let n = phi.nrows();
        if phi.ncols() != n {
            return None;
        }
        let basis = ModalBasis::of(Mat::from_fn(n, n, |i, j| phi[(i, j)]).as_ref(), MAX_CONDITION)?;
        let dense = |m: Mat<f64>| DMatrix::from_fn(n, n, |i, j| m[(i, j)]);
        let (w, w_inv) = (dense(basis.w()), dense(basis.w_inv()));
        // The blocks from `W⁻¹ Φ W` itself, so that `W B W⁻¹` is as close to `Φ` as rounding allows.
        let b = &w_inv * phi * &w;
        let mut at = 0;
        let blocks = basis
            .blocks
            .iter()
            .map(|block| {
                let size = block.size();
                let mut entries = [0.0; 4];
                for (k, e) in entries.iter_mut().take(size * size).enumerate() {
                    *e = b[(at + k / size, at + k % size)];
                }
                at += size;
                Block { at: at - size, size, b: entries }
            })
            .collect();
        Some(ModalForm { w, w_inv, blocks })
    }

    /// `B` as a dense matrix.
    #[cfg(test)]
    fn block_matrix(&self) -> DMatrix<f64> {
        let n = self.w.nrows();
        let mut b = DMatrix::identity(n, n);
        self.rows(&mut b);
        b
    }

    /// `v ← B v`.
    pub fn step(&self, v: &mut DVector<f64>) {
        for &Block { at, size, b } in &self.blocks {
            if size == 1 {
                v[at] *= b[0];
            } else {
                let (p, q) = (v[at], v[at + 1]);
                v[at] = b[0] * p + b[1] * q;
                v[at + 1] = b[2] * p + b[3] * q;
            }
        }
    }

    /// `p ← B p Bᵀ` for a symmetric `p`: each pair of blocks once, mirrored.
    pub fn covariance(&self, p: &mut DMatrix<f64>) {
        // `X` (the pair's part of `p`, row by row), `T = B_i X` and `Y = T B_jᵀ`.
        let (mut x, mut t) = ([0.0; 4], [0.0; 4]);
        for (k, bi) in self.blocks.iter().enumerate() {
            for bj in &self.blocks[k..] {
                let (i, j, a, c) = (bi.at, bj.at, &bi.b, &bj.b);
                if bi.size == 2 && bj.size == 2 {
                    // The common case, unrolled: two rotation–scaling blocks.
                    let (x00, x01, x10, x11) = (p[(i, j)], p[(i, j + 1)], p[(i + 1, j)], p[(i + 1, j + 1)]);
                    let (t00, t01) = (a[0] * x00 + a[1] * x10, a[0] * x01 + a[1] * x11);
                    let (t10, t11) = (a[2] * x00 + a[3] * x10, a[2] * x01 + a[3] * x11);
                    let y00 = t00 * c[0] + t01 * c[1];
                    let y01 = t00 * c[2] + t01 * c[3];
                    let y10 = t10 * c[0] + t11 * c[1];
                    let y11 = t10 * c[2] + t11 * c[3];
                    for (r, s, v) in [(i, j, y00), (i, j + 1, y01), (i + 1, j, y10), (i + 1, j + 1, y11)] {
                        p[(r, s)] = v;
                        p[(s, r)] = v;
                    }
                    continue;
                }
                let (si, sj) = (bi.size, bj.size);
                for r in 0..si {
                    for q in 0..sj {
                        x[r * sj + q] = p[(i + r, j + q)];
                    }
                }
                for r in 0..si {
                    for q in 0..sj {
                        t[r * sj + q] = (0..si).fold(0.0, |acc, l| acc + a[r * si + l] * x[l * sj + q]);
                    }
                }
                for r in 0..si {
                    for q in 0..sj {
                        let v = dot(&t[r * sj..(r + 1) * sj], &c[q * sj..(q + 1) * sj]);
                        p[(i + r, j + q)] = v;
                        p[(j + q, i + r)] = v;
                    }
                }
            }
        }
    }

    /// `m ← B m`, any `m` (the dense form, for checks).
    #[cfg(test)]
    fn rows(&self, m: &mut DMatrix<f64>) {
        for Block { at, size, b } in &self.blocks {
            let new = DMatrix::from_row_slice(*size, *size, &b[..size * size]) * m.rows(*at, *size);
            m.rows_mut(*at, *size).copy_from(&new);
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |acc, (p, q)| acc + p * q)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_repeated_eigenvalue_gets_a_block_per_vector_and_a_jordan_block_none() {
        // Two identical damped rotations (one eigenvalue pair twice, as two channels' equal
        // low-passes give) coupled into a decay: a 2×2 block per eigenvector of the pair.
        let (c, s) = (0.9 * 0.4f64.cos(), 0.9 * 0.4f64.sin());
        let phi = DMatrix::from_row_slice(
            5,
            5,
            &[
                0.5, 0.5, 0.0, 0.2, 0.0, //
                0.0, c, -s, 0.0, 0.0, //
                0.0, s, c, 0.0, 0.0, //
                0.0, 0.0, 0.0, c, -s, //
                0.0, 0.0, 0.0, s, c,
            ],
        );
        let form = ModalForm::of(&phi).expect("a modal form");
        let sizes: Vec<usize> = form.blocks.iter().map(|b| b.size).collect();
        assert_eq!(sizes.iter().filter(|&&s| s == 2).count(), 2);
        // The symmetric step against the dense product.
        assert_covariance_step(&form, DMatrix::from_fn(5, 5, |i, j| ((i * 5 + j) as f64).cos()));
        let rebuilt = &form.w * form.block_matrix() * &form.w_inv;
        assert!((rebuilt - &phi).norm() < 1e-13);
        // A double integrator over one step (a Jordan block: no basis of eigenvectors) has no
        // modal form; the filter keeps the dense product.
        let jordan = DMatrix::from_row_slice(2, 2, &[1.0, 1e-3, 0.0, 1.0]);
        assert!(ModalForm::of(&jordan).is_none());
        assert!(ModalForm::of(&DMatrix::from_row_slice(1, 1, &[f64::NAN])).is_none());
    }

    #[test]
    fn equal_pairs_at_far_apart_scales_are_resolved() {
        // Two undamped forces at one speed (newtons) driving a mode in micrometres: a repeated
        // eigenvalue pair, states twelve orders apart. Balancing keeps the basis well conditioned.
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let phi = DMatrix::from_row_slice(
            6,
            6,
            &[
                0.9, 0.2, 1e-6, 2e-6, -1e-6, 0.0, //
                -0.2, 0.9, 0.0, 1e-6, 3e-6, 1e-6, //
                0.0, 0.0, c, s, 0.0, 0.0, //
                0.0, 0.0, -s, c, 0.0, 0.0, //
                0.0, 0.0, 0.0, 0.0, c, s, //
                0.0, 0.0, 0.0, 0.0, -s, c,
            ],
        );
        let form = ModalForm::of(&phi).expect("a modal form");
        let mut m = form.w_inv.clone();
        form.rows(&mut m);
        let rebuilt = &form.w * m; // W B W⁻¹
        for i in 0..6 {
            for j in 0..6 {
                // Entry by entry, relative to its row's scale: the micrometre rows stay exact.
                let scale = phi.row(i).amax();
                assert!((rebuilt[(i, j)] - phi[(i, j)]).abs() < 1e-13 * scale, "({i}, {j})");
            }
        }
        // The symmetric step against the dense product.
        assert_covariance_step(&form, DMatrix::from_fn(6, 6, |i, j| ((i * 7 + j) as f64).sin()));
    }

    /// `B P Bᵀ` by blocks equals the dense product for `P = X Xᵀ`.
    fn assert_covariance_step(form: &ModalForm, x: DMatrix<f64>) {
        let mut p = &x * x.transpose();
        let b = form.block_matrix();
        let expected = &b * &p * b.transpose();
        form.covariance(&mut p);
        assert!((p - &expected).norm() < 1e-14 * expected.norm());
    }
}
