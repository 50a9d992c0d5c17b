//! The basis against a dense matrix exponential: `W e^{ΛΔt} W⁻¹` (the blocks' exponentials in
//! closed form, as the free response takes them) must equal nalgebra's `exp(A Δt)`, computed
//! without any eigenvectors, on the kinds of matrix that make a modal basis hard.

use super::*;
use nalgebra::DMatrix;

/// `W e^{ΛΔt} W⁻¹` through the basis.
fn modal_exponential(basis: &ModalBasis, dt: f64) -> Mat<f64> {
    let n = basis.d.len();
    let mut e = Mat::<f64>::zeros(n, n);
    let mut at = 0;
    for block in &basis.blocks {
        match *block {
            Block::Real(l) => e[(at, at)] = (l * dt).exp(),
            Block::Pair { re, im, r } => {
                let (s, c) = (im * dt).sin_cos();
                let decay = (re * dt).exp();
                e[(at, at)] = decay * c;
                e[(at, at + 1)] = decay * s / r;
                e[(at + 1, at)] = -decay * s * r;
                e[(at + 1, at + 1)] = decay * c;
            }
        }
        at += block.size();
    }
    super::super::mul(super::super::mul(basis.w().as_ref(), e.as_ref()).as_ref(), basis.w_inv().as_ref())
}

/// `‖W e^{ΛΔt} W⁻¹ − exp(AΔt)‖_F / ‖exp(AΔt)‖_F`, the dense one by nalgebra.
fn error_against_dense(a: &Mat<f64>, basis: &ModalBasis, dt: f64) -> f64 {
    let n = a.nrows();
    let dense = (DMatrix::from_fn(n, n, |i, j| a[(i, j)]) * dt).exp();
    let modal = modal_exponential(basis, dt);
    let error = DMatrix::from_fn(n, n, |i, j| modal[(i, j)] - dense[(i, j)]).norm();
    error / dense.norm()
}

/// `T D T⁻¹`, `T = 2I + noise` (a fixed, well-conditioned, non-orthogonal basis).
fn similar(d: &Mat<f64>, seed: u64) -> Mat<f64> {
    let n = d.nrows();
    let mut seed = seed;
    let t = Mat::<f64>::from_fn(n, n, |i, j| {
        seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        f64::from(u8::from(i == j)) * 2.0 + ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
    });
    let t_inv = t.partial_piv_lu().inverse();
    super::super::mul(super::super::mul(t.as_ref(), d.as_ref()).as_ref(), t_inv.as_ref())
}

/// Block diagonal: a damped oscillator `[[0, ω], [−ω, −2ζω]]` (position and velocity over ω)
/// per `(ω, ζ)`, then decays.
fn oscillators(modes: &[(f64, f64)], decays: &[f64]) -> Mat<f64> {
    let n = 2 * modes.len() + decays.len();
    let mut d = Mat::<f64>::zeros(n, n);
    for (i, &(w, z)) in modes.iter().enumerate() {
        d[(2 * i, 2 * i + 1)] = w;
        d[(2 * i + 1, 2 * i)] = -w;
        d[(2 * i + 1, 2 * i + 1)] = -2.0 * z * w;
    }
    for (i, &l) in decays.iter().enumerate() {
        d[(2 * modes.len() + i, 2 * modes.len() + i)] = l;
    }
    d
}

#[test]
fn a_stiff_system_matches_the_dense_exponential() {
    // Eigenvalues from 0.5 to 3e4 in magnitude (a span of 6e4): slow and fast oscillators and
    // decays, mixed by a non-orthogonal basis.
    let a = similar(&oscillators(&[(10.0, 0.05), (3e4, 0.01), (700.0, 0.2)], &[-0.5, -1e4, -30.0]), 7);
    let basis = ModalBasis::of(a.as_ref(), 1e6).expect("a modal basis");
    for dt in [1e-5, 1e-3] {
        let error = error_against_dense(&a, &basis, dt);
        eprintln!("stiff, Δt = {dt:e}: {error:.1e}");
        assert!(error < 1e-12, "Δt = {dt:e}: {error:e}");
    }
}

#[test]
fn a_non_normal_system_matches_the_dense_exponential() {
    // Strong one-way coupling (1e4 from a slow decay into a fast one, 3e3 from an oscillator
    // into a decay): the eigenvectors are far from orthogonal before balancing.
    let mut a = oscillators(&[(5.0, 0.1)], &[-1.0, -2.0, -200.0]);
    a[(2, 3)] = 1e4;
    a[(2, 0)] = 3e3;
    a[(4, 1)] = -5e2;
    a[(4, 2)] = 1e3;
    let basis = ModalBasis::of(a.as_ref(), 1e6).expect("a modal basis");
    for dt in [1e-3, 0.1] {
        let error = error_against_dense(&a, &basis, dt);
        eprintln!("non-normal, Δt = {dt:e}: {error:.1e}");
        assert!(error < 1e-12, "Δt = {dt:e}: {error:e}");
    }
}

#[test]
fn repeated_eigenvalues_match_the_dense_exponential() {
    // Two equal oscillators and two equal decays, mixed: each repeated eigenvalue's eigenspace
    // is spanned by inverse iteration.
    let a = similar(&oscillators(&[(30.0, 0.02), (30.0, 0.02)], &[-3.0, -3.0, -0.1]), 11);
    let basis = ModalBasis::of(a.as_ref(), 1e6).expect("a modal basis");
    let sizes: Vec<usize> = basis.blocks.iter().map(Block::size).collect();
    assert_eq!(sizes.iter().filter(|&&s| s == 2).count(), 2);
    for dt in [1e-3, 0.05] {
        let error = error_against_dense(&a, &basis, dt);
        eprintln!("repeated, Δt = {dt:e}: {error:.1e}");
        assert!(error < 1e-12, "Δt = {dt:e}: {error:e}");
    }
}

#[test]
fn a_jordan_block_is_refused_where_its_blocks_would_be_inaccurate() {
    // A double integrator (λ = 0 twice, one eigenvector) and a repeated decay with one
    // eigenvector (`[[−1, 1], [0, −1]]`), each beside an oscillator: no eigenbasis.
    let mut free = oscillators(&[(4.0, 0.05)], &[0.0, 0.0]);
    free[(2, 3)] = 1.0;
    let mut decay = oscillators(&[(4.0, 0.05)], &[-1.0, -1.0]);
    decay[(2, 3)] = 1.0;
    // As they stand the solver returns the eigenvalue twice; its spanned eigenspace misses
    // `A W = W Λ`, at any condition limit.
    for a in [&free, &decay] {
        assert!(ModalBasis::of(a.as_ref(), 1e12).is_none());
    }
    // Mixed, rounding may split the eigenvalue into two real ones ~1e-8 apart (which way is the
    // solver's rounding, fixed for these bases): their vectors are near-parallel, condition
    // ~1e8, over either caller's limit (1e6, 1e7). A basis accepted anyway is off by ~5e-9.
    for a in [similar(&free, 9), similar(&decay, 9)] {
        assert!(ModalBasis::of(a.as_ref(), 1e7).is_none());
        let loose = ModalBasis::of(a.as_ref(), 1e9).expect("a basis at a loose limit");
        assert!(error_against_dense(&a, &loose, 0.1) > 1e-10);
    }
    // Or into a complex pair `α ± iβ`, β ~ 1e-9: then the pair's block `[[α, β/r], [−βr, α]]`
    // (r ~ 1e-8) is the Jordan block itself, on a well-conditioned real basis, and exact.
    for a in [similar(&free, 3), similar(&decay, 5)] {
        let basis = ModalBasis::of(a.as_ref(), 1e6).expect("the Jordan block as a pair's block");
        let error = error_against_dense(&a, &basis, 0.1);
        eprintln!("a Jordan block as a pair's block: {error:.1e}");
        assert!(error < 1e-14, "{error:e}");
    }
    // Non-finite and non-square matrices have none either.
    assert!(ModalBasis::of(faer::mat![[f64::NAN]].as_ref(), 1e6).is_none());
    assert!(ModalBasis::of(Mat::<f64>::zeros(2, 3).as_ref(), 1e6).is_none());
}

#[test]
fn the_inverse_and_the_solve_agree() {
    let a = similar(&oscillators(&[(2.0, 0.3)], &[-4.0]), 13);
    let basis = ModalBasis::of(a.as_ref(), 1e6).expect("a modal basis");
    let z = [1.0, -2.0, 0.5];
    let by_inverse = super::super::mul(basis.w_inv().as_ref(), Mat::from_fn(3, 1, |i, _| z[i]).as_ref());
    for (i, v) in basis.solve(&z).iter().enumerate() {
        assert!((v - by_inverse[(i, 0)]).abs() < 1e-14 * (1.0 + v.abs()));
    }
}
