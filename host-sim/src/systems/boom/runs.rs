//! The test runs (what the operator commands and how long the boom is) and the luffing drive
//! that follows the command.

use super::config::{Drive, Runs};
use clap::ValueEnum;

/// A run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Scenario {
    /// Luffing moves with sharp stops at full length, each followed by a free decay.
    Luffing,
    /// Telescoping from `runs.extension_from` to `runs.length` while luffing as above.
    Extension,
}

/// Seconds at rest before the first move.
pub const SETTLE_S: f64 = 2.0;

impl Scenario {
    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::Luffing => "luffing",
            Scenario::Extension => "extension",
        }
    }

    /// The operator's commanded luffing rate at `t`, rad/s: moves of `luff_time` alternately up
    /// and down, each followed by `rest_time` at rest.
    ///
    /// ```
    /// use edgekf_sim::systems::boom::{config::Runs, runs::Scenario};
    /// let r = Runs::default();
    /// assert_eq!(Scenario::Luffing.command(&r, 1.0), 0.0);
    /// assert_eq!(Scenario::Luffing.command(&r, 3.0), r.luff_rate);
    /// assert_eq!(Scenario::Luffing.command(&r, 2.0 + r.luff_time + 1.0), 0.0);
    /// assert_eq!(Scenario::Luffing.command(&r, 3.0 + r.luff_time + r.rest_time), -r.luff_rate);
    /// ```
    pub fn command(self, runs: &Runs, t: f64) -> f64 {
        let s = t - SETTLE_S;
        if s < 0.0 {
            return 0.0;
        }
        let period = runs.luff_time + runs.rest_time;
        let cycle = (s / period).floor();
        if s - cycle * period >= runs.luff_time {
            0.0
        } else if cycle as u64 % 2 == 0 {
            runs.luff_rate
        } else {
            -runs.luff_rate
        }
    }

    /// The boom's length at `t`, m.
    pub fn length(self, runs: &Runs, t: f64) -> f64 {
        match self {
            Scenario::Luffing => runs.length,
            Scenario::Extension => {
                (runs.extension_from + runs.extension_rate * (t - SETTLE_S).max(0.0)).min(runs.length)
            }
        }
    }
}

/// The luffing drive's state: angle and rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Luffing {
    /// Angle from the horizontal, rad.
    pub angle: f64,
    /// Rate, rad/s.
    pub rate: f64,
    /// Acceleration over the last step, rad/s².
    pub accel: f64,
}

impl Luffing {
    /// At rest at `angle`.
    pub fn at_rest(angle: f64) -> Self {
        Self { angle, rate: 0.0, accel: 0.0 }
    }

    /// One step of `dt` towards the commanded rate: first-order lag, acceleration limited
    /// (semi-implicit: the rate first, then the angle with the new rate).
    ///
    /// ```
    /// use edgekf_sim::systems::boom::{config::Drive, runs::Luffing};
    /// let drive = Drive { lag: 0.2, max_accel: 0.1 };
    /// let mut l = Luffing::at_rest(0.5);
    /// l.step(&drive, 0.05, 0.001);
    /// assert_eq!(l.accel, 0.1); // 0.05/0.2 = 0.25 rad/s² is over the limit
    /// for _ in 0..10_000 { l.step(&drive, 0.05, 0.001); }
    /// assert!((l.rate - 0.05).abs() < 1e-9);
    /// ```
    pub fn step(&mut self, drive: &Drive, command: f64, dt: f64) {
        // The lag's exact response over dt, as an acceleration, then limited.
        let wanted = (command - self.rate) * (1.0 - (-dt / drive.lag).exp()) / dt;
        self.accel = wanted.clamp(-drive.max_accel, drive.max_accel);
        self.rate += self.accel * dt;
        self.angle += self.rate * dt;
    }
}
