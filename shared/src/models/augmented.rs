//! Augmented Kalman filter (AKF) models for unknown-input estimation on structures.
//!
//! The unknown input `u` (forces) joins the state with a random-walk model, as in the rotor
//! paper (Lourens et al.'s AKF):
//!
//! ```text
//! [x; u]' = [[A_D, B_D], [0, I]] [x; u] + w,     y = [C, D] [x; u] + v,
//! ```
//!
//! with `A_D, B_D` the exact zero-order-hold discretisation of `ẋ = A x + B u`. Channels may be
//! displacements, velocities or accelerations of a second-order structural model
//! `M q̈ + C_d q̇ + K q = S_f u` (state `x = [q; q̇]`); an acceleration channel has a direct
//! feed-through `D` of the input.
//!
//! With accelerations only, the AKF drifts: a low-frequency error in displacement and force is
//! unobservable, and the random walk lets it grow without bound. The documented fix is the
//! *dummy displacement measurement* of Naets, Cuadrado and Desmet (2015): add channels that
//! "measure" selected displacements as zero with a large variance. It costs nothing at the
//! frequencies of interest (the variance is far above the vibration amplitude's square) and
//! anchors the drift. [`Channel::DummyDisplacement`] builds such a row; feed it `0.0`.

use crate::filter::LinearModel;
use crate::linalg::{solve, zoh, LinalgError};
use nalgebra::SMatrix;

/// What a measurement channel reads, on degree of freedom `dof` of a second-order model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    /// Displacement `q_dof`.
    Displacement(usize),
    /// Velocity `q̇_dof`.
    Velocity(usize),
    /// Acceleration `q̈_dof` (depends on the input directly).
    Acceleration(usize),
    /// A pseudo-measurement `q_dof = 0` against acceleration-only drift (feed it 0).
    DummyDisplacement(usize),
}

/// A second-order structural model in first-order form: `x = [q; q̇]`, `ẋ = A x + B u`.
///
/// `N` must be `2 D`, checked at construction.
#[derive(Debug, Clone, PartialEq)]
pub struct StructuralModel<const D: usize, const N: usize, const P: usize> {
    /// `A = [[0, I], [−M⁻¹K, −M⁻¹C]]`.
    pub a: SMatrix<f64, N, N>,
    /// `B = [0; M⁻¹ S_f]`.
    pub b: SMatrix<f64, N, P>,
}

impl<const D: usize, const N: usize, const P: usize> StructuralModel<D, N, P> {
    /// From mass, damping and stiffness matrices and the input's location matrix `S_f`.
    ///
    /// ```
    /// use edgekf::models::augmented::StructuralModel;
    /// use nalgebra::{Matrix1};
    /// // One mass of 2 kg on a 50 N/m spring: A = [[0, 1], [−25, 0]], B = [0, 0.5].
    /// let s = StructuralModel::<1, 2, 1>::new(&Matrix1::new(2.0), &Matrix1::new(0.0), &Matrix1::new(50.0), &Matrix1::new(1.0)).unwrap();
    /// assert_eq!((s.a[(1, 0)], s.b[(1, 0)]), (-25.0, 0.5));
    /// ```
    pub fn new(
        mass: &SMatrix<f64, D, D>,
        damping: &SMatrix<f64, D, D>,
        stiffness: &SMatrix<f64, D, D>,
        input: &SMatrix<f64, D, P>,
    ) -> Result<Self, LinalgError> {
        if N != 2 * D {
            return Err(LinalgError::SizeMismatch);
        }
        let mk = solve(mass, stiffness).ok_or(LinalgError::Singular)?;
        let mc = solve(mass, damping).ok_or(LinalgError::Singular)?;
        let ms = solve(mass, input).ok_or(LinalgError::Singular)?;
        let mut a = SMatrix::<f64, N, N>::zeros();
        let mut b = SMatrix::<f64, N, P>::zeros();
        for i in 0..D {
            a[(i, D + i)] = 1.0;
            for j in 0..D {
                a[(D + i, j)] = -mk[(i, j)];
                a[(D + i, D + j)] = -mc[(i, j)];
            }
            for j in 0..P {
                b[(D + i, j)] = ms[(i, j)];
            }
        }
        Ok(Self { a, b })
    }

    /// The rows `C` (on the state) and `D` (on the input) of the given channels.
    #[allow(clippy::type_complexity)]
    pub fn output<const M: usize>(
        &self,
        channels: &[Channel; M],
    ) -> Result<(SMatrix<f64, M, N>, SMatrix<f64, M, P>), LinalgError> {
        let mut c = SMatrix::<f64, M, N>::zeros();
        let mut d = SMatrix::<f64, M, P>::zeros();
        for (row, ch) in channels.iter().enumerate() {
            match *ch {
                Channel::Displacement(i) | Channel::DummyDisplacement(i) if i < D => c[(row, i)] = 1.0,
                Channel::Velocity(i) if i < D => c[(row, D + i)] = 1.0,
                Channel::Acceleration(i) if i < D => {
                    c.row_mut(row).copy_from(&self.a.row(D + i));
                    d.row_mut(row).copy_from(&self.b.row(D + i));
                }
                _ => return Err(LinalgError::SizeMismatch),
            }
        }
        Ok((c, d))
    }
}

/// Noise settings of an augmented model.
#[derive(Debug, Clone, PartialEq)]
pub struct AugmentedNoise<const N: usize, const P: usize, const M: usize> {
    /// Discrete process noise on the structural state.
    pub q_state: SMatrix<f64, N, N>,
    /// Discrete random-walk increment covariance of the input, per step.
    pub q_input: SMatrix<f64, P, P>,
    /// Measurement noise (dummy channels included, with their large variance).
    pub r: SMatrix<f64, M, M>,
}

/// Builds the augmented discrete model `[[A_D, B_D], [0, I]]`, `[C, D]`,
/// `Q = diag(Q_x, Q_u)`. `NA` must be `N + P`.
///
/// ```
/// use edgekf::models::augmented::{augment, AugmentedNoise};
/// use nalgebra::{Matrix1, Matrix2, RowVector2, Vector2};
/// // A mass-spring (ωn = 5 rad/s) whose displacement is read; the force is unknown.
/// let a = Matrix2::new(0.0, 1.0, -25.0, 0.0);
/// let b = Vector2::new(0.0, 1.0);
/// let noise = AugmentedNoise { q_state: Matrix2::zeros(), q_input: Matrix1::new(1.0), r: Matrix1::new(1e-6) };
/// let m = augment::<2, 1, 1, 3>(&a, &b, &RowVector2::new(1.0, 0.0), &Matrix1::new(0.0), &noise, 0.01).unwrap();
/// assert_eq!(m.a[(2, 2)], 1.0); // random walk
/// assert!((m.a[(1, 2)] - 0.01).abs() < 1e-5); // B_D ≈ B dt
/// ```
pub fn augment<const N: usize, const P: usize, const M: usize, const NA: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, P>,
    c: &SMatrix<f64, M, N>,
    d: &SMatrix<f64, M, P>,
    noise: &AugmentedNoise<N, P, M>,
    dt: f64,
) -> Result<LinearModel<f64, NA, M>, LinalgError> {
    if NA != N + P {
        return Err(LinalgError::SizeMismatch);
    }
    let (ad, bd) = zoh::<f64, N, P, NA>(a, b, dt)?;
    let mut aa = SMatrix::<f64, NA, NA>::identity();
    aa.fixed_view_mut::<N, N>(0, 0).copy_from(&ad);
    aa.fixed_view_mut::<N, P>(0, N).copy_from(&bd);
    let mut ca = SMatrix::<f64, M, NA>::zeros();
    ca.fixed_view_mut::<M, N>(0, 0).copy_from(c);
    ca.fixed_view_mut::<M, P>(0, N).copy_from(d);
    let mut qa = SMatrix::<f64, NA, NA>::zeros();
    qa.fixed_view_mut::<N, N>(0, 0).copy_from(&noise.q_state);
    qa.fixed_view_mut::<P, P>(N, N).copy_from(&noise.q_input);
    Ok(LinearModel { a: aa, c: ca, q: qa, r: noise.r })
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::filter::KalmanFilter;
    use nalgebra::{Matrix2, Matrix3, SVector, Vector2, Vector3};
    use std::{eprintln, vec, vec::Vec};

    /// Two masses (1 kg each) in a chain of springs (400 N/m each) to ground, 1 % damping-ish;
    /// the unknown force acts on mass 2.
    fn chain() -> StructuralModel<2, 4, 1> {
        let m = Matrix2::identity();
        let k = Matrix2::new(800.0, -400.0, -400.0, 400.0);
        let c = k * 1e-3;
        StructuralModel::new(&m, &c, &k, &Vector2::new(0.0, 1.0)).unwrap()
    }

    /// Force with dynamic content only (2.2 Hz and 4.1 Hz, near the modes at 1.97 and 5.15 Hz),
    /// simulated with RK4 at 20 sub-steps.
    fn simulate(
        s: &StructuralModel<2, 4, 1>,
        dt: f64,
        n: usize,
    ) -> (Vec<SVector<f64, 4>>, Vec<f64>, Vec<Vector2<f64>>) {
        let force = |t: f64| {
            (2.0 * core::f64::consts::PI * 2.2 * t).cos() + 0.5 * (2.0 * core::f64::consts::PI * 4.1 * t).sin()
        };
        let f = |x: &SVector<f64, 4>, t: f64| s.a * x + s.b * force(t);
        let (mut x, mut xs, mut us, mut acc) = (SVector::<f64, 4>::zeros(), vec![], vec![], vec![]);
        let h = dt / 20.0;
        for k in 0..n {
            let t0 = k as f64 * dt;
            xs.push(x);
            us.push(force(t0));
            let xd = f(&x, t0);
            acc.push(Vector2::new(xd[2], xd[3]));
            for j in 0..20 {
                let t = t0 + j as f64 * h;
                let k1 = f(&x, t);
                let k2 = f(&(x + k1 * (h / 2.0)), t + h / 2.0);
                let k3 = f(&(x + k2 * (h / 2.0)), t + h / 2.0);
                let k4 = f(&(x + k3 * h), t + h);
                x += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
            }
        }
        (xs, us, acc)
    }

    /// RMS of the displacement-of-mass-2 error over the last quarter of the run, and of the force.
    fn run_akf<const M: usize, const NA: usize>(channels: [Channel; M], r: SMatrix<f64, M, M>) -> (f64, f64) {
        let s = chain();
        let dt = 1e-3;
        let n = 60_000;
        let (xs, us, acc) = simulate(&s, dt, n);
        let (c, d) = s.output(&channels).unwrap();
        let noise = AugmentedNoise { q_state: SMatrix::identity() * 1e-12, q_input: SMatrix::identity() * Q_INPUT, r };
        let model = augment::<4, 1, M, NA>(&s.a, &s.b, &c, &d, &noise, dt).unwrap();
        let mut kf = KalmanFilter::new(model, SVector::zeros(), SMatrix::identity() * 1e-2);
        let (mut e_x, mut e_u, mut cnt) = (0.0, 0.0, 0);
        for k in 0..n {
            let y = SVector::<f64, M>::from_fn(|row, _| match channels[row] {
                Channel::Acceleration(i) => acc[k][i],
                _ => 0.0,
            });
            kf.update(&y).unwrap();
            if k >= 3 * n / 4 {
                e_x += (kf.state()[1] - xs[k][1]).powi(2);
                e_u += (kf.state()[4] - us[k]).powi(2);
                cnt += 1;
            }
            kf.predict();
        }
        ((e_x / cnt as f64).sqrt(), (e_u / cnt as f64).sqrt())
    }

    const Q_INPUT: f64 = 1e-3;

    #[test]
    fn acceleration_only_drifts_and_the_dummy_measurement_anchors_it() {
        let r_acc = 1e-6;
        let (drift_x, drift_u) =
            run_akf::<2, 5>([Channel::Acceleration(0), Channel::Acceleration(1)], Matrix2::identity() * r_acc);
        let (fixed_x, fixed_u) = run_akf::<3, 5>(
            [Channel::Acceleration(0), Channel::Acceleration(1), Channel::DummyDisplacement(1)],
            Matrix3::from_diagonal(&Vector3::new(r_acc, r_acc, 1e-3)),
        );
        // Mass-2 displacement amplitude is a few millimetres; the dummy channel says "0 ± 32 mm".
        eprintln!("acceleration only: x err {drift_x:.2e} m, u err {drift_u:.2e} N; with dummy: {fixed_x:.2e} m, {fixed_u:.2e} N");
        assert!(fixed_x < 1e-3, "dummy-measurement displacement error {fixed_x}");
        assert!(drift_x > 5.0 * fixed_x, "expected drift without the dummy measurement: {drift_x} vs {fixed_x}");
        assert!(fixed_u < 0.1, "force error {fixed_u}");
    }

    #[test]
    fn output_rows_follow_the_channel_kinds() {
        let s = chain();
        let (c, d) = s.output(&[Channel::Displacement(1), Channel::Velocity(0), Channel::Acceleration(1)]).unwrap();
        assert_eq!(c.row(0).iter().copied().collect::<Vec<_>>(), [0.0, 1.0, 0.0, 0.0]);
        assert_eq!(c.row(1).iter().copied().collect::<Vec<_>>(), [0.0, 0.0, 1.0, 0.0]);
        assert_eq!(c[(2, 0)], 400.0); // −(M⁻¹K)₁₀ = 400
        assert_eq!(d[(2, 0)], 1.0);
        assert!(s.output(&[Channel::Velocity(2)]).is_err());
    }
}
