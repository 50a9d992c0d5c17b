//! Thruster health of an underwater vehicle (the third paper: a joint UKF of the vehicle's
//! state and its thrusters' health factors), on the chip.
//!
//! * [`Vehicle`]: the constants (REMUS 100 by default, Prestero's notation);
//! * [`ReducedDynamics`]: the estimator's 6-DOF model (Euler angles, one midpoint step);
//! * [`Layout`] and [`EstimatorSettings`]: which states the filter carries, its noises and the
//!   detector's thresholds;
//! * [`UuvEstimator`]: the filter, one sample at a time, with a [`ThrusterMonitor`] per
//!   thruster that declares it healthy, degraded or failed.
//!
//! The host's reference simulator (`edgekf_sim::systems::uuv`) is written independently
//! (quaternions, the rigid body in vector form, RK4 at a quarter of the sample interval).

mod detector;
mod dynamics;
mod estimator;
mod sample;
mod settings;
mod update;
mod vehicle;

pub use detector::{open, signatures, watch, Status, ThrusterMonitor};
pub use dynamics::{Attitude, Drive, Nu, ReducedDynamics};
pub use estimator::{Estimate, EstimatorError, Health, UuvEstimator};
pub use sample::{wrap, Command, Sample, CHANNELS};
pub use settings::{
    DetectorSettings, EstimatorSettings, InitialSpread, Layout, MeasurementNoise, ProcessNoise, VEHICLE_STATES,
    VELOCITY,
};
pub use update::{start_vehicle, update, DepthHeading, Detectors, Dvl, UpdateNoise, UpdateObserver};
pub use vehicle::{Actuators, Hydro, Vehicle};
