//! Single-mode oscillator driven by an unknown harmonic force at a known frequency.
//!
//! The physics: a structural mode of natural frequency `ωn`, damping ratio `ζ` and modal mass
//! `m`, excited by a force at the running speed `Ω` (unbalance, misalignment at 1×, …):
//!
//! ```text
//! ẍ + 2ζωn ẋ + ωn² x = p₁            (p = force / m, the force "per unit mass")
//! ṗ₁ = −Ω p₂ ,  ṗ₂ = Ω p₁            (a phasor rotating at Ω: p₁ = |p| cos(Ωt + φ))
//! y  = ẍ = −ωn² x − 2ζωn ẋ + p₁ + v    (an accelerometer on the mode)
//! ```
//!
//! The filter's state is `[ωn² x, ωn ẋ, p₁, p₂]`: all four in m/s², so that the covariance and
//! `C P Cᵀ` stay well conditioned in `f32` (with `[x, ẋ, …]` the measurement row holds
//! `ωn² ≈ 1.6·10⁴` and the f32 innovation variance cancels to nothing). The phasor gets a small
//! random walk so a changing amplitude or phase
//! is tracked, but unlike a free random-walk force it cannot absorb content at other frequencies:
//! the innovations stay informative about what the model lacks.
//!
//! The model is time-invariant, so one discretisation (exact, Van Loan) serves every step, and a
//! steady-state gain would serve too. The estimated force amplitude is `m |p|`.

use crate::filter::{
    solve_riccati, FilterHealth, KalmanFilter, LinearModel, RiccatiError, SteadyState, SteadyStateFilter,
};
use crate::linalg::{van_loan, LinalgError};
use crate::residual::RunningStats;
use crate::Real;
use nalgebra::{Matrix1, Matrix4, RowVector4, SMatrix, SVector, Vector1, Vector4};

/// Number of states: displacement, velocity and the two phasor components.
pub const STATES: usize = 4;

/// Parameters of the harmonic-force model and its filter. All SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarmonicForceParams {
    /// Natural frequency of the mode, Hz.
    pub natural_freq_hz: f64,
    /// Modal damping ratio (dimensionless).
    pub damping_ratio: f64,
    /// Modal mass, kg: turns the estimated force per unit mass into newtons.
    pub modal_mass_kg: f64,
    /// Frequency of the force (running speed), rad/s.
    pub drive_rad_s: f64,
    /// Sample rate of the accelerometer, Hz.
    pub sample_rate_hz: f64,
    /// Standard deviation of the accelerometer noise per sample, m/s².
    pub accel_noise_std: f64,
    /// Spectral density of the phasor random walk, (m/s²)²/s: how fast the force may change.
    pub force_psd: f64,
    /// Spectral density of unmodelled acceleration on the mode, (m/s²)²/s.
    pub motion_psd: f64,
    /// Prior standard deviation of each phasor component, m/s².
    pub initial_force_std: f64,
    /// Innovation gate: a sample whose NIS exceeds this is not used (0, the default, disables
    /// the gate). Meant for the time-varying gain: with a steady-state gain the NIS is only
    /// meaningful once converged, and a gate that drops most samples during start-up or a fast
    /// change leaves a gain tuned for every sample acting on a few, which can be unstable.
    pub gate_nis: f64,
    /// After this many gated samples in a row the gate is bypassed once, so a filter that has
    /// truly lost track re-acquires instead of rejecting everything.
    pub gate_max_consecutive: u32,
    /// Steady-state or time-varying gain.
    pub gain: GainMode,
}

/// How the estimator computes its Kalman gain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GainMode {
    /// The gain of the converged filter, solved once (in `f64`) at construction. The chip's
    /// mode: a few dozen multiply-adds per sample, no covariance arithmetic to go wrong in `f32`.
    #[default]
    SteadyState,
    /// The full covariance recursion every sample (Joseph form). Faster start-up and honest
    /// uncertainty after gaps; for `f64` on the host.
    TimeVarying,
}

impl Default for HarmonicForceParams {
    /// A 20 Hz mode (ζ = 2 %, 1 kg) driven at the rotor paper's running speed 87.96 rad/s, read
    /// by an ADXL355 at 1 kHz: 25 µg/√Hz over its 250 Hz low-pass, 4.86 mm/s² per sample.
    /// The force random walk (1e-3 (m/s²)²/s) gives a steady-state filter whose slowest error
    /// mode decays with τ ≈ 0.1 s and a force standard deviation of about 0.01 m/s² per kg.
    fn default() -> Self {
        Self {
            natural_freq_hz: 20.0,
            damping_ratio: 0.02,
            modal_mass_kg: 1.0,
            drive_rad_s: 87.96,
            sample_rate_hz: 1000.0,
            // 25 µg/√Hz × g × √(π/2 × 250 Hz): the ADXL355's density over its low-pass at ODR/4
            // (the same expression as host-sim's sensor model, so both give the same bits).
            accel_noise_std: 25e-6 * 9.80665 * libm::sqrt(1.57 * (1000.0 / 4.0)),
            force_psd: 1.0e-3,
            motion_psd: 1.0e-6,
            initial_force_std: 10.0,
            gate_nis: 0.0,
            gate_max_consecutive: 20,
            gain: GainMode::SteadyState,
        }
    }
}

impl HarmonicForceParams {
    /// Natural angular frequency `ωn`, rad/s.
    pub fn omega_n(&self) -> f64 {
        2.0 * core::f64::consts::PI * self.natural_freq_hz
    }

    /// Continuous-time system matrix of the scaled state `[ωn² x, ωn ẋ, p₁, p₂]`.
    pub fn continuous_a(&self) -> Matrix4<f64> {
        let wn = self.omega_n();
        let w = self.drive_rad_s;
        Matrix4::new(
            0.0,
            wn,
            0.0,
            0.0, //
            -wn,
            -2.0 * self.damping_ratio * wn,
            wn,
            0.0, //
            0.0,
            0.0,
            0.0,
            -w, //
            0.0,
            0.0,
            w,
            0.0,
        )
    }

    /// Measurement row: the acceleration `ẍ = p₁ − ωn² x − 2ζωn ẋ` in the scaled state.
    pub fn measurement_row(&self) -> RowVector4<f64> {
        RowVector4::new(-1.0, -2.0 * self.damping_ratio, 1.0, 0.0)
    }

    /// The exactly discretised model (Van Loan), in `f64`.
    pub fn discrete_model(&self) -> Result<LinearModel<f64, STATES, 1>, LinalgError> {
        let positive =
            [self.natural_freq_hz, self.sample_rate_hz, self.accel_noise_std].iter().all(|v| v.is_finite() && *v > 0.0);
        // NaN fails every comparison, so `>= 0.0` also rejects NaN.
        let densities_ok = self.force_psd >= 0.0 && self.motion_psd >= 0.0;
        if !positive || !self.drive_rad_s.is_finite() || !self.damping_ratio.is_finite() || !densities_ok {
            return Err(LinalgError::NonFinite);
        }
        let dt = 1.0 / self.sample_rate_hz;
        let wn = self.omega_n();
        // Unmodelled acceleration w enters as ωn ẍ in the scaled velocity state.
        let qc = Matrix4::from_diagonal(&Vector4::new(0.0, wn * wn * self.motion_psd, self.force_psd, self.force_psd));
        let (a, q) = van_loan::<f64, STATES, 8>(&self.continuous_a(), &qc, dt)?;
        Ok(LinearModel {
            a,
            c: self.measurement_row(),
            q,
            r: Matrix1::new(self.accel_noise_std * self.accel_noise_std),
        })
    }
}

/// Counters of what the estimator did with its input. All zero for clean data.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EstimatorCounters {
    /// Samples processed (present or missing).
    pub steps: u32,
    /// Samples that were missing (bridged by prediction alone).
    pub missing: u32,
    /// Samples rejected by the innovation gate.
    pub gated: u32,
    /// Filter repairs (see [`FilterHealth`]).
    pub filter: FilterHealth,
}

/// What one step of the estimator produced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarmonicStep<T: Real> {
    /// Estimated modal displacement, m.
    pub displacement: T,
    /// Estimated modal velocity, m/s.
    pub velocity: T,
    /// In-phase component of the force, N (`F cos(Ωt + φ)`).
    pub force_cos: T,
    /// Quadrature component of the force, N.
    pub force_sin: T,
    /// Force amplitude `|F|`, N.
    pub force_amplitude: T,
    /// Innovation of this sample, m/s² (`None` if the sample was missing).
    pub innovation: Option<T>,
    /// NIS of this sample (`None` if the sample was missing).
    pub nis: Option<T>,
}

/// Kalman filter on [`HarmonicForceParams`]' model, with missing-sample handling, an innovation
/// gate and innovation statistics.
///
/// ```
/// use edgekf::systems::oscillator::{HarmonicForceEstimator, HarmonicForceParams};
/// let p = HarmonicForceParams { gate_nis: 0.0, ..Default::default() };
/// let mut est = HarmonicForceEstimator::<f64>::new(&p).unwrap();
/// // Pure forced response is not needed to see convergence: a resting mode reads zero force.
/// for _ in 0..2000 { est.step(Some(0.0)); }
/// assert!(est.step(Some(0.0)).force_amplitude < 1e-3);
/// ```
#[derive(Debug, Clone)]
pub struct HarmonicForceEstimator<T: Real> {
    core: Core<T>,
    mass: T,
    /// `1/ωn²` and `1/ωn`: scaled state back to displacement and velocity.
    to_displacement: T,
    to_velocity: T,
    gate: T,
    gate_max: u32,
    gated_in_a_row: u32,
    counters: EstimatorCounters,
    innovations: RunningStats<T>,
}

/// The two gain modes behind one interface.
#[derive(Debug, Clone)]
enum Core<T: Real> {
    Steady(SteadyStateFilter<T, STATES, 1>),
    Varying(KalmanFilter<T, STATES, 1>),
}

impl<T: Real> Core<T> {
    fn predict(&mut self) {
        match self {
            Core::Steady(f) => f.predict(),
            Core::Varying(f) => f.predict(),
        }
    }

    /// `(residual, NIS)` of `y` against the prediction, without updating.
    fn innovation(&self, y: &Vector1<T>) -> Option<(T, T)> {
        match self {
            Core::Steady(f) => f.innovation(y).map(|(r, n)| (r[0], n)),
            Core::Varying(f) => f.innovation(y).map(|i| (i.residual[0], i.nis)),
        }
    }

    fn update(&mut self, y: &Vector1<T>) -> Option<(T, T)> {
        match self {
            Core::Steady(f) => f.update(y).map(|(r, n)| (r[0], n)),
            Core::Varying(f) => f.update(y).ok().map(|i| (i.residual[0], i.nis)),
        }
    }

    fn state(&self) -> &SVector<T, STATES> {
        match self {
            Core::Steady(f) => f.state(),
            Core::Varying(f) => f.state(),
        }
    }

    fn health(&self) -> FilterHealth {
        match self {
            Core::Steady(f) => FilterHealth { covariance_resets: f.resets(), refused_updates: 0 },
            Core::Varying(f) => f.health(),
        }
    }
}

/// Why the estimator could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModelError {
    /// Invalid parameters or a failed discretisation.
    Model(LinalgError),
    /// No steady-state gain (see [`RiccatiError`]).
    Gain(RiccatiError),
}

impl<T: Real> HarmonicForceEstimator<T> {
    /// Builds the estimator: discretises (and, in steady-state mode, solves the Riccati
    /// equation) in `f64`, then converts to `T`.
    pub fn new(params: &HarmonicForceParams) -> Result<Self, ModelError> {
        let model = params.discrete_model().map_err(ModelError::Model)?;
        match params.gain {
            GainMode::SteadyState => {
                let ss = solve_riccati(&model, 1e-12, 100_000).map_err(ModelError::Gain)?;
                Self::from_steady_state(params, &model, &ss)
            }
            GainMode::TimeVarying => {
                let f0 = params.initial_force_std * params.initial_force_std;
                // The mode's response is of the order of the force (per unit mass) near resonance.
                let p0 = Matrix4::from_diagonal(&Vector4::new(f0, f0, f0, f0)).map(T::of_f64);
                Ok(Self::with_core(params, Core::Varying(KalmanFilter::new(model.cast::<T>(), SVector::zeros(), p0))))
            }
        }
    }

    /// A steady-state estimator from a model and gain computed elsewhere, typically on the host
    /// and compiled in (`edgekf oscillator export`): no discretisation and no Riccati solve at
    /// start-up. `params` supplies the physical scaling (ωn, modal mass) and the gate.
    pub fn from_steady_state(
        params: &HarmonicForceParams,
        model: &LinearModel<f64, STATES, 1>,
        ss: &SteadyState<STATES, 1>,
    ) -> Result<Self, ModelError> {
        Self::from_gain(params, model, &ss.gain, &ss.innovation)
    }

    /// Like [`HarmonicForceEstimator::from_steady_state`], from the gain `K` and innovation
    /// covariance `S` alone (what `edgekf oscillator export` writes).
    pub fn from_gain(
        params: &HarmonicForceParams,
        model: &LinearModel<f64, STATES, 1>,
        gain: &SMatrix<f64, STATES, 1>,
        innovation: &Matrix1<f64>,
    ) -> Result<Self, ModelError> {
        let filter =
            SteadyStateFilter::from_gain(model, gain, innovation, SVector::zeros()).map_err(ModelError::Gain)?;
        Ok(Self::with_core(params, Core::Steady(filter)))
    }

    fn with_core(params: &HarmonicForceParams, core: Core<T>) -> Self {
        let wn = params.omega_n();
        Self {
            core,
            mass: T::of_f64(params.modal_mass_kg),
            to_displacement: T::of_f64(1.0 / (wn * wn)),
            to_velocity: T::of_f64(1.0 / wn),
            gate: T::of_f64(params.gate_nis),
            gate_max: params.gate_max_consecutive,
            gated_in_a_row: 0,
            counters: EstimatorCounters::default(),
            innovations: RunningStats::new(),
        }
    }

    /// Advances one sample period. `None` marks a missing sample (dropout, stuck or saturated
    /// sensor): the state is predicted and the uncertainty grows, nothing is invented.
    pub fn step(&mut self, accel: Option<T>) -> HarmonicStep<T> {
        self.counters.steps = self.counters.steps.saturating_add(1);
        self.core.predict();
        let (innovation, nis) = match accel {
            None => {
                self.counters.missing = self.counters.missing.saturating_add(1);
                (None, None)
            }
            Some(a) => self.measure(a),
        };
        self.counters.filter = self.core.health();
        HarmonicStep { innovation, nis, ..self.current() }
    }

    fn measure(&mut self, a: T) -> (Option<T>, Option<T>) {
        let y = Vector1::new(a);
        let gate_on = self.gate > T::zero() && self.gated_in_a_row < self.gate_max;
        if gate_on {
            if let Some((r, nis)) = self.core.innovation(&y) {
                if nis > self.gate {
                    self.gated_in_a_row = self.gated_in_a_row.saturating_add(1);
                    self.counters.gated = self.counters.gated.saturating_add(1);
                    return (Some(r), Some(nis));
                }
            }
        }
        self.gated_in_a_row = 0;
        match self.core.update(&y) {
            Some((r, nis)) => {
                self.innovations.push(r);
                (Some(r), Some(nis))
            }
            None => (None, None),
        }
    }

    /// The current estimate in physical units (no innovation attached).
    pub fn current(&self) -> HarmonicStep<T> {
        let x = self.core.state();
        let (fc, fs) = (x[2] * self.mass, x[3] * self.mass);
        HarmonicStep {
            displacement: x[0] * self.to_displacement,
            velocity: x[1] * self.to_velocity,
            force_cos: fc,
            force_sin: fs,
            force_amplitude: (fc * fc + fs * fs).sqrt(),
            innovation: None,
            nis: None,
        }
    }

    /// The filter's scaled state `[ωn² x, ωn ẋ, p₁, p₂]` (all m/s²).
    pub fn state(&self) -> &SVector<T, STATES> {
        self.core.state()
    }

    /// The time-varying filter (covariance, model), if that is the gain mode.
    pub fn kalman(&self) -> Option<&KalmanFilter<T, STATES, 1>> {
        match &self.core {
            Core::Varying(f) => Some(f),
            Core::Steady(_) => None,
        }
    }

    /// What the estimator has done so far.
    pub fn counters(&self) -> EstimatorCounters {
        self.counters
    }

    /// Running statistics of the accepted innovations.
    pub fn innovation_stats(&self) -> &RunningStats<T> {
        &self.innovations
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steady forced response sampled exactly: the filter must recover amplitude to 0.1 %.
    fn forced_response(p: &HarmonicForceParams, amp: f64, phase: f64, n: usize) -> impl Iterator<Item = f64> + '_ {
        let wn = 2.0 * core::f64::consts::PI * p.natural_freq_hz;
        let w = p.drive_rad_s;
        // x = Re{X e^{i(Ωt+φ)}}, X = amp / (ωn² − Ω² + 2iζωnΩ)
        let (re, im) = (wn * wn - w * w, 2.0 * p.damping_ratio * wn * w);
        let den = re * re + im * im;
        let (xr, xi) = (amp * re / den, -amp * im / den);
        (0..n).map(move |k| {
            let t = k as f64 / p.sample_rate_hz;
            let (s, c) = libm::sincos(w * t + phase);
            -w * w * (xr * c - xi * s)
        })
    }

    #[test]
    fn recovers_force_amplitude_from_steady_response() {
        let p = HarmonicForceParams::default();
        let mut est = HarmonicForceEstimator::<f64>::new(&p).unwrap();
        let mut last = None;
        for a in forced_response(&p, 3.0, 0.7, 3000) {
            last = Some(est.step(Some(a)));
        }
        let amp = last.unwrap().force_amplitude;
        assert!((amp - 3.0).abs() < 3e-3, "amplitude {amp}");
        assert_eq!(est.counters().gated, 0);
    }

    #[test]
    fn time_varying_gain_converges_to_the_same_answer() {
        let p = HarmonicForceParams { gain: GainMode::TimeVarying, ..Default::default() };
        let mut est = HarmonicForceEstimator::<f64>::new(&p).unwrap();
        let mut amp = 0.0;
        for a in forced_response(&p, 3.0, 0.7, 3000) {
            amp = est.step(Some(a)).force_amplitude;
        }
        assert!((amp - 3.0).abs() < 3e-3, "amplitude {amp}");
        assert_eq!(est.counters().filter, FilterHealth::default());
    }

    #[test]
    fn time_varying_gain_is_healthy_in_f32() {
        // The scaled state keeps C P Cᵀ + R from cancelling in single precision.
        let p = HarmonicForceParams { gain: GainMode::TimeVarying, ..Default::default() };
        let mut est = HarmonicForceEstimator::<f32>::new(&p).unwrap();
        let mut amp = 0.0f32;
        for a in forced_response(&p, 3.0, 0.7, 3200) {
            amp = est.step(Some(a as f32)).force_amplitude;
        }
        assert_eq!(est.counters().filter, FilterHealth::default());
        assert!((amp - 3.0).abs() < 3e-3, "amplitude {amp}");
    }

    #[test]
    fn f32_and_f64_agree() {
        let p = HarmonicForceParams::default();
        let mut e32 = HarmonicForceEstimator::<f32>::new(&p).unwrap();
        let mut e64 = HarmonicForceEstimator::<f64>::new(&p).unwrap();
        let (mut a32, mut a64) = (0.0f32, 0.0f64);
        for a in forced_response(&p, 2.0, -1.0, 4000) {
            a32 = e32.step(Some(a as f32)).force_amplitude;
            a64 = e64.step(Some(a)).force_amplitude;
        }
        assert!(((a32 as f64) - a64).abs() < 1e-4 * a64, "{a32} vs {a64}");
        assert_eq!(e32.counters().filter, FilterHealth::default());
    }

    #[test]
    fn missing_samples_are_bridged_and_counted() {
        let p = HarmonicForceParams::default();
        let mut est = HarmonicForceEstimator::<f64>::new(&p).unwrap();
        let data: heapless::Vec<f64, 4000> = forced_response(&p, 3.0, 0.2, 4000).collect();
        let mut amp = 0.0;
        for (k, a) in data.iter().enumerate() {
            let gap = (2000..2100).contains(&k);
            let r = est.step(if gap { None } else { Some(*a) });
            if k == 2099 {
                // 100 ms of pure prediction keeps the phasor: the model is exact here.
                assert!((r.force_amplitude - 3.0).abs() < 0.03, "{}", r.force_amplitude);
            }
            amp = r.force_amplitude;
        }
        assert!((amp - 3.0).abs() < 3e-3);
        assert_eq!(est.counters().missing, 100);
    }

    #[test]
    fn gate_rejects_a_spike() {
        let p = HarmonicForceParams { gain: GainMode::TimeVarying, gate_nis: 30.0, ..Default::default() };
        let mut est = HarmonicForceEstimator::<f64>::new(&p).unwrap();
        for (k, a) in forced_response(&p, 3.0, 0.2, 3000).enumerate() {
            let y = if k == 2500 { a + 5.0 } else { a };
            est.step(Some(y));
        }
        assert_eq!(est.counters().gated, 1);
    }

    #[test]
    fn invalid_parameters_are_an_error() {
        let p = HarmonicForceParams { sample_rate_hz: 0.0, ..Default::default() };
        assert!(HarmonicForceEstimator::<f32>::new(&p).is_err());
        let p = HarmonicForceParams { force_psd: f64::NAN, ..Default::default() };
        assert!(HarmonicForceEstimator::<f32>::new(&p).is_err());
    }
}
