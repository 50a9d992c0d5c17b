//! The free response `z_k = e^{F kΔt} z_0` of a linear time-invariant system, read through output
//! rows, by the eigen decomposition of `F` instead of the transition matrix.
//!
//! Why: stepping `z_{k+1} = Φ z_k` with a dense `Φ` costs `O(n²)` a sample, and for the
//! full rotor (~300 states) `Φ` (740 kB) does not fit a core's cache, so every sample streams it
//! from memory. In the real modal form `F = W Λ W⁻¹` (1×1 blocks for real eigenvalues, 2×2
//! rotation–scaling blocks for complex pairs) a sample's step is `O(n)`, and the outputs of a
//! few hundred samples at once are one matrix product `R Ξ` (`R = rows · W`), which runs at the
//! processor's arithmetic speed. `e^{λΔt}` is taken per eigenvalue in closed form, so the step is
//! as exact as the eigenvectors: the basis is [`super::modal_basis`]'s, which is accepted only if
//! it is well-conditioned and reproduces `F`; [`ModalExponential::of`] returns `None` otherwise (a
//! Jordan block, such as a free rotor's rigid-body modes, or near-parallel eigenvectors), where
//! the caller keeps the transition matrix.

use super::modal_basis::{Block, ModalBasis};
use faer::{Accum, Mat, MatRef, Par};

/// `W` may amplify rounding by at most this much (`‖W‖₁ ‖W⁻¹‖₁`, unit columns, balanced). Looser
/// than the residual loop's filter (1e6): the full rotor's ~300-state basis needs it, and here
/// `W⁻¹` is applied once (to `z₀`) and `W` once per output, so its condition enters the
/// response once, where the filter carries covariances through `W` and `W⁻¹` every segment.
const MAX_CONDITION: f64 = 1e7;
/// Samples whose outputs are formed by one product.
const CHUNK: usize = 256;

/// `e^{FΔt}` as `W e^{ΛΔt} W⁻¹`.
#[derive(Debug, Clone)]
pub struct ModalExponential {
    /// The real modal basis (`W`, its factors, the blocks of `Λ`).
    basis: ModalBasis,
    /// `W` in the original coordinates.
    w: Mat<f64>,
    /// `e^{ΛΔt}`'s blocks, row by row (the first entry alone for a real eigenvalue).
    steps: Vec<[f64; 4]>,
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
        if !dt.is_finite() {
            return None;
        }
        let basis = ModalBasis::of(f, MAX_CONDITION)?;
        let steps = basis
            .blocks
            .iter()
            .map(|block| match *block {
                Block::Real(lambda) => [(lambda * dt).exp(), 0.0, 0.0, 0.0],
                Block::Pair { re, im, r } => {
                    // `[[α, β/r], [−β r, α]]`'s exponential is `e^{αΔt} [[c, s/r], [−s r, c]]`
                    // (`c, s` of `βΔt`).
                    let decay = (re * dt).exp();
                    let (s, c) = (im * dt).sin_cos();
                    [decay * c, decay * s / r, -decay * s * r, decay * c]
                }
            })
            .collect();
        Some(Self { w: basis.w(), basis, steps })
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
        let mut xi = self.basis.solve(z0);
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
        for (block, step) in self.basis.blocks.iter().zip(&self.steps) {
            if block.size() == 1 {
                xi[at] *= step[0];
            } else {
                let (p, q) = (xi[at], xi[at + 1]);
                xi[at] = step[0] * p + step[1] * q;
                xi[at + 1] = step[2] * p + step[3] * q;
            }
            at += block.size();
        }
    }
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
