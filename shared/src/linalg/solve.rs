use crate::Real;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OMatrix};

/// Solves `A X = B` by Gaussian elimination with partial pivoting.
///
/// Returns `None` when a pivot is exactly zero or not finite, or (for dynamic sizes) when the
/// shapes do not fit. Used where the system is small and a factorisation object would only add
/// trait bounds; like the rest of [`crate::linalg`] it uses only arithmetic and comparisons, so
/// it is bit-reproducible across platforms, and fixed and dynamic sizes give the same bits.
///
/// ```
/// use edgekf::linalg::solve;
/// use nalgebra::{Matrix2, Vector2};
/// let x = solve(&Matrix2::new(0.0, 2.0, 4.0, 1.0), &Vector2::new(2.0, 9.0)).unwrap();
/// assert_eq!(x, Vector2::new(2.0, 1.0));
/// ```
pub fn solve<T: Real, D: Dim, K: Dim>(a: &OMatrix<T, D, D>, b: &OMatrix<T, D, K>) -> Option<OMatrix<T, D, K>>
where
    DefaultAllocator: Allocator<D, D> + Allocator<D, K>,
{
    let n = a.nrows();
    if a.ncols() != n || b.nrows() != n {
        return None;
    }
    let k_cols = b.ncols();
    let mut a = a.clone();
    let mut x = b.clone();
    // Every index below is in range by the loops' bounds; `get` and `get_mut` say so without a
    // panic path, which the optimiser does not always remove (the firmware's no-panic proof).
    fn at<T: Real, R: Dim, C: Dim>(m: &OMatrix<T, R, C>, i: usize, j: usize) -> T
    where
        DefaultAllocator: Allocator<R, C>,
    {
        m.get((i, j)).copied().unwrap_or_else(T::zero)
    }
    fn sub<T: Real, R: Dim, C: Dim>(m: &mut OMatrix<T, R, C>, i: usize, j: usize, v: T)
    where
        DefaultAllocator: Allocator<R, C>,
    {
        if let Some(e) = m.get_mut((i, j)) {
            *e -= v;
        }
    }
    for col in 0..n {
        let mut pivot = col;
        for row in col + 1..n {
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
        for row in col + 1..n {
            let f = at(&a, row, col) / p;
            if f == T::zero() {
                continue;
            }
            for j in col..n {
                let v = at(&a, col, j);
                sub(&mut a, row, j, f * v);
            }
            for j in 0..k_cols {
                let v = at(&x, col, j);
                sub(&mut x, row, j, f * v);
            }
        }
    }
    for col in (0..n).rev() {
        for j in 0..k_cols {
            let mut s = at(&x, col, j);
            for k in col + 1..n {
                s -= at(&a, col, k) * at(&x, k, j);
            }
            if let Some(e) = x.get_mut((col, j)) {
                *e = s / at(&a, col, col);
            }
        }
    }
    Some(x)
}
