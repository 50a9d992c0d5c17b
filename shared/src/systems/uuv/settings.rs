//! What the thruster-health filter carries and how much it trusts its model and sensors.
//!
//! Noise densities are continuous-time (per √s) so they do not change meaning with the sample
//! rate; measurement noise is per sample, as a sensor's data sheet states it at its output rate.

/// The filter's state: the ten vehicle states `[z φ θ ψ u v w p q r]` always, then what the
/// configuration asks for, in this order: `k_t`, `k_v`, accelerometer biases (3) and gyro
/// biases (3), the current (north, east). Position `x, y` is not a filter state: nothing
/// measures it, so its variance would grow without bound; it is dead-reckoned beside the filter.
///
/// ```
/// use edgekf::systems::uuv::Layout;
/// let all = Layout { main: true, vertical: true, biases: true, current: true };
/// assert_eq!(all.len(), 20);
/// assert_eq!(all.k_v(), Some(11));
/// assert_eq!(all.current(), Some(18));
/// let bare = Layout { main: false, vertical: false, biases: false, current: false };
/// assert_eq!((bare.len(), bare.k_t(), bare.acc_bias()), (10, None, None));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// A health factor for the main thruster.
    pub main: bool,
    /// A health factor for the vertical thruster.
    pub vertical: bool,
    /// Accelerometer and gyro biases.
    pub biases: bool,
    /// A horizontal ocean current.
    pub current: bool,
}

/// Index of the first velocity state `u`.
pub const VELOCITY: usize = 4;
/// Number of vehicle states.
pub const VEHICLE_STATES: usize = 10;

impl Layout {
    /// Number of states.
    pub const fn len(&self) -> usize {
        VEHICLE_STATES
            + self.main as usize
            + self.vertical as usize
            + 6 * self.biases as usize
            + 2 * self.current as usize
    }

    /// Never: the vehicle states are always there (for clippy's `len` rule).
    pub const fn is_empty(&self) -> bool {
        false
    }

    /// Index of `k_t`.
    pub const fn k_t(&self) -> Option<usize> {
        if self.main {
            Some(VEHICLE_STATES)
        } else {
            None
        }
    }

    /// Index of `k_v`.
    pub const fn k_v(&self) -> Option<usize> {
        if self.vertical {
            Some(VEHICLE_STATES + self.main as usize)
        } else {
            None
        }
    }

    /// Index of the first accelerometer bias (x, then y, z, then the gyro's x, y, z).
    pub const fn acc_bias(&self) -> Option<usize> {
        if self.biases {
            Some(VEHICLE_STATES + self.main as usize + self.vertical as usize)
        } else {
            None
        }
    }

    /// Index of the first gyro bias.
    pub const fn gyro_bias(&self) -> Option<usize> {
        match self.acc_bias() {
            Some(i) => Some(i + 3),
            None => None,
        }
    }

    /// Index of the current's north component (east follows).
    pub const fn current(&self) -> Option<usize> {
        if self.current {
            Some(self.len() - 2)
        } else {
            None
        }
    }
}

/// Random-walk densities of the filter's process noise, per √s.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct ProcessNoise {
    /// Unmodelled force on the linear velocities, m/s² per √Hz.
    pub velocity: f64,
    /// Unmodelled moment on the rates, rad/s² per √Hz.
    pub rate: f64,
    /// Attitude, rad/s per √Hz.
    pub attitude: f64,
    /// Depth, m/s per √Hz.
    pub depth: f64,
    /// Health factors, per √s: small, because the detector reopens a factor when its
    /// thruster changes (see [`DetectorSettings`]).
    pub health: f64,
    /// Accelerometer biases, m/s² per √s.
    pub acc_bias: f64,
    /// Gyro biases, rad/s per √s.
    pub gyro_bias: f64,
    /// Current, m/s per √s (a current that changes by 0.1 m/s over a minute is 0.013).
    pub current: f64,
}

impl Default for ProcessNoise {
    fn default() -> Self {
        Self {
            velocity: 0.02,
            rate: 0.005,
            attitude: 2e-4,
            depth: 1e-3,
            health: 0.0005,
            acc_bias: 1e-4,
            gyro_bias: 2e-5,
            current: 0.01,
        }
    }
}

/// Standard deviations of the measurement noise per sample.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct MeasurementNoise {
    /// Accelerometer, m/s².
    pub acc: f64,
    /// Gyro, rad/s.
    pub gyro: f64,
    /// Depth, m.
    pub depth: f64,
    /// Heading, rad.
    pub heading: f64,
    /// DVL, m/s.
    pub dvl: f64,
}

impl Default for MeasurementNoise {
    /// The issue's typical sensors at 50 Hz.
    fn default() -> Self {
        Self { acc: 0.02, gyro: 0.002, depth: 0.02, heading: 0.01, dvl: 0.005 }
    }
}

/// Standard deviations of the first estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct InitialSpread {
    /// Roll and pitch, rad (heading and depth start from their sensors).
    pub attitude: f64,
    /// Linear velocities, m/s.
    pub velocity: f64,
    /// Rates, rad/s.
    pub rate: f64,
    /// Health factors (they start at 1).
    pub health: f64,
    /// Accelerometer biases, m/s².
    pub acc_bias: f64,
    /// Gyro biases, rad/s.
    pub gyro_bias: f64,
    /// Current, m/s.
    pub current: f64,
}

impl Default for InitialSpread {
    fn default() -> Self {
        Self { attitude: 0.1, velocity: 0.5, rate: 0.01, health: 0.05, acc_bias: 0.03, gyro_bias: 0.003, current: 0.3 }
    }
}

/// The change detector on each health factor and the status thresholds.
///
/// A two-sided CUSUM runs on the IMU innovation projected on the direction a change of the
/// thruster's factor would move it (whitened, so the score is N(0, 1) while the model holds).
/// When it crosses `threshold`, the factor's variance is reopened to `reopen`² and the CUSUM
/// restarts: the filter then re-learns the factor in a few samples instead of dragging it with a
/// random walk slow enough to ignore currents.
///
/// The status follows the factor with hysteresis of `sigmas` standard deviations: a thruster is
/// declared `degraded` when `k + sigmas·σ < degraded`, `failed` when `k + sigmas·σ < failed`,
/// and goes back up a class when `k − sigmas·σ` clears that class's threshold.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize, serde::Serialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct DetectorSettings {
    /// CUSUM drift, in standard deviations of the score per sample.
    pub drift: f64,
    /// CUSUM threshold.
    pub threshold: f64,
    /// Standard deviation a factor is reopened to.
    pub reopen: f64,
    /// Hysteresis, in the factor's standard deviations.
    pub sigmas: f64,
    /// Below this a thruster is degraded.
    pub degraded: f64,
    /// Below this it has failed.
    pub failed: f64,
}

impl Default for DetectorSettings {
    fn default() -> Self {
        Self { drift: 1.0, threshold: 12.0, reopen: 0.5, sigmas: 3.0, degraded: 0.7, failed: 0.3 }
    }
}

/// Everything the estimator is built from beside the vehicle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimatorSettings {
    /// Which states it carries.
    pub layout: Layout,
    /// Process noise.
    pub process: ProcessNoise,
    /// Measurement noise.
    pub noise: MeasurementNoise,
    /// First estimate's spread.
    pub initial: InitialSpread,
    /// Change detector and status.
    pub detector: DetectorSettings,
    /// Sample interval, s.
    pub dt: f64,
    /// The DVL's known offset on `u, v, w`, m/s, taken off each reading before it is used: how
    /// an offset the loop found (`sensor_bias` at a DVL axis) becomes part of the node's model
    /// (`[estimator.dvl_offset]`).
    pub dvl_offset: [f64; 3],
}

impl EstimatorSettings {
    /// Defaults for `layout` at `rate` Hz.
    pub fn new(layout: Layout, rate: f64) -> Self {
        Self {
            layout,
            process: ProcessNoise::default(),
            noise: MeasurementNoise::default(),
            initial: InitialSpread::default(),
            detector: DetectorSettings::default(),
            dt: 1.0 / rate,
            dvl_offset: [0.0; 3],
        }
    }
}
