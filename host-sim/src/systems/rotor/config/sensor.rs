//! The sensors of a rotor's configuration: displacement probes and accelerometers (with their
//! low-pass, sensitivity and offset), each at a node in one direction.

use serde::Deserialize;

/// Measuring direction of a sensor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// Along x (horizontal).
    X,
    /// Along y (vertical).
    Y,
}

impl Direction {
    /// `"x"` or `"y"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Direction::X => "x",
            Direction::Y => "y",
        }
    }

    /// The node DOF it measures: 0 (x) or 1 (y).
    pub fn dof(self) -> usize {
        match self {
            Direction::X => 0,
            Direction::Y => 1,
        }
    }
}

/// What a sensor measures, with its own settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SensorKind {
    /// A proximity probe: displacement plus white noise.
    Displacement {
        /// Noise standard deviation per sample, m; default 0.
        noise_std: f64,
    },
    /// An accelerometer: acceleration through a Butterworth low-pass, sampled, plus white noise.
    Acceleration(AccelerometerConfig),
}

/// Settings of an accelerometer channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccelerometerConfig {
    /// White-noise density, m/s²/√Hz; σ per sample is `density · √(sample_rate/2)`. Default 0.
    pub noise_density: f64,
    /// −3 dB corner of the Butterworth low-pass, Hz; default `sample_rate / 4` (the ADXL355's).
    pub lowpass_hz: Option<f64>,
    /// Order of the low-pass; default 2. 0 means no filter.
    pub lowpass_order: usize,
    /// Output in volts: `offset + sensitivity · a`, with sensitivity in V per m/s². Default:
    /// none (the channel is in m/s²).
    pub sensitivity: Option<f64>,
    /// Offset of the volts output, V; default 0 (only with `sensitivity`).
    pub offset: f64,
}

/// A sensor on a node.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(try_from = "SensorToml")]
pub struct SensorConfig {
    /// Node index.
    pub node: usize,
    /// Direction.
    pub direction: Direction,
    /// Kind and settings.
    pub kind: SensorKind,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
enum KindToml {
    Displacement,
    Acceleration,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SensorToml {
    node: usize,
    direction: Direction,
    kind: KindToml,
    noise_std: Option<f64>,
    noise_density: Option<f64>,
    lowpass_hz: Option<f64>,
    lowpass_order: Option<usize>,
    sensitivity: Option<f64>,
    offset: Option<f64>,
}

impl TryFrom<SensorToml> for SensorConfig {
    type Error = String;

    fn try_from(s: SensorToml) -> Result<Self, String> {
        let kind = match s.kind {
            KindToml::Displacement => {
                let accel_keys = [
                    ("noise_density", s.noise_density.is_some()),
                    ("lowpass_hz", s.lowpass_hz.is_some()),
                    ("lowpass_order", s.lowpass_order.is_some()),
                    ("sensitivity", s.sensitivity.is_some()),
                    ("offset", s.offset.is_some()),
                ];
                if let Some((k, _)) = accel_keys.iter().find(|(_, set)| *set) {
                    return Err(format!(
                        "sensor at node {}: `{k}` applies to acceleration sensors; a displacement sensor takes noise_std",
                        s.node
                    ));
                }
                SensorKind::Displacement { noise_std: s.noise_std.unwrap_or(0.0) }
            }
            KindToml::Acceleration => {
                if s.noise_std.is_some() {
                    return Err(format!(
                        "sensor at node {}: an acceleration sensor takes noise_density (m/s²/√Hz), not noise_std",
                        s.node
                    ));
                }
                if s.offset.is_some() && s.sensitivity.is_none() {
                    return Err(format!("sensor at node {}: `offset` needs `sensitivity` (V per m/s²)", s.node));
                }
                SensorKind::Acceleration(AccelerometerConfig {
                    noise_density: s.noise_density.unwrap_or(0.0),
                    lowpass_hz: s.lowpass_hz,
                    lowpass_order: s.lowpass_order.unwrap_or(2),
                    sensitivity: s.sensitivity,
                    offset: s.offset.unwrap_or(0.0),
                })
            }
        };
        Ok(Self { node: s.node, direction: s.direction, kind })
    }
}

impl SensorConfig {
    /// The data-file channel name: `n<node>_<dir>` (displacement, m), `n<node>_a<dir>`
    /// (acceleration, m/s²) or `n<node>_a<dir>_volts` (acceleration in volts).
    ///
    /// ```
    /// use edgekf_sim::systems::rotor::config::{Direction, SensorConfig, SensorKind};
    /// let s = SensorConfig { node: 5, direction: Direction::X, kind: SensorKind::Displacement { noise_std: 1e-6 } };
    /// assert_eq!(s.channel_name(), "n5_x");
    /// ```
    pub fn channel_name(&self) -> String {
        let dir = self.direction.as_str();
        match self.kind {
            SensorKind::Displacement { .. } => format!("n{}_{dir}", self.node),
            SensorKind::Acceleration(AccelerometerConfig { sensitivity: Some(_), .. }) => {
                format!("n{}_a{dir}_volts", self.node)
            }
            SensorKind::Acceleration(_) => format!("n{}_a{dir}", self.node),
        }
    }
}

impl AccelerometerConfig {
    /// The low-pass corner in force for a given sample rate (the default is `sample_rate/4`).
    pub fn corner_hz(&self, sample_rate: f64) -> f64 {
        self.lowpass_hz.unwrap_or(sample_rate / 4.0)
    }

    /// Standard deviation of the white noise in one sample, m/s²: `density · √(rate/2)`.
    pub fn noise_std(&self, sample_rate: f64) -> f64 {
        self.noise_density * (sample_rate / 2.0).sqrt()
    }
}
