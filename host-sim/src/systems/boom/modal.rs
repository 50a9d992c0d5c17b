//! Natural frequencies of the boom at one length and luffing angle, and the Rayleigh damping
//! `C = a M + b K` that gives modes 1 and 2 their configured damping ratios there.

use super::beam::BeamMatrices;
use anyhow::{anyhow, Result};
use nalgebra::{DMatrix, DVector, SymmetricEigen};

/// The stiffness at luffing angle `phi`: elastic plus gravity's geometric part.
pub fn stiffness(b: &BeamMatrices, gravity: f64, phi: f64) -> DMatrix<f64> {
    &b.k + &b.kg * (gravity * phi.sin())
}

/// Natural frequencies, rad/s, ascending (`K x = ω² M x` with `M = L Lᵀ`).
pub fn frequencies(b: &BeamMatrices, gravity: f64, phi: f64) -> Result<Vec<f64>> {
    let l = b.m.clone().cholesky().ok_or_else(|| anyhow!("the mass matrix is not positive definite"))?.l();
    let l_inv = l.clone().try_inverse().ok_or_else(|| anyhow!("the mass matrix is singular"))?;
    let a = &l_inv * stiffness(b, gravity, phi) * l_inv.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let mut w2: Vec<f64> = SymmetricEigen::new(a).eigenvalues.iter().copied().collect();
    w2.sort_by(f64::total_cmp);
    if w2[0] <= 0.0 {
        return Err(anyhow!("the boom buckles under its own weight at {:.2} m (ω² = {:.3e})", b.length, w2[0]));
    }
    Ok(w2.into_iter().map(f64::sqrt).collect())
}

/// The first mode's shape (mass-normalised, its tip deflection positive) and frequency, rad/s.
pub fn first_mode(b: &BeamMatrices, gravity: f64, phi: f64) -> Result<(f64, DVector<f64>)> {
    let l = b.m.clone().cholesky().ok_or_else(|| anyhow!("the mass matrix is not positive definite"))?.l();
    let l_inv = l.clone().try_inverse().ok_or_else(|| anyhow!("the mass matrix is singular"))?;
    let a = &l_inv * stiffness(b, gravity, phi) * l_inv.transpose();
    let eig = SymmetricEigen::new((&a + a.transpose()) * 0.5);
    let i = (0..eig.eigenvalues.len()).min_by(|&x, &y| eig.eigenvalues[x].total_cmp(&eig.eigenvalues[y])).unwrap_or(0);
    let w2 = eig.eigenvalues[i];
    if w2 <= 0.0 {
        return Err(anyhow!("the boom buckles under its own weight at {:.2} m", b.length));
    }
    let mut shape = l_inv.transpose() * eig.eigenvectors.column(i);
    if shape[b.tip()] < 0.0 {
        shape = -shape;
    }
    Ok((w2.sqrt(), shape))
}

/// Rayleigh coefficients `(a, b)` with `ζᵢ = a/(2ωᵢ) + b ωᵢ/2` for the first two modes.
///
/// ```
/// use edgekf_sim::systems::boom::modal::rayleigh;
/// let (a, b) = rayleigh([2.0, 10.0], [0.015, 0.02]);
/// assert!((a / 4.0 + b * 1.0 - 0.015).abs() < 1e-15 && (a / 20.0 + b * 5.0 - 0.02).abs() < 1e-15);
/// ```
pub fn rayleigh(w: [f64; 2], zeta: [f64; 2]) -> (f64, f64) {
    let [w1, w2] = w;
    let [z1, z2] = zeta;
    let b = 2.0 * (z2 * w2 - z1 * w1) / (w2 * w2 - w1 * w1);
    let a = 2.0 * z1 * w1 - b * w1 * w1;
    (a, b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::systems::boom::beam::{assemble, tests::uniform};
    use crate::systems::boom::config::BoomConfig;
    use std::f64::consts::PI;

    #[test]
    fn a_uniform_cantilever_has_the_closed_form_frequencies() {
        // Clamped-free: ωᵢ = (βᵢL)² √(EI / m L⁴), βL = 1.875104, 4.694091, 7.854757.
        let c = uniform(20, 0.0);
        let w = frequencies(&assemble(&c, 10.0), 9.81, 0.0).unwrap();
        let scale = (1e7f64 / (20.0 * 1e4)).sqrt();
        for (wi, bl) in w.iter().zip([1.875_104_068_7, 4.694_091_132_9, 7.854_757_438_2]) {
            assert!((wi / (bl * bl * scale) - 1.0).abs() < 1e-4, "{wi} against {}", bl * bl * scale);
        }
        // Raised, its own weight compresses it: the first mode drops (Greenhill's column).
        let raised = frequencies(&assemble(&c, 10.0), 9.81, PI / 2.0).unwrap();
        assert!(raised[0] < w[0] && raised[0] > 0.95 * w[0], "{} against {}", raised[0], w[0]);
    }

    #[test]
    fn the_ladder_s_first_mode_is_near_0_7_hz_at_30_m() {
        let c = BoomConfig::default();
        let w = frequencies(&assemble(&c, 30.0), c.boom.gravity, c.runs.start_angle).unwrap();
        let f = [w[0] / (2.0 * PI), w[1] / (2.0 * PI)];
        assert!((0.6..0.8).contains(&f[0]), "{f:?} Hz");
        let short = frequencies(&assemble(&c, 18.0), c.boom.gravity, c.runs.start_angle).unwrap();
        assert!(short[0] > 1.5 * w[0], "shorter is stiffer: {} against {}", short[0], w[0]);
        println!("ladder: modes 1, 2 at 30 m: {:.3}, {:.3} Hz; at 18 m: {:.3} Hz", f[0], f[1], short[0] / (2.0 * PI));
    }
}
