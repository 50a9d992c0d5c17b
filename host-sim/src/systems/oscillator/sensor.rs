//! The ADXL355 three-axis MEMS accelerometer, as seen at its output registers.
//!
//! What is modelled, per axis: the input acceleration, plus a constant bias, plus white noise of
//! the datasheet's density over the output low-pass bandwidth, clipped at the measurement range.
//! What is not: the 20-bit quantisation (done by the virtual device, which also produces the
//! register codes), the group delay and passband ripple of the decimation filter (the signals of
//! interest sit far below its corner: 14 Hz against 250 Hz at 1 kHz), temperature drift and
//! cross-axis sensitivity.
//!
//! Noise: the datasheet gives a density of 25 µg/√Hz and a low-pass corner at ODR/4. The noise
//! power in one output sample is density² × equivalent noise bandwidth. We take that bandwidth as
//! `π/2 ≈ 1.57` times the corner, the value for a first-order roll-off; the real filter is
//! steeper, so this is a mildly pessimistic assumption (a brick-wall filter would give 1.0).
//! At 1 kHz: `σ = 25e-6 × 9.80665 × √(1.57 × 250) ≈ 4.86 mm/s²`.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::Deserialize;

/// Standard gravity, m/s² (the unit "g" of the datasheet).
pub const G: f64 = 9.80665;

/// Equivalent noise bandwidth of the output filter relative to its corner (see the module docs).
pub const NOISE_BANDWIDTH_FACTOR: f64 = 1.57;

/// Output data rates the ADXL355 offers: 4000 Hz / 2ⁿ, n = 0 … 10.
pub const ODR_CHOICES_HZ: [f64; 11] =
    [4000.0, 2000.0, 1000.0, 500.0, 250.0, 125.0, 62.5, 31.25, 15.625, 7.8125, 3.90625];

/// Measurement ranges the ADXL355 offers, g (nominally ±2.048, ±4.096, ±8.192 g).
pub const RANGE_CHOICES_G: [f64; 3] = [2.0, 4.0, 8.0];

/// Settings of the accelerometer model. SI units unless the name says otherwise.
///
/// ```
/// use edgekf_sim::systems::oscillator::sensor::Adxl355Config;
/// let c = Adxl355Config::default();
/// assert_eq!(c.lowpass_hz(), 250.0);
/// assert!((c.noise_std() - 4.857e-3).abs() < 1e-6); // m/s² per sample
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Adxl355Config {
    /// Noise density, g/√Hz (datasheet: 25e-6).
    pub noise_density_g_per_rt_hz: f64,
    /// Output data rate, Hz: one of [`ODR_CHOICES_HZ`].
    pub odr_hz: f64,
    /// Measurement range, ±g: one of [`RANGE_CHOICES_G`]. Readings beyond it clip.
    pub range_g: f64,
    /// Constant bias of each axis (x, y, z), m/s².
    pub bias_m_s2: [f64; 3],
}

impl Default for Adxl355Config {
    /// 25 µg/√Hz, 1000 Hz, ±2 g, no bias.
    fn default() -> Self {
        Self { noise_density_g_per_rt_hz: 25e-6, odr_hz: 1000.0, range_g: 2.0, bias_m_s2: [0.0; 3] }
    }
}

impl Adxl355Config {
    /// Corner of the output low-pass filter, Hz: ODR / 4.
    pub fn lowpass_hz(&self) -> f64 {
        self.odr_hz / 4.0
    }

    /// Standard deviation of the white noise in one output sample, m/s²:
    /// `density · g · √(1.57 · lowpass)`.
    pub fn noise_std(&self) -> f64 {
        self.noise_density_g_per_rt_hz * G * (NOISE_BANDWIDTH_FACTOR * self.lowpass_hz()).sqrt()
    }

    /// Full scale, m/s².
    pub fn range_m_s2(&self) -> f64 {
        self.range_g * G
    }

    /// Checks the settings against what the part can do.
    pub fn validate(&self) -> Result<(), String> {
        if !ODR_CHOICES_HZ.contains(&self.odr_hz) {
            return Err(format!(
                "sensor.odr_hz = {} is not an ADXL355 output data rate (4000 Hz / 2ⁿ: 4000, 2000, 1000, …, 3.90625)",
                self.odr_hz
            ));
        }
        if !RANGE_CHOICES_G.contains(&self.range_g) {
            return Err(format!("sensor.range_g = {} is not an ADXL355 range (2, 4 or 8)", self.range_g));
        }
        if !(self.noise_density_g_per_rt_hz.is_finite() && self.noise_density_g_per_rt_hz >= 0.0) {
            return Err(format!(
                "sensor.noise_density_g_per_rt_hz = {} must be a non-negative number",
                self.noise_density_g_per_rt_hz
            ));
        }
        if self.bias_m_s2.iter().any(|b| !b.is_finite()) {
            return Err("sensor.bias_m_s2 must be finite".into());
        }
        Ok(())
    }
}

/// A seeded ADXL355: the same seed gives the same noise, sample for sample, on every machine.
///
/// Each axis draws from its own ChaCha8 stream of the seed, so the x-axis noise does not change
/// when another axis is added or read differently.
///
/// ```
/// use edgekf_sim::systems::oscillator::sensor::{Adxl355, Adxl355Config, G};
/// let mut a = Adxl355::new(Adxl355Config::default(), 7);
/// let mut b = Adxl355::new(Adxl355Config::default(), 7);
/// let [x, _, z] = a.measure([1.0, 0.0, 3.0 * G]);
/// assert_eq!([x, z], { let r = b.measure([1.0, 0.0, 3.0 * G]); [r[0], r[2]] });
/// assert_eq!(z, 2.0 * G); // clipped at the ±2 g range
/// ```
#[derive(Debug, Clone)]
pub struct Adxl355 {
    config: Adxl355Config,
    sigma: f64,
    range: f64,
    rngs: [ChaCha8Rng; 3],
}

impl Adxl355 {
    /// The sensor with `config`, its noise seeded by `seed`.
    pub fn new(config: Adxl355Config, seed: u64) -> Self {
        let rngs = [0u64, 1, 2].map(|axis| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(axis);
            rng
        });
        Self { config, sigma: config.noise_std(), range: config.range_m_s2(), rngs }
    }

    /// The settings.
    pub fn config(&self) -> &Adxl355Config {
        &self.config
    }

    /// One output sample of the three axes for the true accelerations `input` (m/s²): input +
    /// bias + noise, clipped to the range. Not quantised.
    pub fn measure(&mut self, input: [f64; 3]) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (axis, o) in out.iter_mut().enumerate() {
            let z: f64 = self.rngs[axis].sample(StandardNormal);
            let v = input[axis] + self.config.bias_m_s2[axis] + self.sigma * z;
            *o = v.clamp(-self.range, self.range);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(v: &[f64]) -> (f64, f64) {
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, var.sqrt())
    }

    #[test]
    fn noise_has_the_datasheet_level_and_is_white() {
        let cfg = Adxl355Config { bias_m_s2: [0.0, 0.01, -0.02], ..Default::default() };
        let mut s = Adxl355::new(cfg, 42);
        let n = 100_000;
        let samples: Vec<[f64; 3]> = (0..n).map(|_| s.measure([0.0; 3])).collect();
        let sigma = 25e-6 * G * (1.57f64 * 250.0).sqrt();
        assert!((sigma - 4.8571e-3).abs() < 1e-7);
        for axis in 0..3 {
            let v: Vec<f64> = samples.iter().map(|r| r[axis]).collect();
            let (mean, std) = stats(&v);
            // Standard error of the std over 1e5 samples is 0.22 %; of the mean 1.5e-5 m/s².
            assert!((std / sigma - 1.0).abs() < 0.01, "axis {axis} std {std}");
            assert!((mean - cfg.bias_m_s2[axis]).abs() < 7e-5, "axis {axis} mean {mean}");
            // Lag-1 autocorrelation of white noise: 0 ± 1/√n = 0.003.
            let r1: f64 = v.windows(2).map(|w| (w[0] - mean) * (w[1] - mean)).sum::<f64>() / (n as f64 * std * std);
            assert!(r1.abs() < 0.015, "axis {axis} r1 {r1}");
        }
        // The axes are independent streams.
        let cross: f64 = samples.iter().map(|r| r[0] * r[1]).sum::<f64>() / (n as f64 * sigma * sigma);
        assert!(cross.abs() < 0.015, "{cross}");
    }

    #[test]
    fn noise_scales_with_odr() {
        let slow = Adxl355Config { odr_hz: 125.0, ..Default::default() };
        assert!((Adxl355Config::default().noise_std() / slow.noise_std() - 8f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn same_seed_same_noise_other_seed_other_noise() {
        let mut a = Adxl355::new(Adxl355Config::default(), 1);
        let mut b = Adxl355::new(Adxl355Config::default(), 1);
        let mut c = Adxl355::new(Adxl355Config::default(), 2);
        let (ra, rb, rc) = (a.measure([0.0; 3]), b.measure([0.0; 3]), c.measure([0.0; 3]));
        assert_eq!(ra, rb);
        assert_ne!(ra, rc);
    }

    #[test]
    fn readings_clip_at_the_range() {
        let mut s = Adxl355::new(Adxl355Config { range_g: 4.0, ..Default::default() }, 3);
        let r = s.measure([50.0, -50.0, 30.0]);
        assert_eq!([r[0], r[1]], [4.0 * G, -4.0 * G]);
        assert!((r[2] - 30.0).abs() < 0.05, "30 m/s² is inside ±4 g");
    }

    #[test]
    fn impossible_settings_are_refused() {
        let bad = Adxl355Config { odr_hz: 1200.0, ..Default::default() };
        assert!(bad.validate().unwrap_err().contains("odr_hz = 1200"));
        assert!(Adxl355Config { range_g: 3.0, ..Default::default() }.validate().is_err());
        assert!(Adxl355Config { noise_density_g_per_rt_hz: -1.0, ..Default::default() }.validate().is_err());
        assert!(Adxl355Config::default().validate().is_ok());
    }
}
