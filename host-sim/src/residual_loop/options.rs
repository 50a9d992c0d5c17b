//! How the loop runs: the engine's own settings ([`LoopOptions`]); a system's tuning is its
//! own data.

use super::signature::SignatureOptions;

/// How the loop runs (the engine's own settings; a system's tuning is its own data).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopOptions {
    /// What counts as a signature.
    pub signatures: SignatureOptions,
    /// At most this many effects are added.
    pub max_effects: usize,
    /// Each half of the run must gain at least this fraction of an effect's BIC cost: an
    /// effect that only helps part of the run is not a constant property of the machine.
    pub half_gain: f64,
    /// Log-likelihood per scalar measurement an effect must gain beyond its BIC cost: what a
    /// healthy baseline's own record would still gain from its best next effect (0 without
    /// a baseline). A change must be larger than what the healthy machine leaves unexplained.
    /// It is scaled by the current model's NIS per channel (at least 1): on a record whose
    /// innovations carry k times the power the model expects, a wrong effect gains about k
    /// times more.
    pub gain_floor: f64,
    /// Two locations of the same kind whose log-likelihoods differ by less than this are
    /// reported as not identifiable from each other.
    pub identifiable_margin: f64,
    /// Check at the end which declared parameters and settings the data cannot see (moving
    /// each over its range changes the log-likelihood by less than an effect must gain).
    pub screen_parameters: bool,
    /// The factor on the system's tunable process noise a healthy baseline showed: applied
    /// instead of fitted on a record that may carry the change (see
    /// [`tuning`](super::tuning)).
    pub noise_scale: Option<f64>,
    /// Print progress to standard error.
    pub progress: bool,
}

impl Default for LoopOptions {
    fn default() -> Self {
        Self {
            signatures: SignatureOptions::default(),
            max_effects: 4,
            half_gain: 0.25,
            gain_floor: 0.0,
            identifiable_margin: 2.0,
            screen_parameters: true,
            noise_scale: None,
            progress: false,
        }
    }
}
