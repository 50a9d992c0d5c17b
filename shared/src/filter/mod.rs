//! Kalman-family filters.
//!
//! The linear filters ([`GenericKalmanFilter`], [`GenericSteadyStateFilter`],
//! [`solve_riccati`]) are generic over nalgebra's dimensions: [`KalmanFilter`] and
//! [`SteadyStateFilter`] with sizes fixed at compile time on the chip, and with the `alloc`
//! feature [`DKalmanFilter`] and [`DSteadyStateFilter`] with sizes known at run time on the host,
//! one implementation for both. The unscented filter has fixed sizes only.
//!
//! The filters never panic and never return a silent NaN: every step checks the covariance
//! (finite, positive diagonal), and a broken one is replaced by the stated reset value and
//! counted in [`FilterHealth`], so a monitor can tell a healthy filter from one that keeps
//! recovering.

mod dims;
mod joint;
mod kalman;
mod low_rank;
mod sigma;
mod steady;
mod ukf;

pub use joint::{JointModel, ParameterEstimate, ParametricModel};
#[cfg(feature = "alloc")]
pub use kalman::{DKalmanFilter, DLinearModel};
pub use kalman::{
    FilterAllocator, FilterDim, FilterError, FilterHealth, GenericInnovation, GenericKalmanFilter, GenericLinearModel,
    GenericSequentialInnovation, Innovation, KalmanFilter, LinearModel, SequentialInnovation,
};
pub use low_rank::{LowRankDesign, LowRankFit, LowRankKalmanFilter};
pub use sigma::{MerweSigmaPoints, SigmaWeights, UkfError};
pub use steady::{
    solve_riccati, GenericSteadyState, GenericSteadyStateFilter, RiccatiError, SteadyState, SteadyStateFilter,
};
#[cfg(feature = "alloc")]
pub use steady::{DSteadyState, DSteadyStateFilter};
pub use ukf::{UkfMeasurement, UkfModel, UnscentedKalmanFilter};
