//! One sample's measurement updates, shared by the node's estimator and the host's residual
//! loop (which runs the same filter with extra effect states): the IMU, depth and heading in
//! one update when all are present, else each alone, then the DVL when it has a reading; the
//! IMU innovation feeds each thruster's CUSUM. Kept in one place so that what the loop tests
//! is the update the node runs.

use super::detector::{signatures, watch, ThrusterMonitor};
use super::sample::{wrap, Sample};
use super::settings::{MeasurementNoise, VELOCITY};
use crate::filter::{Innovation, UkfMeasurement, UkfModel, UnscentedKalmanFilter};
use crate::Real;
use nalgebra::{SMatrix, SVector};

/// The measurement noise covariances of the four updates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UpdateNoise<T: Real> {
    /// Specific force and rates.
    pub imu: SMatrix<T, 6, 6>,
    /// Depth and heading.
    pub depth_heading: SMatrix<T, 2, 2>,
    /// The IMU, depth and heading together.
    pub imu_depth_heading: SMatrix<T, 8, 8>,
    /// The DVL.
    pub dvl: SMatrix<T, 3, 3>,
}

impl<T: Real> UpdateNoise<T> {
    /// The covariances of `noise`'s standard deviations (each channel independent).
    ///
    /// ```
    /// use edgekf::systems::uuv::{MeasurementNoise, UpdateNoise};
    /// let noise = MeasurementNoise { acc: 0.1, gyro: 0.01, depth: 0.05, heading: 0.02, dvl: 0.01 };
    /// let r = UpdateNoise::<f64>::new(&noise);
    /// assert_eq!(r.imu_depth_heading[(7, 7)], 0.02 * 0.02);
    /// assert_eq!(r.imu[(0, 0)], r.imu_depth_heading[(0, 0)]);
    /// ```
    pub fn new(noise: &MeasurementNoise) -> Self {
        let var = |s: f64| T::of_f64(s * s);
        let n = noise;
        let imu = [n.acc, n.acc, n.acc, n.gyro, n.gyro, n.gyro].map(var);
        let all = [imu[0], imu[1], imu[2], imu[3], imu[4], imu[5], var(n.depth), var(n.heading)];
        Self {
            imu: SMatrix::<T, 6, 6>::from_diagonal(&SVector::<T, 6>::from(imu)),
            depth_heading: SMatrix::<T, 2, 2>::from_diagonal(&SVector::<T, 2>::new(var(n.depth), var(n.heading))),
            imu_depth_heading: SMatrix::<T, 8, 8>::from_diagonal(&SVector::<T, 8>::from(all)),
            dvl: SMatrix::<T, 3, 3>::identity() * var(n.dvl),
        }
    }
}

/// Depth and heading: the first and fourth states.
pub struct DepthHeading;

impl<T: Real, const N: usize> UkfMeasurement<T, N, 2> for DepthHeading {
    fn h(&self, x: &SVector<T, N>) -> SVector<T, 2> {
        SVector::<T, 2>::new(x[0], x[3])
    }
}

/// DVL bottom track: the body velocity over ground.
pub struct Dvl;

impl<T: Real, const N: usize> UkfMeasurement<T, N, 3> for Dvl {
    fn h(&self, x: &SVector<T, N>) -> SVector<T, 3> {
        x.fixed_rows::<3>(VELOCITY).into_owned()
    }
}

/// Sees every update applied, with the channels it covered (indices into the channels
/// `acc_x … gyro_z, depth, heading, dvl_u, dvl_v, dvl_w`): the loop records every innovation,
/// the node none (`()`).
pub trait UpdateObserver<T: Real> {
    /// One applied update's innovation.
    fn seen<const K: usize>(&mut self, innovation: &Innovation<T, K>, channels: [usize; K]);
}

impl<T: Real> UpdateObserver<T> for () {
    fn seen<const K: usize>(&mut self, _: &Innovation<T, K>, _: [usize; K]) {}
}

/// The thrusters' detectors: their monitors, the health factors' states, the reopening spread.
pub struct Detectors<'a, T: Real> {
    /// One CUSUM per thruster (main, vertical).
    pub monitors: &'a mut [ThrusterMonitor<T>; 2],
    /// The states of the main and vertical health factors, where carried.
    pub factors: [Option<usize>; 2],
    /// The spread a factor's variance reopens to after an alarm.
    pub reopen: T,
}

/// Applies `s`'s updates after the prediction: `model` gives the IMU (and, joined with depth
/// and heading, the 8-channel update), `dvl` the DVL's. Returns the IMU update's NIS if one was
/// applied; a refused update is counted in the filter's health and skipped.
pub fn update<T, const N: usize, M, D, O>(
    ukf: &mut UnscentedKalmanFilter<T, N, 6>,
    (model, dvl): (&M, &D),
    s: &Sample<T>,
    r: &UpdateNoise<T>,
    detectors: Detectors<'_, T>,
    observer: &mut O,
) -> Option<T>
where
    T: Real,
    M: UkfModel<T, N, 6> + UkfMeasurement<T, N, 8>,
    D: UkfMeasurement<T, N, 3>,
    O: UpdateObserver<T>,
{
    let Detectors { monitors, factors, reopen } = detectors;
    let imu = [s.acc[0], s.acc[1], s.acc[2], s.gyro[0], s.gyro[1], s.gyro[2]];
    let imu_ok = imu.iter().all(|v| v.is_finite());
    let dh_ok = s.depth.is_finite() && s.heading.is_finite();
    // The heading on the branch of the estimate, so the innovation is the short way round.
    let psi = ukf.state()[3];
    let heading = psi + wrap(s.heading - psi);
    let mut nis = None;
    if imu_ok && dh_ok {
        let y = SVector::<T, 8>::from([imu[0], imu[1], imu[2], imu[3], imu[4], imu[5], s.depth, heading]);
        let sig = signatures(|x| UkfMeasurement::<T, N, 8>::h(model, x), ukf.state(), factors);
        if let Ok(inn) = ukf.update_with(model, &y, &r.imu_depth_heading) {
            nis = Some(inn.nis);
            observer.seen(&inn, [0, 1, 2, 3, 4, 5, 6, 7]);
            watch(ukf, monitors, &inn, &sig, factors, reopen);
        }
    } else {
        if imu_ok {
            let sig = signatures(|x| UkfModel::<T, N, 6>::h(model, x), ukf.state(), factors);
            if let Ok(inn) = ukf.update(model, &SVector::<T, 6>::from(imu)) {
                nis = Some(inn.nis);
                observer.seen(&inn, [0, 1, 2, 3, 4, 5]);
                watch(ukf, monitors, &inn, &sig, factors, reopen);
            }
        }
        if dh_ok {
            let y = SVector::<T, 2>::new(s.depth, heading);
            if let Ok(inn) = ukf.update_with(&DepthHeading, &y, &r.depth_heading) {
                observer.seen(&inn, [6, 7]);
            }
        }
    }
    if let Some(d) = s.dvl {
        if let Ok(inn) = ukf.update_with(dvl, &SVector::<T, 3>::from(d), &r.dvl) {
            observer.seen(&inn, [8, 9, 10]);
        }
    }
    nis
}

/// The vehicle's ten states at the first sample and their spreads, into `x` and `sd` (the
/// other states are the caller's): depth and heading from their sensors, roll and pitch from
/// the specific force as if steady, velocity from the DVL (else the cruise speed of the main
/// thruster's command), rates from the gyro; a missing channel starts at 0 with a wide spread.
///
/// ```
/// use edgekf::systems::uuv::{start_vehicle, Command, EstimatorSettings, Layout, ReducedDynamics, Sample, Vehicle};
/// use nalgebra::SVector;
/// let settings = EstimatorSettings::new(Layout { main: true, vertical: false, biases: false, current: false }, 50.0);
/// let dynamics = ReducedDynamics::<f64>::new(&Vehicle::default()).unwrap();
/// let s = Sample { acc: [0.0, 0.0, -9.81], gyro: [0.0; 3], depth: 10.0, heading: 0.5, dvl: Some([1.5, 0.0, 0.0]),
///                  command: Command::default() };
/// let (mut x, mut sd) = (SVector::<f64, 11>::zeros(), [0.0; 11]);
/// start_vehicle(&dynamics, &settings, &s, &mut x, &mut sd);
/// assert_eq!((x[0], x[3], x[4]), (10.0, 0.5, 1.5));
/// ```
pub fn start_vehicle<T: Real, const N: usize>(
    dynamics: &super::dynamics::ReducedDynamics<T>,
    settings: &super::settings::EstimatorSettings,
    s: &Sample<T>,
    x: &mut SVector<T, N>,
    sd: &mut [f64; N],
) {
    if N < VELOCITY + 6 {
        return;
    }
    let (init, noise) = (&settings.initial, &settings.noise);
    let known = |v: T, spread: f64, wide: f64| if v.is_finite() { (v, spread) } else { (T::zero(), wide) };
    (x[0], sd[0]) = known(s.depth, noise.depth, 100.0);
    (x[3], sd[3]) = known(s.heading, noise.heading, 3.0);
    let f = s.acc.map(|v| v.as_f64());
    if f.iter().all(|v| v.is_finite()) && f[2] < 0.0 {
        x[1] = T::of_f64(libm::atan2(-f[1], -f[2]));
        x[2] = T::of_f64(libm::atan2(f[0], libm::sqrt(f[1] * f[1] + f[2] * f[2])));
    }
    sd[1] = init.attitude;
    sd[2] = init.attitude;
    match s.dvl.filter(|d| d.iter().all(|v| v.is_finite())) {
        Some(d) => {
            for i in 0..3 {
                (x[VELOCITY + i], sd[VELOCITY + i]) = (d[i], noise.dvl.max(0.05));
            }
        }
        None => {
            x[VELOCITY] = T::of_f64(dynamics.cruise_speed(s.command.n_t.as_f64()));
            sd[VELOCITY..VELOCITY + 3].fill(init.velocity);
        }
    }
    for i in 0..3 {
        (x[VELOCITY + 3 + i], sd[VELOCITY + 3 + i]) = known(s.gyro[i], init.rate, 0.5);
    }
}
