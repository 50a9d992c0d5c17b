//! The soak of the vehicle's joint UKF of state and thruster health (20 states), as the node
//! runs it: the truth is the filter's own model ([`ReducedDynamics`], one midpoint step a
//! sample) flown by the host simulator's autopilots (heading by the rudder, pitch by the
//! elevator, depth by the vertical thruster with an integral), with white forcing of the
//! filter's process-noise densities, constant sensor biases and current, and both thrusters'
//! health drifting slowly (the main one between 1 and 0.8 over 20 minutes, the vertical one
//! between 1 and 0.9 over 30); the sensors read it with the filter's noise, the DVL at 5 Hz.

use super::UuvImage;
use crate::hil::HilImage;
use super::{estimator, LAYOUT, SAMPLE_RATE_HZ, STATES};
use crate::soak::engine::{Blocks, Drift, Noise, SoakFrame, SoakRow};
use edgekf::systems::uuv::{
    wrap, Command, Drive, ReducedDynamics, Sample, Status, VELOCITY,
};
use nalgebra::SVector;

/// Its rows.
pub const SOAKS: &[SoakRow] = &[UUV];

/// The vehicle's row.
pub const UUV: SoakRow = SoakRow {
    name: "uuv",
    system: "uuv",
    image: Some(UuvImage::NAME),
    what: "vehicle joint UKF of state and thruster health (20 states, 50 Hz)",
    drift: "main thruster's health 1–0.8 over 20 min, vertical's 1–0.9 over 30 min",
    error_of: "both health factors",
    host_steps: 20_000,
    qemu_steps: 2_000,
    qemu_long_steps: 9_000,
    nis_limit: Some(1.3),
    error_limit: 0.05,
    run: uuv,
};

/// Samples per block (20 s).
const BLOCK: u32 = 1000;

/// DVL readings every this many samples (5 Hz).
const DVL_EVERY: u32 = 10;

/// The soak (see the module docs); `n` samples.
#[inline(never)]
pub fn uuv(n: u32) -> SoakFrame {
    let vehicle = super::VEHICLE;
    let (Ok(mut est), Some(dynamics)) = (estimator(), ReducedDynamics::<f32>::new(&vehicle)) else {
        return crate::soak::engine::not_started(n);
    };
    let dt = 1.0 / f64::from(SAMPLE_RATE_HZ);
    let (k_t, k_v, bias, current) = match (LAYOUT.k_t(), LAYOUT.k_v(), LAYOUT.acc_bias(), LAYOUT.current()) {
        (Some(a), Some(b), Some(c), Some(d)) => (a, b, c, d),
        _ => return crate::soak::engine::not_started(n),
    };
    let (depth, heading, rpm) = (10.0f32, core::f32::consts::FRAC_PI_4, 1500.0f32);
    let mut x = SVector::<f32, STATES>::zeros();
    x[0] = depth;
    x[3] = heading;
    x[VELOCITY] = dynamics.cruise_speed(f64::from(rpm)) as f32;
    let biases = [0.01f32, -0.005, 0.008, 2e-4, -1e-4, 3e-4];
    for (i, b) in biases.iter().enumerate() {
        put(&mut x, bias + i, *b);
    }
    put(&mut x, current, 0.1);
    put(&mut x, current + 1, -0.05);
    let process = super::ESTIMATOR.process;
    let per_step = |density: f64| (density * libm::sqrt(dt)) as f32;
    // Per step: depth, the three attitudes, the three velocities, the three rates.
    let (d, a, v, r) =
        (per_step(process.depth), per_step(process.attitude), per_step(process.velocity), per_step(process.rate));
    let sd: [f32; 10] = [d, a, a, a, v, v, v, r, r, r];
    let sensors = super::ESTIMATOR.noise;
    let (acc_sd, gyro_sd) = (sensors.acc as f32, sensors.gyro as f32);
    let (depth_sd, heading_sd, dvl_sd) = (sensors.depth as f32, sensors.heading as f32, sensors.dvl as f32);
    let a = &vehicle.actuators;
    let mut pilot = Autopilot {
        depth,
        heading,
        rpm,
        fin_max: a.fin_max as f32,
        v_thrust: a.vertical_thrust as f32,
        v_max: a.vertical_max_rpm as f32,
        net: (vehicle.buoyancy - vehicle.weight) as f32,
        dt: dt as f32,
        integral: 0.0,
    };
    let mut command = Command { n_t: rpm, n_v: 0.0, rudder: 0.0, elevator: 0.0 };
    let mut health = (Drift::new(dt), Drift::new(dt));
    let mut noise = Noise(0x50A4_0005);
    let mut blocks = Blocks::new(n, 8.0);
    for k in 0..n {
        let truth_t = 0.9 * health.0.at(k, |t| 1.0 + (0.1 / 0.9) * libm::cos(core::f64::consts::TAU * t / 1200.0));
        let truth_v = 0.95 * health.1.at(k, |t| 1.0 + (0.05 / 0.95) * libm::cos(core::f64::consts::TAU * t / 1800.0));
        put(&mut x, k_t, truth_t);
        put(&mut x, k_v, truth_v);
        let drive = |x: &SVector<f32, STATES>, c: &Command<f32>| Drive {
            n_t: c.n_t,
            n_v: c.n_v,
            rudder: c.rudder,
            elevator: c.elevator,
            k_t: get(x, k_t),
            k_v: get(x, k_v),
            current: [get(x, current), get(x, current + 1)],
        };
        // The sensors, under the commands in force since the last sample.
        let imu = dynamics.imu(&x, &drive(&x, &command));
        let mut reading = [0.0f32; 6];
        for (i, r) in reading.iter_mut().enumerate() {
            let sd = if i < 3 { acc_sd } else { gyro_sd };
            *r = imu.get(i).copied().unwrap_or(0.0) + get(&x, bias + i) + sd * noise.unit();
        }
        let dvl = (k % DVL_EVERY == 0).then(|| {
            let v: [f32; 3] = core::array::from_fn(|i| x[VELOCITY + i] + dvl_sd * noise.unit());
            v
        });
        let z = x[0] + depth_sd * noise.unit();
        let psi = wrap(x[3] + heading_sd * noise.unit());
        // The autopilots (the host simulator's, on the truth), for the interval to come.
        command = pilot.command(&x);
        let sample = Sample {
            acc: [reading[0], reading[1], reading[2]],
            gyro: [reading[3], reading[4], reading[5]],
            depth: z,
            heading: psi,
            dvl,
            command,
        };
        let e = est.step(&sample);
        let (Some(main), Some(vertical)) = (e.main, e.vertical) else {
            blocks.non_finite();
            continue;
        };
        // The first sample starts the filter: no update, no NIS.
        let nis = e.imu_nis.unwrap_or(if k == 0 { 0.0 } else { f32::NAN });
        if !(main.k.is_finite() && vertical.k.is_finite() && e.z.is_finite() && nis.is_finite()) {
            blocks.non_finite();
        }
        if main.status != Status::Healthy || vertical.status != Status::Healthy {
            blocks.out_of_bounds();
        }
        let (e_t, e_v) = (f64::from(main.k - truth_t), f64::from(vertical.k - truth_v));
        let err2 = e_t * e_t + e_v * e_v;
        let truth2 = f64::from(truth_t * truth_t) + f64::from(truth_v * truth_v);
        blocks.push(nis, err2, truth2);
        // The truth's step under the new commands, with its white forcing.
        x = dynamics.midpoint_step(&x, dt as f32, |x| drive(x, &command));
        for (i, s) in sd.iter().enumerate() {
            if let Some(v) = x.get_mut(i) {
                *v += *s * noise.unit();
            }
        }
        if (k + 1) % BLOCK == 0 {
            blocks.close();
            if let Some((_, p)) = est.filter() {
                blocks.covariance(p);
            }
        }
    }
    blocks.finish(est.health())
}

/// The host simulator's autopilots on the truth: depth by the tunnel thruster (a PI law on
/// the net buoyancy, its integral held while the thruster saturates), pitch by the elevator,
/// heading by the rudder, at a constant main-thruster speed.
struct Autopilot {
    depth: f32,
    heading: f32,
    rpm: f32,
    fin_max: f32,
    v_thrust: f32,
    v_max: f32,
    net: f32,
    dt: f32,
    integral: f32,
}

impl Autopilot {
    /// The commands for the interval to come, from the true state `x`.
    fn command(&mut self, x: &SVector<f32, STATES>) -> Command<f32> {
        let (theta, w, q, r) = (x[2], x[VELOCITY + 2], x[VELOCITY + 4], x[VELOCITY + 5]);
        let fin_max = self.fin_max;
        let fin = |d: f32| d.max(-fin_max).min(fin_max);
        let error = self.depth - x[0];
        let push = self.net + 20.0 * error + 2.0 * self.integral - 40.0 * w;
        let wanted = push.signum() * libm::sqrtf(push.abs() / self.v_thrust);
        let n_v = wanted.max(-self.v_max).min(self.v_max);
        if n_v == wanted {
            self.integral += error * self.dt;
        }
        Command { n_t: self.rpm, n_v, rudder: fin(wrap(x[3] - self.heading) + r), elevator: fin(8.0 * theta + 4.0 * q) }
    }
}

/// `x[i]`, 0 out of range (no panic path).
fn get(x: &SVector<f32, STATES>, i: usize) -> f32 {
    x.get(i).copied().unwrap_or(0.0)
}

/// Sets `x[i]` if in range.
fn put(x: &mut SVector<f32, STATES>, i: usize, v: f32) {
    if let Some(e) = x.get_mut(i) {
        *e = v;
    }
}
