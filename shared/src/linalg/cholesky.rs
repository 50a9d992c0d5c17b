//! Cholesky factor and triangular solves for fixed sizes, written with checked indexing so
//! that no panic path survives in a firmware image (nalgebra's own keep shape assertions the
//! optimiser does not always remove), and with `+ − × ÷ sqrt` only, so that the chip and the
//! host compute the same bits.

use crate::Real;
use nalgebra::SMatrix;

fn at<T: Real, const R: usize, const C: usize>(m: &SMatrix<T, R, C>, i: usize, j: usize) -> T {
    m.get((i, j)).copied().unwrap_or_else(T::zero)
}

fn put<T: Real, const R: usize, const C: usize>(m: &mut SMatrix<T, R, C>, i: usize, j: usize, v: T) {
    if let Some(e) = m.get_mut((i, j)) {
        *e = v;
    }
}

/// The lower Cholesky factor `L` of a symmetric positive definite `a` (`a = L Lᵀ`, read from
/// its lower triangle); `None` if a pivot is not positive or an entry of `L` is not finite
/// (so a NaN or an infinity in the lower triangle is caught on the way).
///
/// ```
/// use edgekf::linalg::cholesky;
/// use nalgebra::Matrix2;
/// let l = cholesky(&Matrix2::new(4.0, 2.0, 2.0, 5.0)).unwrap();
/// assert_eq!(l, Matrix2::new(2.0, 0.0, 1.0, 2.0));
/// assert!(cholesky(&Matrix2::new(1.0, 2.0, 2.0, 1.0)).is_none());
/// ```
pub fn cholesky<T: Real, const N: usize>(a: &SMatrix<T, N, N>) -> Option<SMatrix<T, N, N>> {
    let mut l = SMatrix::<T, N, N>::zeros();
    factor_into(|i, j| at(a, i, j), &mut l).then_some(l)
}

/// [`cholesky`] of `scale · a`, written into `l` in place: `true` if the factor exists. The
/// product is formed entry by entry as the factor reads it (the same bits as factoring
/// `a * scale`), so neither it nor the factor is a temporary on the caller's stack: an
/// unscented filter's 20 × 20 `f32` matrices are 1.6 KB each. On `false`, `l` holds a partial
/// factor.
///
/// ```
/// use edgekf::linalg::{cholesky, cholesky_scaled_into};
/// use nalgebra::Matrix2;
/// let a = Matrix2::new(2.0, 1.0, 1.0, 2.5);
/// let mut l = Matrix2::zeros();
/// assert!(cholesky_scaled_into(&a, 2.0, &mut l));
/// assert_eq!(Some(l), cholesky(&(a * 2.0)));
/// assert!(!cholesky_scaled_into(&a, -1.0, &mut l));
/// ```
pub fn cholesky_scaled_into<T: Real, const N: usize>(a: &SMatrix<T, N, N>, scale: T, l: &mut SMatrix<T, N, N>) -> bool {
    l.fill(T::zero());
    factor_into(|i, j| at(a, i, j) * scale, l)
}

/// The factor of the matrix whose lower-triangle entry `(i, j)` is `a(i, j)` (each read once),
/// into the lower triangle of a zeroed `l`; `false` as soon as a pivot or an entry fails.
#[inline(always)]
fn factor_into<T: Real, const N: usize>(a: impl Fn(usize, usize) -> T, l: &mut SMatrix<T, N, N>) -> bool {
    for j in 0..N {
        let mut d = a(j, j);
        for k in 0..j {
            let v = at(l, j, k);
            d -= v * v;
        }
        if !(d > T::zero() && d.is_finite()) {
            return false;
        }
        let d = d.sqrt();
        put(l, j, j, d);
        for i in j + 1..N {
            let mut s = a(i, j);
            for k in 0..j {
                s -= at(l, i, k) * at(l, j, k);
            }
            let v = s / d;
            if !v.is_finite() {
                return false;
            }
            put(l, i, j, v);
        }
    }
    true
}

/// `L⁻¹ B` for a lower triangular `L` with a positive diagonal (from [`cholesky`]).
///
/// ```
/// use edgekf::linalg::{cholesky, solve_lower, solve_lower_transposed};
/// use nalgebra::{Matrix2, Vector2};
/// let a = Matrix2::new(4.0, 2.0, 2.0, 5.0);
/// let l = cholesky(&a).unwrap();
/// let x = solve_lower_transposed(&l, &solve_lower(&l, &Vector2::new(8.0, 9.0)));
/// assert!((a * x - Vector2::new(8.0, 9.0)).norm() < 1e-12);
/// ```
pub fn solve_lower<T: Real, const N: usize, const C: usize>(
    l: &SMatrix<T, N, N>,
    b: &SMatrix<T, N, C>,
) -> SMatrix<T, N, C> {
    let mut x = *b;
    for c in 0..C {
        for i in 0..N {
            let mut s = at(&x, i, c);
            for k in 0..i {
                s -= at(l, i, k) * at(&x, k, c);
            }
            put(&mut x, i, c, s / at(l, i, i));
        }
    }
    x
}

/// `L⁻ᵀ B` for a lower triangular `L` with a positive diagonal (from [`cholesky`]).
pub fn solve_lower_transposed<T: Real, const N: usize, const C: usize>(
    l: &SMatrix<T, N, N>,
    b: &SMatrix<T, N, C>,
) -> SMatrix<T, N, C> {
    let mut x = *b;
    for c in 0..C {
        for i in (0..N).rev() {
            let mut s = at(&x, i, c);
            for k in i + 1..N {
                s -= at(l, k, i) * at(&x, k, c);
            }
            put(&mut x, i, c, s / at(l, i, i));
        }
    }
    x
}
