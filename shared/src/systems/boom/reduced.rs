//! The boom's reduced model for the estimators: Rayleigh–Ritz on [`BASIS`] static deflection
//! shapes of the boom itself (under a tip force, a tip moment, and loads growing as 1, ξ and ξ²
//! along it), each integrated exactly from `M / EI` over the pieces where the sections
//! overlap, so the shapes carry the stiffness steps a global polynomial cannot. With the
//! platform and gravity's geometric stiffness, it gives the first [`MODES`] modes at one length
//! and luffing angle: frequency, the tip's deflection and slope per unit modal coordinate, the
//! luffing load's participation, and the gravity sag at the tip.
//!
//! This is not the host's reference (finite elements with Hermite shape functions): the two
//! agree where they should, which the host's tests check.

use crate::Real;
use nalgebra::{SMatrix, SVector};

/// Polynomials in the Ritz basis.
pub const BASIS: usize = 5;
/// Modes kept.
pub const MODES: usize = 3;
/// Most sections a boom may have.
pub const MAX_SECTIONS: usize = 8;

/// One section, from the root up (each slides out of the one below, synchronously).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoomSection {
    /// Length, m.
    pub length: f64,
    /// Bending stiffness, N·m².
    pub ei: f64,
    /// Mass per length, kg/m.
    pub mass_per_length: f64,
}

/// The boom's constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoomConstants {
    /// Sections, root first (`count` of them are used).
    pub sections: [BoomSection; MAX_SECTIONS],
    /// Sections in use.
    pub count: usize,
    /// Platform mass, kg.
    pub tip_mass: f64,
    /// Platform rotary inertia, kg·m².
    pub tip_inertia: f64,
    /// Gravitational acceleration, m/s².
    pub gravity: f64,
}

/// One mode of the reduced boom.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mode {
    /// Natural frequency, rad/s.
    pub omega: f64,
    /// Tip deflection per unit modal coordinate (mass-normalised), m.
    pub tip_deflection: f64,
    /// Tip slope per unit modal coordinate, rad.
    pub tip_slope: f64,
    /// Participation of the luffing acceleration: `η̈ + … = −participation · φ̈`.
    pub participation: f64,
}

/// The reduced boom at one length and angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReducedBoom {
    /// Length, m.
    pub length: f64,
    /// The first [`MODES`] modes, ascending.
    pub modes: [Mode; MODES],
    /// The gravity sag's tip deflection (m) and slope (rad).
    pub sag: (f64, f64),
}

/// Why a reduced boom cannot be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReducedError {
    /// No section, too many, or a length, stiffness or mass that is not positive.
    Constants,
    /// The mass matrix is not positive definite or the boom buckles under its own weight.
    Singular,
}

/// Coefficients of a polynomial in ξ, lowest first.
type Poly = [f64; DEGREE + 1];
/// Highest degree the products need (a shape is of degree 6, products of two 12).
const DEGREE: usize = 13;
/// Most pieces: every section's two ends, and the tip.
const MAX_PIECES: usize = 2 * MAX_SECTIONS + 1;

fn eval(p: &Poly, x: f64) -> f64 {
    p.iter().rev().fold(0.0, |acc, c| acc * x + c)
}

/// Index of the highest non-zero coefficient (0 for the zero polynomial).
fn degree(p: &Poly) -> usize {
    p.iter().rposition(|c| *c != 0.0).unwrap_or(0)
}

fn mul(a: &Poly, b: &Poly) -> Poly {
    let mut out = [0.0; DEGREE + 1];
    // Only up to each factor's degree: the shapes are of degree 6 in a basis of 14.
    let (da, db) = (degree(a), degree(b));
    for (i, ai) in a.iter().enumerate().take(da + 1) {
        if *ai == 0.0 {
            continue;
        }
        for (j, bj) in b.iter().enumerate().take(db + 1) {
            if let Some(o) = out.get_mut(i + j) {
                *o += ai * bj;
            }
        }
    }
    out
}

fn scale(p: &Poly, s: f64) -> Poly {
    p.map(|c| c * s)
}

fn deriv(p: &Poly) -> Poly {
    let mut out = [0.0; DEGREE + 1];
    for i in 1..=DEGREE {
        out[i - 1] = p[i] * i as f64;
    }
    out
}

/// The antiderivative that is `at_a` at `a`.
fn antiderivative(p: &Poly, a: f64, at_a: f64) -> Poly {
    let mut out = [0.0; DEGREE + 1];
    for i in 0..DEGREE {
        out[i + 1] = p[i] / (i + 1) as f64;
    }
    out[0] = at_a - eval(&out, a);
    out
}

/// `∫ p dξ` over `[a, b]`.
fn integral(p: &Poly, a: f64, b: f64) -> f64 {
    let q = antiderivative(p, 0.0, 0.0);
    eval(&q, b) - eval(&q, a)
}

/// The bending moment (per unit load, lengths in units of l) of the basis's loads: a tip force,
/// a tip moment, and distributed loads 1, ξ, ξ² (`M(ξ) = ∫_ξ^1 (s − ξ) q(s) ds`).
fn moment_of_load(j: usize) -> Poly {
    let mut p = [0.0; DEGREE + 1];
    match j {
        0 => (p[0], p[1]) = (1.0, -1.0),
        1 => p[0] = 1.0,
        // A load ξⁿ (n = j − 2): M = 1/(n+2) − ξ/(n+1) + ξⁿ⁺²/((n+1)(n+2)).
        _ => {
            let n = (j - 2) as f64;
            p[0] = 1.0 / (n + 2.0);
            p[1] = -1.0 / (n + 1.0);
            if let Some(c) = p.get_mut(j) {
                *c += 1.0 / ((n + 1.0) * (n + 2.0));
            }
        }
    }
    p
}

impl BoomConstants {
    /// Where each section starts at `length`, m (synchronous extension).
    fn starts(&self, length: f64) -> [f64; MAX_SECTIONS] {
        let n = self.count;
        let top = self.sections.get(n.wrapping_sub(1)).map_or(0.0, |s| s.length);
        let e = if n > 1 { (length - top).max(0.0) / (n - 1) as f64 } else { 0.0 };
        let mut s = [0.0; MAX_SECTIONS];
        for (k, v) in s.iter_mut().enumerate().take(n) {
            *v = k as f64 * e;
        }
        s
    }

    /// The reduced boom at `length` m and luffing angle `phi` rad.
    ///
    /// ```
    /// use edgekf::systems::boom::{BoomConstants, BoomSection};
    /// // One uniform 10 m section: clamped-free, ω₁ = 1.875² √(EI / m L⁴).
    /// let s = BoomSection { length: 10.0, ei: 1e7, mass_per_length: 20.0 };
    /// let c = BoomConstants { sections: [s; 8], count: 1, tip_mass: 0.0, tip_inertia: 0.0, gravity: 9.81 };
    /// let b = c.reduce(10.0, 0.0).unwrap();
    /// let exact = 1.875_104_068_7f64.powi(2) * (1e7f64 / (20.0 * 1e4)).sqrt();
    /// assert!((b.modes[0].omega / exact - 1.0).abs() < 1e-4);
    /// // Its sag under its own weight, q L⁴ / 8 EI, downwards.
    /// assert!((b.sag.0 + 20.0 * 9.81 * 1e4 / 8e7).abs() < 1e-6);
    /// ```
    pub fn reduce(&self, length: f64, phi: f64) -> Result<ReducedBoom, ReducedError> {
        let n = self.count;
        if n == 0 || n > MAX_SECTIONS || !(length.is_finite() && length > 0.0) {
            return Err(ReducedError::Constants);
        }
        if self.sections[..n].iter().any(|s| !(s.length > 0.0 && s.ei > 0.0 && s.mass_per_length > 0.0)) {
            return Err(ReducedError::Constants);
        }
        let l = length;
        let (pieces, np) = self.pieces(&self.sections[..n], l)?;
        let pieces = pieces.get(..np).unwrap_or(&[]);
        let shape = shapes(pieces, np)?;
        let m = self.assemble(pieces, &shape, np, l, phi);
        let modes = m.modes()?;
        // Sag: K c = −g cos φ gm.
        let kchol = crate::linalg::cholesky(&m.kk).ok_or(ReducedError::Singular)?;
        let f = m.gm * (-self.gravity * libm::cos(phi));
        let c = crate::linalg::solve_lower_transposed(&kchol, &crate::linalg::solve_lower(&kchol, &f));
        Ok(ReducedBoom { length, modes, sag: m.tip_values(&c) })
    }

    /// The pieces of a boom of length `l` between the ends of every one of `sections` (the
    /// first `count`, checked by the caller), in `ξ = x / l`: their bounds, EI and mass per
    /// length (sums over the sections covering them), and how many there are.
    // Inlined: the bound on `sections` that keeps `cuts[nc]` in range is the caller's check,
    // which the firmware's link-time no-panic proof must see.
    #[inline(always)]
    fn pieces(&self, sections: &[BoomSection], l: f64) -> Result<([Piece; MAX_PIECES], usize), ReducedError> {
        let starts = self.starts(l);
        // Every section's ends, in ξ.
        let mut cuts = [0.0f64; 2 * MAX_SECTIONS + 2];
        let mut nc = 0;
        for (start, section) in starts.iter().zip(sections) {
            for x in [*start, (start + section.length).min(l)] {
                cuts[nc] = x / l;
                nc += 1;
            }
        }
        cuts[nc] = 1.0;
        nc += 1;
        let cuts = &mut cuts[..nc];
        cuts.sort_unstable_by(f64::total_cmp);
        let mut pieces = [(0.0f64, 0.0f64, 0.0f64, 0.0f64); MAX_PIECES];
        let mut np = 0;
        for w in cuts.windows(2) {
            let (a, b) = (w[0], w[1]);
            if b - a <= 1e-12 || np >= MAX_PIECES {
                continue;
            }
            let x = 0.5 * (a + b) * l;
            let (mut ei, mut m) = (0.0, 0.0);
            for (start, section) in starts.iter().zip(sections) {
                if x >= *start && x < start + section.length {
                    ei += section.ei;
                    m += section.mass_per_length;
                }
            }
            if ei <= 0.0 {
                return Err(ReducedError::Constants);
            }
            pieces[np] = (a, b, ei, m);
            np += 1;
        }
        Ok((pieces, np))
    }

    /// The mass and stiffness matrices of the basis `shape` over `pieces` (`np` of them) at
    /// length `l` and angle `phi`, the tip's platform included.
    fn assemble(&self, pieces: &[Piece], shape: &Shapes, np: usize, l: f64, phi: f64) -> Assembled {
        let (g, sp) = (self.gravity, libm::sin(phi));
        let mut mm = SMatrix::<f64, BASIS, BASIS>::zeros();
        let mut kk = SMatrix::<f64, BASIS, BASIS>::zeros();
        let mut r = SVector::<f64, BASIS>::zeros();
        let mut gm = SVector::<f64, BASIS>::zeros();
        let mut xi = [0.0; DEGREE + 1];
        xi[1] = 1.0;
        // Mass beyond ξ (for the axial load), from the tip down.
        let mut beyond = self.tip_mass;
        for (i, &(a, b, ei, m)) in pieces.iter().enumerate().rev() {
            // On this piece: beyond(b) + m l (b − ξ) = A − B ξ; P = −g sin φ (A − B ξ).
            let mut axial = [0.0; DEGREE + 1];
            (axial[0], axial[1]) = (-g * sp * (beyond + m * l * b), g * sp * m * l);
            // Each shape on this piece (`i < np ≤ MAX_PIECES`: `get` only keeps the proof).
            let on: [Poly; BASIS] = core::array::from_fn(|j| shape[j].get(i).copied().unwrap_or([0.0; DEGREE + 1]));
            let slopes: [Poly; BASIS] = core::array::from_fn(|j| on.get(j).map_or([0.0; DEGREE + 1], deriv));
            let curvatures: [Poly; BASIS] = core::array::from_fn(|j| slopes.get(j).map_or([0.0; DEGREE + 1], deriv));
            for (j, ((wj, dj), cj)) in on.iter().zip(&slopes).zip(&curvatures).enumerate() {
                r[j] += m * l * l * integral(&mul(&xi, wj), a, b);
                gm[j] += m * l * integral(wj, a, b);
                // The upper triangle; both matrices are symmetric (mirrored below).
                for (k, ((wk, dk), ck)) in on.iter().zip(&slopes).zip(&curvatures).enumerate().skip(j) {
                    if let (Some(mjk), Some(kjk)) = (mm.get_mut((j, k)), kk.get_mut((j, k))) {
                        *mjk += m * l * integral(&mul(wj, wk), a, b);
                        *kjk += ei / (l * l * l) * integral(&mul(cj, ck), a, b)
                            + integral(&mul(&axial, &mul(dj, dk)), a, b) / l;
                    }
                }
            }
            beyond += m * l * (b - a);
        }
        for j in 0..BASIS {
            for k in 0..j {
                mm[(j, k)] = mm[(k, j)];
                kk[(j, k)] = kk[(k, j)];
            }
        }
        // The platform at the tip: every shape is 1 there; its slope per unit ξ.
        let last = np.wrapping_sub(1);
        let tip_slope: [f64; BASIS] =
            core::array::from_fn(|j| shape[j].get(last).map_or(f64::NAN, |w| eval(&deriv(w), 1.0) / l));
        for j in 0..BASIS {
            r[j] += self.tip_mass * l + self.tip_inertia * tip_slope[j];
            gm[j] += self.tip_mass;
            for k in 0..BASIS {
                mm[(j, k)] += self.tip_mass + self.tip_inertia * tip_slope[j] * tip_slope[k];
            }
        }
        Assembled { mm, kk, r, gm, tip_slope }
    }
}

/// One piece of the boom: `(ξ from, ξ to, EI, mass per length)`.
type Piece = (f64, f64, f64, f64);

/// Each basis shape's polynomial on each piece.
type Shapes = [[Poly; MAX_PIECES]; BASIS];

/// Each basis shape per piece: w'' = M / EI integrated twice from the clamped root, then
/// scaled to a unit tip deflection.
fn shapes(pieces: &[Piece], np: usize) -> Result<Shapes, ReducedError> {
    let mut shape = [[[0.0; DEGREE + 1]; MAX_PIECES]; BASIS];
    for (j, sh) in shape.iter_mut().enumerate() {
        let moment = moment_of_load(j);
        let (mut slope0, mut w0) = (0.0, 0.0);
        for (piece, out) in pieces.iter().zip(sh.iter_mut()) {
            let &(a, b, ei, _) = piece;
            let slope = antiderivative(&scale(&moment, 1.0 / ei), a, slope0);
            let w = antiderivative(&slope, a, w0);
            (slope0, w0) = (eval(&slope, b), eval(&w, b));
            *out = w;
        }
        if w0.is_nan() || w0 <= 0.0 {
            return Err(ReducedError::Singular);
        }
        for p in sh.iter_mut().take(np) {
            *p = scale(p, 1.0 / w0);
        }
    }
    Ok(shape)
}

/// The reduced boom's matrices over the basis shapes: mass `mm`, stiffness `kk` (bending and
/// the axial load's), the coupling to the root's rotation `r`, the gravity load `gm`, and each
/// shape's tip slope.
struct Assembled {
    mm: SMatrix<f64, BASIS, BASIS>,
    kk: SMatrix<f64, BASIS, BASIS>,
    r: SVector<f64, BASIS>,
    gm: SVector<f64, BASIS>,
    tip_slope: [f64; BASIS],
}

impl Assembled {
    /// The tip deflection and slope of the combination `c` of the basis shapes.
    fn tip_values(&self, c: &SVector<f64, BASIS>) -> (f64, f64) {
        let mut d = 0.0;
        let mut s = 0.0;
        for j in 0..BASIS {
            d += c[j];
            s += c[j] * self.tip_slope[j];
        }
        (d, s)
    }

    /// The first [`MODES`] modes, ascending: `K ψ = ω² M ψ` through the Cholesky factor of `M`.
    fn modes(&self) -> Result<[Mode; MODES], ReducedError> {
        let chol = crate::linalg::cholesky(&self.mm).ok_or(ReducedError::Singular)?;
        let a = crate::linalg::solve_lower(&chol, &crate::linalg::solve_lower(&chol, &self.kk).transpose());
        let a = (a + a.transpose()) * 0.5;
        // Ascending (Jacobi rotations: no panic path on the chip).
        let (values, vectors) = crate::linalg::symmetric_eigen(&a);
        let mut modes = [Mode { omega: 0.0, tip_deflection: 0.0, tip_slope: 0.0, participation: 0.0 }; MODES];
        for (i, mode) in modes.iter_mut().enumerate() {
            let w2 = values.get(i).copied().unwrap_or(f64::NAN);
            if w2.is_nan() || w2 <= 0.0 {
                return Err(ReducedError::Singular);
            }
            // ψ = L⁻ᵀ u, mass-normalised; its tip deflection positive.
            let u = SVector::<f64, BASIS>::from_fn(|r, _| vectors.get((r, i)).copied().unwrap_or(f64::NAN));
            let mut psi = crate::linalg::solve_lower_transposed(&chol, &u);
            if self.tip_values(&psi).0 < 0.0 {
                psi = -psi;
            }
            let (d, s) = self.tip_values(&psi);
            *mode = Mode { omega: libm::sqrt(w2), tip_deflection: d, tip_slope: s, participation: psi.dot(&self.r) };
        }
        Ok(modes)
    }
}

impl ReducedBoom {
    /// The modes' values in the estimator's precision.
    pub fn mode<T: Real>(&self, i: usize) -> Option<(T, T, T, T)> {
        self.modes.get(i).map(|m| {
            (T::of_f64(m.omega), T::of_f64(m.tip_deflection), T::of_f64(m.tip_slope), T::of_f64(m.participation))
        })
    }
}
