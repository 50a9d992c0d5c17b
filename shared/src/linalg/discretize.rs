use super::{expm, LinalgError};
use crate::Real;
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, Dim, OMatrix, SMatrix};

/// Exact zero-order-hold discretisation of `ẋ = A x + B u` over a step `dt`:
/// `A_D = e^{A dt}`, `B_D = ∫₀^dt e^{A s} ds B`, both read from the exponential of the block
/// matrix `[[A, B], [0, 0]] dt`. Unlike `A⁻¹(A_D − I)B` this needs no invertible `A` (rigid-body
/// modes and random-walk inputs are fine).
///
/// `NM` must equal `N + M` (stable Rust cannot add const generics); otherwise
/// [`LinalgError::SizeMismatch`]. For any nalgebra dimensions (a `DMatrix`) see [`zoh_with`].
///
/// ```
/// use edgekf::linalg::zoh;
/// use nalgebra::{Matrix1, SMatrix};
/// // Integrator ẋ = u: A_D = 1, B_D = dt.
/// let (ad, bd) = zoh::<f64, 1, 1, 2>(&Matrix1::new(0.0), &Matrix1::new(1.0), 0.25).unwrap();
/// assert_eq!((ad[(0, 0)], bd[(0, 0)]), (1.0, 0.25));
/// ```
#[allow(clippy::type_complexity)]
pub fn zoh<T: Real, const N: usize, const M: usize, const NM: usize>(
    a: &SMatrix<T, N, N>,
    b: &SMatrix<T, N, M>,
    dt: T,
) -> Result<(SMatrix<T, N, N>, SMatrix<T, N, M>), LinalgError> {
    zoh_with(a, b, dt, Const::<NM>)
}

/// [`zoh`] for any nalgebra dimensions: `block` is the dimension of the `(N + M)`-square block
/// matrix, `Const::<{N + M}>` for fixed sizes or `Dyn(n + m)` for a `DMatrix` (nalgebra cannot
/// add two generic dimensions for us). Shapes that do not fit are
/// [`LinalgError::SizeMismatch`], never a panic.
///
/// ```
/// # #[cfg(feature = "alloc")] {
/// use edgekf::linalg::zoh_with;
/// use nalgebra::{DMatrix, Dyn};
/// let (a, b) = (DMatrix::from_element(1, 1, 0.0), DMatrix::from_element(1, 1, 1.0));
/// let (ad, bd) = zoh_with(&a, &b, 0.25, Dyn(2)).unwrap();
/// assert_eq!((ad[(0, 0)], bd[(0, 0)]), (1.0, 0.25));
/// assert!(zoh_with(&a, &b, 0.25, Dyn(3)).is_err());
/// # }
/// ```
#[allow(clippy::type_complexity)]
pub fn zoh_with<T: Real, N: Dim, M: Dim, B: Dim>(
    a: &OMatrix<T, N, N>,
    b: &OMatrix<T, N, M>,
    dt: T,
    block: B,
) -> Result<(OMatrix<T, N, N>, OMatrix<T, N, M>), LinalgError>
where
    DefaultAllocator: Allocator<N, N> + Allocator<N, M> + Allocator<B, B>,
{
    let (n, m) = b.shape_generic();
    if a.nrows() != n.value() || a.ncols() != n.value() || block.value() != n.value() + m.value() {
        return Err(LinalgError::SizeMismatch);
    }
    let e = block_expm(block, |big| {
        big.generic_view_mut((0, 0), (n, n)).copy_from(&(a * dt));
        big.generic_view_mut((0, n.value()), (n, m)).copy_from(&(b * dt));
    })?;
    Ok((e.generic_view((0, 0), (n, n)).into_owned(), e.generic_view((0, n.value()), (n, m)).into_owned()))
}

/// Van Loan's method: the exact discrete process-noise covariance
/// `Q_D = ∫₀^dt e^{A s} Q_c e^{Aᵀ s} ds` of a continuous white-noise model, together with
/// `A_D = e^{A dt}`. `N2` must equal `2 N`. For any nalgebra dimensions (a `DMatrix`) see
/// [`van_loan_with`].
///
/// The result is symmetrised, since round-off leaves it a few ulps off.
///
/// ```
/// use edgekf::linalg::van_loan;
/// use nalgebra::{Matrix1, Matrix2};
/// // Random walk ẋ = w, E[w w] = q: Q_D = q dt.
/// let (ad, qd) = van_loan::<f64, 1, 2>(&Matrix1::new(0.0), &Matrix1::new(3.0), 0.5).unwrap();
/// assert_eq!(ad[(0, 0)], 1.0);
/// assert!((qd[(0, 0)] - 1.5).abs() < 1e-15);
/// ```
#[allow(clippy::type_complexity)]
pub fn van_loan<T: Real, const N: usize, const N2: usize>(
    a: &SMatrix<T, N, N>,
    qc: &SMatrix<T, N, N>,
    dt: T,
) -> Result<(SMatrix<T, N, N>, SMatrix<T, N, N>), LinalgError> {
    van_loan_with(a, qc, dt, Const::<N2>)
}

/// [`van_loan`] for any nalgebra dimensions: `block` is the dimension of the `2N`-square block
/// matrix, `Const::<{2 N}>` for fixed sizes or `Dyn(2 n)` for a `DMatrix`. The host's reduced
/// models of any size discretise here, by the chip's arithmetic. Shapes that do not fit are
/// [`LinalgError::SizeMismatch`], never a panic.
///
/// ```
/// # #[cfg(feature = "alloc")] {
/// use edgekf::linalg::van_loan_with;
/// use nalgebra::{DMatrix, Dyn};
/// // ẍ = w with E[w w] = 2: Q_D = 2 [[dt³/3, dt²/2], [dt²/2, dt]].
/// let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
/// let qc = DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, 2.0]);
/// let (ad, qd) = van_loan_with(&a, &qc, 0.5f64, Dyn(4)).unwrap();
/// assert_eq!(ad[(0, 1)], 0.5);
/// assert!((qd[(0, 0)] - 2.0 * 0.125 / 3.0).abs() < 1e-16 && (qd[(1, 1)] - 1.0).abs() < 1e-15);
/// assert!(van_loan_with(&a, &qc, 0.5, Dyn(3)).is_err());
/// # }
/// ```
#[allow(clippy::type_complexity)]
pub fn van_loan_with<T: Real, N: Dim, B: Dim>(
    a: &OMatrix<T, N, N>,
    qc: &OMatrix<T, N, N>,
    dt: T,
    block: B,
) -> Result<(OMatrix<T, N, N>, OMatrix<T, N, N>), LinalgError>
where
    DefaultAllocator: Allocator<N, N> + Allocator<B, B>,
{
    let (n, cols) = a.shape_generic();
    let square = |m: &OMatrix<T, N, N>| m.nrows() == n.value() && m.ncols() == n.value();
    if cols.value() != n.value() || !square(qc) || block.value() != 2 * n.value() {
        return Err(LinalgError::SizeMismatch);
    }
    let k = n.value();
    let e = block_expm(block, |big| {
        big.generic_view_mut((0, 0), (n, n)).copy_from(&(-a * dt));
        big.generic_view_mut((0, k), (n, n)).copy_from(&(qc * dt));
        big.generic_view_mut((k, k), (n, n)).copy_from(&(a.transpose() * dt));
    })?;
    let ad = e.generic_view((k, k), (n, n)).transpose();
    let qd = &ad * e.generic_view((0, k), (n, n));
    let half = T::of_f64(0.5);
    Ok((ad, (&qd + qd.transpose()) * half))
}

/// The exponential of the `block`-square matrix that `fill` writes its blocks into (zero
/// elsewhere): the one step of both discretisations above.
fn block_expm<T: Real, B: Dim>(
    block: B,
    fill: impl FnOnce(&mut OMatrix<T, B, B>),
) -> Result<OMatrix<T, B, B>, LinalgError>
where
    DefaultAllocator: Allocator<B, B>,
{
    let mut big = OMatrix::<T, B, B>::zeros_generic(block, block);
    fill(&mut big);
    expm(&big)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector2};

    #[test]
    fn zoh_of_double_integrator() {
        // ẍ = u: A_D = [[1, dt],[0, 1]], B_D = [dt²/2, dt]
        let a = Matrix2::new(0.0, 1.0, 0.0, 0.0);
        let b = Vector2::new(0.0, 1.0);
        let dt = 0.1;
        let (ad, bd) = zoh::<f64, 2, 1, 3>(&a, &b, dt).unwrap();
        assert!((ad - Matrix2::new(1.0, dt, 0.0, 1.0)).abs().max() < 1e-16);
        assert!((bd[0] - dt * dt / 2.0).abs() < 1e-16 && (bd[1] - dt).abs() < 1e-16);
    }

    #[test]
    fn van_loan_of_white_noise_acceleration() {
        // ẍ = w with E[w w] = q: Q_D = q [[dt³/3, dt²/2],[dt²/2, dt]].
        let a = Matrix2::new(0.0, 1.0, 0.0, 0.0);
        let qc = Matrix2::new(0.0, 0.0, 0.0, 2.0);
        let dt = 0.01;
        let (_, qd) = van_loan::<f64, 2, 4>(&a, &qc, dt).unwrap();
        let expect = Matrix2::new(dt.powi(3) / 3.0, dt * dt / 2.0, dt * dt / 2.0, dt) * 2.0;
        assert!(((qd - expect).abs().max()) < 1e-18, "{qd} vs {expect}");
    }

    #[test]
    fn wrong_block_size_is_reported() {
        let a = Matrix2::<f64>::zeros();
        assert_eq!(van_loan::<f64, 2, 3>(&a, &a, 1.0), Err(LinalgError::SizeMismatch));
        assert_eq!(zoh::<f64, 2, 1, 4>(&a, &Vector2::zeros(), 1.0).unwrap_err(), LinalgError::SizeMismatch);
    }

    #[cfg(feature = "alloc")]
    #[test]
    fn dynamic_sizes_match_the_const_generic_forms() {
        use nalgebra::{DMatrix, Dyn, Matrix3, Vector3};
        // A damped mode with a random-walk force: the shape of the host's reduced models.
        let a = Matrix3::new(0.0, 1.0, 0.0, -400.0, -2.0, 1.0, 0.0, 0.0, 0.0);
        let qc = Matrix3::from_diagonal(&Vector3::new(0.0, 1e-3, 5.0));
        let dyn_of = |m: &Matrix3<f64>| DMatrix::from_fn(3, 3, |i, j| m[(i, j)]);
        let (ad, qd) = van_loan::<f64, 3, 6>(&a, &qc, 1e-3).unwrap();
        let (ad_d, qd_d) = van_loan_with(&dyn_of(&a), &dyn_of(&qc), 1e-3, Dyn(6)).unwrap();
        // The same algorithm; nalgebra's `std` products of a 6 × 6 `DMatrix` may sum in another
        // order, so allow a few ulps.
        let close = |f: &Matrix3<f64>, d: &DMatrix<f64>| {
            (0..3).all(|i| (0..3).all(|j| (f[(i, j)] - d[(i, j)]).abs() <= 1e-14 * f.abs().max()))
        };
        assert!(close(&ad, &ad_d) && close(&qd, &qd_d), "{ad} {ad_d} {qd} {qd_d}");
        let b = DMatrix::from_element(3, 1, 1.0);
        let (_, bd) = zoh_with(&dyn_of(&a), &b, 1e-3, Dyn(4)).unwrap();
        let (_, bd_f) = zoh::<f64, 3, 1, 4>(&a, &Vector3::repeat(1.0), 1e-3).unwrap();
        assert!((0..3).all(|i| (bd[(i, 0)] - bd_f[i]).abs() <= 1e-15 * bd_f.abs().max()));
        // Shapes that do not fit are errors, not panics.
        let rect = DMatrix::<f64>::zeros(3, 2);
        assert_eq!(van_loan_with(&rect, &rect, 1.0, Dyn(6)).unwrap_err(), LinalgError::SizeMismatch);
        assert_eq!(
            van_loan_with(&dyn_of(&a), &DMatrix::zeros(2, 2), 1.0, Dyn(6)).unwrap_err(),
            LinalgError::SizeMismatch
        );
        assert_eq!(zoh_with(&dyn_of(&a), &DMatrix::zeros(2, 1), 1.0, Dyn(4)).unwrap_err(), LinalgError::SizeMismatch);
        assert!(super::super::solve(&rect, &DMatrix::<f64>::zeros(3, 1)).is_none());
        assert!(super::super::solve(&dyn_of(&a), &DMatrix::<f64>::zeros(2, 1)).is_none());
    }
}
