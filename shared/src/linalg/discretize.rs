use super::{expm, LinalgError};
use crate::Real;
use nalgebra::SMatrix;

/// Exact zero-order-hold discretisation of `ẋ = A x + B u` over a step `dt`:
/// `A_D = e^{A dt}`, `B_D = ∫₀^dt e^{A s} ds B`, both read from the exponential of the block
/// matrix `[[A, B], [0, 0]] dt`. Unlike `A⁻¹(A_D − I)B` this needs no invertible `A` (rigid-body
/// modes and random-walk inputs are fine).
///
/// `NM` must equal `N + M` (stable Rust cannot add const generics); otherwise
/// [`LinalgError::SizeMismatch`].
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
    if NM != N + M {
        return Err(LinalgError::SizeMismatch);
    }
    let mut block = SMatrix::<T, NM, NM>::zeros();
    block.fixed_view_mut::<N, N>(0, 0).copy_from(&(a * dt));
    block.fixed_view_mut::<N, M>(0, N).copy_from(&(b * dt));
    let e = expm(&block)?;
    Ok((e.fixed_view::<N, N>(0, 0).into_owned(), e.fixed_view::<N, M>(0, N).into_owned()))
}

/// Van Loan's method: the exact discrete process-noise covariance
/// `Q_D = ∫₀^dt e^{A s} Q_c e^{Aᵀ s} ds` of a continuous white-noise model, together with
/// `A_D = e^{A dt}`. `N2` must equal `2 N`.
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
    if N2 != 2 * N {
        return Err(LinalgError::SizeMismatch);
    }
    let mut block = SMatrix::<T, N2, N2>::zeros();
    block.fixed_view_mut::<N, N>(0, 0).copy_from(&(-a * dt));
    block.fixed_view_mut::<N, N>(0, N).copy_from(&(qc * dt));
    block.fixed_view_mut::<N, N>(N, N).copy_from(&(a.transpose() * dt));
    let e = expm(&block)?;
    let ad = e.fixed_view::<N, N>(N, N).transpose();
    let qd = ad * e.fixed_view::<N, N>(0, N);
    let half = T::of_f64(0.5);
    Ok((ad, (qd + qd.transpose()) * half))
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
}
