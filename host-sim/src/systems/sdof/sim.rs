//! The mount's reference simulator: the continuous equation of motion integrated in `f64`,
//! independent of the reduced model the node runs.
//!
//! Where its numbers come from:
//! * the equation `z̈ + 2ζωn ż + ωn² z = −a_b(t)` for the displacement `z` of the mass
//!   relative to the base, in physical coordinates `[z, ż]` (not the filter's scaled state),
//!   integrated by classical fourth-order Runge–Kutta at [`SUBSTEPS`] steps per sample (4 kHz
//!   at 1 kHz: `ωn h = 0.016`, a local error near 10⁻¹¹ of the state), not by the filter's exact
//!   discretisation, so the filter's agreement with it is evidence rather than a tautology;
//! * the base acceleration `a_b(t)`: a sum of [`LINES`] sinusoids, one in each
//!   [`BAND_HZ`]`/LINES` wide bin of 0–50 Hz at a seeded random place in its bin with a seeded
//!   random phase, each of amplitude `√(2 S₁ Δf)` for the one-sided density `S₁ = 2 base_psd`:
//!   a smooth function of time (RK4 evaluates it between samples) whose spectrum is the
//!   filter's white process noise over the band that matters, `2 base_psd · 50 Hz` in power
//!   (1 (m/s²)² with the default 0.01 (m/s²)²/Hz);
//! * the accelerometer on the mass: its absolute acceleration `−ωn² z − 2ζωn ż` (the spring's
//!   and the damper's force over the mass), read by the host's ADXL355 model
//!   ([`crate::systems::oscillator::sensor::Adxl355`]: the datasheet's noise, its range), with
//!   `ay = 0` and `az = g` (the mount stands upright) for the node's three-axis reader.

use crate::io::data::{self, DataError};
use crate::systems::oscillator::sensor::{Adxl355, Adxl355Config, G};
use edgekf::systems::sdof::SdofParams;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;

/// RK4 steps per sample.
pub const SUBSTEPS: usize = 4;

/// Sinusoids in the base acceleration.
pub const LINES: usize = 250;

/// Upper edge of the base acceleration's band, Hz.
pub const BAND_HZ: f64 = 50.0;

/// The longest run the simulator accepts, s (a day at 1 kHz is 8.6·10⁷ rows: far more than a
/// test needs, and it keeps a mistyped duration from filling the memory).
pub const MAX_DURATION_S: f64 = 3600.0;

/// The base acceleration: a seeded sum of sinusoids (see the module's documentation).
#[derive(Debug, Clone)]
pub struct BaseMotion {
    /// Angular frequency, amplitude (m/s²) and phase of each line.
    lines: Vec<(f64, f64, f64)>,
}

impl BaseMotion {
    /// The base motion of two-sided density `psd` ((m/s²)²/Hz) over 0–[`BAND_HZ`], seeded.
    pub fn new(psd: f64, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let df = BAND_HZ / LINES as f64;
        let amplitude = (2.0 * (2.0 * psd) * df).sqrt();
        let lines = (0..LINES)
            .map(|i| {
                let f = (i as f64 + rng.gen::<f64>()) * df;
                (2.0 * std::f64::consts::PI * f, amplitude, 2.0 * std::f64::consts::PI * rng.gen::<f64>())
            })
            .collect();
        Self { lines }
    }

    /// One sinusoid of `amplitude` m/s² at `hz`, phase 0 (a test's exact case).
    pub fn single(hz: f64, amplitude: f64) -> Self {
        Self { lines: vec![(2.0 * std::f64::consts::PI * hz, amplitude, 0.0)] }
    }

    /// The base acceleration at `t`, m/s².
    pub fn accel(&self, t: f64) -> f64 {
        self.lines.iter().map(|(w, a, phi)| a * (w * t + phi).sin()).sum()
    }
}

/// What to simulate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimOptions {
    /// Length of the run, s.
    pub duration: f64,
    /// Seed of the base motion and of the sensor's noise.
    pub seed: u64,
}

impl Default for SimOptions {
    fn default() -> Self {
        Self { duration: 20.0, seed: 1 }
    }
}

/// A simulated run: the accelerometer's three axes and the truth.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Recording {
    /// Time of each sample, s.
    pub t: Vec<f64>,
    /// The accelerometer's axes, m/s²: `ax` along the mount, `ay`, `az` across it.
    pub accel: [Vec<f64>; 3],
    /// Relative displacement of the mass, m.
    pub truth_displacement: Vec<f64>,
    /// Relative velocity, m/s.
    pub truth_velocity: Vec<f64>,
    /// Absolute acceleration of the mass without the sensor's noise, m/s².
    pub truth_accel: Vec<f64>,
    /// The base's acceleration, m/s².
    pub truth_base_accel: Vec<f64>,
}

/// The data file's channels, in its column order.
pub const COLUMNS: [&str; 7] =
    ["ax", "ay", "az", "truth_displacement", "truth_velocity", "truth_accel", "truth_base_accel"];

impl Recording {
    /// The recording as CSV text in the data contract (`t`, [`COLUMNS`]).
    pub fn to_csv_string(&self) -> Result<String, DataError> {
        data::to_csv_string(Path::new("<sdof>"), &COLUMNS, &self.t, &self.columns())
    }

    /// Writes the recording to `path` (through a temporary file, renamed into place).
    pub fn write(&self, path: &Path) -> Result<(), DataError> {
        data::write(path, &COLUMNS, &self.t, &self.columns())
    }

    fn columns(&self) -> [&[f64]; 7] {
        let [ax, ay, az] = &self.accel;
        [ax, ay, az, &self.truth_displacement, &self.truth_velocity, &self.truth_accel, &self.truth_base_accel]
    }
}

/// Why a simulation was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// The duration is not a number of seconds in (0, [`MAX_DURATION_S`]].
    #[error("duration {0} s: must be a positive number of seconds up to {MAX_DURATION_S}")]
    Duration(f64),
    /// The mount's parameters do not make a model.
    #[error("the mount's parameters are invalid: {0:?}")]
    Params(SdofParams),
}

/// Simulates `opts.duration` s of the mount `params` on a base shaken by [`BaseMotion::new`]
/// with `params.base_psd`, sampled at `params.sample_rate_hz` by an ADXL355 (±2 g, its noise
/// seeded by `opts.seed`).
pub fn simulate(params: &SdofParams, opts: &SimOptions) -> Result<Recording, SimError> {
    simulate_with(params, &BaseMotion::new(params.base_psd, opts.seed), opts)
}

/// [`simulate`] on a given base motion.
pub fn simulate_with(params: &SdofParams, base: &BaseMotion, opts: &SimOptions) -> Result<Recording, SimError> {
    if !(opts.duration > 0.0 && opts.duration <= MAX_DURATION_S) {
        return Err(SimError::Duration(opts.duration));
    }
    params.discrete_model().map_err(|_| SimError::Params(*params))?;
    let (wn, zeta, fs) = (params.omega_n(), params.damping_ratio, params.sample_rate_hz);
    let sensor_config = Adxl355Config { odr_hz: fs, ..Adxl355Config::default() };
    let mut sensor = Adxl355::new(sensor_config, opts.seed);
    let n = (opts.duration * fs).round() as usize;
    let h = 1.0 / (fs * SUBSTEPS as f64);
    // ẋ of the state [z, ż] at time t.
    let rate = |t: f64, [z, v]: [f64; 2]| [v, -wn * wn * z - 2.0 * zeta * wn * v - base.accel(t)];
    let mut rec = Recording::default();
    let mut x = [0.0f64; 2];
    for k in 0..n {
        let t = k as f64 / fs;
        let absolute = -wn * wn * x[0] - 2.0 * zeta * wn * x[1];
        let [ax, ay, az] = sensor.measure([absolute, 0.0, G]);
        rec.t.push(t);
        for (column, value) in rec.accel.iter_mut().zip([ax, ay, az]) {
            column.push(value);
        }
        rec.truth_displacement.push(x[0]);
        rec.truth_velocity.push(x[1]);
        rec.truth_accel.push(absolute);
        rec.truth_base_accel.push(base.accel(t));
        for s in 0..SUBSTEPS {
            x = rk4(&rate, t + s as f64 * h, x, h);
        }
    }
    Ok(rec)
}

/// One classical Runge–Kutta step of `ẋ = f(t, x)`.
fn rk4(f: &impl Fn(f64, [f64; 2]) -> [f64; 2], t: f64, x: [f64; 2], h: f64) -> [f64; 2] {
    let add = |x: [f64; 2], k: [f64; 2], s: f64| [x[0] + s * k[0], x[1] + s * k[1]];
    let k1 = f(t, x);
    let k2 = f(t + 0.5 * h, add(x, k1, 0.5 * h));
    let k3 = f(t + 0.5 * h, add(x, k2, 0.5 * h));
    let k4 = f(t + h, add(x, k3, h));
    [0, 1].map(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
}
