//! Faults a scenario can inject.
//!
//! Two kinds are instructions for the *virtual accelerometer* of the hardware-in-the-loop tests
//! (they travel as the `fault_nack` and `fault_stuck` columns of the recording, and the host
//! simulation leaves `ax` untouched for them); one kind changes the physics the sensor sees.

use serde::Deserialize;

/// Tolerance when a fault's time is compared with sample times, s.
pub const TIME_TOLERANCE: f64 = 1e-9;

/// A fault, declared in TOML as `[[faults]]` with a `kind`:
///
/// ```toml
/// [[faults]]
/// kind = "nack_burst"   # the next 3 I²C transactions from t = 3 s are not acknowledged
/// t = 3.0
/// transactions = 3
///
/// [[faults]]
/// kind = "stuck"        # the data registers stop updating
/// t_start = 4.8
/// t_end = 4.85
///
/// [[faults]]
/// kind = "saturation"   # the x axis sees 30 m/s², beyond the ±2 g range: it reads clipped
/// t_start = 9.0
/// t_end = 9.02
/// accel = 30.0
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Fault {
    /// The virtual device does not acknowledge `transactions` I²C transactions, starting with the
    /// first sample at or after `t` (written to `fault_nack` at that sample).
    NackBurst {
        /// When, s.
        t: f64,
        /// How many transactions in a row fail.
        transactions: u8,
    },
    /// The virtual device's data registers freeze for samples with `t_start ≤ t < t_end`
    /// (`fault_stuck` = 1 there).
    Stuck {
        /// Start, s.
        t_start: f64,
        /// End (exclusive), s.
        t_end: f64,
    },
    /// For `t_start ≤ t < t_end` the x-axis input is replaced by `accel`, m/s² (meant beyond the
    /// range, so the reading clips as a real overload would).
    Saturation {
        /// Start, s.
        t_start: f64,
        /// End (exclusive), s.
        t_end: f64,
        /// Acceleration the x axis sees, m/s².
        accel: f64,
    },
}

impl Fault {
    /// One fault of each kind, placed at fixed fractions of a run of `duration_s` so that the
    /// filter has converged before each and recovers between them: a 3-transaction NACK burst at
    /// 25 %, registers stuck for 50 ms at 40 %, and 20 ms of 3 g on the x axis at 75 %.
    ///
    /// ```
    /// use edgekf_sim::systems::oscillator::scenario::Fault;
    /// let f = Fault::demo_set(12.0);
    /// assert_eq!(f[0], Fault::NackBurst { t: 3.0, transactions: 3 });
    /// ```
    pub fn demo_set(duration_s: f64) -> Vec<Fault> {
        let d = duration_s;
        vec![
            Fault::NackBurst { t: 0.25 * d, transactions: 3 },
            Fault::Stuck { t_start: 0.4 * d, t_end: 0.4 * d + 0.05 },
            Fault::Saturation {
                t_start: 0.75 * d,
                t_end: 0.75 * d + 0.02,
                accel: 3.0 * crate::systems::oscillator::sensor::G,
            },
        ]
    }

    /// Whether the interval fault covers the sample at time `t` (always false for a NACK burst).
    ///
    /// Times are compared with a [`TIME_TOLERANCE`] of 1 ns, so that a boundary computed as
    /// `0.4 × 12.0 = 4.800000000000001` still selects the sample at 4.8 s.
    pub fn covers(&self, t: f64) -> bool {
        match *self {
            Fault::NackBurst { .. } => false,
            Fault::Stuck { t_start, t_end } | Fault::Saturation { t_start, t_end, .. } => {
                t_start - TIME_TOLERANCE <= t && t < t_end - TIME_TOLERANCE
            }
        }
    }

    /// Checks the times are finite and ordered.
    pub fn validate(&self) -> Result<(), String> {
        match *self {
            Fault::NackBurst { t, .. } if !t.is_finite() => Err("nack_burst: t must be finite".into()),
            Fault::Stuck { t_start, t_end } | Fault::Saturation { t_start, t_end, .. }
                if !(t_start.is_finite() && t_end.is_finite() && t_start < t_end) =>
            {
                Err(format!("fault interval [{t_start}, {t_end}) must be finite with t_start < t_end"))
            }
            Fault::Saturation { accel, .. } if !accel.is_finite() => Err("saturation: accel must be finite".into()),
            _ => Ok(()),
        }
    }
}
