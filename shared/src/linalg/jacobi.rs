//! Eigenvalues and eigenvectors of a small symmetric matrix by cyclic Jacobi rotations: only
//! `+ − × ÷` and `sqrt` on fixed arrays, so it has no panic path (nalgebra's
//! `symmetric_eigen` asserts on its dimensions) and gives the chip and the host the same bits.

use nalgebra::{SMatrix, SVector};

/// Most sweeps: a few suffice for small matrices (convergence is quadratic).
const SWEEPS: usize = 30;

/// The eigenvalues (ascending) and the eigenvectors (columns, in the same order) of the
/// symmetric `a` (its upper triangle is read). Non-finite input gives non-finite output.
///
/// ```
/// use edgekf::linalg::symmetric_eigen;
/// use nalgebra::{Matrix3, Vector3};
/// let a = Matrix3::new(4.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 2.0);
/// let (w, v) = symmetric_eigen(&a);
/// assert!(w[0] <= w[1] && w[1] <= w[2]);
/// for i in 0..3 {
///     let x: Vector3<f64> = v.column(i).into_owned();
///     assert!((a * x - x * w[i]).norm() < 1e-12 && (x.norm() - 1.0).abs() < 1e-12);
/// }
/// ```
pub fn symmetric_eigen<const N: usize>(a: &SMatrix<f64, N, N>) -> (SVector<f64, N>, SMatrix<f64, N, N>) {
    let mut m = [[0.0f64; N]; N];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            // The upper triangle, mirrored.
            *v = if i <= j { a.get((i, j)) } else { a.get((j, i)) }.copied().unwrap_or(f64::NAN);
        }
    }
    let mut v = [[0.0f64; N]; N];
    for (i, row) in v.iter_mut().enumerate() {
        if let Some(d) = row.get_mut(i) {
            *d = 1.0;
        }
    }
    for _ in 0..SWEEPS {
        let mut off = 0.0;
        let mut diag = 0.0;
        for (i, row) in m.iter().enumerate() {
            for (j, x) in row.iter().enumerate() {
                if i == j {
                    diag += x * x;
                } else {
                    off += x * x;
                }
            }
        }
        // Converged, or nothing finite left to rotate (NaN compares false).
        let rotating = off > 1e-30 * diag;
        if !rotating {
            break;
        }
        for p in 0..N {
            for q in p + 1..N {
                rotate(&mut m, &mut v, p, q);
            }
        }
    }
    // Ascending, by insertion on an index array.
    let mut order = [0usize; N];
    for (i, o) in order.iter_mut().enumerate() {
        *o = i;
    }
    let value = |i: usize| m.get(i).and_then(|r| r.get(i)).copied().unwrap_or(f64::NAN);
    for i in 1..N {
        let mut j = i;
        while j > 0 {
            let (Some(&lo), Some(&hi)) = (order.get(j - 1), order.get(j)) else { break };
            if !value(lo).total_cmp(&value(hi)).is_gt() {
                break;
            }
            if let Some(o) = order.get_mut(j - 1) {
                *o = hi;
            }
            if let Some(o) = order.get_mut(j) {
                *o = lo;
            }
            j -= 1;
        }
    }
    let values = SVector::<f64, N>::from_fn(|i, _| order.get(i).map_or(f64::NAN, |&k| value(k)));
    let vectors = SMatrix::<f64, N, N>::from_fn(|r, c| {
        order.get(c).and_then(|&k| v.get(r).and_then(|row| row.get(k))).copied().unwrap_or(f64::NAN)
    });
    (values, vectors)
}

/// One rotation in the `(p, q)` plane that zeroes `m[p][q]`: `m = Jᵀ m J`, `v = v J`.
fn rotate<const N: usize>(m: &mut [[f64; N]; N], v: &mut [[f64; N]; N], p: usize, q: usize) {
    let (Some(&apq), Some(&app), Some(&aqq)) =
        (m.get(p).and_then(|r| r.get(q)), m.get(p).and_then(|r| r.get(p)), m.get(q).and_then(|r| r.get(q)))
    else {
        return;
    };
    if apq == 0.0 {
        return;
    }
    let theta = (aqq - app) / (2.0 * apq);
    let t = if theta.abs() > 1e150 {
        0.5 / theta
    } else {
        let t = 1.0 / (theta.abs() + libm::sqrt(theta * theta + 1.0));
        if theta < 0.0 {
            -t
        } else {
            t
        }
    };
    let c = 1.0 / libm::sqrt(t * t + 1.0);
    let s = t * c;
    // Columns p and q of m and v, then rows p and q of m.
    for row in m.iter_mut().chain(v.iter_mut()) {
        if let (Some(&x), Some(&y)) = (row.get(p), row.get(q)) {
            if let Some(r) = row.get_mut(p) {
                *r = c * x - s * y;
            }
            if let Some(r) = row.get_mut(q) {
                *r = s * x + c * y;
            }
        }
    }
    if let (Some(&rp), Some(&rq)) = (m.get(p), m.get(q)) {
        let (mut np, mut nq) = (rp, rq);
        for (((a, b), x), y) in np.iter_mut().zip(nq.iter_mut()).zip(&rp).zip(&rq) {
            *a = c * x - s * y;
            *b = s * x + c * y;
        }
        if let Some(r) = m.get_mut(p) {
            *r = np;
        }
        if let Some(r) = m.get_mut(q) {
            *r = nq;
        }
    }
}
