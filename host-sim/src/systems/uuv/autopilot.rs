//! The autopilots that fly the scenarios closed loop, as at sea: heading by the rudder, pitch
//! by the elevator, depth by the vertical thruster (with the net buoyancy fed forward and an
//! integral for what the feed-forward misses, such as a weak thruster). They act on the
//! sensors; pitch comes from the vehicle's attitude reference, which the sensors' table does
//! not model (its error is the compass's order).

use super::config::AutopilotConfig;
use super::sensors::{wrap, Reading};
use edgekf::systems::uuv::{Command, Vehicle};

/// The autopilots' memory: the depth integral and the last DVL heave.
#[derive(Debug, Clone)]
pub struct Autopilot {
    config: AutopilotConfig,
    integral: f64,
    heave: f64,
}

impl Autopilot {
    /// Autopilots with empty memory.
    pub fn new(config: &AutopilotConfig) -> Self {
        Self { config: config.clone(), integral: 0.0, heave: 0.0 }
    }

    /// The commands for the next sample interval from this sample's `reading` and `pitch`
    /// (rad), `dt` seconds after the last.
    pub fn command(&mut self, reading: &Reading, pitch: f64, vehicle: &Vehicle, dt: f64) -> Command<f64> {
        let c = &self.config;
        let a = &vehicle.actuators;
        let fin = |d: f64| d.clamp(-a.fin_max, a.fin_max);
        // N_uuδr < 0: a positive rudder turns to port.
        let rudder = fin(c.heading_gain * wrap(reading.heading - c.heading) + c.yaw_rate_gain * reading.gyro[2]);
        // M_uuδs < 0: a positive elevator pitches the nose down.
        let elevator = fin(c.pitch_gain * pitch + c.pitch_rate_gain * reading.gyro[1]);
        if let Some(d) = reading.dvl {
            self.heave = d[2];
        }
        let error = c.depth - reading.depth;
        let push = (vehicle.buoyancy - vehicle.weight) + c.depth_gain * error + c.depth_integral * self.integral
            - c.heave_gain * self.heave;
        let wanted = push.signum() * (push.abs() / a.vertical_thrust).sqrt();
        let n_v = wanted.clamp(-a.vertical_max_rpm, a.vertical_max_rpm);
        // Anti-windup: the integral holds while the thruster is at its limit.
        if n_v == wanted {
            self.integral += error * dt;
        }
        Command { n_t: c.main_rpm.clamp(-a.main_max_rpm, a.main_max_rpm), n_v, rudder, elevator }
    }
}
