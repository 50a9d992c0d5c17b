//! The vocabulary of a healthy baseline, the same for every system: where a baseline came
//! from ([`BaselineSource`]) and how a record compares with it ([`Comparison`], the report's
//! `baseline_comparison`). What a baseline holds is the system's own (its noise levels,
//! resonances, synchronous levels…); a baseline belongs to one operating condition.

use serde::{Deserialize, Serialize};

/// Where a baseline was learned, so that a report can say which baseline served it.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BaselineSource {
    /// The healthy recording.
    pub data: String,
    /// SHA-256 of its bytes, hex.
    pub data_sha256: String,
    /// The configuration it was learned with.
    pub config: String,
    /// The command line.
    pub command: String,
    /// edgekf's version.
    pub version: String,
}

/// One level of the record under diagnosis beside the baseline's (`baseline_comparison` in
/// `report.json`): `kind` is `unbalance` (kg·m, per disk, from the filter's unbalance
/// estimate) or `order_level` (a synchronous order's amplitude on a channel).
///
/// ```
/// use edgekf_sim::residual_loop::baseline::Comparison;
/// let c = Comparison::new("unbalance", "disk 6", None, "kg m", 2.5e-4, 5e-5);
/// assert!((c.ratio_to_baseline - 5.0).abs() < 1e-12);
/// assert!(Comparison::new("order_level", "n1_ay", Some(2), "m/s^2", 0.1, 0.0).ratio_to_baseline.is_infinite());
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    /// `unbalance` or `order_level`.
    pub kind: String,
    /// `disk <node>` or a channel.
    pub location: String,
    /// The order of the running speed (`order_level`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<u32>,
    /// Unit of the values.
    pub unit: String,
    /// On the record under diagnosis.
    pub value: f64,
    /// On the baseline's record.
    pub baseline_value: f64,
    /// `value / baseline_value`.
    pub ratio_to_baseline: f64,
}

impl Comparison {
    /// `value` against `baseline_value`.
    pub fn new(kind: &str, location: &str, order: Option<u32>, unit: &str, value: f64, baseline_value: f64) -> Self {
        Self {
            kind: kind.into(),
            location: location.into(),
            order,
            unit: unit.into(),
            value,
            baseline_value,
            ratio_to_baseline: value / baseline_value,
        }
    }

    /// `disk 6: unbalance 2.50e-4 kg m, ×5.00 the baseline's`.
    pub fn describe(&self) -> String {
        let what = match self.order {
            Some(o) => format!("{o}x level"),
            None => self.kind.clone(),
        };
        format!(
            "{}: {what} {:.3e} {}, ×{:.2} the baseline's ({:.3e})",
            self.location, self.value, self.unit, self.ratio_to_baseline, self.baseline_value
        )
    }
}
