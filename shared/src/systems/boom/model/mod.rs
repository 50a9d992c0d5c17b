//! The model-based boom estimator: one Kalman filter on the reduced boom ([`BoomConstants`]'s
//! first [`MODES`] modes), driven by the operator's luffing command through the drive's lag,
//! fusing both sensors at every sample.
//!
//! Its state is the root's angle and rate, each mode's coordinate and rate (the vibration about
//! the static equilibrium), the gyro's bias, the inclinometer's lagged angle and the gyro's
//! AR(2) noise. So the gyro's coloured noise is modelled rather than filtered out with the
//! vibration, the bias is read from the angle the inclinometer sees, the inclinometer's lag
//! is the sensor's and not the boom's, and the tip's deflection per unit slope comes from the
//! mode shapes at the current length, not from a fixed `α`.
//!
//! A mode the reduced boom lacks (the boom's sideways bending seen by a gyro that leans toward
//! it, say) has a slot of its own ([`ExtraMode`]): an oscillator driven by white noise whose
//! rate the gyro reads. The residual loop fits its frequency; without one the slot is inert.
//!
//! As the boom telescopes or luffs the reduced boom is re-reduced around the current length
//! and angle and extrapolated linearly in between; the gravity sag's slope changes with both,
//! and its rate (which the gyro reads) is in the measurement.

use super::ar::Ar2;
use super::reduced::{BoomConstants, ReducedError, MODES};
use crate::filter::{KalmanFilter, LinearModel};
use crate::Real;
use nalgebra::{SMatrix, SVector};

mod discrete;
use discrete::{discretise, transition, Discrete, Linearised};

/// States: `[φ, φ̇, η₁, η̇₁, …, η₃, η̇₃, ξ, ξ̇, b, ψ, n_k, n_{k−1}]` (`ξ`: the extra mode's slot).
pub const STATES: usize = 8 + 2 * MODES;
/// Measurements: `[gyro_rate, incl_angle]`.
pub const MEASUREMENTS: usize = 2;

/// Where each quantity sits in the state.
pub mod slot {
    /// Root (luffing) angle, rad.
    pub const ANGLE: usize = 0;
    /// Root rate, rad/s.
    pub const RATE: usize = 1;
    /// Mode `i`'s coordinate is at `MODE + 2 i`, its rate at `MODE + 2 i + 1`.
    pub const MODE: usize = 2;
    /// The extra mode's coordinate (rad, as the gyro sees it) and rate.
    pub const EXTRA: usize = MODE + 2 * super::MODES;
    /// Gyro bias, rad/s.
    pub const BIAS: usize = super::STATES - 4;
    /// The inclinometer's lagged angle, rad.
    pub const LAGGED: usize = super::STATES - 3;
    /// The gyro's AR(2) noise now and one sample ago, rad/s.
    pub const NOISE: usize = super::STATES - 2;
}

/// Reduced-boom quantities that are extrapolated: per mode `ω, d, τ, p`, then the sag's tip
/// deflection and slope.
const VALUES: usize = 4 * MODES + 2;
/// Re-reduce beyond this from the last reduction: length (m) and angle (rad).
const RECENTRE: (f64, f64) = (0.5, 0.1);
/// Finite-difference steps of the gradients: length (m) and angle (rad).
const STEP: (f64, f64) = (0.25, 0.05);
/// Rediscretise beyond this from the last discretisation: length (m) and angle (rad).
const REDISCRETISE: (f64, f64) = (0.01, 0.005);
/// A missing reading's variance: its update moves nothing.
const MISSING: f64 = 1e12;

/// A mode the reduced boom lacks, seen by the gyro: `ξ̈ + 2ζω ξ̇ + ω² ξ = w`, the gyro reading
/// `ξ̇` beside the boom's rates, `w` white with the intensity that gives `ξ̇` the standard
/// deviation `level`.
///
/// ```
/// use edgekf::systems::boom::ExtraMode;
/// let m = ExtraMode { hz: 1.1, zeta: 0.02, level: 1e-3 };
/// assert!(m.is_valid() && !ExtraMode { hz: -1.0, ..m }.is_valid());
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtraMode {
    /// Natural frequency, Hz.
    pub hz: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// Standard deviation of its rate, rad/s.
    pub level: f64,
}

impl ExtraMode {
    /// A positive frequency and level and a damping ratio in (0, 1).
    pub fn is_valid(&self) -> bool {
        self.hz.is_finite()
            && self.hz > 0.0
            && self.zeta > 0.0
            && self.zeta < 1.0
            && self.level.is_finite()
            && self.level > 0.0
    }

    fn omega(&self) -> f64 {
        2.0 * core::f64::consts::PI * self.hz
    }
}

/// The filter's settings: the boom, its sensors as declared, and the process noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelSettings {
    /// Sample interval, s.
    pub dt: f64,
    /// The boom.
    pub constants: BoomConstants,
    /// Damping ratios of the first two modes; the others' follow from the Rayleigh damping
    /// through these two (as the reference's damping is fitted).
    pub zeta: [f64; 2],
    /// The luffing drive's first-order lag (s) and acceleration limit (rad/s²).
    pub drive: (f64, f64),
    /// The gyro's declared scale factor.
    pub gyro_scale: f64,
    /// The gyro's AR(2) noise and bias at rest (from the static record).
    pub ar: Ar2,
    /// The gyro's white measurement noise beside the AR noise, rad/s.
    pub gyro_floor: f64,
    /// The inclinometer's first-order lag (s, 0: none), offset (rad) and noise (rad).
    pub inclinometer: (f64, f64, f64),
    /// Luffing acceleration the drive's model misses, rad/s² (per sample).
    pub drive_noise: f64,
    /// Tip acceleration the modes' model misses, m/s² per √Hz.
    pub mode_noise: f64,
    /// The bias's random walk, rad/s per √s.
    pub bias_walk: f64,
    /// The bias's known drift, rad/s per s (0: none; the residual loop fits it).
    pub bias_drift: f64,
    /// How far the inclinometer's declared lag may be off, s: while the boom luffs at φ̇ its
    /// reading is trusted to `lag_sd · φ̇` less (a lag off by δτ reads δτ · φ̇ behind).
    pub lag_sd: f64,
    /// A mode the reduced boom lacks (none: the slot is inert).
    pub extra_mode: Option<ExtraMode>,
}

impl ModelSettings {
    /// Settings with this crate's process noise: 0.01 rad/s² of drive error, 0.003 m/s²/√Hz at
    /// the tip, a bias walking 1e-5 rad/s per √s, a gyro floor a tenth of its AR noise, and the
    /// inclinometer's lag taken as uncertain by half of itself (0.1 s if none is declared).
    pub fn new(
        dt: f64,
        constants: BoomConstants,
        zeta: [f64; 2],
        drive: (f64, f64),
        gyro_scale: f64,
        ar: Ar2,
        inclinometer: (f64, f64, f64),
    ) -> Self {
        Self {
            dt,
            constants,
            zeta,
            drive,
            gyro_scale,
            ar,
            gyro_floor: 0.1 * ar.sigma,
            inclinometer,
            drive_noise: 0.01,
            mode_noise: 0.003,
            bias_walk: 1e-5,
            bias_drift: 0.0,
            lag_sd: if inclinometer.0 > 0.0 { 0.5 * inclinometer.0 } else { 0.1 },
            extra_mode: None,
        }
    }
}

/// One sample's estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelEstimate<T> {
    /// The tip's angle from the horizontal, rad.
    pub tip_angle: T,
    /// The tip's vibration about the static equilibrium, m.
    pub vibration: T,
    /// The tip's deflection with the gravity sag, m.
    pub deflection: T,
    /// Innovations `[gyro, inclinometer]`, the inclinometer's after the gyro's update (0 where a
    /// reading was missing).
    pub innovation: [T; MEASUREMENTS],
    /// Their variances (NaN where a reading was missing).
    pub variance: [T; MEASUREMENTS],
    /// Normalised innovation squared of the readings used.
    pub nis: T,
}

/// Why the model-based estimator cannot start.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModelError {
    /// A setting is not finite or not positive where it must be.
    Settings,
    /// The boom cannot be reduced at the first length.
    Reduced(ReducedError),
}

/// The model-based estimator.
///
/// ```
/// use edgekf::systems::boom::{Ar2, BoomConstants, BoomSection, ModelEstimator, ModelSettings};
/// let s = BoomSection { length: 10.0, ei: 1e7, mass_per_length: 20.0 };
/// let c = BoomConstants { sections: [s; 8], count: 1, tip_mass: 20.0, tip_inertia: 1.0, gravity: 9.81 };
/// let ar = Ar2 { a: [-0.6538, 0.06745], sigma: 3e-4, mean: 0.002 };
/// let settings = ModelSettings::new(0.01, c, [0.015, 0.02], (0.15, 0.3), 1.0, ar, (0.3, 0.0, 5e-4));
/// let mut est = ModelEstimator::<f32>::new(&settings, 10.0).unwrap();
/// // A boom at rest at 0.5 rad: no vibration, the tip below the root's line by the sag.
/// let mut last = None;
/// for _ in 0..500 { last = Some(est.step(0.002, 0.5, 10.0, 0.0)); }
/// let e = last.unwrap();
/// assert!(e.vibration.abs() < 1e-3 && e.deflection < 0.0 && (e.tip_angle - 0.5).abs() < 0.05);
/// ```
#[derive(Debug, Clone)]
pub struct ModelEstimator<T: Real> {
    settings: ModelSettings,
    kf: KalmanFilter<T, STATES, MEASUREMENTS>,
    lin: Linearised,
    discrete: Discrete<T>,
    /// The last length and command used (held across missing readings).
    length: f64,
    command: T,
    /// Samples taken.
    k: u64,
    /// Reductions that failed (the last good one kept).
    reduce_failures: u32,
    /// The settings' fixed exponentials, once (soft-float `f64` on the chip): the drive's
    /// acceleration per unit rate error over a sample, and the inclinometer lag's step.
    drive_gain: f64,
    lag_step: f64,
    /// The extra mode's transition and its rate's process noise per sample; inert without
    /// one (no transition, and a unit variance renewed every step: the filter resets a
    /// covariance whose diagonal is not positive).
    extra: ([[T; 2]; 2], T),
    /// The last step's known input and the gyro reading's part it took out ([`LastStep`]).
    input: SVector<T, STATES>,
    gyro_offset: T,
}

/// What the filter's last step ran on, so that a truth can be simulated from the filter's own
/// model (the firmware's numerical soak): `x' = A x + input + w` with `w ~ N(0, Q)`, read as
/// `C x + gyro_offset` (on the gyro) plus noise of `R`.
#[derive(Debug, Clone, Copy)]
pub struct LastStep<'a, T: Real> {
    /// The transition, measurement and noises of the step.
    pub model: &'a LinearModel<T, STATES, MEASUREMENTS>,
    /// The known input (the luffing command through the drive) the step added.
    pub input: &'a SVector<T, STATES>,
    /// The part of the gyro reading the state does not carry (the sag's slope rate by length),
    /// which the step took out of the reading.
    pub gyro_offset: T,
    /// Each mode's tip deflection per unit coordinate (the vibration is their sum over the
    /// modes' coordinates).
    pub tip: [T; MODES],
}

impl<T: Real> ModelEstimator<T> {
    /// An estimator for a boom `length` m long at its first sample.
    pub fn new(settings: &ModelSettings, length: f64) -> Result<Self, ModelError> {
        let s = settings;
        let positive = [s.dt, s.gyro_scale, s.drive.0, s.drive.1, s.ar.sigma];
        let non_negative =
            [s.gyro_floor, s.inclinometer.0, s.inclinometer.2, s.drive_noise, s.mode_noise, s.bias_walk, s.lag_sd];
        if positive.iter().any(|v| !(v.is_finite() && *v > 0.0))
            || !s.bias_drift.is_finite()
            || non_negative.iter().any(|v| !(v.is_finite() && *v >= 0.0))
            || !(length.is_finite() && length > 0.0)
            || s.extra_mode.is_some_and(|m| !m.is_valid())
        {
            return Err(ModelError::Settings);
        }
        let angle = 0.0;
        let lin = Linearised::new(&s.constants, length, angle).map_err(ModelError::Reduced)?;
        let discrete = discretise(&lin.values, &lin, s, length, angle);
        let model =
            LinearModel { a: SMatrix::identity(), c: SMatrix::zeros(), q: SMatrix::zeros(), r: SMatrix::identity() };
        let kf = KalmanFilter::new(model, SVector::zeros(), SMatrix::identity());
        let drive_gain = (1.0 - libm::exp(-s.dt / s.drive.0)) / s.dt;
        let lag_step = if s.inclinometer.0 > 0.0 { 1.0 - libm::exp(-s.dt / s.inclinometer.0) } else { 1.0 };
        // White forcing of intensity S gives the rate the variance S / (4ζω).
        let extra = match s.extra_mode {
            Some(m) => {
                let f = transition(m.omega(), m.zeta, s.dt);
                let intensity = 4.0 * m.zeta * m.omega() * m.level * m.level;
                (f.map(|row| row.map(T::of_f64)), T::of_f64(intensity * s.dt))
            }
            None => ([[T::zero(); 2]; 2], T::one()),
        };
        Ok(Self {
            settings: *s,
            kf,
            lin,
            discrete,
            length,
            command: T::zero(),
            k: 0,
            reduce_failures: 0,
            drive_gain,
            lag_step,
            extra,
            input: SVector::zeros(),
            gyro_offset: T::zero(),
        })
    }

    /// Reductions that failed since the start (the last good reduced boom was kept for them).
    pub fn reduce_failures(&self) -> u32 {
        self.reduce_failures
    }

    /// The filter's repair counters.
    pub fn health(&self) -> crate::filter::FilterHealth {
        self.kf.health()
    }

    /// The filter's state (see [`slot`]).
    pub fn state(&self) -> &SVector<T, STATES> {
        self.kf.state()
    }

    /// The filter's covariance.
    pub fn covariance(&self) -> &SMatrix<T, STATES, STATES> {
        self.kf.covariance()
    }

    /// What the last step ran on ([`LastStep`]).
    pub fn last_step(&self) -> LastStep<'_, T> {
        LastStep {
            model: self.kf.model(),
            input: &self.input,
            gyro_offset: self.gyro_offset,
            tip: core::array::from_fn(|i| self.discrete.tip.get(i).map_or(T::zero(), |t| t.0)),
        }
    }

    /// The first sample: the boom at rest in its static equilibrium at the inclinometer's angle.
    fn start(&mut self, incl: T, length: f64) {
        let t = T::of_f64;
        let angle = if incl.is_finite() { incl.as_f64() - self.settings.inclinometer.1 } else { 0.0 };
        self.refresh(length, angle);
        let s = &self.settings;
        let mut x = SVector::<T, STATES>::zeros();
        x[slot::ANGLE] = t(angle);
        x[slot::LAGGED] = t(angle);
        x[slot::BIAS] = t(s.ar.mean);
        let mut p = SMatrix::<T, STATES, STATES>::zeros();
        let sd_angle = s.inclinometer.2.max(1e-4);
        p[(slot::ANGLE, slot::ANGLE)] = t(sd_angle * sd_angle);
        p[(slot::LAGGED, slot::LAGGED)] = t(sd_angle * sd_angle);
        p[(slot::ANGLE, slot::LAGGED)] = t(sd_angle * sd_angle);
        p[(slot::LAGGED, slot::ANGLE)] = t(sd_angle * sd_angle);
        p[(slot::RATE, slot::RATE)] = t(1e-6);
        // 1 cm at the tip in each mode, at its frequency in rate.
        let values = self.lin.at(length, angle);
        for i in 0..MODES {
            let (w, d) = (values[4 * i], values[4 * i + 1].abs().max(1e-9));
            let sd = 0.01 / d;
            p[(slot::MODE + 2 * i, slot::MODE + 2 * i)] = t(sd * sd);
            p[(slot::MODE + 2 * i + 1, slot::MODE + 2 * i + 1)] = t(sd * sd * w * w);
        }
        let (var, rate_var) = match s.extra_mode {
            Some(m) => (m.level * m.level / (m.omega() * m.omega()), m.level * m.level),
            None => (1.0, 1.0),
        };
        p[(slot::EXTRA, slot::EXTRA)] = t(var);
        p[(slot::EXTRA + 1, slot::EXTRA + 1)] = t(rate_var);
        p[(slot::BIAS, slot::BIAS)] = t(1e-8);
        // The AR process's stationary variance.
        let [a1, a2] = s.ar.a;
        let den = (1.0 + a2) * ((1.0 - a2) * (1.0 - a2) - a1 * a1);
        let var = if den > 0.0 { (1.0 - a2) * s.ar.sigma * s.ar.sigma / den } else { s.ar.sigma * s.ar.sigma };
        let cov1 = a1 / (1.0 - a2) * var;
        p[(slot::NOISE, slot::NOISE)] = t(var);
        p[(slot::NOISE + 1, slot::NOISE + 1)] = t(var);
        p[(slot::NOISE, slot::NOISE + 1)] = t(cov1);
        p[(slot::NOISE + 1, slot::NOISE)] = t(cov1);
        self.kf = KalmanFilter::new(self.kf.model().clone(), x, p);
    }

    /// Re-reduces or rediscretises the boom if it has moved far enough.
    fn refresh(&mut self, length: f64, angle: f64) {
        if !self.lin.covers(length, angle) || self.k == 0 {
            match Linearised::new(&self.settings.constants, length, angle) {
                Ok(lin) => self.lin = lin,
                Err(_) => self.reduce_failures = self.reduce_failures.saturating_add(1),
            }
        }
        let d = &self.discrete;
        if (length - d.length).abs() > REDISCRETISE.0 || (angle - d.angle).abs() > REDISCRETISE.1 || self.k == 0 {
            let values = self.lin.at(length, angle);
            self.discrete = discretise(&values, &self.lin, &self.settings, length, angle);
        }
    }

    /// The model for the step from the last sample to this one, and the known input's effect.
    fn model(
        &self,
        rate: T,
        gyro_ok: bool,
        incl_ok: bool,
    ) -> (LinearModel<T, STATES, MEASUREMENTS>, SVector<T, STATES>) {
        let s = &self.settings;
        let t = T::of_f64;
        let dt = s.dt;
        // The drive: φ̈ = (u − φ̇)(1 − e^{−Δ/τ})/Δ, limited: φ̈ = a0 + g φ̇ over the step.
        let (c, max_accel) = (self.drive_gain, s.drive.1);
        let wanted = (self.command - rate) * t(c);
        let (a0, g) = if wanted.abs() <= t(max_accel) {
            (self.command * t(c), t(-c))
        } else if wanted > T::zero() {
            (t(max_accel), T::zero())
        } else {
            (t(-max_accel), T::zero())
        };
        let dtt = t(dt);
        let half = t(0.5);
        let mut a = SMatrix::<T, STATES, STATES>::zeros();
        let mut u = SVector::<T, STATES>::zeros();
        // φ̇' = φ̇ + Δ φ̈, φ' = φ + Δ (φ̇ + φ̇')/2.
        a[(slot::RATE, slot::RATE)] = T::one() + dtt * g;
        u[slot::RATE] = dtt * a0;
        a[(slot::ANGLE, slot::ANGLE)] = T::one();
        a[(slot::ANGLE, slot::RATE)] = dtt * half * (t(2.0) + dtt * g);
        u[slot::ANGLE] = dtt * dtt * half * a0;
        // The drive's unmodelled acceleration, held over the step: how it moves each state.
        let mut kick = SVector::<T, STATES>::zeros();
        kick[slot::RATE] = dtt;
        kick[slot::ANGLE] = dtt * dtt * half;
        for (i, (phi, gamma)) in self.discrete.modes.iter().enumerate() {
            let (e, r) = (slot::MODE + 2 * i, slot::MODE + 2 * i + 1);
            a[(e, e)] = phi[0][0];
            a[(e, r)] = phi[0][1];
            a[(r, e)] = phi[1][0];
            a[(r, r)] = phi[1][1];
            a[(e, slot::RATE)] = gamma[0] * g;
            a[(r, slot::RATE)] = gamma[1] * g;
            u[e] = gamma[0] * a0;
            u[r] = gamma[1] * a0;
            kick[e] = gamma[0];
            kick[r] = gamma[1];
        }
        let (f, noise) = self.extra;
        for (i, row) in f.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                a[(slot::EXTRA + i, slot::EXTRA + j)] = *v;
            }
        }
        a[(slot::BIAS, slot::BIAS)] = T::one();
        u[slot::BIAS] = t(s.bias_drift * dt);
        // ψ' = (1 − k) ψ + k φ'.
        let kt = t(self.lag_step);
        a[(slot::LAGGED, slot::LAGGED)] = T::one() - kt;
        a[(slot::LAGGED, slot::ANGLE)] = kt * a[(slot::ANGLE, slot::ANGLE)];
        a[(slot::LAGGED, slot::RATE)] = kt * a[(slot::ANGLE, slot::RATE)];
        u[slot::LAGGED] = kt * u[slot::ANGLE];
        kick[slot::LAGGED] = kt * kick[slot::ANGLE];
        // The gyro's AR(2) noise.
        a[(slot::NOISE, slot::NOISE)] = t(s.ar.a[0]);
        a[(slot::NOISE, slot::NOISE + 1)] = t(s.ar.a[1]);
        a[(slot::NOISE + 1, slot::NOISE)] = T::one();
        // Q: the drive's error through `kick`, each mode's own forcing, the bias walk, the AR
        // driving noise.
        let mut q = kick * kick.transpose() * t(s.drive_noise * s.drive_noise);
        for (i, (d, _)) in self.discrete.tip.iter().enumerate() {
            let sd = s.mode_noise / d.as_f64().abs().max(1e-9);
            let r = slot::MODE + 2 * i + 1;
            q[(r, r)] += t(sd * sd * dt);
        }
        q[(slot::EXTRA + 1, slot::EXTRA + 1)] += noise;
        if s.extra_mode.is_none() {
            q[(slot::EXTRA, slot::EXTRA)] += noise;
        }
        q[(slot::BIAS, slot::BIAS)] += t(s.bias_walk * s.bias_walk * dt);
        q[(slot::NOISE, slot::NOISE)] += t(s.ar.sigma * s.ar.sigma);
        // The gyro reads s (φ̇ (1 + ∂S/∂φ) + Σ τᵢ η̇ᵢ) + b + n (the sag's slope rate by length is
        // taken out of the reading); the inclinometer ψ + offset.
        let mut c = SMatrix::<T, MEASUREMENTS, STATES>::zeros();
        let scale = t(s.gyro_scale);
        c[(0, slot::RATE)] = scale * (T::one() + self.discrete.sag_slope_rate.0);
        for (i, (_, slope)) in self.discrete.tip.iter().enumerate() {
            c[(0, slot::MODE + 2 * i + 1)] = scale * *slope;
        }
        if s.extra_mode.is_some() {
            c[(0, slot::EXTRA + 1)] = scale;
        }
        c[(0, slot::BIAS)] = T::one();
        c[(0, slot::NOISE)] = T::one();
        c[(1, slot::LAGGED)] = T::one();
        let mut r = SMatrix::<T, MEASUREMENTS, MEASUREMENTS>::zeros();
        let floor = s.gyro_floor.max(1e-7);
        r[(0, 0)] = t(if gyro_ok { floor * floor } else { MISSING });
        let sd = s.inclinometer.2.max(1e-6);
        let lagging = t(s.lag_sd) * rate;
        r[(1, 1)] = if incl_ok { t(sd * sd) + lagging * lagging } else { t(MISSING) };
        (LinearModel { a, c, q, r }, u)
    }

    /// Takes one sample: the gyro's rate (rad/s), the inclinometer's angle (rad), the boom's
    /// length (m) and the operator's commanded luffing rate (rad/s) over the sample to come.
    /// A non-finite reading is skipped (the filter predicts through it); a non-finite length or
    /// command holds the last.
    pub fn step(&mut self, gyro: T, incl: T, length: T, command: T) -> ModelEstimate<T> {
        let t = T::of_f64;
        let length = if length.is_finite() && length > T::zero() { length.as_f64() } else { self.length };
        let (gyro_ok, incl_ok) = (gyro.is_finite(), incl.is_finite());
        let length_rate = if self.k == 0 { 0.0 } else { (length - self.length) / self.settings.dt };
        if self.k == 0 {
            self.start(incl, length);
        } else {
            let x = *self.kf.state();
            self.refresh(length, x[slot::ANGLE].as_f64());
            let (model, u) = self.model(x[slot::RATE], gyro_ok, incl_ok);
            // Sizes are fixed: neither call can refuse here.
            let _ = self.kf.set_model(model);
            self.kf.predict();
            let _ = self.kf.shift(&u);
            self.input = u;
        }
        if self.k == 0 {
            let (model, _) = self.model(T::zero(), gyro_ok, incl_ok);
            let _ = self.kf.set_model(model);
        }
        self.length = length;
        // The readings less what the state does not carry: the sag's slope rate by length, the
        // inclinometer's offset. A missing one is replaced by its prediction.
        let predicted = self.kf.model().c * self.kf.state();
        let s = &self.settings;
        self.gyro_offset = t(s.gyro_scale) * self.discrete.sag_slope_rate.1 * t(length_rate);
        let y = SVector::<T, MEASUREMENTS>::new(
            if gyro_ok { gyro - self.gyro_offset } else { predicted[0] },
            if incl_ok { incl - t(s.inclinometer.1) } else { predicted[1] },
        );
        let ok = [gyro_ok, incl_ok];
        let (innovation, variance, nis) = match self.kf.update_sequential(&y) {
            Ok(i) => (
                core::array::from_fn(|c| i.scalar.get(c).copied().unwrap_or_else(T::zero)),
                core::array::from_fn(|c| match (ok.get(c), i.variance.get(c)) {
                    (Some(true), Some(v)) => *v,
                    _ => T::of_f64(f64::NAN),
                }),
                i.nis,
            ),
            Err(_) => ([T::zero(); MEASUREMENTS], [T::of_f64(f64::NAN); MEASUREMENTS], T::zero()),
        };
        if command.is_finite() {
            self.command = command;
        }
        self.k += 1;
        let x = self.kf.state();
        let values = self.lin.at(length, x[slot::ANGLE].as_f64());
        let mut vibration = T::zero();
        let mut slope = T::zero();
        for (i, (d, tau)) in self.discrete.tip.iter().enumerate() {
            vibration += *d * x[slot::MODE + 2 * i];
            slope += *tau * x[slot::MODE + 2 * i];
        }
        ModelEstimate {
            tip_angle: x[slot::ANGLE] + t(values[4 * MODES + 1]) + slope,
            vibration,
            deflection: t(values[4 * MODES]) + vibration,
            innovation,
            variance,
            nis,
        }
    }
}
