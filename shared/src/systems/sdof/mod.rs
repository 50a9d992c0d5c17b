//! A base-excited single-degree-of-freedom mount: the smallest system of the project, there to
//! prove what adding a system costs (it is behind the `sdof` feature, off by default).
//!
//! The physics: a mass `m` on a spring and a damper whose other end is fixed to a base that
//! moves with an unknown acceleration `a_b(t)`. With `z` the displacement of the mass relative
//! to the base (what no sensor measures: the mount's deflection),
//!
//! ```text
//! z̈ + 2ζωn ż + ωn² z = −a_b            (the base's motion drives the relative motion)
//! y  = ẍ_abs = −ωn² z − 2ζωn ż + v      (an accelerometer on the mass reads its absolute
//!                                        acceleration: spring and damper force over m)
//! ```
//!
//! The base acceleration never enters the measurement, so it is the model's process noise: a
//! white acceleration of two-sided density `base_psd`. The filter's state is
//! `[ωn² z, ωn ż]`, both in m/s², for the reason the oscillator's is scaled: with `[z, ż]` the
//! measurement row holds `ωn² ≈ 4·10³` and `C P Cᵀ + R` loses its digits in `f32`.
//!
//! The model is discretised once, exactly (Van Loan, [`crate::linalg::van_loan`]) in `f64`,
//! and run by the shared time-varying [`KalmanFilter`] in `T`: two states cost the chip little,
//! and after a gap the covariance says how uncertain the bridged estimate is.

use crate::filter::{FilterHealth, KalmanFilter, LinearModel};
use crate::linalg::{van_loan, LinalgError};
use crate::Real;
use nalgebra::{Matrix1, Matrix2, RowVector2, Vector1, Vector2};

/// Number of states: scaled relative displacement and velocity.
pub const STATES: usize = 2;

/// The mount's model and its filter's tuning. All SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SdofParams {
    /// Natural frequency of the mount, Hz.
    pub natural_freq_hz: f64,
    /// Damping ratio (dimensionless).
    pub damping_ratio: f64,
    /// Sample rate of the accelerometer, Hz.
    pub sample_rate_hz: f64,
    /// Standard deviation of the accelerometer's noise per sample, m/s².
    pub accel_noise_std: f64,
    /// Two-sided spectral density of the base acceleration, (m/s²)²/Hz: how hard the base
    /// shakes the mount (the process noise).
    pub base_psd: f64,
    /// Prior standard deviation of each scaled state, m/s².
    pub initial_std: f64,
}

impl Default for SdofParams {
    /// A 10 Hz mount with 5 % damping, shaken by a base of 0.01 (m/s²)²/Hz (1 m/s² RMS over
    /// 0–50 Hz), read by an ADXL355 at 1 kHz: 25 µg/√Hz over its 250 Hz low-pass, the
    /// oscillator's 4.86 mm/s² per sample.
    fn default() -> Self {
        Self {
            natural_freq_hz: 10.0,
            damping_ratio: 0.05,
            sample_rate_hz: 1000.0,
            // The same expression as the oscillator's and host-sim's sensor model: the same bits.
            accel_noise_std: 25e-6 * 9.80665 * libm::sqrt(1.57 * (1000.0 / 4.0)),
            base_psd: 0.01,
            initial_std: 10.0,
        }
    }
}

impl SdofParams {
    /// Natural angular frequency `ωn`, rad/s.
    pub fn omega_n(&self) -> f64 {
        2.0 * core::f64::consts::PI * self.natural_freq_hz
    }

    /// Continuous-time system matrix of the scaled state `[ωn² z, ωn ż]`.
    pub fn continuous_a(&self) -> Matrix2<f64> {
        let wn = self.omega_n();
        Matrix2::new(0.0, wn, -wn, -2.0 * self.damping_ratio * wn)
    }

    /// Measurement row: the absolute acceleration `−ωn² z − 2ζωn ż` in the scaled state.
    pub fn measurement_row(&self) -> RowVector2<f64> {
        RowVector2::new(-1.0, -2.0 * self.damping_ratio)
    }

    /// The exactly discretised model (Van Loan), in `f64`. Non-finite or non-positive
    /// frequencies, rate or noise, a negative damping or density are
    /// [`LinalgError::NonFinite`].
    pub fn discrete_model(&self) -> Result<LinearModel<f64, STATES, 1>, LinalgError> {
        let positive = [self.natural_freq_hz, self.sample_rate_hz, self.accel_noise_std, self.initial_std]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0);
        // NaN fails every comparison, so `>= 0.0` also rejects NaN.
        let others = self.damping_ratio >= 0.0 && self.base_psd >= 0.0 && self.base_psd.is_finite();
        if !positive || !others || !self.damping_ratio.is_finite() {
            return Err(LinalgError::NonFinite);
        }
        let wn = self.omega_n();
        // The base acceleration enters ż with gain −1, so the scaled velocity with gain −ωn.
        let qc = Matrix2::new(0.0, 0.0, 0.0, wn * wn * self.base_psd);
        let (a, q) = van_loan::<f64, STATES, 4>(&self.continuous_a(), &qc, 1.0 / self.sample_rate_hz)?;
        let r = Matrix1::new(self.accel_noise_std * self.accel_noise_std);
        Ok(LinearModel { a, c: self.measurement_row(), q, r })
    }
}

/// What the estimator has done with its input. All zero but `steps` for clean data.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SdofCounters {
    /// Samples processed (present or missing).
    pub steps: u32,
    /// Samples that were missing (bridged by prediction alone).
    pub missing: u32,
    /// The filter's repairs and refusals (a non-finite reading is refused and counted here).
    pub filter: FilterHealth,
}

/// One step's estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SdofStep<T: Real> {
    /// Relative displacement of the mass, m.
    pub displacement: T,
    /// Relative velocity, m/s.
    pub velocity: T,
    /// Innovation of this sample, m/s² (`None`: missing or refused).
    pub innovation: Option<T>,
    /// Its normalised innovation squared (`None`: missing or refused).
    pub nis: Option<T>,
}

/// The 2-state Kalman filter of the mount's relative motion from its absolute acceleration.
///
/// ```
/// use edgekf::systems::sdof::{SdofEstimator, SdofParams};
/// let p = SdofParams::default();
/// let mut est = SdofEstimator::<f32>::new(&p).unwrap();
/// // A mount held 1 mm off its rest position reads −ωn² z on the mass.
/// let wn = p.omega_n();
/// let y = (-wn * wn * 1e-3) as f32;
/// let mut last = est.step(Some(y));
/// for _ in 0..2000 {
///     last = est.step(Some(y));
/// }
/// // The filter cannot hold it there (nothing in the model does), but it reads the spring.
/// assert!(last.displacement > 0.0);
/// assert_eq!(est.counters().steps, 2001);
/// ```
#[derive(Debug, Clone)]
pub struct SdofEstimator<T: Real> {
    filter: KalmanFilter<T, STATES, 1>,
    /// `1/ωn²` and `1/ωn`: scaled state back to displacement and velocity.
    to_displacement: T,
    to_velocity: T,
    counters: SdofCounters,
}

impl<T: Real> SdofEstimator<T> {
    /// Discretises the model in `f64` and starts the filter at rest with the prior
    /// `initial_std` on each scaled state.
    pub fn new(params: &SdofParams) -> Result<Self, LinalgError> {
        let model = params.discrete_model()?;
        let p0 = params.initial_std * params.initial_std;
        let filter =
            KalmanFilter::new(model.cast::<T>(), Vector2::zeros(), Matrix2::from_diagonal_element(T::of_f64(p0)));
        let wn = params.omega_n();
        Ok(Self {
            filter,
            to_displacement: T::of_f64(1.0 / (wn * wn)),
            to_velocity: T::of_f64(1.0 / wn),
            counters: SdofCounters::default(),
        })
    }

    /// Advances one sample period with the mass's absolute acceleration `accel` (m/s²), or
    /// `None` for a missing sample (predicted across, counted).
    pub fn step(&mut self, accel: Option<T>) -> SdofStep<T> {
        self.counters.steps = self.counters.steps.saturating_add(1);
        self.filter.predict();
        let used = match accel {
            Some(a) => self.filter.update(&Vector1::new(a)).ok(),
            None => {
                self.counters.missing = self.counters.missing.saturating_add(1);
                None
            }
        };
        self.counters.filter = self.filter.health();
        SdofStep { innovation: used.map(|i| i.residual[0]), nis: used.map(|i| i.nis), ..self.current() }
    }

    /// The current estimate in physical units (no innovation attached).
    pub fn current(&self) -> SdofStep<T> {
        let x = self.filter.state();
        SdofStep {
            displacement: x[0] * self.to_displacement,
            velocity: x[1] * self.to_velocity,
            innovation: None,
            nis: None,
        }
    }

    /// The filter (its scaled state, covariance and model).
    pub fn kalman(&self) -> &KalmanFilter<T, STATES, 1> {
        &self.filter
    }

    /// What the estimator has done so far.
    pub fn counters(&self) -> SdofCounters {
        self.counters
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The filter's model driven by its own process noise (a deterministic LCG), read with its
    /// own measurement noise: the consistent case, where the NIS must average one.
    #[test]
    fn nis_averages_one_on_the_models_own_data() {
        let p = SdofParams::default();
        let m = p.discrete_model().unwrap();
        let mut est = SdofEstimator::<f64>::new(&p).unwrap();
        let mut lcg = crate::models::synthetic::Lcg(7);
        // Unit-variance uniform numbers; `Q = L Lᵀ` by its 2 × 2 Cholesky factor.
        let mut unit = || lcg.next() * libm::sqrt(3.0);
        let l = m.q.cholesky().unwrap().l();
        let r = libm::sqrt(m.r[(0, 0)]);
        let mut x = Vector2::new(0.0, 0.0);
        let (mut nis, mut n) = (0.0, 0);
        for k in 0..20_000 {
            x = m.a * x + l * Vector2::new(unit(), unit());
            let y = (m.c * x)[0] + r * unit();
            let s = est.step(Some(y));
            if k >= 2000 {
                nis += s.nis.unwrap();
                n += 1;
            }
        }
        let mean = nis / f64::from(n);
        assert!((0.9..1.1).contains(&mean), "NIS mean {mean}");
        assert_eq!(est.counters().filter, FilterHealth::default());
    }

    #[test]
    fn missing_and_non_finite_samples_are_counted() {
        let mut est = SdofEstimator::<f32>::new(&SdofParams::default()).unwrap();
        est.step(None);
        let s = est.step(Some(f32::NAN));
        assert_eq!((s.innovation, s.nis), (None, None));
        let c = est.counters();
        assert_eq!((c.steps, c.missing, c.filter.refused_updates), (2, 1, 1));
        assert!(est.current().displacement.is_finite());
    }

    #[test]
    fn invalid_parameters_are_an_error() {
        for p in [
            SdofParams { natural_freq_hz: 0.0, ..Default::default() },
            SdofParams { damping_ratio: f64::NAN, ..Default::default() },
            SdofParams { base_psd: -1.0, ..Default::default() },
            SdofParams { sample_rate_hz: f64::INFINITY, ..Default::default() },
        ] {
            assert_eq!(SdofEstimator::<f32>::new(&p).err(), Some(LinalgError::NonFinite), "{p:?}");
        }
    }
}
