//! Modal analysis at a speed: damped natural frequencies, logarithmic decrements, mode shapes and
//! whirl directions; the Campbell diagram over a range of speeds.
//!
//! The eigenproblem is that of the first-order state matrix
//! `A = [[0, I], [−M⁻¹K, −M⁻¹(C + ΩG)]]` (complex modes: gyroscopic and non-proportional bearing
//! damping couple x and y). Each oscillating mode appears as a conjugate pair `λ, λ̄`; the member
//! with `Im λ > 0` is kept. Real eigenvalues (overdamped motion), pairs damped beyond
//! [`MAX_DAMPING_RATIO`] and rigid-body motion (`|λ| <` [`RIGID_BODY_LIMIT`]) are not modes in
//! this list. Definitions, as in ROSS:
//! * frequency `f = Im λ / 2π` (damped), undamped `|λ| / 2π`;
//! * damping ratio `ζ = −Re λ / |λ|`, logarithmic decrement `δ = −2π Re λ / Im λ`.
//!
//! The matrix is balanced (see [`super::linalg`]) before the dense eigen solver runs: without
//! it, the stiff rotational DOFs (`|λ|` up to ~3·10⁷ rad/s) would leave the first modes (~10²
//! rad/s) with only five or six correct digits.

use super::assembly::RotorModel;
use super::{dof, RotorError};
use crate::linalg::{balance, solve};
use faer::{c64, Mat};
use std::f64::consts::PI;
use std::fmt;

/// Damping ratio from which a complex pair counts as overdamped rather than as a mode: under
/// stiffness-proportional damping the stiff DOFs become (near-)critically damped pairs whose
/// imaginary part is rounding noise; they would otherwise head the frequency-sorted list.
pub const MAX_DAMPING_RATIO: f64 = 0.999;

/// Eigenvalues with `|λ|` below this (rad/s) are rigid-body motion, not modes (as in ROSS): a
/// free rotor's zero eigenvalues come out of a dense solver as ±1e-4 rad/s pairs.
pub const RIGID_BODY_LIMIT: f64 = 0.1;

/// Modes beyond the asked-for count whose shapes the Campbell diagram's reduced basis takes.
const BASIS_EXTRA: usize = 6;

/// Minor-to-major axis ratio below which a mode's orbits count as planar (straight lines).
pub const PLANAR_ELLIPTICITY: f64 = 0.01;

/// Whirl direction of a mode, from the orbits its shape traces at the nodes.
///
/// At standstill the reference direction is x → y (that of a positive speed). An isotropic
/// rotor at standstill has degenerate x/y twins, of which any combination is a mode: the whirl
/// reported there is that of the combination the eigen solver happens to return.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Whirl {
    /// The orbits run in the direction of rotation (x → y for a positive speed).
    Forward,
    /// Against the rotation.
    Backward,
    /// Straight-line orbits (within [`PLANAR_ELLIPTICITY`]).
    Planar,
}

impl Whirl {
    /// `"forward"`, `"backward"` or `"planar"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Whirl::Forward => "forward",
            Whirl::Backward => "backward",
            Whirl::Planar => "planar",
        }
    }
}

impl fmt::Display for Whirl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Mode {
    /// Eigenvalue λ (Im λ > 0), rad/s.
    pub eigenvalue: c64,
    /// Damped natural frequency `Im λ / 2π`, Hz.
    pub frequency_hz: f64,
    /// Undamped natural frequency `|λ| / 2π`, Hz.
    pub undamped_hz: f64,
    /// Damping ratio `−Re λ / |λ|`.
    pub damping_ratio: f64,
    /// Logarithmic decrement `−2π Re λ / Im λ`.
    pub log_dec: f64,
    /// Whirl direction.
    pub whirl: Whirl,
    /// Signed minor/major axis ratio of the orbits, weighted by amplitude over the nodes:
    /// +1 circular forward, −1 circular backward, 0 planar. A mode whose nodes whirl partly
    /// forward and partly backward gets the sign of the larger orbits.
    pub ellipticity: f64,
    /// Mode shape over all DOFs (`[x, y, α, β]` per node), scaled so that the largest
    /// displacement (x or y) is 1 (real). The motion is `Re(shape · e^{λt})`.
    pub shape: Vec<c64>,
}

impl Mode {
    /// The complex displacement `(x, y)` of a node in this mode.
    pub fn node_xy(&self, node: usize) -> (c64, c64) {
        (self.shape[dof(node, 0)], self.shape[dof(node, 1)])
    }
}

/// The modes of the rotor at one speed, lowest frequency first.
#[derive(Debug, Clone, PartialEq)]
pub struct ModalAnalysis {
    /// Speed Ω, rad/s.
    pub speed: f64,
    /// Oscillating modes sorted by damped frequency.
    pub modes: Vec<Mode>,
}

/// Campbell diagram data: the first modes at each speed.
#[derive(Debug, Clone, PartialEq)]
pub struct Campbell {
    /// Speeds, rad/s.
    pub speeds: Vec<f64>,
    /// `modes[i]`: the first modes at `speeds[i]`, sorted by frequency (not tracked across
    /// speeds: a crossing of two branches swaps their order).
    pub modes: Vec<Vec<Mode>>,
}

impl RotorModel {
    /// The first-order state matrix `A = [[0, I], [−M⁻¹K, −M⁻¹(C + ΩG)]]` at `speed`, with state
    /// `[q, q̇]`.
    pub fn state_matrix(&self, speed: f64) -> Result<Mat<f64>, RotorError> {
        let s = self.matrices();
        let n = s.n();
        let mut rhs = Mat::<f64>::zeros(n, 2 * n);
        let ct = s.c_total(speed);
        for j in 0..n {
            for i in 0..n {
                rhs[(i, j)] = s.k[(i, j)];
                rhs[(i, n + j)] = ct[(i, j)];
            }
        }
        let minv = solve(s.m.as_ref(), rhs.as_ref(), "M⁻¹[K, C]")?;
        Ok(Mat::from_fn(2 * n, 2 * n, |i, j| {
            if i < n {
                if j == n + i {
                    1.0
                } else {
                    0.0
                }
            } else {
                -minv[(i - n, j)]
            }
        }))
    }

    /// Modal analysis at `speed` (rad/s).
    ///
    /// ```
    /// use edgekf_sim::systems::rotor::{RotorConfig, RotorModel, Whirl};
    /// let cfg = RotorConfig::from_toml_str(include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml"))).unwrap();
    /// let model = RotorModel::from_config(&cfg).unwrap();
    /// let m = model.modes(300.0).unwrap();
    /// // At speed the gyroscopic coupling splits each pair into a backward and a forward whirl.
    /// assert_eq!(m.modes[2].whirl, Whirl::Backward);
    /// assert_eq!(m.modes[3].whirl, Whirl::Forward);
    /// ```
    pub fn modes(&self, speed: f64) -> Result<ModalAnalysis, RotorError> {
        if !speed.is_finite() {
            return Err(RotorError::Invalid(format!("speed = {speed} rad/s must be finite")));
        }
        let n = self.n_dofs();
        modes_of(self.state_matrix(speed)?, speed, usize::MAX, |u, k| (0..n).map(|i| u(i, k)).collect())
    }

    /// Campbell diagram data: the first `count` modes at each of `speeds`.
    ///
    /// On a reduced basis: the shapes (real and imaginary parts) of the first `count + 6`
    /// modes of the full model at the lowest and the highest speed asked for, `M`-orthonormal,
    /// span the low modes at every speed between; the first-order problem of the projected
    /// `M`, `K`, `C + ΩG` is solved at each speed and the shapes mapped back to every DOF. The
    /// first modes agree with [`modes`](Self::modes) on the full model
    /// (`host-sim/tests/rotor.rs`) at a fraction of its cost per speed.
    pub fn campbell(&self, speeds: &[f64], count: usize) -> Result<Campbell, RotorError> {
        let s = self.matrices();
        let n = s.n();
        if let Some(w) = speeds.iter().find(|w| !w.is_finite()) {
            return Err(RotorError::Invalid(format!("speed = {w} rad/s must be finite")));
        }
        let (low, high) = speeds.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), w| (a.min(*w), b.max(*w)));
        if speeds.is_empty() {
            return Ok(Campbell { speeds: Vec::new(), modes: Vec::new() });
        }
        let mut vectors: Vec<Vec<f64>> = Vec::new();
        for w in [low, high] {
            for m in self.modes(w)?.modes.iter().take(BASIS_EXTRA + count) {
                vectors.push(m.shape.iter().map(|v| v.re).collect());
                vectors.push(m.shape.iter().map(|v| v.im).collect());
            }
        }
        let phi = m_orthonormal(&s.m, vectors);
        let r = phi.ncols();
        let project = |m: &Mat<f64>| phi.transpose() * m * &phi;
        let (mr, kr, cr, gr) = (project(&s.m), project(&s.k), project(&s.c), project(&s.g));
        let mut modes = Vec::with_capacity(speeds.len());
        for &w in speeds {
            let mut rhs = Mat::<f64>::zeros(r, 2 * r);
            for j in 0..r {
                for i in 0..r {
                    rhs[(i, j)] = kr[(i, j)];
                    rhs[(i, r + j)] = cr[(i, j)] + w * gr[(i, j)];
                }
            }
            let minv = solve(mr.as_ref(), rhs.as_ref(), "reduced M⁻¹[K, C]")?;
            let a = Mat::from_fn(
                2 * r,
                2 * r,
                |i, j| {
                    if i < r {
                        f64::from(u8::from(j == r + i))
                    } else {
                        -minv[(i - r, j)]
                    }
                },
            );
            let shape = |u: &dyn Fn(usize, usize) -> c64, k: usize| -> Vec<c64> {
                (0..n).map(|i| (0..r).map(|j| u(j, k) * phi[(i, j)]).sum()).collect()
            };
            modes.push(modes_of(a, w, count, shape)?.modes);
        }
        Ok(Campbell { speeds: speeds.to_vec(), modes })
    }
}

/// The span of `vectors` as `M`-orthonormal columns (modified Gram–Schmidt, twice; a vector
/// left with under 10⁻⁸ of its `M`-norm is dependent and dropped).
fn m_orthonormal(m: &Mat<f64>, vectors: Vec<Vec<f64>>) -> Mat<f64> {
    let n = m.nrows();
    let times_m = |v: &[f64]| -> Vec<f64> { (0..n).map(|i| (0..n).map(|j| m[(i, j)] * v[j]).sum()).collect() };
    let dot = |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(x, y)| x * y).sum() };
    // The basis and M times each of its vectors.
    let mut basis: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
    for mut v in vectors {
        let norm0 = dot(&v, &times_m(&v)).sqrt();
        if !(norm0 > 0.0 && norm0.is_finite()) {
            continue;
        }
        for _ in 0..2 {
            for (b, mb) in &basis {
                let c = dot(mb, &v);
                for (vi, bi) in v.iter_mut().zip(b) {
                    *vi -= c * bi;
                }
            }
        }
        let mv = times_m(&v);
        let norm = dot(&v, &mv).sqrt();
        if norm > 1e-8 * norm0 {
            basis.push((v.iter().map(|x| x / norm).collect(), mv.iter().map(|x| x / norm).collect()));
        }
    }
    Mat::from_fn(n, basis.len(), |i, j| basis[j].0[i])
}

/// The oscillating modes of the first-order state matrix `a` at `speed`; `shape(u, k)` maps
/// column `k` of `a`'s (balancing undone) eigenvectors, read through `u(row, col)`, to the
/// displacement of every DOF.
fn modes_of(
    mut a: Mat<f64>,
    speed: f64,
    limit: usize,
    shape: impl Fn(&dyn Fn(usize, usize) -> c64, usize) -> Vec<c64>,
) -> Result<ModalAnalysis, RotorError> {
    let size = a.nrows();
    let d = balance(&mut a);
    let evd = a.eigen().map_err(|e| RotorError::Numerical(format!("eigen decomposition: {e:?}")))?;
    let (u, s) = (evd.U(), evd.S());
    let values = s.column_vector();
    let read = |i: usize, k: usize| u[(i, k)] * d[i];
    // The oscillating modes by frequency; shapes only for the first `limit`.
    let mut kept = Vec::new();
    for k in 0..size {
        let lambda = values[k];
        if !(lambda.re.is_finite() && lambda.im.is_finite()) {
            return Err(RotorError::Numerical("eigen decomposition: non-finite eigenvalue".into()));
        }
        let abs = lambda.norm();
        if lambda.im > 0.0 && abs >= RIGID_BODY_LIMIT && -lambda.re / abs < MAX_DAMPING_RATIO {
            kept.push((k, lambda));
        }
    }
    kept.sort_by(|a, b| a.1.im.total_cmp(&b.1.im));
    kept.truncate(limit);
    let mut modes = Vec::new();
    for (k, lambda) in kept {
        let abs = lambda.norm();
        // Displacement part of the eigenvector, balancing undone.
        let mut shape = shape(&read, k);
        normalise(&mut shape);
        // Forward means "with the rotation": x → y for a positive speed, y → x for a negative one.
        let ellipticity = if speed < 0.0 { -ellipticity(&shape) } else { ellipticity(&shape) };
        let whirl = if ellipticity.abs() < PLANAR_ELLIPTICITY {
            Whirl::Planar
        } else if ellipticity > 0.0 {
            Whirl::Forward
        } else {
            Whirl::Backward
        };
        modes.push(Mode {
            eigenvalue: lambda,
            frequency_hz: lambda.im / (2.0 * PI),
            undamped_hz: abs / (2.0 * PI),
            damping_ratio: -lambda.re / abs,
            log_dec: -2.0 * PI * lambda.re / lambda.im,
            whirl,
            ellipticity,
            shape,
        });
    }
    modes.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    Ok(ModalAnalysis { speed, modes })
}

/// Scales a shape so that its largest translation is 1 (real).
fn normalise(shape: &mut [c64]) {
    let nodes = shape.len() / 4;
    let mut best = c64::new(0.0, 0.0);
    for i in 0..nodes {
        for d in 0..2 {
            let v = shape[dof(i, d)];
            if v.norm() > best.norm() {
                best = v;
            }
        }
    }
    if best.norm() == 0.0 {
        // A purely rotational shape: normalise on the largest entry of any kind.
        best = shape.iter().copied().fold(c64::new(0.0, 0.0), |b, v| if v.norm() > b.norm() { v } else { b });
    }
    if best.norm() > 0.0 {
        let inv = best.inv();
        for v in shape.iter_mut() {
            *v *= inv;
        }
    }
}

/// Amplitude-weighted signed minor/major axis ratio of the node orbits of a shape.
///
/// At a node with complex amplitudes `(u, v)` the orbit is `x = Re(u e^{iωt})`,
/// `y = Re(v e^{iωt})`; `s = 2 Im(u v̄) / (|u|² + |v|²)` is +1 for a circle run x → y, −1 for the
/// reverse and 0 for a line. Summing numerator and denominator over the nodes weights each orbit
/// by its size; the minor/major ratio `κ` follows from `s = 2κ / (1 + κ²)`.
pub fn ellipticity(shape: &[c64]) -> f64 {
    let nodes = shape.len() / 4;
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..nodes {
        let (u, v) = (shape[dof(i, 0)], shape[dof(i, 1)]);
        num += 2.0 * (u * v.conj()).im;
        den += u.norm_sqr() + v.norm_sqr();
    }
    if den == 0.0 {
        return 0.0;
    }
    let s = (num / den).clamp(-1.0, 1.0);
    s / (1.0 + (1.0 - s * s).sqrt())
}
