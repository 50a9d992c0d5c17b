//! The vehicle configuration (TOML): the vehicle's constants, its sensors, the sea, the
//! autopilots and the estimator. `host-sim/configs/uuv_remus100.toml` writes the defaults out.
//!
//! Every table may be left out and then takes the defaults (REMUS 100, the issue's typical
//! sensors); unknown keys are refused with their name.
//!
//! ```
//! use edgekf_sim::systems::uuv::UuvConfig;
//! let c = UuvConfig::from_toml_str("[estimator]\nhealth = [\"main\"]\ncurrent = false\n").unwrap();
//! assert!(c.estimator.layout().main && !c.estimator.layout().vertical && !c.estimator.layout().current);
//! assert_eq!(c.vehicle.weight, 299.0);
//! let e = UuvConfig::from_toml_str("[estimator]\nhealth = [\"rudder\"]\n").unwrap_err();
//! assert!(e.to_string().contains("rudder"), "{e}");
//! ```

use super::error::UuvError;
use edgekf::systems::uuv::{
    DetectorSettings, EstimatorSettings, InitialSpread, Layout, MeasurementNoise, ProcessNoise, Vehicle,
};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Sensors as a real vehicle has them; noise is per sample at `rate`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct SensorConfig {
    /// Sample rate of the IMU, depth and heading, Hz.
    pub rate: f64,
    /// DVL update rate, Hz (its columns are empty between updates).
    pub dvl_rate: f64,
    /// Accelerometer white noise, m/s².
    pub acc_noise: f64,
    /// Accelerometer bias: standard deviation of each axis's constant, drawn per seed, m/s².
    pub acc_bias: f64,
    /// A further accelerometer offset on every seed, body x, y, z, m/s² (an effect nobody
    /// declared, for the residual loop's tests; zero by default).
    pub acc_offset: [f64; 3],
    /// A DVL offset on every seed, body u, v, w, m/s (an effect nobody declared, for the
    /// residual loop's tests; zero by default).
    pub dvl_offset: [f64; 3],
    /// Gyro white noise, rad/s.
    pub gyro_noise: f64,
    /// Gyro bias: stationary standard deviation of each axis, rad/s.
    pub gyro_bias: f64,
    /// Correlation time of the gyro bias's wander (first-order Gauss–Markov), s.
    pub gyro_bias_time: f64,
    /// Depth sensor noise, m.
    pub depth_noise: f64,
    /// Compass noise, rad.
    pub heading_noise: f64,
    /// DVL noise per reading, m/s.
    pub dvl_noise: f64,
}

impl Default for SensorConfig {
    fn default() -> Self {
        Self {
            rate: 50.0,
            dvl_rate: 5.0,
            acc_noise: 0.02,
            acc_bias: 0.02,
            acc_offset: [0.0; 3],
            dvl_offset: [0.0; 3],
            gyro_noise: 0.002,
            gyro_bias: 0.0015,
            gyro_bias_time: 300.0,
            depth_noise: 0.02,
            heading_noise: 0.01,
            dvl_noise: 0.005,
        }
    }
}

/// The ocean current: a mean drawn per seed plus slow oscillations.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct CurrentConfig {
    /// Range of the mean speed, m/s (drawn uniformly per seed; the direction uniformly).
    pub speed: [f64; 2],
    /// Amplitude of the variation of each horizontal component, m/s.
    pub variation: f64,
    /// Range of the variation's periods, s.
    pub periods: [f64; 2],
}

impl Default for CurrentConfig {
    /// 0.15–0.25 m/s mean, ±0.05 m/s over 40–120 s: 0.1–0.3 m/s, changing over about a minute.
    fn default() -> Self {
        Self { speed: [0.15, 0.25], variation: 0.05, periods: [40.0, 120.0] }
    }
}

/// The mission and its autopilots (depth by the vertical thruster, pitch by the elevator,
/// heading by the rudder), run at the sensors' rate from the sensors.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct AutopilotConfig {
    /// Depth to hold, m.
    pub depth: f64,
    /// Heading to hold, rad.
    pub heading: f64,
    /// Main thruster speed, rpm.
    pub main_rpm: f64,
    /// Heading gain, rad of rudder per rad of error.
    pub heading_gain: f64,
    /// Yaw-rate gain, rad of rudder per rad/s.
    pub yaw_rate_gain: f64,
    /// Pitch gain, rad of elevator per rad.
    pub pitch_gain: f64,
    /// Pitch-rate gain, rad of elevator per rad/s.
    pub pitch_rate_gain: f64,
    /// Depth gain, N per m.
    pub depth_gain: f64,
    /// Depth integral gain, N per m·s.
    pub depth_integral: f64,
    /// Heave damping gain, N per m/s (on the DVL's w).
    pub heave_gain: f64,
    /// Time the vehicle runs before the recording starts, s (so it starts in steady flight).
    pub preroll: f64,
}

impl Default for AutopilotConfig {
    fn default() -> Self {
        Self {
            depth: 10.0,
            heading: core::f64::consts::FRAC_PI_4,
            main_rpm: 1500.0,
            heading_gain: 1.0,
            yaw_rate_gain: 1.0,
            pitch_gain: 8.0,
            pitch_rate_gain: 4.0,
            depth_gain: 20.0,
            depth_integral: 2.0,
            heave_gain: 40.0,
            preroll: 60.0,
        }
    }
}

/// The reference integrator.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct IntegratorConfig {
    /// RK4 step, s (at most 0.01; a whole number of steps per sample).
    pub step: f64,
}

impl Default for IntegratorConfig {
    fn default() -> Self {
        Self { step: 0.005 }
    }
}

/// What the estimator carries and how it is tuned.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct EstimatorConfig {
    /// Thrusters with a health state: `"main"`, `"vertical"`, both or none.
    pub health: Vec<String>,
    /// Carry accelerometer and gyro biases.
    pub sensor_biases: bool,
    /// Carry a horizontal ocean current.
    pub current: bool,
    /// Process noise densities.
    pub process: ProcessNoise,
    /// Measurement noise (defaults: the sensors' table's typical figures).
    pub noise: MeasurementNoise,
    /// First estimate's spread.
    pub initial: InitialSpread,
    /// Change detector and status thresholds.
    pub detector: DetectorSettings,
    /// The DVL's known offset, taken off its readings (what the loop writes when it finds
    /// one; the simulated part's is `[sensors] dvl_offset`).
    pub dvl_offset: DvlOffset,
}

/// `[estimator.dvl_offset]`: a table of three keys, not an array, so that a corrected
/// configuration can name the axis it changes (`estimator.dvl_offset.v`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct DvlOffset {
    /// Surge, m/s.
    pub u: f64,
    /// Sway, m/s.
    pub v: f64,
    /// Heave, m/s.
    pub w: f64,
}

impl Default for EstimatorConfig {
    fn default() -> Self {
        Self {
            health: vec!["main".into(), "vertical".into()],
            sensor_biases: true,
            current: true,
            process: ProcessNoise::default(),
            noise: MeasurementNoise::default(),
            initial: InitialSpread::default(),
            detector: DetectorSettings::default(),
            dvl_offset: DvlOffset::default(),
        }
    }
}

impl EstimatorConfig {
    /// The filter's states.
    pub fn layout(&self) -> Layout {
        let has = |n: &str| self.health.iter().any(|h| h == n);
        Layout { main: has("main"), vertical: has("vertical"), biases: self.sensor_biases, current: self.current }
    }

    /// The shared estimator's settings at `rate` Hz.
    pub fn settings(&self, rate: f64) -> EstimatorSettings {
        EstimatorSettings {
            process: self.process,
            noise: self.noise,
            initial: self.initial,
            detector: self.detector,
            dvl_offset: [self.dvl_offset.u, self.dvl_offset.v, self.dvl_offset.w],
            ..EstimatorSettings::new(self.layout(), rate)
        }
    }
}

/// The whole configuration.
#[derive(Debug, Clone, PartialEq, Default, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct UuvConfig {
    /// The vehicle's constants.
    pub vehicle: Vehicle,
    /// Its sensors.
    pub sensors: SensorConfig,
    /// The sea's current.
    pub current: CurrentConfig,
    /// Mission and autopilots.
    pub autopilot: AutopilotConfig,
    /// Reference integrator.
    pub integrator: IntegratorConfig,
    /// The estimator.
    pub estimator: EstimatorConfig,
}

impl UuvConfig {
    /// Parses and validates a configuration text.
    pub fn from_toml_str(text: &str) -> Result<Self, UuvError> {
        let c: UuvConfig = crate::io::config::parse_toml(text).map_err(|e| UuvError::Config(e.to_string()))?;
        c.validate()?;
        Ok(c)
    }

    /// Reads, parses and validates a configuration file; messages name the file.
    pub fn load(path: &Path) -> Result<Self, UuvError> {
        let text = std::fs::read_to_string(path).map_err(|reason| UuvError::Io { path: path.into(), reason })?;
        Self::from_toml_str(&text).map_err(|e| UuvError::Config(format!("{}: {e}", path.display())))
    }

    /// The configuration as TOML (the defaults give `configs/uuv_remus100.toml`'s values).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }

    /// Checks every figure; the message names the key.
    pub fn validate(&self) -> Result<(), UuvError> {
        let bad = |m: String| Err(UuvError::Config(m));
        self.vehicle.check().map_err(|m| UuvError::Config(format!("[vehicle]: {m}")))?;
        let s = &self.sensors;
        for (k, v) in
            [("sensors.rate", s.rate), ("sensors.dvl_rate", s.dvl_rate), ("sensors.gyro_bias_time", s.gyro_bias_time)]
        {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!("{k} = {v} must be positive"));
            }
        }
        let ratio = s.rate / s.dvl_rate;
        if (ratio - ratio.round()).abs() > 1e-9 || ratio < 1.0 {
            return bad(format!("sensors.dvl_rate = {} must divide sensors.rate = {}", s.dvl_rate, s.rate));
        }
        let noises = [s.acc_noise, s.acc_bias, s.gyro_noise, s.gyro_bias, s.depth_noise, s.heading_noise, s.dvl_noise];
        let o = &self.estimator.dvl_offset;
        if noises.iter().chain(&s.acc_offset).chain(&s.dvl_offset).chain(&[o.u, o.v, o.w]).any(|v| !v.is_finite())
            || noises.iter().any(|v| *v < 0.0)
        {
            return bad(
                "[sensors], [estimator.dvl_offset]: noises and biases must be finite, noises not negative".into()
            );
        }
        let c = &self.current;
        let speed_ok = c.speed[0] >= 0.0 && c.speed[1] >= c.speed[0] && c.speed[1].is_finite();
        let variation_ok = c.variation >= 0.0 && c.variation.is_finite();
        let periods_ok = c.periods[0] > 0.0 && c.periods[1] >= c.periods[0] && c.periods[1].is_finite();
        if !(speed_ok && variation_ok && periods_ok) {
            return bad("[current]: speed and periods must be ranges [low, high] with 0 ≤ low ≤ high".into());
        }
        let a = &self.autopilot;
        let gains = [
            a.depth,
            a.heading,
            a.main_rpm,
            a.heading_gain,
            a.yaw_rate_gain,
            a.pitch_gain,
            a.pitch_rate_gain,
            a.depth_gain,
            a.depth_integral,
            a.heave_gain,
            a.preroll,
        ];
        if gains.iter().any(|v| !v.is_finite()) || a.preroll < 0.0 {
            return bad("[autopilot]: every value must be finite, preroll not negative".into());
        }
        let h = self.integrator.step;
        let per_sample = 1.0 / (s.rate * h);
        if !(h > 0.0 && h <= 0.01) || (per_sample - per_sample.round()).abs() > 1e-6 {
            return bad(format!("integrator.step = {h} must be at most 0.01 s and divide 1/sensors.rate"));
        }
        for name in &self.estimator.health {
            if name != "main" && name != "vertical" {
                return bad(format!("estimator.health: `{name}` is not a thruster (main, vertical)"));
            }
        }
        let probe = edgekf::systems::uuv::UuvEstimator::<f64, 20>::new(
            &self.vehicle,
            &EstimatorSettings {
                layout: Layout { main: true, vertical: true, biases: true, current: true },
                ..self.estimator.settings(s.rate)
            },
        );
        if probe.is_err() {
            return bad("[estimator]: noises must be positive and finite".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_file_is_the_defaults() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/uuv_remus100.toml");
        assert_eq!(UuvConfig::load(Path::new(path)).unwrap(), UuvConfig::default());
    }

    #[test]
    fn a_bad_value_names_its_key() {
        let e = UuvConfig::from_toml_str("[integrator]\nstep = 0.03\n").unwrap_err();
        assert!(e.to_string().contains("integrator.step"), "{e}");
        let e = UuvConfig::from_toml_str("[vehicle]\nweigth = 3\n").unwrap_err();
        assert!(e.to_string().contains("weigth"), "{e}");
    }
}
