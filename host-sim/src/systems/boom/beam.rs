//! The boom's finite-element model at one length: Euler–Bernoulli (Hermite) elements over the
//! current length, the root clamped to the turntable, the sections' stiffness and mass added up
//! where they overlap, the platform at the tip, and gravity's geometric stiffness.
//!
//! The transverse deflection `w(x)` is measured in the luffing plane from the boom's rigid axis,
//! which the turntable turns by φ. Per element, integrals are split at the section ends and
//! taken by 4-point Gauss–Legendre, exact for the piecewise-constant properties. Degrees of
//! freedom: `[w₁ w₁' … w_n w_n']` (node 0, the root, is clamped).

use super::config::BoomConfig;
use nalgebra::{DMatrix, DVector};

/// 4-point Gauss–Legendre nodes and weights on [0, 1].
const GAUSS: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
    (0.330_009_478_207_571_87, 0.326_072_577_431_273_07),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
];

/// The matrices of the boom at one length.
#[derive(Debug, Clone)]
pub struct BeamMatrices {
    /// Length, m.
    pub length: f64,
    /// Mass.
    pub m: DMatrix<f64>,
    /// Elastic stiffness.
    pub k: DMatrix<f64>,
    /// Geometric stiffness of the axial load at unit `g sin φ` (add `g sin φ · kg`): gravity
    /// along the raised boom compresses it and softens it.
    pub kg: DMatrix<f64>,
    /// Inertial load per unit luffing acceleration, `∫ m x N dx` plus the platform's: the load is
    /// `−r φ̈`.
    pub r: DVector<f64>,
    /// Mass distribution, `∫ m N dx` plus the platform's: gravity's load is `−g cos φ · gm`.
    pub gm: DVector<f64>,
    /// Total mass of the boom and platform, kg.
    pub mass: f64,
}

impl BeamMatrices {
    /// Degrees of freedom.
    pub fn dofs(&self) -> usize {
        self.m.nrows()
    }

    /// Index of the tip's deflection (its slope follows).
    pub fn tip(&self) -> usize {
        self.dofs() - 2
    }
}

/// Where each section starts at boom length `length`, m from the root (synchronous extension).
///
/// ```
/// use edgekf_sim::systems::boom::{beam::section_starts, BoomConfig};
/// let c = BoomConfig::default();
/// let s = section_starts(&c, 30.0);
/// let top = c.section.last().unwrap().length;
/// assert!((s[3] + top - 30.0).abs() < 1e-12 && s[0] == 0.0);
/// ```
pub fn section_starts(config: &BoomConfig, length: f64) -> Vec<f64> {
    let n = config.section.len();
    let top = config.section.last().map_or(0.0, |s| s.length);
    let e = if n > 1 { (length - top).max(0.0) / (n - 1) as f64 } else { 0.0 };
    (0..n).map(|k| k as f64 * e).collect()
}

/// Hermite shape functions on an element of length `h` at `ξ ∈ [0, 1]`: values, slopes and
/// curvatures.
fn shapes(xi: f64, h: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    let (x2, x3) = (xi * xi, xi * xi * xi);
    let n = [1.0 - 3.0 * x2 + 2.0 * x3, h * (xi - 2.0 * x2 + x3), 3.0 * x2 - 2.0 * x3, h * (x3 - x2)];
    let d = [(6.0 * x2 - 6.0 * xi) / h, 1.0 - 4.0 * xi + 3.0 * x2, (6.0 * xi - 6.0 * x2) / h, 3.0 * x2 - 2.0 * xi];
    let c = [(12.0 * xi - 6.0) / (h * h), (6.0 * xi - 4.0) / h, (6.0 - 12.0 * xi) / (h * h), (6.0 * xi - 2.0) / h];
    (n, d, c)
}

/// Assembles the boom of `config` at `length` m.
pub fn assemble(config: &BoomConfig, length: f64) -> BeamMatrices {
    let ne = config.boom.elements;
    let h = length / ne as f64;
    let starts = section_starts(config, length);
    let sections: Vec<(f64, f64, f64, f64)> = config
        .section
        .iter()
        .zip(&starts)
        .map(|(s, &a)| (a, (a + s.length).min(length), s.ei, s.mass_per_length))
        .collect();
    let props = |x: f64| {
        sections.iter().filter(|(a, b, _, _)| x >= *a && x < *b).fold((0.0, 0.0), |(ei, m), s| (ei + s.2, m + s.3))
    };
    // Mass beyond x (for the axial load), from the sections' ends.
    let mass_beyond = |x: f64| -> f64 {
        sections.iter().map(|(a, b, _, m)| m * (b - a.max(x)).max(0.0)).sum::<f64>() + config.tip.mass
    };
    // Breakpoints where properties jump.
    let mut cuts: Vec<f64> = sections.iter().flat_map(|(a, b, _, _)| [*a, *b]).collect();
    cuts.sort_by(f64::total_cmp);
    let dofs = 2 * ne;
    let mut m = DMatrix::zeros(dofs, dofs);
    let mut k = DMatrix::zeros(dofs, dofs);
    let mut kg = DMatrix::zeros(dofs, dofs);
    let mut r = DVector::zeros(dofs);
    let mut gm = DVector::zeros(dofs);
    for e in 0..ne {
        let (x0, x1) = (e as f64 * h, (e + 1) as f64 * h);
        let mut pieces = vec![x0];
        pieces.extend(cuts.iter().copied().filter(|c| *c > x0 + 1e-12 && *c < x1 - 1e-12));
        pieces.push(x1);
        let mut me = [[0.0; 4]; 4];
        let mut ke = [[0.0; 4]; 4];
        let mut ge = [[0.0; 4]; 4];
        let (mut re, mut gme) = ([0.0; 4], [0.0; 4]);
        for w in pieces.windows(2) {
            let (a, b) = (w[0], w[1]);
            let mid = 0.5 * (a + b);
            let (ei, mu) = props(mid);
            for (g, wt) in GAUSS {
                let x = a + g * (b - a);
                let wx = wt * (b - a);
                let (n, d, c) = shapes((x - x0) / h, h);
                // Axial force: compression by `g sin φ` per unit of the mass beyond (factor 1).
                let p = -mass_beyond(x);
                for i in 0..4 {
                    re[i] += wx * mu * x * n[i];
                    gme[i] += wx * mu * n[i];
                    for j in 0..4 {
                        me[i][j] += wx * mu * n[i] * n[j];
                        ke[i][j] += wx * ei * c[i] * c[j];
                        ge[i][j] += wx * p * d[i] * d[j];
                    }
                }
            }
        }
        // Element DOFs: node e (w, w') and node e + 1; node 0 is clamped.
        let map = |i: usize| -> Option<usize> {
            let global = 2 * e + i;
            global.checked_sub(2)
        };
        for i in 0..4 {
            let Some(gi) = map(i) else { continue };
            r[gi] += re[i];
            gm[gi] += gme[i];
            for j in 0..4 {
                let Some(gj) = map(j) else { continue };
                m[(gi, gj)] += me[i][j];
                k[(gi, gj)] += ke[i][j];
                kg[(gi, gj)] += ge[i][j];
            }
        }
    }
    let tip = dofs - 2;
    m[(tip, tip)] += config.tip.mass;
    m[(tip + 1, tip + 1)] += config.tip.rotary_inertia;
    r[tip] += config.tip.mass * length;
    r[tip + 1] += config.tip.rotary_inertia;
    gm[tip] += config.tip.mass;
    let mass = sections.iter().map(|(a, b, _, m)| m * (b - a)).sum::<f64>() + config.tip.mass;
    BeamMatrices { length, m, k, kg, r, gm, mass }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::systems::boom::config::{BoomTable, Section, Tip};

    /// One 10 m section (EI 1e7 N·m², 20 kg/m) in `elements` elements, a point mass at the tip.
    pub(crate) fn uniform(elements: usize, tip_mass: f64) -> BoomConfig {
        BoomConfig {
            section: vec![Section { length: 10.0, ei: 1e7, mass_per_length: 20.0 }],
            boom: BoomTable { elements, ..BoomTable::default() },
            tip: Tip { mass: tip_mass, rotary_inertia: 0.0 },
            ..BoomConfig::default()
        }
    }

    #[test]
    fn a_uniform_cantilever_sags_as_beam_theory_says() {
        // Tip deflection under its own weight q: q L⁴ / 8EI; under a tip load P: P L³ / 3EI.
        let c = uniform(10, 50.0);
        let b = assemble(&c, 10.0);
        let chol = b.k.clone().cholesky().unwrap();
        let sag = chol.solve(&(&b.gm * 9.81));
        let (q, p, l, ei): (f64, f64, f64, f64) = (20.0 * 9.81, 50.0 * 9.81, 10.0, 1e7);
        let expected = q * l.powi(4) / (8.0 * ei) + p * l.powi(3) / (3.0 * ei);
        assert!((sag[b.tip()] / expected - 1.0).abs() < 1e-9, "{} against {expected}", sag[b.tip()]);
        assert!((b.mass - 250.0).abs() < 1e-9);
        // The rigid rotation's inertia: r · 1 over the deflections is ∫ m x dx + M L.
        let first_moment: f64 = (0..b.dofs()).step_by(2).map(|i| b.r[i]).sum();
        assert!(first_moment > 0.0);
    }

    #[test]
    fn overlapping_sections_add_their_stiffness() {
        let c = BoomConfig {
            section: vec![
                Section { length: 6.0, ei: 2e7, mass_per_length: 30.0 },
                Section { length: 6.0, ei: 1e7, mass_per_length: 20.0 },
            ],
            ..uniform(12, 0.0)
        };
        // At 9 m the second section starts at 3 m: 3 m of overlap.
        assert_eq!(section_starts(&c, 9.0), vec![0.0, 3.0]);
        let b = assemble(&c, 9.0);
        assert!((b.mass - (6.0 * 30.0 + 6.0 * 20.0)).abs() < 1e-9);
        // Unit tip load against the closed form of a stepped cantilever (EI 2e7 on [0,3),
        // 3e7 on [3,6), 1e7 on [6,9]): δ = ∫ (L − x)² / EI(x) dx.
        let seg = |a: f64, b: f64, ei: f64| ((9.0 - a).powi(3) - (9.0 - b).powi(3)) / (3.0 * ei);
        let expected = seg(0.0, 3.0, 2e7) + seg(3.0, 6.0, 3e7) + seg(6.0, 9.0, 1e7);
        let mut f = DVector::zeros(b.dofs());
        f[b.tip()] = 1.0;
        let d = b.k.clone().cholesky().unwrap().solve(&f);
        assert!((d[b.tip()] / expected - 1.0).abs() < 1e-9, "{} against {expected}", d[b.tip()]);
    }
}
