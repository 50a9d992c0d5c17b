use crate::Real;
use nalgebra::SMatrix;

/// Dot product of two equally long slices, unrolled by eight with four partial sums.
///
/// The filters spend almost all their time here. Independent sums let the Cortex-M4F's FPU
/// pipeline overlap the multiply-adds, and the unrolling cuts the loop overhead to a few
/// instructions per eight products (measured: 3.5 instructions per multiply-add); the summation order
/// is fixed by this code, so the result is still bit-identical on the chip and the host. Extra
/// elements of the longer slice are ignored.
///
/// ```
/// use edgekf::linalg::dot;
/// assert_eq!(dot(&[1.0, 2.0, 3.0, 4.0, 5.0], &[1.0, 1.0, 1.0, 1.0, 2.0]), 20.0);
/// ```
#[inline]
pub fn dot<T: Real>(a: &[T], b: &[T]) -> T {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [T::zero(); 4];
    let mut ca = a.chunks_exact(8);
    let mut cb = b.chunks_exact(8);
    for (x, y) in (&mut ca).zip(&mut cb) {
        acc[0] += x[0] * y[0] + x[4] * y[4];
        acc[1] += x[1] * y[1] + x[5] * y[5];
        acc[2] += x[2] * y[2] + x[6] * y[6];
        acc[3] += x[3] * y[3] + x[7] * y[7];
    }
    let mut tail = T::zero();
    for (x, y) in ca.remainder().iter().zip(cb.remainder()) {
        tail += *x * *y;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// Column `j` of a column-major static matrix as a contiguous slice (empty if out of range).
///
/// ```
/// use edgekf::linalg::column;
/// use nalgebra::Matrix2;
/// assert_eq!(column(&Matrix2::new(1.0, 2.0, 3.0, 4.0), 1), &[2.0, 4.0]);
/// ```
#[inline]
pub fn column<T: Real, const R: usize, const C: usize>(m: &SMatrix<T, R, C>, j: usize) -> &[T] {
    m.as_slice().get(j * R..(j + 1) * R).unwrap_or(&[])
}

/// Eight dot products at once: columns `a0..a3` against columns `b0, b1`, each summed in
/// order of `k`. Six loads serve eight multiply-adds (about 2.3 instructions per multiply-add on
/// the Cortex-M4F, against 4 for a plain dot product).
///
/// The operands are fixed-length arrays (nalgebra's column storage), so the loop has a
/// compile-time trip count and no bounds checks whatever the surrounding code. With slices the
/// same kernel lost its hoisted checks when another filter size was instantiated elsewhere in
/// the image (measured: 140k → 224k instructions for the 24-state step).
#[inline(always)]
fn dot4x2<T: Real, const K: usize>(a: [&[T; K]; 4], b0: &[T; K], b1: &[T; K]) -> [T; 8] {
    let mut s = [T::zero(); 8];
    for k in 0..K {
        let (y0, y1) = (b0[k], b1[k]);
        let (x0, x1, x2, x3) = (a[0][k], a[1][k], a[2][k], a[3][k]);
        s[0] += x0 * y0;
        s[1] += x1 * y0;
        s[2] += x2 * y0;
        s[3] += x3 * y0;
        s[4] += x0 * y1;
        s[5] += x1 * y1;
        s[6] += x2 * y1;
        s[7] += x3 * y1;
    }
    s
}

/// Four dot products at once (`[a0·b0, a0·b1, a1·b0, a1·b1]`), for the rows left over by
/// [`dot4x2`].
#[inline(always)]
fn dot2x2<T: Real, const K: usize>(a0: &[T; K], a1: &[T; K], b0: &[T; K], b1: &[T; K]) -> [T; 4] {
    let mut s = [T::zero(); 4];
    for k in 0..K {
        s[0] += a0[k] * b0[k];
        s[1] += a0[k] * b1[k];
        s[2] += a1[k] * b0[k];
        s[3] += a1[k] * b1[k];
    }
    s
}

/// `out = aᵀ b` (that is `out[i][j] = a[:, i] · b[:, j]`), on the upper triangle only
/// (`i ≤ j`) when `upper` is set. See [`mul_tr_add`] to add to `out` instead. Every element is a dot product of two contiguous columns in
/// a fixed order (index `k` ascending), so the result does not depend on the platform.
///
/// ```
/// use edgekf::linalg::mul_tr;
/// use nalgebra::{Matrix2, Matrix2x3, Matrix3x2};
/// let a = Matrix3x2::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0);
/// let b = Matrix3x2::new(1.0, 0.0, 0.0, 1.0, 1.0, 1.0);
/// let mut out = Matrix2::zeros();
/// mul_tr(&a, &b, &mut out, false);
/// assert_eq!(out, a.transpose() * b);
/// ```
pub fn mul_tr<T: Real, const K: usize, const R: usize, const C: usize>(
    a: &SMatrix<T, K, R>,
    b: &SMatrix<T, K, C>,
    out: &mut SMatrix<T, R, C>,
    upper: bool,
) {
    product(a, b, out, upper, false);
}

/// `out += aᵀ b`, like [`mul_tr`] otherwise (the addition comes after each dot product).
///
/// ```
/// use edgekf::linalg::mul_tr_add;
/// use nalgebra::Matrix2;
/// let mut out = Matrix2::identity();
/// mul_tr_add(&Matrix2::new(1.0, 0.0, 0.0, 2.0), &Matrix2::new(3.0, 0.0, 0.0, 4.0), &mut out, false);
/// assert_eq!(out, Matrix2::new(4.0, 0.0, 0.0, 9.0));
/// ```
pub fn mul_tr_add<T: Real, const K: usize, const R: usize, const C: usize>(
    a: &SMatrix<T, K, R>,
    b: &SMatrix<T, K, C>,
    out: &mut SMatrix<T, R, C>,
    upper: bool,
) {
    product(a, b, out, upper, true);
}

#[inline]
fn product<T: Real, const K: usize, const R: usize, const C: usize>(
    a: &SMatrix<T, K, R>,
    b: &SMatrix<T, K, C>,
    out: &mut SMatrix<T, R, C>,
    upper: bool,
    add: bool,
) {
    let mut put = |i: usize, j: usize, v: T| {
        // `get_mut`: in range by the loops' bounds, without a panic path (the no-panic proof).
        if let Some(o) = out.get_mut((i, j)) {
            if add {
                *o += v;
            } else {
                *o = v;
            }
        }
    };
    let (ac, bc) = (&a.data.0, &b.data.0);
    let mut j = 0;
    while j < C {
        let two_j = j + 1 < C;
        let Some(b0) = bc.get(j) else { break };
        let b1 = if two_j { bc.get(j + 1).unwrap_or(b0) } else { b0 };
        let rows = if upper { (j + 2).min(R) } else { R };
        let mut i = 0;
        while i + 4 <= rows {
            let Some([a0, a1, a2, a3]) = ac.get(i..i + 4) else { break };
            let s = dot4x2([a0, a1, a2, a3], b0, b1);
            for r in 0..4 {
                put(i + r, j, s[r]);
                if two_j {
                    put(i + r, j + 1, s[4 + r]);
                }
            }
            i += 4;
        }
        while i < rows {
            let two_i = i + 1 < rows;
            // `get`: the optimiser does not always see `i < rows <= R` here (no panic path).
            let Some(a0) = ac.get(i) else { break };
            let a1 = if two_i { ac.get(i + 1).unwrap_or(a0) } else { a0 };
            let s = dot2x2(a0, a1, b0, b1);
            put(i, j, s[0]);
            if two_j {
                put(i, j + 1, s[1]);
            }
            if two_i {
                put(i + 1, j, s[2]);
                if two_j {
                    put(i + 1, j + 1, s[3]);
                }
            }
            i += if two_i { 2 } else { 1 };
        }
        j += 2;
    }
}
