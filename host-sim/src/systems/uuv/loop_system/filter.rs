//! The loop's filter: the node's joint UKF (`edgekf::filter::UnscentedKalmanFilter` on
//! `edgekf::systems::uuv::ReducedDynamics`, the same updates and the same thruster detectors)
//! in `f64` on the fixed [`STATES`], with the slots the model's effects switch on.
//!
//! A slot switched on from sample `k` keeps its neutral value and a negligible variance until
//! then (it takes no part in the model); at `k` it opens to its prior spread and gets its
//! process noise. Every sample yields the innovations of the channels it had, their variances,
//! the NIS and `ln det S` summed over the updates applied: what the engine reads.

use super::effect::{slot, CHANNELS, STATES};
use crate::residual_loop::filter::Run;
use anyhow::{anyhow, Result};
use edgekf::filter::{Innovation, MerweSigmaPoints, UkfMeasurement, UkfModel, UnscentedKalmanFilter};
use edgekf::systems::uuv::{
    open, start_vehicle, update, Command, Detectors, Drive, EstimatorSettings, ReducedDynamics, Sample,
    ThrusterMonitor, UpdateNoise, UpdateObserver, Vehicle, VEHICLE_STATES, VELOCITY,
};
use nalgebra::{SMatrix, SVector};
use std::ops::Range;

type X = SVector<f64, STATES>;

/// Standard deviation of a slot no effect uses: small enough to take no part, large enough for
/// the sigma-point factor.
const INERT_SD: f64 = 1e-6;

/// A slot switched on: its states, the first sample it acts at, and its prior spread and
/// noise density (per √s).
#[derive(Debug, Clone, PartialEq)]
pub struct Switch {
    /// The states.
    pub states: Range<usize>,
    /// First sample with the effect (0: from the start).
    pub from: usize,
    /// Prior standard deviation when it opens.
    pub sd: f64,
    /// Random-walk density, per √s.
    pub psd: f64,
}

/// What one run is made with.
#[derive(Debug, Clone)]
pub struct Plan<'a> {
    /// The vehicle (with any parameter effects applied).
    pub vehicle: Vehicle,
    /// The configuration's filter settings (vehicle-state noises, sensors, detectors, `dt`).
    pub settings: &'a EstimatorSettings,
    /// The slots switched on.
    pub switches: Vec<Switch>,
    /// States whose estimates go to [`Run::effect_states`], in this order.
    pub tracked: Vec<usize>,
}

/// The step's model: which slots act, the commands of the interval.
struct Model<'a> {
    dynamics: &'a ReducedDynamics<f64>,
    on: [bool; STATES],
    dt: f64,
    command: Command<f64>,
}

impl Model<'_> {
    /// As the node's estimator: the factors linear (bounded only to keep a wild sigma point
    /// finite), 1 and no current where their slots are off.
    fn drive(&self, x: &X) -> Drive<f64> {
        let factor = |i: usize| if self.on[i] { x[i].clamp(-2.0, 3.0) } else { 1.0 };
        let c = slot::CURRENT_N;
        Drive {
            n_t: self.command.n_t,
            n_v: self.command.n_v,
            rudder: self.command.rudder,
            elevator: self.command.elevator,
            k_t: factor(slot::HEALTH[0]),
            k_v: factor(slot::HEALTH[1]),
            current: if self.on[c] { [x[c], x[c + 1]] } else { [0.0; 2] },
        }
    }

    /// The bias on channel `channel` of [`CHANNELS`], if its slot is on.
    fn bias(&self, x: &X, channel: usize) -> f64 {
        slot::BIAS[channel].filter(|&i| self.on[i]).map_or(0.0, |i| x[i])
    }

    fn imu(&self, x: &X) -> SVector<f64, 6> {
        let mut y = self.dynamics.imu(x, &self.drive(x));
        for (i, v) in y.iter_mut().enumerate() {
            *v += self.bias(x, i);
        }
        y
    }
}

impl UkfModel<f64, STATES, 6> for Model<'_> {
    fn f(&self, x: &X) -> X {
        self.dynamics.midpoint_step(x, self.dt, |x| self.drive(x))
    }

    fn h(&self, x: &X) -> SVector<f64, 6> {
        self.imu(x)
    }
}

/// IMU, depth and heading together (the node's joint update).
impl UkfMeasurement<f64, STATES, 8> for Model<'_> {
    fn h(&self, x: &X) -> SVector<f64, 8> {
        let imu = self.imu(x);
        SVector::<f64, 8>::from([imu[0], imu[1], imu[2], imu[3], imu[4], imu[5], x[0], x[3]])
    }
}

/// The DVL, with its biases where on.
struct Dvl<'a>(&'a Model<'a>);

impl UkfMeasurement<f64, STATES, 3> for Dvl<'_> {
    fn h(&self, x: &X) -> SVector<f64, 3> {
        SVector::<f64, 3>::from([0, 1, 2].map(|i| x[VELOCITY + i] + self.0.bias(x, 8 + i)))
    }
}

/// What one sample's updates gave.
struct Record<'a> {
    run: &'a mut Run,
    k: usize,
}

impl UpdateObserver<f64> for Record<'_> {
    /// Stores an update's innovations on `channels`.
    fn seen<const K: usize>(&mut self, inn: &Innovation<f64, K>, channels: [usize; K]) {
        let log_det =
            edgekf::linalg::cholesky(&inn.s).map_or(f64::NAN, |l| 2.0 * (0..K).map(|i| l[(i, i)].ln()).sum::<f64>());
        for (i, &c) in channels.iter().enumerate() {
            self.run.innovation[c][self.k] = inn.residual[i];
            self.run.variance[c][self.k] = inn.s[(i, i)];
        }
        let add = |v: &mut f64, d: f64| *v = if v.is_finite() { *v + d } else { d };
        add(&mut self.run.nis[self.k], inn.nis);
        add(&mut self.run.log_det_s[self.k], log_det);
    }
}

/// Runs the filter of `plan` over `samples`. The outputs are `k_t`, `k_v` (1 where their slots
/// are off) and `u`.
pub fn run(plan: &Plan<'_>, samples: &[Sample<f64>]) -> Result<Run> {
    let settings = plan.settings;
    let dynamics =
        ReducedDynamics::<f64>::new(&plan.vehicle).ok_or_else(|| anyhow!("the vehicle has no valid model"))?;
    let n = samples.len();
    let first = samples.first().ok_or_else(|| anyhow!("no samples"))?;
    let nan = vec![f64::NAN; n];
    let mut run = Run {
        innovation: vec![nan.clone(); CHANNELS.len()],
        variance: vec![nan.clone(); CHANNELS.len()],
        nis: nan.clone(),
        log_det_s: nan.clone(),
        outputs: vec![nan.clone(); 3],
        effect_states: vec![nan; plan.tracked.len()],
        ..Run::default()
    };
    let dt = settings.dt;
    let (x0, sd0) = start(&dynamics, settings, first);
    let mut sd = sd0;
    let mut q = [0.0f64; STATES];
    let p = &settings.process;
    q[0] = p.depth;
    q[1..4].fill(p.attitude);
    q[VELOCITY..VELOCITY + 3].fill(p.velocity);
    q[VELOCITY + 3..VEHICLE_STATES].fill(p.rate);
    let mut on = [false; STATES];
    on[..VEHICLE_STATES].fill(true);
    for s in plan.switches.iter().filter(|s| s.from == 0) {
        for i in s.states.clone() {
            (on[i], sd[i], q[i]) = (true, s.sd, s.psd);
        }
    }
    let diag = |v: [f64; STATES]| SMatrix::<f64, STATES, STATES>::from_diagonal(&X::from(v));
    let points = MerweSigmaPoints { alpha: 0.5, beta: 2.0, kappa: 0.0 };
    let r = UpdateNoise::<f64>::new(&settings.noise);
    let var = |s: f64| s * s;
    let mut ukf = UnscentedKalmanFilter::new(points, diag(q.map(|s| s * s * dt)), r.imu, x0, diag(sd.map(var)))
        .map_err(|e| anyhow!("the loop's filter refused its start: {e:?}"))?;
    let mut monitors = [ThrusterMonitor::<f64>::new(&settings.detector); 2];
    let reopen = settings.detector.reopen;
    let mut command = first.command;
    let record_outputs = |run: &mut Run, k: usize, x: &X, on: &[bool; STATES]| {
        let factor = |i: usize| if on[i] { x[i] } else { 1.0 };
        run.outputs[0][k] = factor(slot::HEALTH[0]);
        run.outputs[1][k] = factor(slot::HEALTH[1]);
        run.outputs[2][k] = x[VELOCITY];
        for (series, &i) in run.effect_states.iter_mut().zip(&plan.tracked) {
            series[k] = x[i];
        }
    };
    record_outputs(&mut run, 0, &x0, &on);
    for (k, s) in samples.iter().enumerate().skip(1) {
        for sw in plan.switches.iter().filter(|sw| sw.from == k) {
            for i in sw.states.clone() {
                on[i] = true;
                ukf.q[(i, i)] = sw.psd * sw.psd * dt;
                open(&mut ukf, i, sw.sd);
            }
        }
        let model = Model { dynamics: &dynamics, on, dt, command };
        ukf.predict(&model);
        let factors = slot::HEALTH.map(|i| on[i].then_some(i));
        let detectors = Detectors { monitors: &mut monitors, factors, reopen };
        update(&mut ukf, (&model, &Dvl(&model)), s, &r, detectors, &mut Record { run: &mut run, k });
        record_outputs(&mut run, k, ukf.state(), &on);
        command = command.held(&s.command);
    }
    let health = ukf.health();
    if health.covariance_resets > 0 {
        return Err(anyhow!("the loop's filter diverged ({} covariance resets)", health.covariance_resets));
    }
    Ok(run)
}

/// The start from the first sample, as the node's estimator makes it; slots at their neutral
/// value (health 1, the rest 0) and inert.
fn start(dynamics: &ReducedDynamics<f64>, settings: &EstimatorSettings, s: &Sample<f64>) -> (X, [f64; STATES]) {
    let mut x = X::zeros();
    let mut sd = [INERT_SD; STATES];
    start_vehicle(dynamics, settings, s, &mut x, &mut sd);
    for i in slot::HEALTH {
        x[i] = 1.0;
    }
    (x, sd)
}
