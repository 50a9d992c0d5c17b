//! The free response `z_k = e^{F kΔt} z_0` of a linear time-invariant system, read through output
//! rows, by the eigen decomposition of `F` instead of the transition matrix.
//!
//! Why: stepping `z_{k+1} = Φ z_k` with a dense `Φ` costs `O(n²)` a sample, and for the
//! full rotor (~300 states) `Φ` (740 kB) does not fit a core's cache, so every sample streams it
//! from memory. In the real modal form `F = W Λ W⁻¹` (1×1 blocks for real eigenvalues, 2×2
//! rotation–scaling blocks for complex pairs) a sample's step is `O(n)`, and the outputs of a
//! few hundred samples at once are one matrix product `R Ξ` (`R = rows · W`), which runs at the
//! processor's arithmetic speed. `e^{λΔt}` is taken per eigenvalue in closed form, so the step is
//! as exact as the eigenvectors: [`ModalExponential::of`] accepts a basis only if it is
//! well-conditioned and reproduces `F`, and returns `None` otherwise (a Jordan block, such as a
//! free rotor's rigid-body modes, or near-parallel eigenvectors), where the caller keeps the
//! transition matrix.

use super::{balance, norm1};
use faer::linalg::solvers::{PartialPivLu, Solve};
use faer::{c64, Accum, Mat, MatRef, Par};
use std::cmp::Ordering;

/// `W` may amplify rounding by at most this much (`‖W‖₁ ‖W⁻¹‖₁`, unit columns, balanced).
const MAX_CONDITION: f64 = 1e7;
/// `F W = W Λ` must hold to this accuracy relative to `‖F‖_F` (unit columns).
const MAX_RESIDUAL: f64 = 1e-11;
/// Eigenvalues this close (relative to the largest) are one repeated eigenvalue.
const SAME: f64 = 1e-9;
/// Inverse iteration's shift from a repeated eigenvalue (relative to the largest).
const SHIFT: f64 = 1e-10;
/// Samples whose outputs are formed by one product.
const CHUNK: usize = 256;

/// One diagonal block of `Λ` and of the step `e^{ΛΔt}`, row by row.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Block {
    /// A real eigenvalue `λ` and `e^{λΔt}`.
    Real { lambda: f64, step: f64 },
    /// A complex pair on the columns `[Re v, Im v]`.
    Pair { lambda: [f64; 4], step: [f64; 4] },
}

/// `e^{FΔt}` as `W e^{ΛΔt} W⁻¹`.
#[derive(Debug, Clone)]
pub struct ModalExponential {
    /// The real modal basis, in the original coordinates.
    w: Mat<f64>,
    /// `W`'s factors (balanced), for `W⁻¹ z₀`.
    lu: PartialPivLu<f64>,
    /// The balancing `D` (`W = D W_b`).
    d: Vec<f64>,
    blocks: Vec<Block>,
}

impl ModalExponential {
    /// The modal form of `f` over a step `dt`, or `None` where `f` has no well-conditioned
    /// eigenbasis.
    ///
    /// ```
    /// use edgekf_sim::linalg::free_response::ModalExponential;
    /// // A damped oscillator, ω = 10 rad/s, ζ = 0.1, released from x = 1.
    /// let f = faer::mat![[0.0, 1.0], [-100.0, -2.0]];
    /// let m = ModalExponential::of(f.as_ref(), 0.01).unwrap();
    /// let x = m.outputs(&[1.0, 0.0], faer::mat![[1.0, 0.0]].as_ref(), 101, &mut |_| {});
    /// let wd = (100.0f64 - 1.0).sqrt();
    /// let exact = (-1.0f64).exp() * (wd.cos() + wd.sin() / wd); // t = 1 s
    /// assert!((x[(100, 0)] - exact).abs() < 1e-13);
    /// ```
    pub fn of(f: MatRef<'_, f64>, dt: f64) -> Option<Self> {
        let n = f.nrows();
        if n == 0 || f.ncols() != n || !dt.is_finite() || !super::all_finite(f) {
            return None;
        }
        // Balanced first: the rotor's states mix metres, metres per second and newtons.
        let mut fb = f.to_owned();
        let d = balance(&mut fb);
        let evd = fb.eigen().ok()?;
        let mut values: Vec<c64> = evd.S().column_vector().iter().copied().collect();
        let mut u = evd.U().to_owned();
        // Identical parts of a system (two channels' equal low-passes) repeat an eigenvalue, and
        // the solver's vectors for it may be near-parallel: its eigenspace is spanned anew.
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
                let (basis, lambda) = eigenspace(fb.as_ref(), values[k], cluster.len(), scale)?;
                for (c, &j) in cluster.iter().enumerate() {
                    u.col_mut(j).copy_from(basis.col(c));
                    values[j] = lambda;
                }
            }
        }
        let mut w = Mat::<f64>::zeros(n, n);
        let mut blocks = Vec::with_capacity(n);
        let (mut column, mut above, mut below) = (0, 0usize, 0usize);
        for k in 0..n {
            let l = values[k];
            let size = if l.im > 0.0 { 2 } else { 1 };
            if l.im < 0.0 {
                below += 1;
                continue;
            } else if column + size > n {
                return None;
            }
            // Unit columns `Re v / |Re v|` and `Im v / |Im v|`.
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
            let decay = (l.re * dt).exp();
            if size == 1 {
                blocks.push(Block::Real { lambda: l.re, step: decay });
            } else {
                // `F [P Q] = [P Q] [[α, β/r], [−β r, α]]` with `r = |Im v| / |Re v|`, whose
                // exponential is `e^{αΔt} [[c, s/r], [−s r, c]]` (`c, s` of `βΔt`).
                let r = norm_im / norm_re;
                let (s, c) = (l.im * dt).sin_cos();
                blocks.push(Block::Pair {
                    lambda: [l.re, l.im / r, -l.im * r, l.re],
                    step: [decay * c, decay * s / r, -decay * s * r, decay * c],
                });
                above += 1;
            }
            column += size;
        }
        if column != n || above != below {
            return None;
        }
        let lu = w.partial_piv_lu();
        let condition = norm1(w.as_ref()) * inverse_norm1(&lu, n);
        if condition.is_nan() || condition > MAX_CONDITION {
            return None;
        }
        // `F W = W Λ` to rounding: the basis and the blocks describe `F`.
        let mut residual = super::mul(fb.as_ref(), w.as_ref());
        let mut at = 0;
        for block in &blocks {
            let (lambda, size): (&[f64], usize) = match block {
                Block::Real { lambda, .. } => (std::slice::from_ref(lambda), 1),
                Block::Pair { lambda, .. } => (lambda, 2),
            };
            for c in 0..size {
                for r in 0..size {
                    let l = lambda[r * size + c];
                    residual.col_mut(at + c).iter_mut().zip(w.col(at + r).iter()).for_each(|(x, v)| *x -= v * l);
                }
            }
            at += size;
        }
        let residual = residual.norm_l2();
        if residual.is_nan() || residual > MAX_RESIDUAL * fb.norm_l2() {
            return None;
        }
        // Balancing undone for the outputs: `W ← D W_b`.
        let mut plant = w;
        for (i, di) in d.iter().enumerate() {
            plant.row_mut(i).iter_mut().for_each(|v| *v *= di);
        }
        Some(Self { w: plant, lu, d, blocks })
    }

    /// `rows · z_k` for `k < samples`, `z_k = e^{F kΔt} z0`, as a `samples × rows` matrix (column
    /// `r` is output `r` over time). `progress` hears the samples done after each product.
    ///
    /// # Panics
    /// If `z0` or the rows are not as long as `F` is wide (a caller's error, not the data's).
    pub fn outputs(
        &self,
        z0: &[f64],
        rows: MatRef<'_, f64>,
        samples: usize,
        progress: &mut dyn FnMut(usize),
    ) -> Mat<f64> {
        let n = self.w.nrows();
        assert!(
            z0.len() == n && rows.ncols() == n,
            "free response: {n} states, z0 of {} and rows of {}",
            z0.len(),
            rows.ncols()
        );
        let r = super::mul(rows, self.w.as_ref());
        // `ξ₀ = W⁻¹ z₀ = W_b⁻¹ D⁻¹ z₀`.
        let scaled = Mat::<f64>::from_fn(n, 1, |i, _| z0[i] / self.d[i]);
        let mut xi: Vec<f64> = self.lu.solve(scaled).col(0).iter().copied().collect();
        let mut out = Mat::<f64>::zeros(samples, rows.nrows());
        let mut chunk = Mat::<f64>::zeros(n, CHUNK);
        let mut done = 0;
        while done < samples {
            let len = CHUNK.min(samples - done);
            for k in 0..len {
                chunk.col_mut(k).iter_mut().zip(&xi).for_each(|(c, v)| *c = *v);
                self.step(&mut xi);
            }
            let mut target = out.as_mut().subrows_mut(done, len);
            let modal = chunk.as_ref().subcols(0, len);
            faer::linalg::matmul::matmul(&mut target, Accum::Replace, modal.transpose(), r.transpose(), 1.0, Par::Seq);
            done += len;
            progress(done);
        }
        // Sample 0 is `z0` itself, exactly (a start from rest reads zero, not rounding).
        if samples > 0 {
            let start = Mat::<f64>::from_fn(n, 1, |i, _| z0[i]);
            let mut first = out.as_mut().subrows_mut(0, 1);
            faer::linalg::matmul::matmul(
                &mut first,
                Accum::Replace,
                start.transpose(),
                rows.transpose(),
                1.0,
                Par::Seq,
            );
        }
        out
    }

    /// `ξ ← e^{ΛΔt} ξ`.
    fn step(&self, xi: &mut [f64]) {
        let mut at = 0;
        for block in &self.blocks {
            match *block {
                Block::Real { step, .. } => {
                    xi[at] *= step;
                    at += 1;
                }
                Block::Pair { step: [a, b, c, d], .. } => {
                    let (p, q) = (xi[at], xi[at + 1]);
                    xi[at] = a * p + b * q;
                    xi[at + 1] = c * p + d * q;
                    at += 2;
                }
            }
        }
    }
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
mod tests {
    use super::*;

    #[test]
    fn a_jordan_block_has_no_modal_form() {
        // A free mass (a rigid-body mode: λ = 0 twice, one eigenvector) beside an oscillator.
        let f = faer::mat![[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], [0.0, 0.0, -4.0, -0.1]];
        assert!(ModalExponential::of(f.as_ref(), 0.01).is_none());
        // Damped, the same mass has two distinct real eigenvalues and a form.
        let f = faer::mat![[0.0, 1.0, 0.0, 0.0], [-1e-4, -1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], [0.0, 0.0, -4.0, -0.1]];
        assert!(ModalExponential::of(f.as_ref(), 0.01).is_some());
    }

    #[test]
    fn two_equal_oscillators_and_a_decay_follow_their_closed_forms() {
        // A repeated complex pair whose solver vectors serve, and a real eigenvalue, with states
        // of unequal scale (mm and m/s): x(t) = e^{−ζωt}(cos ω_d t + ζω/ω_d sin ω_d t), e^{−3t}.
        let (w, z) = (30.0f64, 0.02);
        let f = faer::mat![
            [0.0, 1e-3, 0.0, 0.0, 0.0],
            [-w * w * 1e3, -2.0 * z * w, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1e-3, 0.0],
            [0.0, 0.0, -w * w * 1e3, -2.0 * z * w, 0.0],
            [0.0, 0.0, 0.0, 0.0, -3.0],
        ];
        let m = ModalExponential::of(f.as_ref(), 1e-3).expect("a modal form");
        let rows = faer::mat![[1.0, 0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 2.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 1.0]];
        let mut heard = Vec::new();
        let y = m.outputs(&[1.0, 0.0, 0.5, 0.0, 1.0], rows.as_ref(), 2000, &mut |done| heard.push(done));
        assert_eq!(heard.last(), Some(&2000));
        let wd = w * (1.0 - z * z).sqrt();
        for k in [0, 1, 999, 1999] {
            let t = k as f64 * 1e-3;
            let x = (-z * w * t).exp() * ((wd * t).cos() + z * w / wd * (wd * t).sin());
            assert!((y[(k, 0)] - x).abs() < 1e-12, "{k}: {} vs {x}", y[(k, 0)]);
            assert!((y[(k, 1)] - x).abs() < 1e-12);
            assert!((y[(k, 2)] - (-3.0 * t).exp()).abs() < 1e-13);
        }
    }
}

#[cfg(test)]
mod accuracy {
    use super::*;

    #[test]
    fn a_stiff_non_normal_system_follows_its_closed_form_as_closely_as_the_transition_matrix() {
        // F = T D T⁻¹, D: lightly damped oscillators at 100 and 300 rad/s beside stiff ones at
        // 1e5–3e6 rad/s (the rotor's spread), T a random well-conditioned basis. Over 1000 steps
        // of 1 ms the slow modes' phase is where rounding in ‖F‖ would show.
        let freqs = [100.0f64, 300.0, 1e5, 1e6, 3e6];
        let n = 2 * freqs.len();
        let mut dm = Mat::<f64>::zeros(n, n);
        for (i, w) in freqs.iter().enumerate() {
            dm[(2 * i, 2 * i + 1)] = *w;
            dm[(2 * i + 1, 2 * i)] = -*w;
            dm[(2 * i, 2 * i)] = -1e-6 * w;
            dm[(2 * i + 1, 2 * i + 1)] = -1e-6 * w;
        }
        let mut seed = 1u64;
        let t = Mat::<f64>::from_fn(n, n, |i, j| {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            f64::from(u8::from(i == j)) * 2.0 + ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
        });
        let tinv = {
            use faer::linalg::solvers::DenseSolveCore;
            t.partial_piv_lu().inverse()
        };
        let f = super::super::mul(super::super::mul(t.as_ref(), dm.as_ref()).as_ref(), tinv.as_ref());
        let z0: Vec<f64> = (0..n).map(|i| 1.0 / (1.0 + i as f64)).collect();
        let rows = Mat::<f64>::identity(n, n);
        let dt = 1e-3;
        let samples = 1001;
        let modal = ModalExponential::of(f.as_ref(), dt).unwrap().outputs(&z0, rows.as_ref(), samples, &mut |_| {});
        let phi = super::super::expm((&f * dt).as_ref()).unwrap();
        let mut z = Mat::<f64>::from_fn(n, 1, |i, _| z0[i]);
        let mut dense = Mat::<f64>::zeros(samples, n);
        for k in 0..samples {
            for i in 0..n {
                dense[(k, i)] = z[(i, 0)];
            }
            z = super::super::mul(phi.as_ref(), z.as_ref());
        }
        // Truth: T e^{Dt} T⁻¹ z0, e^{Dt} in closed form.
        let y0 = super::super::mul(tinv.as_ref(), Mat::<f64>::from_fn(n, 1, |i, _| z0[i]).as_ref());
        for k in [10usize, 100, 1000] {
            let tt = k as f64 * dt;
            let mut y = Mat::<f64>::zeros(n, 1);
            for (i, w) in freqs.iter().enumerate() {
                let (s, c) = (w * tt).sin_cos();
                let e = (-1e-6 * w * tt).exp();
                y[(2 * i, 0)] = e * (c * y0[(2 * i, 0)] + s * y0[(2 * i + 1, 0)]);
                y[(2 * i + 1, 0)] = e * (-s * y0[(2 * i, 0)] + c * y0[(2 * i + 1, 0)]);
            }
            let truth = super::super::mul(t.as_ref(), y.as_ref());
            let em = (0..n).map(|i| (modal[(k, i)] - truth[(i, 0)]).abs()).fold(0.0, f64::max);
            let ed = (0..n).map(|i| (dense[(k, i)] - truth[(i, 0)]).abs()).fold(0.0, f64::max);
            eprintln!("step {k}: modal {em:.2e}, transition matrix {ed:.2e} from the closed form");
            assert!(em < 2e-10 && em < 3.0 * ed.max(1e-11), "step {k}: {em:e} against {ed:e}");
        }
    }
}
