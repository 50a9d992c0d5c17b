//! Dense host linear algebra beyond what [`faer`] offers directly: balancing, the matrix
//! exponential of large systems (the rotor's ~300 states), their free response in modal form
//! ([`free_response`]) on the one real modal basis builder ([`modal_basis`]), and solves that
//! report failure instead of producing NaN.
//!
//! This is the reference simulator's own linear algebra, used only by the full finite-element
//! rotor (`systems::rotor::{simulate, modal, response}` and `loop_system::inject`, which drives
//! that model). Reduced models, whatever their size, are discretised by the shared core
//! ([`edgekf::linalg`]: [6/6] Padé, the chip's arithmetic). The two are kept apart on purpose: a
//! reference must not share code with the reduced model it checks, or a fault in that code would
//! agree with itself. A different algorithm here (balancing, [13/13] Padé, faer's products) is
//! what makes the comparison an independent one. The exception is [`modal_basis`], which the
//! residual loop's filter also uses: there it is only a change of coordinates for speed (an exact
//! similarity, checked when built), so the filter's estimates do not depend on it beyond rounding.
//!
//! Why balancing: a rotor's first-order matrix `[[0, I], [−M⁻¹K, −M⁻¹C]]` mixes metres and
//! metres per second, radians and newtons; its entries span twenty orders of magnitude (the
//! `M⁻¹K` block reaches ~10¹⁵ s⁻² for the rotational DOFs of a 27 mm element, the identity block
//! is 1). A diagonal similarity by powers of two (Parlett–Reinsch, as LAPACK's `gebal`) brings
//! row and column norms together without any rounding, which lets the eigen solver resolve the
//! low modes to near machine precision and cuts the number of squarings of the matrix
//! exponential from ~40 to ~15.

pub mod free_response;
pub mod modal_basis;

use faer::linalg::solvers::Solve;
use faer::{Accum, Mat, MatRef, Par};

/// A dense computation that failed (non-finite entries, a singular matrix, overflow).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct LinalgError(pub String);

/// Balances `a` in place by a diagonal similarity `D⁻¹ A D` with powers of two and returns `D`.
///
/// ```
/// use edgekf_sim::linalg::balance;
/// let mut a = faer::mat![[1.0, 1e6], [1e-6, 1.0]];
/// let d = balance(&mut a);
/// assert!(a[(0, 1)] <= 2.0 && a[(1, 0)] >= 0.5); // rows and columns of equal weight
/// assert_eq!(a[(0, 1)] * d[0] / d[1], 1e6); // exact: scaling by powers of two
/// ```
pub fn balance(a: &mut Mat<f64>) -> Vec<f64> {
    let n = a.nrows();
    let mut d = vec![1.0; n];
    const RADIX: f64 = 2.0;
    let mut converged = false;
    let mut sweeps = 0;
    while !converged && sweeps < 100 {
        converged = true;
        sweeps += 1;
        for i in 0..n {
            let mut c = 0.0;
            let mut r = 0.0;
            for j in 0..n {
                if j != i {
                    c += a[(j, i)].abs();
                    r += a[(i, j)].abs();
                }
            }
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let s = c + r;
            let mut f = 1.0;
            let mut cc = c;
            let mut rr = r;
            while cc < rr / RADIX {
                cc *= RADIX;
                rr /= RADIX;
                f *= RADIX;
            }
            while cc >= rr * RADIX {
                cc /= RADIX;
                rr *= RADIX;
                f /= RADIX;
            }
            if (cc + rr) < 0.95 * s {
                converged = false;
                d[i] *= f;
                for j in 0..n {
                    a[(i, j)] /= f;
                    a[(j, i)] *= f;
                }
            }
        }
    }
    d
}

/// Operator 1-norm (largest column sum of magnitudes).
pub fn norm1(a: MatRef<'_, f64>) -> f64 {
    (0..a.ncols()).map(|j| (0..a.nrows()).map(|i| a[(i, j)].abs()).sum::<f64>()).fold(0.0, f64::max)
}

/// Whether every entry is finite.
pub fn all_finite(a: MatRef<'_, f64>) -> bool {
    (0..a.ncols()).all(|j| (0..a.nrows()).all(|i| a[(i, j)].is_finite()))
}

/// `a · b`.
pub fn mul(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut c = Mat::zeros(a.nrows(), b.ncols());
    faer::linalg::matmul::matmul(&mut c, Accum::Replace, a, b, 1.0, Par::Seq);
    c
}

/// Solves `a x = b` by LU with partial pivoting; refuses a singular or non-finite result.
pub fn solve(a: MatRef<'_, f64>, b: MatRef<'_, f64>, what: &str) -> Result<Mat<f64>, LinalgError> {
    if !all_finite(a) || !all_finite(b) {
        return Err(LinalgError(format!("{what}: non-finite matrix entries")));
    }
    let x = a.partial_piv_lu().solve(b);
    if all_finite(x.as_ref()) {
        Ok(x)
    } else {
        Err(LinalgError(format!("{what}: the matrix is singular")))
    }
}

/// Numerator and denominator coefficients of the [13/13] Padé approximant of `eˣ` (Higham 2005).
const PADE13: [f64; 14] = [
    64764752532480000.0,
    32382376266240000.0,
    7771770303897600.0,
    1187353796428800.0,
    129060195264000.0,
    10559470521600.0,
    670442572800.0,
    33522128640.0,
    1323241920.0,
    40840800.0,
    960960.0,
    16380.0,
    182.0,
    1.0,
];

/// Largest 1-norm for which the [13/13] Padé approximant is accurate to double precision.
const THETA13: f64 = 5.371920351148152;

/// The matrix exponential `eᴬ` by balancing, scaling and squaring with the [13/13] Padé
/// approximant (Higham 2005, "The scaling and squaring method for the matrix exponential
/// revisited"): backward error below the unit round-off for the scaled matrix.
///
/// ```
/// use edgekf_sim::linalg::expm;
/// // Rotation generator: e^{[[0, -θ], [θ, 0]]} is the rotation by θ.
/// let th = 2.0;
/// let r = expm(faer::mat![[0.0, -th], [th, 0.0]].as_ref()).unwrap();
/// assert!((r[(0, 0)] - th.cos()).abs() < 1e-14 && (r[(1, 0)] - th.sin()).abs() < 1e-14);
/// ```
pub fn expm(a: MatRef<'_, f64>) -> Result<Mat<f64>, LinalgError> {
    let n = a.nrows();
    if n != a.ncols() {
        return Err(LinalgError("expm of a non-square matrix".into()));
    }
    if !all_finite(a) {
        return Err(LinalgError("expm: non-finite matrix entries".into()));
    }
    let mut ab = a.to_owned();
    let d = balance(&mut ab);
    let norm = norm1(ab.as_ref());
    let s = if norm > THETA13 { (norm / THETA13).log2().ceil() as i32 } else { 0 };
    let scale = 0.5f64.powi(s);
    let x = Mat::from_fn(n, n, |i, j| ab[(i, j)] * scale);
    let x2 = mul(x.as_ref(), x.as_ref());
    let x4 = mul(x2.as_ref(), x2.as_ref());
    let x6 = mul(x4.as_ref(), x2.as_ref());
    let b = &PADE13;
    let eye = Mat::<f64>::identity(n, n);
    let lin = |c6: f64, c4: f64, c2: f64, c0: f64| {
        Mat::from_fn(n, n, |i, j| c6 * x6[(i, j)] + c4 * x4[(i, j)] + c2 * x2[(i, j)] + c0 * eye[(i, j)])
    };
    let u_inner = {
        let hi = mul(x6.as_ref(), lin(b[13], b[11], b[9], 0.0).as_ref());
        let lo = lin(b[7], b[5], b[3], b[1]);
        Mat::from_fn(n, n, |i, j| hi[(i, j)] + lo[(i, j)])
    };
    let u = mul(x.as_ref(), u_inner.as_ref());
    let v = {
        let hi = mul(x6.as_ref(), lin(b[12], b[10], b[8], 0.0).as_ref());
        let lo = lin(b[6], b[4], b[2], b[0]);
        Mat::from_fn(n, n, |i, j| hi[(i, j)] + lo[(i, j)])
    };
    let p = Mat::from_fn(n, n, |i, j| v[(i, j)] + u[(i, j)]);
    let q = Mat::from_fn(n, n, |i, j| v[(i, j)] - u[(i, j)]);
    let mut r = solve(q.as_ref(), p.as_ref(), "expm (Padé denominator)")?;
    for _ in 0..s {
        r = mul(r.as_ref(), r.as_ref());
    }
    // Undo the balancing: e^A = D e^{D⁻¹AD} D⁻¹.
    let out = Mat::from_fn(n, n, |i, j| r[(i, j)] * d[i] / d[j]);
    if all_finite(out.as_ref()) {
        Ok(out)
    } else {
        Err(LinalgError("expm: overflow while squaring".into()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expm_of_a_stiff_damped_oscillator_matches_the_closed_form() {
        // ẍ + 2ζω ẋ + ω² x = 0 with ω = 1e5 rad/s over 1 ms (100 periods / 2π): a stiff case.
        let (w, z, h) = (1e5f64, 0.01f64, 1e-3f64);
        let a = faer::mat![[0.0, 1.0], [-w * w, -2.0 * z * w]];
        let e = expm(Mat::from_fn(2, 2, |i, j| a[(i, j)] * h).as_ref()).unwrap();
        let wd = w * (1.0 - z * z).sqrt();
        let decay = (-z * w * h).exp();
        let x_from_x = decay * ((wd * h).cos() + z * w / wd * (wd * h).sin());
        let x_from_v = decay * (wd * h).sin() / wd;
        assert!((e[(0, 0)] - x_from_x).abs() < 1e-9 * decay, "{} vs {x_from_x}", e[(0, 0)]);
        assert!((e[(0, 1)] - x_from_v).abs() < 1e-9 * decay / w, "{} vs {x_from_v}", e[(0, 1)]);
    }

    #[test]
    fn solve_reports_a_singular_matrix() {
        let a = faer::mat![[1.0, 2.0], [2.0, 4.0]];
        let b = faer::mat![[1.0], [1.0]];
        assert!(matches!(solve(a.as_ref(), b.as_ref(), "t"), Err(LinalgError(_))));
    }
}
