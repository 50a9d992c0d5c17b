//! The vehicle's sensors: IMU at the centre of buoyancy (specific force with a constant bias per
//! seed, gyro with a wandering bias), depth, compass, and a DVL at its own slower rate.

use super::config::SensorConfig;
use rand::Rng;
use rand_distr::StandardNormal;

/// One sample of every sensor; the DVL's is `None` between its readings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    /// Specific force, body axes, m/s².
    pub acc: [f64; 3],
    /// Rates, rad/s.
    pub gyro: [f64; 3],
    /// Depth, m.
    pub depth: f64,
    /// Heading, rad, wrapped to (−π, π].
    pub heading: f64,
    /// Velocity over ground, body axes, m/s.
    pub dvl: Option<[f64; 3]>,
}

/// What the sensors sense, from the reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensed {
    /// Specific force at the origin, m/s².
    pub specific_force: [f64; 3],
    /// Body velocity over ground `[u v w p q r]`.
    pub nu: [f64; 6],
    /// Depth, m.
    pub depth: f64,
    /// Heading, rad.
    pub heading: f64,
}

/// The sensors of one seed.
#[derive(Debug, Clone)]
pub struct Sensors {
    config: SensorConfig,
    acc_bias: [f64; 3],
    gyro_bias: [f64; 3],
    samples: u64,
    dvl_every: u64,
}

impl Sensors {
    /// Sensors with biases drawn from `rng`.
    pub fn draw(config: &SensorConfig, rng: &mut impl Rng) -> Self {
        let mut normal = || rng.sample::<f64, _>(StandardNormal);
        let acc_bias = [0, 1, 2].map(|i| config.acc_bias * normal() + config.acc_offset[i]);
        let gyro_bias = [(); 3].map(|_| config.gyro_bias * normal());
        Self {
            config: config.clone(),
            acc_bias,
            gyro_bias,
            samples: 0,
            dvl_every: (config.rate / config.dvl_rate).round() as u64,
        }
    }

    /// The accelerometer's bias (constant) and the gyro's (now), for the truth columns.
    pub fn biases(&self) -> ([f64; 3], [f64; 3]) {
        (self.acc_bias, self.gyro_bias)
    }

    /// Reads one sample and lets the gyro bias wander for one sample interval.
    pub fn read(&mut self, s: &Sensed, rng: &mut impl Rng) -> Reading {
        let c = &self.config;
        let mut normal = || rng.sample::<f64, _>(StandardNormal);
        let acc = [0, 1, 2].map(|i| s.specific_force[i] + self.acc_bias[i] + c.acc_noise * normal());
        let gyro = [0, 1, 2].map(|i| s.nu[3 + i] + self.gyro_bias[i] + c.gyro_noise * normal());
        let depth = s.depth + c.depth_noise * normal();
        let heading = wrap(s.heading + c.heading_noise * normal());
        let dvl = (self.samples % self.dvl_every == 0)
            .then(|| [0, 1, 2].map(|i| s.nu[i] + c.dvl_offset[i] + c.dvl_noise * normal()));
        // First-order Gauss–Markov wander with stationary deviation `gyro_bias`.
        let decay = (-1.0 / (c.rate * c.gyro_bias_time)).exp();
        let kick = c.gyro_bias * (1.0 - decay * decay).sqrt();
        for b in &mut self.gyro_bias {
            *b = decay * *b + kick * normal();
        }
        self.samples += 1;
        Reading { acc, gyro, depth, heading, dvl }
    }
}

/// An angle wrapped to (−π, π].
pub fn wrap(a: f64) -> f64 {
    let w = a - std::f64::consts::TAU * (a / std::f64::consts::TAU).round();
    if w <= -std::f64::consts::PI {
        w + std::f64::consts::TAU
    } else {
        w
    }
}
