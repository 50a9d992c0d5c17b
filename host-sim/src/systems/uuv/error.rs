//! Why a vehicle configuration, option or run was refused.

/// An error of the vehicle's simulator or estimator: the systems' common
/// [`SimError`](crate::systems::common::SimError) (its `Data` variant is the crank's; the vehicle's
/// code does not return it).
pub type UuvError = crate::systems::common::SimError;
