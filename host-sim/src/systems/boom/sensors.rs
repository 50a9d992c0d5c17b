//! The boom's true sensors: a tip gyro about the luffing axis (scale error, AR(2) noise, a
//! bias with a slow drift, quantisation) and a root inclinometer (first-order lag, offset,
//! noise, quantisation). What they are is the declared sensor with `[sim.*]` on top; what
//! neither says takes the defaults below.

use super::config::BoomConfig;
use rand::Rng;
use rand_distr::StandardNormal;

/// The AR(2) coefficients the paper fits to its gyro's noise.
pub const PAPER_AR: [f64; 2] = [-0.6538, 0.06745];
/// Defaults of what neither the declaration nor `[sim.gyro]` gives: AR driving noise and bias
/// (rad/s), drift (rad/s per s) and quantum (rad/s) of a MEMS rate gyro.
pub const GYRO_DEFAULTS: (f64, f64, f64, f64) = (3e-4, 2e-3, 1e-6, 1e-5);
/// Defaults of the inclinometer's noise and quantum, rad (0.03° and 0.006°).
pub const INCLINOMETER_DEFAULTS: (f64, f64) = (5e-4, 1e-4);

/// The true gyro.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GyroModel {
    /// Scale factor.
    pub scale: f64,
    /// AR(2) coefficients of the noise.
    pub ar: [f64; 2],
    /// AR driving noise, rad/s.
    pub noise: f64,
    /// Bias at t = 0, rad/s.
    pub bias: f64,
    /// Drift of the bias, rad/s per s.
    pub bias_drift: f64,
    /// Quantisation step, rad/s (0: none).
    pub quantum: f64,
}

/// The true inclinometer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InclinometerModel {
    /// First-order time constant, s.
    pub lag: f64,
    /// Offset, rad.
    pub offset: f64,
    /// Noise, rad.
    pub noise: f64,
    /// Quantisation step, rad (0: none).
    pub quantum: f64,
}

impl GyroModel {
    /// The simulator's gyro of `config`.
    pub fn of(config: &BoomConfig) -> Self {
        let (g, s) = (&config.gyro, &config.sim.gyro);
        let (noise, bias, drift, quantum) = GYRO_DEFAULTS;
        Self {
            scale: s.scale.unwrap_or(g.scale),
            ar: s.ar.or(g.ar).unwrap_or(PAPER_AR),
            noise: s.noise.or(g.noise).unwrap_or(noise),
            bias: s.bias.or(g.bias).unwrap_or(bias),
            bias_drift: s.bias_drift.unwrap_or(drift),
            quantum: s.quantum.unwrap_or(quantum),
        }
    }
}

impl InclinometerModel {
    /// The simulator's inclinometer of `config`.
    pub fn of(config: &BoomConfig) -> Self {
        let (i, s) = (&config.inclinometer, &config.sim.inclinometer);
        let (noise, quantum) = INCLINOMETER_DEFAULTS;
        Self {
            lag: s.lag.unwrap_or(i.lag),
            offset: s.offset.unwrap_or(i.offset),
            noise: s.noise.or(i.noise).unwrap_or(noise),
            quantum: s.quantum.unwrap_or(quantum),
        }
    }
}

fn quantise(v: f64, q: f64) -> f64 {
    if q > 0.0 {
        (v / q).round() * q
    } else {
        v
    }
}

/// The gyro's noise and bias as they evolve.
#[derive(Debug, Clone)]
pub struct Gyro {
    model: GyroModel,
    past: [f64; 2],
}

impl Gyro {
    /// A gyro whose noise starts from rest.
    pub fn new(model: GyroModel) -> Self {
        Self { model, past: [0.0; 2] }
    }

    /// The bias at `t`, rad/s.
    pub fn bias(&self, t: f64) -> f64 {
        self.model.bias + self.model.bias_drift * t
    }

    /// The reading of the true rate `rate` at `t`.
    pub fn read(&mut self, rate: f64, t: f64, rng: &mut impl Rng) -> f64 {
        let [a1, a2] = self.model.ar;
        let r: f64 = rng.sample(StandardNormal);
        let n = a1 * self.past[0] + a2 * self.past[1] + self.model.noise * r;
        self.past = [n, self.past[0]];
        quantise(self.model.scale * rate + self.bias(t) + n, self.model.quantum)
    }
}

/// The inclinometer's lagged angle.
#[derive(Debug, Clone)]
pub struct Inclinometer {
    model: InclinometerModel,
    lagged: f64,
    dt: f64,
}

impl Inclinometer {
    /// An inclinometer settled at `angle`, read every `dt` s.
    pub fn new(model: InclinometerModel, angle: f64, dt: f64) -> Self {
        Self { model, lagged: angle, dt }
    }

    /// The reading after the root has been at `angle` for the last sample interval (the lag's
    /// exact response to a held input).
    pub fn read(&mut self, angle: f64, rng: &mut impl Rng) -> f64 {
        let k = if self.model.lag > 0.0 { 1.0 - (-self.dt / self.model.lag).exp() } else { 1.0 };
        self.lagged += k * (angle - self.lagged);
        let r: f64 = rng.sample(StandardNormal);
        quantise(self.lagged + self.model.offset + self.model.noise * r, self.model.quantum)
    }
}
