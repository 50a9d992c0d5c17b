use super::LinalgError;
use crate::Real;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OMatrix};

/// Degree of the diagonal Padé approximant. With the argument scaled to an ∞-norm of at most
/// 1/2 the truncation error of the [6/6] approximant is below 1e-16 relative, i.e. at f64
/// rounding level (Moler & Van Loan, "Nineteen dubious ways", method 3).
const PADE_DEGREE: usize = 6;
/// Scaling target for the ∞-norm before the Padé step.
const NORM_TARGET: f64 = 0.5;

/// Matrix exponential `e^A` by scaling and squaring with a [6/6] Padé approximant.
///
/// Only arithmetic and comparisons are used, and the scaling is by exact powers of two, so the
/// result is bit-identical on every IEEE-754 platform. Generic over nalgebra's dimensions: a
/// fixed-size `SMatrix` on the chip, a `DMatrix` on the host (with the `alloc` feature), by the
/// same algorithm (nalgebra's `std` products of `DMatrix`es wider than 5 sum in another order,
/// so those can differ from the fixed-size result in the last bits). Returns [`LinalgError::NonFinite`] for NaN or
/// infinite input, [`LinalgError::SizeMismatch`] for a non-square `DMatrix`, and
/// [`LinalgError::Singular`] if the Padé denominator cannot be solved (which does not happen
/// for finite input, but is reported rather than assumed).
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
pub fn expm<T: Real, D: Dim>(a: &OMatrix<T, D, D>) -> Result<OMatrix<T, D, D>, LinalgError>
where
    DefaultAllocator: Allocator<D, D>,
{
    let (d, cols) = a.shape_generic();
    if d.value() != cols.value() {
        return Err(LinalgError::SizeMismatch);
    }
    let n = d.value();
    if a.iter().any(|v| !v.is_finite()) {
        return Err(LinalgError::NonFinite);
    }
    // ∞-norm (largest absolute row sum).
    let mut norm = T::zero();
    for i in 0..n {
        let row: T = (0..n).fold(T::zero(), |s, j| s + a[(i, j)].abs());
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
    let mut x_pow = OMatrix::<T, D, D>::identity_generic(d, d);
    let mut num = x_pow.clone();
    let mut den = x_pow.clone();
    for k in 1..=q {
        c = c * T::of_f64((q - k + 1) as f64) / T::of_f64((k * (2 * q - k + 1)) as f64);
        x_pow = &x_pow * &x;
        let term = &x_pow * c;
        num += &term;
        if k % 2 == 0 {
            den += &term;
        } else {
            den -= &term;
        }
    }
    let mut e = super::solve(&den, &num).ok_or(LinalgError::Singular)?;
    for _ in 0..squarings {
        e = &e * &e;
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

    #[cfg(feature = "alloc")]
    #[test]
    fn dynamic_sizes_give_the_fixed_size_bits() {
        use nalgebra::{DMatrix, Matrix4};
        let a = Matrix4::from_fn(|i, j| ((3 * i + 7 * j) % 5) as f64 - 1.7 * f64::from(u8::from(i == j))) * 0.9;
        let fixed = expm(&a).unwrap();
        let dynamic = expm(&DMatrix::from_fn(4, 4, |i, j| a[(i, j)])).unwrap();
        assert!(fixed.iter().zip(dynamic.iter()).all(|(f, d)| f.to_bits() == d.to_bits()));
        assert_eq!(expm(&DMatrix::<f64>::zeros(2, 3)), Err(LinalgError::SizeMismatch));
        assert_eq!(expm(&DMatrix::<f64>::zeros(0, 0)).map(|e| e.len()), Ok(0));
    }
}
