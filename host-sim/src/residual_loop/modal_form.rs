//! The transition in real modal form, `Φ = W B W⁻¹` with `B` block diagonal: a 1×1 block per
//! real eigenvalue, a 2×2 rotation–scaling block per complex pair, one block for the whole
//! invariant subspace of a repeated eigenvalue. In those coordinates the filter's covariance
//! step `B P Bᵀ` costs `O(n²)` instead of the `O(n³)` of a dense product, which is most of the
//! loop's time: a reduced model with undamped effect states (an unbalance, a harmonic force)
//! never reaches a steady gain, so every sample takes a covariance step.
//!
//! A transition whose eigenvectors are close to parallel without being equal has no
//! well-conditioned `W`; [`ModalForm::of`] then returns `None` and the filter keeps the dense
//! product.

use crate::linalg::balance;
use faer::{c64, Mat, MatRef};
use nalgebra::{DMatrix, DVector};

/// `W` may amplify rounding by at most this much (`‖W‖₁ ‖W⁻¹‖₁`, unit columns).
const MAX_CONDITION: f64 = 1e6;
/// `W B W⁻¹` must reproduce `Φ` to this relative accuracy (Frobenius norm).
const MAX_RECONSTRUCTION: f64 = 1e-11;
/// An eigenvalue this close to the real axis (relative to the largest) is real.
const REAL: f64 = 1e-14;
/// Eigenvalues this close (relative to the largest) are one repeated eigenvalue.
const SAME: f64 = 1e-9;
/// Blocks up to this size step through a stack buffer.
const SCRATCH: usize = 16;

/// One diagonal block of `B`: its first row and its entries, row by row.
#[derive(Debug, Clone, PartialEq)]
struct Block {
    at: usize,
    size: usize,
    b: Vec<f64>,
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
        let values: Vec<c64> = (0..n).map(|k| values[k]).collect();
        let solver = |k: usize| (0..n).map(|i| u[(i, k)]).collect::<Vec<c64>>();
        // Identical parts of a model (two channels' low-passes, an unbalance's x and y) repeat
        // an eigenvalue. The solver's vectors usually serve, one block each; where they do not
        // (parallel, or a defective eigenvalue), a repeated eigenvalue's invariant subspace
        // becomes one block.
        let mut form = Self::with_blocks(&phi_b, &values, 0.0, &solver)
            .or_else(|| Self::with_blocks(&phi_b, &values, SAME, &solver))?;
        // Balancing undone: `W ← D W`, `W⁻¹ ← W⁻¹ D⁻¹`.
        for (i, di) in d.iter().enumerate() {
            form.w.row_mut(i).scale_mut(*di);
            form.w_inv.column_mut(i).scale_mut(1.0 / di);
        }
        Some(form)
    }

    /// The form of `phi` with eigenvalues within `same` (relative to the largest) of each other
    /// as one block, their vectors from their invariant subspace; a single eigenvalue's vector
    /// from `solver(k)`. `None` if the basis is ill-conditioned or misses `phi`.
    fn with_blocks(phi: &DMatrix<f64>, values: &[c64], same: f64, solver: &dyn Fn(usize) -> Vec<c64>) -> Option<Self> {
        let n = phi.nrows();
        let scale = values.iter().map(|v| v.norm()).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
        // The eigenvalues on or above the real axis, equal ones together.
        let mut clusters: Vec<(c64, Vec<usize>)> = Vec::new();
        let mut below = 0usize;
        for (k, &lambda) in values.iter().enumerate() {
            if lambda.im < -REAL * scale {
                below += 1;
            } else if let Some((_, members)) =
                clusters.iter_mut().find(|(l, _)| same > 0.0 && (l - lambda).norm() <= same * scale)
            {
                members.push(k);
            } else {
                clusters.push((lambda, vec![k]));
            }
        }
        let mut w = DMatrix::<f64>::zeros(n, n);
        let mut sizes = Vec::new();
        let mut column = 0;
        for (lambda, members) in &clusters {
            let real = lambda.im.abs() <= REAL * scale;
            let vectors: Vec<Vec<c64>> = if members.len() == 1 {
                vec![solver(members[0])]
            } else {
                invariant_subspace(phi, *lambda, members.len(), real)?
            };
            let before = column;
            for v in vectors {
                let re = DVector::from_iterator(n, v.iter().map(|z| z.re));
                let im = DVector::from_iterator(n, v.iter().map(|z| z.im));
                if real {
                    // A real eigenvalue's vector, whatever complex phase the solver gave it.
                    set_unit(&mut w, column, if re.norm() >= im.norm() { &re } else { &im })?;
                    column += 1;
                } else {
                    set_unit(&mut w, column, &re)?;
                    set_unit(&mut w, column + 1, &im)?;
                    column += 2;
                    below = below.checked_sub(1)?;
                }
            }
            sizes.push(column - before);
        }
        if column != n || below != 0 {
            return None;
        }
        let w_inv = w.clone().try_inverse()?;
        if w.lp_norm(1) * w_inv.lp_norm(1) > MAX_CONDITION * n as f64 {
            return None;
        }
        // The blocks from `W⁻¹ Φ W` itself, so that `W B W⁻¹` is as close to `Φ` as rounding allows.
        let b = &w_inv * phi * &w;
        let mut at = 0;
        let blocks = sizes
            .iter()
            .map(|&size| {
                let block =
                    Block { at, size, b: (0..size * size).map(|k| b[(at + k / size, at + k % size)]).collect() };
                at += size;
                block
            })
            .collect();
        let form = ModalForm { w, w_inv, blocks };
        let rebuilt = &form.w * form.block_matrix() * &form.w_inv;
        let accurate = (&rebuilt - phi).norm() <= MAX_RECONSTRUCTION * phi.norm().max(f64::MIN_POSITIVE);
        accurate.then_some(form)
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
        let mut x = [0.0; SCRATCH];
        for Block { at, size, b } in &self.blocks {
            let (at, size) = (*at, *size);
            match size {
                1 => v[at] *= b[0],
                2 => {
                    let (p, q) = (v[at], v[at + 1]);
                    v[at] = b[0] * p + b[1] * q;
                    v[at + 1] = b[2] * p + b[3] * q;
                }
                _ if size <= SCRATCH => {
                    x[..size].copy_from_slice(&v.as_slice()[at..at + size]);
                    for r in 0..size {
                        v[at + r] = dot(&b[r * size..(r + 1) * size], &x[..size]);
                    }
                }
                _ => {
                    let new = DMatrix::from_row_slice(size, size, b) * v.rows(at, size);
                    v.rows_mut(at, size).copy_from(&new);
                }
            }
        }
    }

    /// `p ← B p Bᵀ` for a symmetric `p`: each pair of blocks once, mirrored.
    pub fn covariance(&self, p: &mut DMatrix<f64>) {
        let largest = self.blocks.iter().map(|b| b.size).max().unwrap_or(0);
        // `X` (the pair's part of `p`, row by row), `T = B_i X` and `Y = T B_jᵀ`.
        let (mut x, mut t) = (vec![0.0; largest * largest], vec![0.0; largest * largest]);
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
    fn rows(&self, m: &mut DMatrix<f64>) {
        for Block { at, size, b } in &self.blocks {
            let new = DMatrix::from_row_slice(*size, *size, b) * m.rows(*at, *size);
            m.rows_mut(*at, *size).copy_from(&new);
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |acc, (p, q)| acc + p * q)
}

/// `count` vectors spanning the invariant subspace of `phi` at a `count`-fold eigenvalue `λ`:
/// the null space of `(phi − λI)^count` (which holds a defective eigenvalue's generalised
/// vectors too), from the right singular vectors of its smallest singular values; real ones
/// for a `real` λ. `None` if the solver fails.
fn invariant_subspace(phi: &DMatrix<f64>, lambda: c64, count: usize, real: bool) -> Option<Vec<Vec<c64>>> {
    let n = phi.nrows();
    let last = |v: MatRef<'_, c64>| (n - count..n).map(|k| (0..n).map(|i| v[(i, k)]).collect()).collect();
    if real {
        // A real eigenvalue's subspace has a real basis: the real solver gives it.
        let shifted = Mat::<f64>::from_fn(n, n, |i, j| phi[(i, j)] - if i == j { lambda.re } else { 0.0 });
        let svd = power(&shifted, count).svd().ok()?;
        return Some(last(Mat::<c64>::from_fn(n, n, |i, k| c64::new(svd.V()[(i, k)], 0.0)).as_ref()));
    }
    let shifted =
        Mat::<c64>::from_fn(n, n, |i, j| c64::new(phi[(i, j)], 0.0) - if i == j { lambda } else { c64::ZERO });
    let svd = power(&shifted, count).svd().ok()?;
    Some(last(svd.V()))
}

/// `m^k` for `k ≥ 1`, real or complex.
fn power<T>(m: &Mat<T>, k: usize) -> Mat<T>
where
    Mat<T>: Clone,
    for<'a> &'a Mat<T>: std::ops::Mul<&'a Mat<T>, Output = Mat<T>>,
{
    (1..k).fold(m.clone(), |p, _| &p * m)
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
    fn a_repeated_eigenvalue_keeps_its_subspace_as_one_block() {
        // A double integrator over one step (a Jordan block: no basis of eigenvectors) beside
        // two identical damped rotations (one eigenvalue pair twice, as two channels' equal
        // low-passes give): each repeated eigenvalue becomes one block of its whole subspace.
        let (c, s) = (0.9 * 0.4f64.cos(), 0.9 * 0.4f64.sin());
        let phi = DMatrix::from_row_slice(
            6,
            6,
            &[
                1.0, 1e-3, 0.5, 0.0, 0.2, 0.0, //
                0.0, 1.0, 0.0, 0.1, 0.0, 0.3, //
                0.0, 0.0, c, -s, 0.0, 0.0, //
                0.0, 0.0, s, c, 0.0, 0.0, //
                0.0, 0.0, 0.0, 0.0, c, -s, //
                0.0, 0.0, 0.0, 0.0, s, c,
            ],
        );
        let form = ModalForm::of(&phi).expect("a modal form");
        // The Jordan block as one 2×2 block, the repeated pair as one 4×4.
        let sizes: Vec<usize> = form.blocks.iter().map(|b| b.size).collect();
        assert_eq!(sizes, [2, 4]);
        // The symmetric step against the dense product, through the 4×4 block.
        assert_covariance_step(&form, DMatrix::from_fn(6, 6, |i, j| ((i * 5 + j) as f64).cos()));
        let rebuilt = &form.w * form.block_matrix() * &form.w_inv;
        assert!((rebuilt - &phi).norm() < 1e-13);
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
