//! A scenario flown closed loop by the reference vehicle, sampled by its sensors, as a data
//! file: the columns of the issue, ground truth in `truth_` columns.
//!
//! Each row holds the sensors at `t` and the commands the autopilots issued from them, which are
//! in force from `t` to the next row; the sensors at `t` felt the previous row's commands.

use super::autopilot::Autopilot;
use super::config::UuvConfig;
use super::error::UuvError;
use super::reference::{at, Forcing, ReferenceVehicle};
use super::scenario::Scenario;
use super::sea::Current;
use super::sensors::{wrap, Sensed, Sensors};
use edgekf::systems::uuv::{Command, ReducedDynamics};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The measured channels, in file order.
pub const MEASURED: [&str; 15] = edgekf::systems::uuv::CHANNELS;

/// The truth channels, in file order.
pub const TRUTH: [&str; 22] = [
    "truth_k_t",
    "truth_k_v",
    "truth_x",
    "truth_y",
    "truth_z",
    "truth_phi",
    "truth_theta",
    "truth_psi",
    "truth_u",
    "truth_v",
    "truth_w",
    "truth_p",
    "truth_q",
    "truth_r",
    "truth_current_n",
    "truth_current_e",
    "truth_acc_bias_x",
    "truth_acc_bias_y",
    "truth_acc_bias_z",
    "truth_gyro_bias_x",
    "truth_gyro_bias_y",
    "truth_gyro_bias_z",
];

/// What to simulate: the health timeline, its length and the noise's seed.
pub type SimOptions = crate::systems::common::SimOptions<Scenario>;

/// A simulated recording: time and the [`MEASURED`] then [`TRUTH`] columns.
#[derive(Debug, Clone, PartialEq)]
pub struct UuvRecording {
    /// Sample times from 0, s.
    pub t: Vec<f64>,
    /// One column per name of [`MEASURED`] and [`TRUTH`], in that order; NaN is missing
    /// (the DVL between its readings).
    pub columns: Vec<Vec<f64>>,
}

impl UuvRecording {
    /// Every column's name, in order.
    pub fn names() -> Vec<&'static str> {
        MEASURED.iter().chain(TRUTH.iter()).copied().collect()
    }

    /// The column called `name`.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        crate::systems::common::column_of(&Self::names(), &self.columns, name)
    }

    /// As a data file in memory, as `edgekf uuv estimate` would read it back.
    pub fn to_data_file(&self) -> crate::io::data::DataFile {
        crate::systems::common::data_file(&Self::names(), &self.t, &self.columns)
    }

    /// The CSV text, DVL cells empty between readings.
    pub fn to_csv(&self, path: &std::path::Path) -> Result<String, crate::io::data::DataError> {
        let cols: Vec<&[f64]> = self.columns.iter().map(|c| c.as_slice()).collect();
        crate::io::data::to_csv_string_sparse(path, &Self::names(), &self.t, &cols)
    }
}

/// Flies `options.scenario` for `options.duration` seconds after the configured preroll, with
/// progress to `progress` every simulated minute.
///
/// ```
/// use edgekf_sim::systems::uuv::{simulate, Scenario, SimOptions, UuvConfig};
/// let rec = simulate(&UuvConfig::default(), &SimOptions { scenario: Scenario::Healthy, duration: 2.0, seed: 1 }, &mut |_| {})?;
/// assert_eq!(rec.t.len(), 100);
/// let u = rec.column("truth_u").unwrap();
/// assert!(u.iter().all(|u| (1.2..1.9).contains(u))); // over ground: 1.54 m/s through the water plus the current
/// let dvl = rec.column("dvl_u").unwrap();
/// assert!(dvl[0].is_finite() && dvl[1].is_nan() && dvl[10].is_finite()); // 5 Hz in 50 Hz rows
/// # Ok::<(), edgekf_sim::systems::uuv::UuvError>(())
/// ```
pub fn simulate(
    config: &UuvConfig,
    options: &SimOptions,
    progress: &mut dyn FnMut(f64),
) -> Result<UuvRecording, UuvError> {
    config.validate()?;
    if !(options.duration.is_finite() && options.duration > 0.0) {
        return Err(UuvError::Options(format!("duration = {} must be positive", options.duration)));
    }
    let vehicle = &config.vehicle;
    let reference =
        ReferenceVehicle::new(vehicle).ok_or_else(|| UuvError::Config("[vehicle]: singular mass matrix".into()))?;
    let rate = config.sensors.rate;
    let dt = 1.0 / rate;
    let h = config.integrator.step;
    let substeps = (dt / h).round() as usize;
    let mut sea_rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut sensor_rng = ChaCha8Rng::seed_from_u64(options.seed ^ 0x5e45_0125);
    let current = Current::draw(&config.current, &mut sea_rng);
    let mut sensors = Sensors::draw(&config.sensors, &mut sensor_rng);
    let mut autopilot = Autopilot::new(&config.autopilot);
    let ap = &config.autopilot;
    let cruise = ReducedDynamics::<f64>::new(vehicle).map_or(1.5, |d| d.cruise_speed(ap.main_rpm));
    let mut x = ReferenceVehicle::level(ap.depth, ap.heading, cruise);
    let preroll = (ap.preroll * rate).round() as i64;
    let rows = (options.duration * rate).round() as i64;
    let names = UuvRecording::names().len();
    let mut rec =
        UuvRecording { t: Vec::with_capacity(rows as usize), columns: vec![Vec::with_capacity(rows as usize); names] };
    let mut command = Command { n_t: ap.main_rpm, ..Command::default() };
    let health = |t: f64| if t < 0.0 { (1.0, 1.0) } else { options.scenario.health(t) };
    let forcing = |t: f64, c: &Command<f64>| {
        let (k_t, k_v) = health(t);
        Forcing {
            n_t: c.n_t,
            n_v: c.n_v,
            rudder: c.rudder,
            elevator: c.elevator,
            k_t,
            k_v,
            current: current.at(t),
            current_rate: current.rate(t),
        }
    };
    let mut next_report = 60.0;
    for k in -preroll..rows {
        let t = k as f64 * dt;
        let f = forcing(t, &command);
        let [phi, theta, psi] = ReferenceVehicle::euler(&x);
        let sf = reference.specific_force(&x, &f);
        let nu: [f64; 6] = std::array::from_fn(|i| x[at::VELOCITY + i]);
        let sensed = Sensed { specific_force: [sf.x, sf.y, sf.z], nu, depth: x[2], heading: psi };
        let (acc_bias, gyro_bias) = sensors.biases();
        let reading = sensors.read(&sensed, &mut sensor_rng);
        command = autopilot.command(&reading, theta, vehicle, dt);
        if k >= 0 {
            let dvl = reading.dvl.unwrap_or([f64::NAN; 3]);
            let row = [
                reading.acc[0],
                reading.acc[1],
                reading.acc[2],
                reading.gyro[0],
                reading.gyro[1],
                reading.gyro[2],
                reading.depth,
                reading.heading,
                dvl[0],
                dvl[1],
                dvl[2],
                command.n_t,
                command.n_v,
                command.rudder,
                command.elevator,
                f.k_t,
                f.k_v,
                x[0],
                x[1],
                x[2],
                phi,
                theta,
                wrap(psi),
                nu[0],
                nu[1],
                nu[2],
                nu[3],
                nu[4],
                nu[5],
                f.current[0],
                f.current[1],
                acc_bias[0],
                acc_bias[1],
                acc_bias[2],
                gyro_bias[0],
                gyro_bias[1],
                gyro_bias[2],
            ];
            rec.t.push(t);
            for (col, v) in rec.columns.iter_mut().zip(row) {
                col.push(v);
            }
            if t >= next_report {
                progress(t);
                next_report += 60.0;
            }
        }
        for j in 0..substeps {
            let ts = t + j as f64 * h;
            x = reference.rk4(&x, &forcing(ts, &command), h);
        }
        if x.iter().any(|v| !v.is_finite()) {
            return Err(UuvError::Diverged { t: t + dt, reason: "the vehicle's state is not finite".into() });
        }
    }
    Ok(rec)
}
