//! Faults a scenario can inject.
//!
//! Six kinds are instructions for the *virtual accelerometer* of the hardware-in-the-loop tests
//! (they travel as the `fault_nack`, `fault_timeout`, `fault_garbage`, `fault_stuck`,
//! `fault_drop` and `fault_reset` columns of the recording, and the host simulation leaves `ax`
//! untouched for them); two change what the x axis reads: a saturation (the physics the sensor
//! sees) and an offset that starts mid-run (a knock that shifts the sensor's zero, the effect
//! the round trip of `cargo xtask roundtrip oscillator` finds and carries back to the node).

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
/// kind = "timeout"      # the next 2 I²C transactions from t = 3.5 s time out
/// t = 3.5
/// transactions = 2
///
/// [[faults]]
/// kind = "garbage"      # the next 5 transactions from t = 4 s read back 0xFF (wrong IDs)
/// t = 4.0
/// transactions = 5
///
/// [[faults]]
/// kind = "dropout"      # the part produces no samples for 30 ms
/// t_start = 5.0
/// t_end = 5.03
///
/// [[faults]]
/// kind = "reset"        # the part resets to its defaults at t = 6 s
/// t = 6.0
///
/// [[faults]]
/// kind = "saturation"   # the x axis sees 30 m/s², beyond the ±2 g range: it reads clipped
/// t_start = 9.0
/// t_end = 9.02
/// accel = 30.0
///
/// [[faults]]
/// kind = "offset"       # the x axis reads 0.05 m/s² more from t = 4 s to the end
/// t = 4.0
/// accel = 0.05
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
    /// The virtual device's bus times out on `transactions` I²C transactions, starting with
    /// the first sample at or after `t` (written to `fault_timeout` at that sample).
    Timeout {
        /// When, s.
        t: f64,
        /// How many transactions in a row time out.
        transactions: u8,
    },
    /// The virtual device answers `transactions` I²C transactions with garbage (every byte
    /// read `0xFF`, the ID registers included; writes lost), starting with the first sample at
    /// or after `t` (written to `fault_garbage` at that sample).
    Garbage {
        /// When, s.
        t: f64,
        /// How many transactions in a row read garbage.
        transactions: u8,
    },
    /// The virtual device produces no samples for `t_start ≤ t < t_end` (`fault_drop` = 1
    /// there): nothing enters its FIFO.
    Dropout {
        /// Start, s.
        t_start: f64,
        /// End (exclusive), s.
        t_end: f64,
    },
    /// The virtual device resets at the first sample at or after `t` (`fault_reset` = 1
    /// there): its registers go back to their defaults (standby), its FIFO is cleared, and it
    /// produces nothing until the node reconfigures it.
    Reset {
        /// When, s.
        t: f64,
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
    /// From the first sample at or after `t` to the end of the run, the x axis reads `accel`
    /// more (added to the acceleration it sees, so it clips as the part's own offset would):
    /// a shifted zero, which the scenario's `[sensor] bias_m_s2` holds from the start.
    Offset {
        /// When, s.
        t: f64,
        /// The offset, m/s².
        accel: f64,
    },
}

impl Fault {
    /// One fault of each kind, placed at fixed fractions of a run of `duration_s` so that the
    /// filter has converged before each and recovers between them: a 3-transaction NACK burst at
    /// 25 %, 2 timeouts at 30 %, 3 garbage reads at 35 %, registers stuck for 50 ms at 40 %, no
    /// samples for 20 ms at 50 %, a reset at 60 %, and 20 ms of 3 g on the x axis at 75 %.
    ///
    /// ```
    /// use edgekf_sim::systems::oscillator::scenario::Fault;
    /// let f = Fault::demo_set(12.0);
    /// assert_eq!(f[0], Fault::NackBurst { t: 3.0, transactions: 3 });
    /// assert_eq!(f.len(), 7);
    /// ```
    pub fn demo_set(duration_s: f64) -> Vec<Fault> {
        let d = duration_s;
        vec![
            Fault::NackBurst { t: 0.25 * d, transactions: 3 },
            Fault::Timeout { t: 0.3 * d, transactions: 2 },
            Fault::Garbage { t: 0.35 * d, transactions: 3 },
            Fault::Stuck { t_start: 0.4 * d, t_end: 0.4 * d + 0.05 },
            Fault::Dropout { t_start: 0.5 * d, t_end: 0.5 * d + 0.02 },
            Fault::Reset { t: 0.6 * d },
            Fault::Saturation {
                t_start: 0.75 * d,
                t_end: 0.75 * d + 0.02,
                accel: 3.0 * crate::systems::oscillator::sensor::G,
            },
        ]
    }

    /// Whether the interval fault covers the sample at time `t` (always false for the faults
    /// at an instant: bus bursts and resets).
    ///
    /// Times are compared with a [`TIME_TOLERANCE`] of 1 ns, so that a boundary computed as
    /// `0.4 × 12.0 = 4.800000000000001` still selects the sample at 4.8 s.
    pub fn covers(&self, t: f64) -> bool {
        match *self {
            Fault::NackBurst { .. }
            | Fault::Timeout { .. }
            | Fault::Garbage { .. }
            | Fault::Reset { .. }
            | Fault::Offset { .. } => false,
            Fault::Stuck { t_start, t_end }
            | Fault::Dropout { t_start, t_end }
            | Fault::Saturation { t_start, t_end, .. } => t_start - TIME_TOLERANCE <= t && t < t_end - TIME_TOLERANCE,
        }
    }

    /// The fault's `kind` as TOML spells it.
    pub fn kind(&self) -> &'static str {
        match self {
            Fault::NackBurst { .. } => "nack_burst",
            Fault::Timeout { .. } => "timeout",
            Fault::Garbage { .. } => "garbage",
            Fault::Dropout { .. } => "dropout",
            Fault::Reset { .. } => "reset",
            Fault::Stuck { .. } => "stuck",
            Fault::Saturation { .. } => "saturation",
            Fault::Offset { .. } => "offset",
        }
    }

    /// The first sample at or after the instant fault's time `t` among sample times `times`
    /// (`None` for interval faults, or past the end).
    pub fn first_sample(&self, times: &[f64]) -> Option<usize> {
        match *self {
            Fault::NackBurst { t, .. }
            | Fault::Timeout { t, .. }
            | Fault::Garbage { t, .. }
            | Fault::Reset { t }
            | Fault::Offset { t, .. } => times.iter().position(|&tk| tk >= t - TIME_TOLERANCE),
            _ => None,
        }
    }

    /// Checks the times are finite and ordered.
    pub fn validate(&self) -> Result<(), String> {
        match *self {
            Fault::NackBurst { t, .. }
            | Fault::Timeout { t, .. }
            | Fault::Garbage { t, .. }
            | Fault::Reset { t }
            | Fault::Offset { t, .. }
                if !t.is_finite() =>
            {
                Err(format!("{}: t must be finite", self.kind()))
            }
            Fault::Stuck { t_start, t_end }
            | Fault::Dropout { t_start, t_end }
            | Fault::Saturation { t_start, t_end, .. }
                if !(t_start.is_finite() && t_end.is_finite() && t_start < t_end) =>
            {
                Err(format!("fault interval [{t_start}, {t_end}) must be finite with t_start < t_end"))
            }
            Fault::Saturation { accel, .. } if !accel.is_finite() => Err("saturation: accel must be finite".into()),
            Fault::Offset { accel, .. } if !accel.is_finite() => Err("offset: accel must be finite".into()),
            _ => Ok(()),
        }
    }
}
