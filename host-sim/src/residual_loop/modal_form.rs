//! The transition in real modal form, `Φ = W B W⁻¹` with `B` block diagonal: a 1×1 block per
//! real eigenvalue, a 2×2 rotation–scaling block per complex pair. In those coordinates the
//! filter's covariance step `B P Bᵀ` costs `O(n²)` instead of the `O(n³)` of a dense product,
//! which is most of the loop's time: a reduced model with undamped effect states (an unbalance,
//! a harmonic force) never reaches a steady gain, so every sample takes a covariance step.
//!
//! A transition that is defective or nearly so (a Jordan block, eigenvectors close to parallel)
//! has no well-conditioned `W`; [`ModalForm::of`] then returns `None` and the filter keeps the
//! dense product.

use crate::linalg::balance;
use faer::Mat;
use nalgebra::{DMatrix, DVector};

/// `W` may amplify rounding by at most this much (`‖W‖₁ ‖W⁻¹‖₁`, unit columns).
const MAX_CONDITION: f64 = 1e6;
/// `W B W⁻¹` must reproduce `Φ` to this relative accuracy (Frobenius norm).
const MAX_RECONSTRUCTION: f64 = 1e-11;

/// One diagonal block of `B`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Block {
    /// A real eigenvalue.
    One(f64),
    /// A complex pair: `[[b00, b01], [b10, b11]]`.
    Two([[f64; 2]; 2]),
}

/// `Φ = W B W⁻¹` with `B` block diagonal.
#[derive(Debug, Clone)]
pub struct ModalForm {
    /// The modal basis `W` (columns of unit length).
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
        if n == 0 || phi.ncols() != n || phi.iter().any(|v| !v.is_finite()) {
            return None;
        }
        // Balanced first (`D⁻¹ Φ D`, powers of two): a reduced model's states mix metres and
        // newtons, and unit eigenvectors of the unbalanced matrix would be far from orthogonal.
        let mut balanced = Mat::from_fn(n, n, |i, j| phi[(i, j)]);
        let d = balance(&mut balanced);
        let phi_b = DMatrix::from_fn(n, n, |i, j| balanced[(i, j)]);
        let evd = balanced.eigen().ok()?;
        let (u, values) = (evd.U(), evd.S().column_vector());
        let scale = (0..n).map(|k| values[k].norm()).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
        let mut w = DMatrix::<f64>::zeros(n, n);
        // The size of each block, in the order of `W`'s columns.
        let mut sizes = Vec::new();
        let mut conjugates = 0usize;
        for k in 0..n {
            let lambda = values[k];
            let part = |re: bool| DVector::from_fn(n, |i, _| if re { u[(i, k)].re } else { u[(i, k)].im });
            let column: usize = sizes.iter().sum();
            if lambda.im.abs() <= 1e-14 * scale {
                // A real eigenvalue's vector, whatever complex phase the solver gave it.
                let (re, im) = (part(true), part(false));
                set_unit(&mut w, column, if re.norm() >= im.norm() { &re } else { &im })?;
                sizes.push(1);
            } else if lambda.im > 0.0 {
                set_unit(&mut w, column, &part(true))?;
                set_unit(&mut w, column + 1, &part(false))?;
                sizes.push(2);
            } else {
                conjugates += 1;
            }
        }
        if sizes.iter().sum::<usize>() != n || 2 * conjugates != n - sizes.iter().filter(|&&s| s == 1).count() {
            return None;
        }
        let w_inv = w.clone().try_inverse()?;
        if w.lp_norm(1) * w_inv.lp_norm(1) > MAX_CONDITION * n as f64 {
            return None;
        }
        // The blocks from `W⁻¹ Φ W` itself, so that `W B W⁻¹` is as close to `Φ` as rounding allows.
        let b = &w_inv * &phi_b * &w;
        let mut i = 0;
        let blocks = sizes
            .iter()
            .map(|&size| {
                let block = match size {
                    1 => Block::One(b[(i, i)]),
                    _ => Block::Two([[b[(i, i)], b[(i, i + 1)]], [b[(i + 1, i)], b[(i + 1, i + 1)]]]),
                };
                i += size;
                block
            })
            .collect();
        let form = ModalForm { w, w_inv, blocks };
        let rebuilt = &form.w * form.block_matrix() * &form.w_inv;
        let error = (&rebuilt - &phi_b).norm() / phi_b.norm().max(f64::MIN_POSITIVE);
        // Balancing undone: `W ← D W`, `W⁻¹ ← W⁻¹ D⁻¹`.
        let mut form = form;
        for (i, di) in d.iter().enumerate() {
            form.w.row_mut(i).scale_mut(*di);
            form.w_inv.column_mut(i).scale_mut(1.0 / di);
        }
        (error <= MAX_RECONSTRUCTION).then_some(form)
    }

    /// `B` as a dense matrix.
    fn block_matrix(&self) -> DMatrix<f64> {
        let n = self.w.nrows();
        let mut b = DMatrix::identity(n, n);
        self.rows(&mut b);
        b
    }

    /// `v ← B v`.
    pub fn step(&self, v: &mut DVector<f64>) {
        let mut i = 0;
        for block in &self.blocks {
            match *block {
                Block::One(a) => {
                    v[i] *= a;
                    i += 1;
                }
                Block::Two(b) => {
                    let (p, q) = (v[i], v[i + 1]);
                    v[i] = b[0][0] * p + b[0][1] * q;
                    v[i + 1] = b[1][0] * p + b[1][1] * q;
                    i += 2;
                }
            }
        }
    }

    /// `m ← B m`.
    pub fn rows(&self, m: &mut DMatrix<f64>) {
        let mut i = 0;
        for block in &self.blocks {
            match *block {
                Block::One(a) => {
                    m.row_mut(i).scale_mut(a);
                    i += 1;
                }
                Block::Two(b) => {
                    for j in 0..m.ncols() {
                        let (p, q) = (m[(i, j)], m[(i + 1, j)]);
                        m[(i, j)] = b[0][0] * p + b[0][1] * q;
                        m[(i + 1, j)] = b[1][0] * p + b[1][1] * q;
                    }
                    i += 2;
                }
            }
        }
    }

    /// `m ← m Bᵀ`.
    pub fn cols_t(&self, m: &mut DMatrix<f64>) {
        let mut i = 0;
        for block in &self.blocks {
            match *block {
                Block::One(a) => {
                    m.column_mut(i).scale_mut(a);
                    i += 1;
                }
                Block::Two(b) => {
                    for r in 0..m.nrows() {
                        let (p, q) = (m[(r, i)], m[(r, i + 1)]);
                        m[(r, i)] = b[0][0] * p + b[0][1] * q;
                        m[(r, i + 1)] = b[1][0] * p + b[1][1] * q;
                    }
                    i += 2;
                }
            }
        }
    }
}

/// Column `at` of `w` set to `v / ‖v‖` (`None` for a zero or non-finite vector).
fn set_unit(w: &mut DMatrix<f64>, at: usize, v: &DVector<f64>) -> Option<()> {
    let norm = v.norm();
    if !(norm.is_finite() && norm > 0.0) || at >= w.ncols() {
        return None;
    }
    w.set_column(at, &(v / norm));
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_defective_transition_has_no_modal_form() {
        // A double integrator over one step: a Jordan block, no basis of eigenvectors.
        let phi = DMatrix::from_row_slice(2, 2, &[1.0, 1e-3, 0.0, 1.0]);
        assert!(ModalForm::of(&phi).is_none());
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
        // `m Bᵀ` is the transpose of `B mᵀ`.
        let mut a = DMatrix::from_fn(6, 6, |i, j| (i * 7 + j) as f64);
        let mut b = a.transpose();
        form.cols_t(&mut a);
        form.rows(&mut b);
        assert_eq!(a, b.transpose());
    }
}
