//! The paper's joint UKF of the vehicle's state and its thrusters' health factors, with the
//! nuisance states a careful engineer adds, and a change detector per thruster on top.
//!
//! Per sample: predict one midpoint step through [`ReducedDynamics`] with the commands in force
//! since the last sample, then three updates, each applied only if its channels are present:
//! the IMU (specific force and rates, which see the thrust directly), depth and heading, and the
//! DVL when it has a new reading. The IMU innovation feeds each thruster's CUSUM
//! ([`ThrusterMonitor`]).

use super::detector::{Status, ThrusterMonitor};
use super::dynamics::{Attitude, Drive, ReducedDynamics};
use super::sample::{wrap, Command, Sample};
use super::settings::{EstimatorSettings, Layout, VELOCITY};
use super::update::{start_vehicle, update, Detectors, Dvl, UpdateNoise, UpdateObserver};
use super::vehicle::Vehicle;
use crate::filter::{FilterHealth, MerweSigmaPoints, UkfError, UkfMeasurement, UkfModel, UnscentedKalmanFilter};
use crate::Real;
use nalgebra::{SMatrix, SVector};

/// A health factor and its standard deviation, with the thruster's status.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Health<T> {
    /// Health factor (1 healthy, 0 dead).
    pub k: T,
    /// Its standard deviation.
    pub sd: T,
    /// What is declared.
    pub status: Status,
    /// CUSUM alarms so far.
    pub alarms: u32,
}

/// The estimate after one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate<T> {
    /// Dead-reckoned north and east position from the start, m (not a filter state).
    pub position: [T; 2],
    /// Depth, m.
    pub z: T,
    /// Roll, pitch, heading (wrapped to (−π, π]), rad.
    pub attitude: [T; 3],
    /// `[u v w p q r]`.
    pub nu: [T; 6],
    /// Main thruster, if the filter carries its health.
    pub main: Option<Health<T>>,
    /// Vertical thruster, likewise.
    pub vertical: Option<Health<T>>,
    /// Current north, east, m/s, if carried.
    pub current: Option<[T; 2]>,
    /// Accelerometer biases, m/s², if carried.
    pub acc_bias: Option<[T; 3]>,
    /// Gyro biases, rad/s, if carried.
    pub gyro_bias: Option<[T; 3]>,
    /// NIS of this sample's IMU update, if it was applied: 8 degrees of freedom when depth and
    /// heading were present too (one joint update), 6 when not.
    pub imu_nis: Option<T>,
}

/// Why an estimator cannot be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EstimatorError {
    /// The layout has a different number of states than the filter's `N`.
    StateCount {
        /// States the layout asks for.
        layout: usize,
        /// The filter's size.
        filter: usize,
    },
    /// The vehicle's constants fail [`Vehicle::check`] or its mass matrix is singular.
    Vehicle,
    /// A setting is not finite or not positive where it must be.
    Settings,
    /// The filter refused its start (sigma-point parameters, first covariance).
    Filter(UkfError),
}

/// The step's model: reduced dynamics, layout and the commands of the interval.
struct StepModel<'a, T: Real> {
    dynamics: &'a ReducedDynamics<T>,
    layout: Layout,
    dt: T,
    command: Command<T>,
}

impl<T: Real> StepModel<'_, T> {
    fn drive<const N: usize>(&self, x: &SVector<T, N>) -> Drive<T> {
        // Thrust stays linear in the factor, also below 0 and above 1: a clamp at the physical
        // range would flatten the sigma points beyond it, bias the mean and blind the detector
        // (whose signature is the derivative in k). The wide bounds only keep a wild sigma
        // point's thrust finite.
        let clamp = |k: T| k.max(T::of_f64(-2.0)).min(T::of_f64(3.0));
        let one = T::one();
        Drive {
            n_t: self.command.n_t,
            n_v: self.command.n_v,
            rudder: self.command.rudder,
            elevator: self.command.elevator,
            k_t: self.layout.k_t().map_or(one, |i| clamp(get(x, i))),
            k_v: self.layout.k_v().map_or(one, |i| clamp(get(x, i))),
            current: self.layout.current().map_or([T::zero(); 2], |i| [get(x, i), get(x, i + 1)]),
        }
    }
}

impl<T: Real, const N: usize> UkfModel<T, N, 6> for StepModel<'_, T> {
    /// Midpoint step of the vehicle states; the rest are random walks.
    fn f(&self, x: &SVector<T, N>) -> SVector<T, N> {
        self.dynamics.midpoint_step(x, self.dt, |x| self.drive(x))
    }

    /// Specific force and rates, with the biases if carried.
    fn h(&self, x: &SVector<T, N>) -> SVector<T, 6> {
        let mut y = self.dynamics.imu(x, &self.drive(x));
        if let Some(b) = self.layout.acc_bias() {
            for i in 0..6 {
                y[i] += get(x, b + i);
            }
        }
        y
    }
}

/// The IMU, depth and heading in one update (when all are present: one sigma-point pass and
/// one covariance factor fewer than two updates).
impl<T: Real, const N: usize> UkfMeasurement<T, N, 8> for StepModel<'_, T> {
    fn h(&self, x: &SVector<T, N>) -> SVector<T, 8> {
        let imu = UkfModel::<T, N, 6>::h(self, x);
        SVector::<T, 8>::from([imu[0], imu[1], imu[2], imu[3], imu[4], imu[5], x[0], x[3]])
    }
}

/// The estimator with `N` states (`N` must equal the layout's [`Layout::len`]).
///
/// ```
/// use edgekf::systems::uuv::{Command, EstimatorSettings, Layout, Sample, UuvEstimator, Vehicle};
/// let layout = Layout { main: true, vertical: false, biases: false, current: false };
/// let settings = EstimatorSettings::new(layout, 50.0);
/// let mut est = UuvEstimator::<f32, 11>::new(&Vehicle::default(), &settings).unwrap();
/// let row = Sample {
///     acc: [0.0, -0.9, -9.77], gyro: [0.0; 3], depth: 10.0, heading: 0.785, dvl: Some([1.54, 0.0, 0.0]),
///     command: Command { n_t: 1500.0, ..Default::default() },
/// };
/// let e = est.step(&row);
/// assert!((e.main.unwrap().k - 1.0).abs() < 0.2);
/// ```
pub struct UuvEstimator<T: Real, const N: usize> {
    dynamics: ReducedDynamics<T>,
    settings: EstimatorSettings,
    points: MerweSigmaPoints<T>,
    r: UpdateNoise<T>,
    ukf: Option<UnscentedKalmanFilter<T, N, 6>>,
    command: Command<T>,
    monitors: [ThrusterMonitor<T>; 2],
    position: [T; 2],
    dt: T,
}

impl<T: Real, const N: usize> UuvEstimator<T, N> {
    /// An estimator that starts at its first sample.
    pub fn new(vehicle: &Vehicle, settings: &EstimatorSettings) -> Result<Self, EstimatorError> {
        let layout = settings.layout;
        if layout.len() != N {
            return Err(EstimatorError::StateCount { layout: layout.len(), filter: N });
        }
        let dynamics = ReducedDynamics::new(vehicle).ok_or(EstimatorError::Vehicle)?;
        let p = &settings.process;
        let n = &settings.noise;
        let values = [
            settings.dt,
            p.velocity,
            p.rate,
            p.attitude,
            p.depth,
            p.health,
            p.acc_bias,
            p.gyro_bias,
            p.current,
            n.acc,
            n.gyro,
            n.depth,
            n.heading,
            n.dvl,
        ];
        if values.iter().any(|v| !(v.is_finite() && *v > 0.0)) || settings.dvl_offset.iter().any(|v| !v.is_finite()) {
            return Err(EstimatorError::Settings);
        }
        Ok(Self {
            dynamics,
            settings: *settings,
            points: MerweSigmaPoints { alpha: T::of_f64(0.5), beta: T::of_f64(2.0), kappa: T::zero() },
            r: UpdateNoise::new(n),
            ukf: None,
            command: Command { n_t: T::zero(), n_v: T::zero(), rudder: T::zero(), elevator: T::zero() },
            monitors: [ThrusterMonitor::new(&settings.detector); 2],
            position: [T::zero(); 2],
            dt: T::of_f64(settings.dt),
        })
    }

    /// The filter's repair counters (zero before the first sample).
    pub fn health(&self) -> FilterHealth {
        self.ukf.as_ref().map(|u| u.health()).unwrap_or_default()
    }

    /// CUSUM alarms of the main and vertical thrusters so far.
    pub fn alarms(&self) -> [u32; 2] {
        self.monitors.map(|m| m.alarms())
    }

    /// The filter's state and covariance, once started.
    pub fn filter(&self) -> Option<(&SVector<T, N>, &SMatrix<T, N, N>)> {
        self.ukf.as_ref().map(|u| (u.state(), u.covariance()))
    }

    /// Takes one sample: the first starts the filter from the sensors; every later one
    /// predicts with the previous sample's commands and updates with what is present. A
    /// missing (NaN) command holds the last one; a sample with nothing present is a prediction
    /// (a lost row bridged). A DVL reading has the declared offset
    /// ([`EstimatorSettings::dvl_offset`]) taken off first.
    pub fn step(&mut self, s: &Sample<T>) -> Estimate<T> {
        self.step_observed(s, &mut ())
    }

    /// [`step`](Self::step), with every update it applies shown to `observer` (its innovation
    /// and the channels it covered, as [`UpdateObserver`] numbers them): how the node's model
    /// monitor reads each channel's normalised innovation without a second filter. The first
    /// sample starts the filter and applies no update.
    pub fn step_observed<O: UpdateObserver<T>>(&mut self, s: &Sample<T>, observer: &mut O) -> Estimate<T> {
        let mut imu_nis = None;
        let [ou, ov, ow] = self.settings.dvl_offset.map(T::of_f64);
        let s = &Sample { dvl: s.dvl.map(|[u, v, w]| [u - ou, v - ov, w - ow]), ..*s };
        if self.ukf.is_none() {
            self.start(s);
        } else if let Some(nis) = self.advance(s, observer) {
            imu_nis = Some(nis);
        }
        self.command = self.command.held(&s.command);
        self.estimate(imu_nis)
    }

    /// Builds the filter at the first sample. A first sample without depth or heading starts at
    /// 0 with a wide spread; the guard's reset target is this start.
    #[inline(never)] // nor `advance`: the two frames are not summed in `step`'s
    fn start(&mut self, s: &Sample<T>) {
        let layout = self.settings.layout;
        let init = &self.settings.initial;
        let mut x = SVector::<T, N>::zeros();
        let mut sd = [0.0f64; N];
        start_vehicle(&self.dynamics, &self.settings, s, &mut x, &mut sd);
        for i in [layout.k_t(), layout.k_v()].into_iter().flatten() {
            if let (Some(xi), Some(si)) = (x.get_mut(i), sd.get_mut(i)) {
                *xi = T::one();
                *si = init.health;
            }
        }
        fill(&mut sd, layout.acc_bias(), 3, init.acc_bias);
        fill(&mut sd, layout.gyro_bias(), 3, init.gyro_bias);
        fill(&mut sd, layout.current(), 2, init.current);
        let p0 = SMatrix::<T, N, N>::from_diagonal(&SVector::<T, N>::from(sd.map(|v| T::of_f64(v * v))));
        // Settings were checked and the spreads are positive: the start cannot be refused; if it
        // were, the estimator stays unstarted and tries again at the next sample. Built in place:
        // `new` would put two copies of the filter (6.6 KB each at 20 `f32` states) on this frame,
        // which runs within the loop's stack.
        let q = process_noise(&self.settings);
        let _ = UnscentedKalmanFilter::new_in(&mut self.ukf, self.points, &q, &self.r.imu, &x, &p0);
    }

    /// Predict and update; the IMU update's NIS if it was applied.
    #[inline(never)]
    fn advance<O: UpdateObserver<T>>(&mut self, s: &Sample<T>, observer: &mut O) -> Option<T> {
        let layout = self.settings.layout;
        let model = StepModel { dynamics: &self.dynamics, layout, dt: self.dt, command: self.command };
        let ukf = self.ukf.as_mut()?;
        ukf.predict(&model);
        let factors = [layout.k_t(), layout.k_v()];
        let reopen = T::of_f64(self.settings.detector.reopen);
        let detectors = Detectors { monitors: &mut self.monitors, factors, reopen };
        let nis = update(ukf, (&model, &Dvl), s, &self.r, detectors, observer);
        // Dead reckoning on the updated velocity over ground.
        let x = ukf.state();
        let earth = Attitude::new(x[1], x[2], x[3]).to_earth() * x.fixed_rows::<3>(VELOCITY);
        self.position[0] += self.dt * earth[0];
        self.position[1] += self.dt * earth[1];
        nis
    }

    fn estimate(&mut self, imu_nis: Option<T>) -> Estimate<T> {
        let layout = self.settings.layout;
        // The state and the variances, not the whole covariance: a copy of that would be 1.6 KB
        // on the stack of every sample at 20 `f32` states.
        let (x, var) = match &self.ukf {
            Some(u) => (*u.state(), u.covariance().diagonal()),
            None => (SVector::<T, N>::repeat(T::of_f64(f64::NAN)), SVector::<T, N>::repeat(T::of_f64(f64::NAN))),
        };
        let monitors = &mut self.monitors;
        let mut health = |j: usize, i: Option<usize>| {
            i.map(|i| {
                let sd = get(&var, i).max(T::zero()).sqrt();
                let k = get(&x, i);
                let status = monitors[j].status(k, sd);
                Health { k, sd, status, alarms: monitors[j].alarms() }
            })
        };
        let main = health(0, layout.k_t());
        let vertical = health(1, layout.k_v());
        let three = |i: usize| [get(&x, i), get(&x, i + 1), get(&x, i + 2)];
        Estimate {
            position: self.position,
            z: x[0],
            attitude: [x[1], x[2], wrap(x[3])],
            nu: [x[4], x[5], x[6], x[7], x[8], x[9]],
            main,
            vertical,
            current: layout.current().map(|c| [get(&x, c), get(&x, c + 1)]),
            acc_bias: layout.acc_bias().map(three),
            gyro_bias: layout.gyro_bias().map(three),
            imu_nis,
        }
    }
}

/// The process noise `Q` (diagonal: each state's density² · dt), formed when the filter starts
/// rather than kept beside the filter's own copy (1.6 KB at 20 `f32` states).
fn process_noise<T: Real, const N: usize>(settings: &EstimatorSettings) -> SMatrix<T, N, N> {
    let layout = settings.layout;
    let p = &settings.process;
    let mut qd = [0.0f64; N];
    fill(&mut qd, Some(0), 1, p.depth);
    fill(&mut qd, Some(1), 3, p.attitude);
    fill(&mut qd, Some(VELOCITY), 3, p.velocity);
    fill(&mut qd, Some(VELOCITY + 3), 3, p.rate);
    fill(&mut qd, layout.k_t(), 1, p.health);
    fill(&mut qd, layout.k_v(), 1, p.health);
    fill(&mut qd, layout.acc_bias(), 3, p.acc_bias);
    fill(&mut qd, layout.gyro_bias(), 3, p.gyro_bias);
    fill(&mut qd, layout.current(), 2, p.current);
    let dt = settings.dt;
    SMatrix::<T, N, N>::from_diagonal(&SVector::<T, N>::from(qd.map(|s| T::of_f64(s * s * dt))))
}

/// `v[from..from + count] = value`, where `from` is given and the indices exist.
fn fill<const N: usize>(v: &mut [f64; N], from: Option<usize>, count: usize, value: f64) {
    for i in from.into_iter().flat_map(|f| f..f + count) {
        if let Some(e) = v.get_mut(i) {
            *e = value;
        }
    }
}

/// `x[i]`, or 0 for an index the layout cannot give (no panic path on the chip).
fn get<T: Real, const N: usize>(x: &SVector<T, N>, i: usize) -> T {
    x.get(i).copied().unwrap_or_else(T::zero)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_layout_of_another_size_is_refused() {
        let s = EstimatorSettings::new(Layout { main: true, vertical: true, biases: true, current: true }, 50.0);
        let e = UuvEstimator::<f64, 12>::new(&Vehicle::default(), &s).err();
        assert_eq!(e, Some(EstimatorError::StateCount { layout: 20, filter: 12 }));
    }

    #[test]
    fn a_declared_dvl_offset_is_taken_off_the_readings() {
        // Readings offset by 0.05 m/s sideways into an estimator told of it: the same estimates
        // as the readings without it (the same arithmetic up to the subtraction's rounding).
        let layout = Layout { main: true, vertical: true, biases: true, current: true };
        let clean = EstimatorSettings::new(layout, 50.0);
        let told = EstimatorSettings { dvl_offset: [0.0, 0.05, 0.0], ..clean };
        let mut a = UuvEstimator::<f64, 20>::new(&Vehicle::default(), &clean).unwrap();
        let mut b = UuvEstimator::<f64, 20>::new(&Vehicle::default(), &told).unwrap();
        let row = |k: usize, v: f64| Sample {
            acc: [0.0, -0.9, -9.77],
            gyro: [0.0; 3],
            depth: 10.0,
            heading: 0.785,
            dvl: (k % 10 == 0).then_some([1.54, v, 0.0]),
            command: Command { n_t: 1500.0, n_v: 1670.0, ..Default::default() },
        };
        for k in 0..50 {
            let (ea, eb) = (a.step(&row(k, 0.0)), b.step(&row(k, 0.05)));
            assert!((ea.nu[1] - eb.nu[1]).abs() < 1e-9 && (ea.z - eb.z).abs() < 1e-9, "sample {k}");
        }
        let bad = EstimatorSettings { dvl_offset: [f64::NAN, 0.0, 0.0], ..clean };
        assert_eq!(UuvEstimator::<f64, 20>::new(&Vehicle::default(), &bad).err(), Some(EstimatorError::Settings));
    }
}
