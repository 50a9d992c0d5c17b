use crate::Real;
use nalgebra::SMatrix;

/// Solves `A X = B` by Gaussian elimination with partial pivoting.
///
/// Returns `None` when a pivot is exactly zero or not finite. Used where the system is small and
/// a factorisation object would only add trait bounds; like the rest of [`crate::linalg`] it uses
/// only arithmetic and comparisons, so it is bit-reproducible across platforms.
///
/// ```
/// use edgekf::linalg::solve;
/// use nalgebra::{Matrix2, Vector2};
/// let x = solve(&Matrix2::new(0.0, 2.0, 4.0, 1.0), &Vector2::new(2.0, 9.0)).unwrap();
/// assert_eq!(x, Vector2::new(2.0, 1.0));
/// ```
pub fn solve<T: Real, const N: usize, const K: usize>(
    a: &SMatrix<T, N, N>,
    b: &SMatrix<T, N, K>,
) -> Option<SMatrix<T, N, K>> {
    // Every index below is in range by the loops' bounds; `get` and `get_mut` say so without
    // a panic path, which the optimiser does not always remove (the no-panic proof).
    fn at<T: Real, const R: usize, const C: usize>(m: &SMatrix<T, R, C>, i: usize, j: usize) -> T {
        m.get((i, j)).copied().unwrap_or_else(T::zero)
    }
    fn sub<T: Real, const R: usize, const C: usize>(m: &mut SMatrix<T, R, C>, i: usize, j: usize, v: T) {
        if let Some(e) = m.get_mut((i, j)) {
            *e -= v;
        }
    }
    let mut a = *a;
    let mut x = *b;
    for col in 0..N {
        let mut pivot = col;
        for row in col + 1..N {
            if at(&a, row, col).abs() > at(&a, pivot, col).abs() {
                pivot = row;
            }
        }
        let p = at(&a, pivot, col);
        if p == T::zero() || !p.is_finite() {
            return None;
        }
        a.swap_rows(col, pivot);
        x.swap_rows(col, pivot);
        for row in col + 1..N {
            let f = at(&a, row, col) / p;
            if f == T::zero() {
                continue;
            }
            for j in col..N {
                let v = at(&a, col, j);
                sub(&mut a, row, j, f * v);
            }
            for j in 0..K {
                let v = at(&x, col, j);
                sub(&mut x, row, j, f * v);
            }
        }
    }
    for col in (0..N).rev() {
        for j in 0..K {
            let mut s = at(&x, col, j);
            for k in col + 1..N {
                s -= at(&a, col, k) * at(&x, k, j);
            }
            if let Some(e) = x.get_mut((col, j)) {
                *e = s / at(&a, col, col);
            }
        }
    }
    Some(x)
}
