//! Kalman-family filters with fixed sizes.
//!
//! The filters never panic and never return a silent NaN: every step checks the covariance
//! (finite, positive diagonal), and a broken one is replaced by the stated reset value and
//! counted in [`FilterHealth`], so a monitor can tell a healthy filter from one that keeps
//! recovering.

mod joint;
mod kalman;
mod steady;
mod ukf;

pub use joint::{JointModel, ParameterEstimate, ParametricModel};
pub use kalman::{FilterError, FilterHealth, Innovation, KalmanFilter, LinearModel, SequentialInnovation};
pub use steady::{solve_riccati, RiccatiError, SteadyState, SteadyStateFilter};
pub use ukf::{MerweSigmaPoints, SigmaWeights, UkfError, UkfModel, UnscentedKalmanFilter};
