use super::LinalgError;
use crate::Real;
use nalgebra::SMatrix;

/// Degree of the diagonal Padé approximant. With the argument scaled to an ∞-norm of at most
/// 1/2 the truncation error of the [6/6] approximant is below 1e-16 relative, i.e. at f64
/// rounding level (Moler & Van Loan, "Nineteen dubious ways", method 3).
const PADE_DEGREE: usize = 6;
/// Scaling target for the ∞-norm before the Padé step.
const NORM_TARGET: f64 = 0.5;

/// Matrix exponential `e^A` by scaling and squaring with a [6/6] Padé approximant.
///
/// Only arithmetic and comparisons are used, and the scaling is by exact powers of two, so the
/// result is bit-identical on every IEEE-754 platform. Returns [`LinalgError::NonFinite`] for
/// NaN or infinite input and [`LinalgError::Singular`] if the Padé denominator cannot be solved
/// (which does not happen for finite input, but is reported rather than assumed).
///
/// ```
/// use edgekf::linalg::expm;
/// use nalgebra::Matrix2;
/// // e^{[[0, w], [-w, 0]]} is a rotation by w radians.
/// let w = 0.3_f64;
/// let e = expm(&Matrix2::new(0.0, w, -w, 0.0)).unwrap();
/// assert!((e[(0, 0)] - w.cos()).abs() < 1e-15);
/// assert!((e[(0, 1)] - w.sin()).abs() < 1e-15);
/// ```
// Kept out of line: its f64 temporaries would otherwise be inlined into (and stay reserved in)
// the caller's stack frame on the chip, which for the firmware's `main` is the whole run.
#[inline(never)]
pub fn expm<T: Real, const N: usize>(a: &SMatrix<T, N, N>) -> Result<SMatrix<T, N, N>, LinalgError> {
    if a.iter().any(|v| !v.is_finite()) {
        return Err(LinalgError::NonFinite);
    }
    // ∞-norm (largest absolute row sum).
    let mut norm = T::zero();
    for i in 0..N {
        let row: T = (0..N).fold(T::zero(), |s, j| s + a[(i, j)].abs());
        if row > norm {
            norm = row;
        }
    }
    let half = T::of_f64(0.5);
    let target = T::of_f64(NORM_TARGET);
    let mut squarings = 0u32;
    let mut scale = T::one();
    while norm > target {
        norm *= half;
        scale *= half;
        squarings += 1;
    }
    let x = a * scale;

    // Padé coefficients c_k = c_{k-1} (q − k + 1) / (k (2q − k + 1)).
    let q = PADE_DEGREE;
    let mut c = T::one();
    let mut x_pow = SMatrix::<T, N, N>::identity();
    let mut num = SMatrix::<T, N, N>::identity();
    let mut den = SMatrix::<T, N, N>::identity();
    for k in 1..=q {
        c = c * T::of_f64((q - k + 1) as f64) / T::of_f64((k * (2 * q - k + 1)) as f64);
        x_pow *= x;
        let term = x_pow * c;
        num += term;
        if k % 2 == 0 {
            den += term;
        } else {
            den -= term;
        }
    }
    let mut e = super::solve(&den, &num).ok_or(LinalgError::Singular)?;
    for _ in 0..squarings {
        e = e * e;
    }
    if e.iter().any(|v| !v.is_finite()) {
        return Err(LinalgError::NonFinite);
    }
    Ok(e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Matrix3};

    #[test]
    fn diagonal_matrix_gives_scalar_exponentials() {
        let a = Matrix3::from_diagonal(&nalgebra::Vector3::new(-3.0, 0.5, 7.0));
        let e = expm(&a).unwrap();
        for (i, v) in [-3.0f64, 0.5, 7.0].iter().enumerate() {
            assert!((e[(i, i)] / v.exp() - 1.0).abs() < 1e-14, "{} vs {}", e[(i, i)], v.exp());
        }
        assert_eq!(e[(0, 1)], 0.0);
    }

    #[test]
    fn nilpotent_matrix_is_exact() {
        // e^{[[0,t],[0,0]]} = [[1,t],[0,1]]
        let e = expm(&Matrix2::new(0.0, 2.5, 0.0, 0.0)).unwrap();
        assert_eq!(e, Matrix2::new(1.0, 2.5, 0.0, 1.0));
    }

    #[test]
    fn damped_oscillator_matches_closed_form() {
        // x'' + 2ζω x' + ω² x = 0: closed-form state transition over t.
        let (w, z, t) = (2.0 * core::f64::consts::PI * 20.0, 0.05f64, 0.013);
        let a = Matrix2::new(0.0, 1.0, -w * w, -2.0 * z * w);
        let e = expm(&(a * t)).unwrap();
        let wd = w * (1.0 - z * z).sqrt();
        let decay = (-z * w * t).exp();
        let phi00 = decay * ((wd * t).cos() + z * w / wd * (wd * t).sin());
        let phi01 = decay * (wd * t).sin() / wd;
        assert!((e[(0, 0)] - phi00).abs() < 1e-13);
        assert!((e[(0, 1)] - phi01).abs() < 1e-15);
    }

    #[test]
    fn non_finite_input_is_an_error() {
        assert_eq!(expm(&Matrix2::new(f64::NAN, 0.0, 0.0, 0.0)), Err(LinalgError::NonFinite));
    }
}
