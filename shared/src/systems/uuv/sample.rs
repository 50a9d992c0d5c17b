//! One row of the vehicle's data as the estimator takes it ([`Sample`]), the commands in force
//! until the next ([`Command`]), the data file's channels and the heading's wrap: what the
//! node's estimator and the loop's filter both read, kept apart from either.

use crate::Real;

/// The commands in force from one sample to the next.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Command<T> {
    /// Main thruster, rpm.
    pub n_t: T,
    /// Vertical thruster, rpm (positive pushes down).
    pub n_v: T,
    /// Rudder, rad.
    pub rudder: T,
    /// Elevator, rad.
    pub elevator: T,
}

/// The vehicle data file's input channels, in its order: specific force (m/s²), rates
/// (rad/s), depth (m), heading (rad), DVL (m/s, empty between readings), then the commands
/// (rpm, rad) in force until the next row.
pub const CHANNELS: [&str; 15] = [
    "acc_x",
    "acc_y",
    "acc_z",
    "gyro_x",
    "gyro_y",
    "gyro_z",
    "depth",
    "heading",
    "dvl_u",
    "dvl_v",
    "dvl_w",
    "cmd_n_t",
    "cmd_n_v",
    "cmd_rudder",
    "cmd_elevator",
];

impl<T: Real> Command<T> {
    /// `new` where it is finite, `self` where not: a missing command holds the last one (the
    /// thrusters keep what they were told).
    ///
    /// ```
    /// use edgekf::systems::uuv::Command;
    /// let last = Command { n_t: 1500.0, n_v: 200.0, rudder: 0.01, elevator: 0.0 };
    /// let now = Command { n_t: f64::NAN, n_v: 300.0, ..last };
    /// assert_eq!(last.held(&now), Command { n_v: 300.0, ..last });
    /// ```
    pub fn held(&self, new: &Command<T>) -> Command<T> {
        let pick = |new: T, old: T| if new.is_finite() { new } else { old };
        Command {
            n_t: pick(new.n_t, self.n_t),
            n_v: pick(new.n_v, self.n_v),
            rudder: pick(new.rudder, self.rudder),
            elevator: pick(new.elevator, self.elevator),
        }
    }
}

/// One row of sensor data. Missing channels are NaN; `dvl` is `None` between its readings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample<T> {
    /// Specific force, body axes, m/s².
    pub acc: [T; 3],
    /// Rates, body axes, rad/s.
    pub gyro: [T; 3],
    /// Depth, m (positive down).
    pub depth: T,
    /// Heading, rad (any branch).
    pub heading: T,
    /// Bottom-track velocity over ground, body axes, m/s.
    pub dvl: Option<[T; 3]>,
    /// The commands issued at this sample, in force until the next.
    pub command: Command<T>,
}

/// An angle wrapped to (−π, π].
///
/// ```
/// use edgekf::systems::uuv::wrap;
/// assert_eq!(wrap(-std::f64::consts::PI), std::f64::consts::PI);
/// ```
pub fn wrap<T: Real>(a: T) -> T {
    let two_pi = T::two_pi();
    let turns = libm::round((a / two_pi).as_f64());
    let mut w = a - two_pi * T::of_f64(turns);
    if w <= -T::pi() {
        w += two_pi;
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_takes_the_short_way() {
        assert!((wrap(3.0 * core::f64::consts::PI / 2.0) + core::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(wrap(core::f64::consts::PI), core::f64::consts::PI);
        assert_eq!(wrap(-core::f64::consts::PI), core::f64::consts::PI);
        assert!((wrap(0.3f32) - 0.3).abs() < 1e-7);
    }
}
