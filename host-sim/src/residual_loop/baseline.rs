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

/// Blocks a record is cut into for a level's standard error (batch means): enough for a
/// usable spread, few enough that each block spans many periods of what it measures.
pub const BLOCKS: usize = 10;

/// Student's t at 97.5 % with [`BLOCKS`] − 1 = 9 degrees of freedom: batch means over ten
/// blocks give their standard error from nine, so a 95 % interval is ±2.262 of them.
const T_95: f64 = 2.262;

/// The standard error of a whole record's mean from its blocks' means (batch means): their
/// spread over √K. NaN with fewer than two finite blocks.
///
/// ```
/// use edgekf_sim::residual_loop::baseline::batch_std_error;
/// // Blocks 1, 2, 3, 4: sample standard deviation 1.291, over √4.
/// assert!((batch_std_error(&[1.0, 2.0, 3.0, 4.0]) - 1.2910 / 2.0).abs() < 1e-4);
/// assert!(batch_std_error(&[1.0]).is_nan());
/// ```
pub fn batch_std_error(blocks: &[f64]) -> f64 {
    let finite: Vec<f64> = blocks.iter().copied().filter(|v| v.is_finite()).collect();
    let k = finite.len();
    if k < 2 {
        return f64::NAN;
    }
    let mean = finite.iter().sum::<f64>() / k as f64;
    let var = finite.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (k - 1) as f64;
    (var / k as f64).sqrt()
}

/// The ranges of `n` samples' [`BLOCKS`] contiguous blocks (the last takes the remainder);
/// fewer, down to none, when there are fewer samples than blocks.
///
/// ```
/// use edgekf_sim::residual_loop::baseline::blocks;
/// let b = blocks(25);
/// assert_eq!((b.len(), b[0].clone(), b[9].clone()), (10, 0..2, 18..25));
/// assert!(blocks(3).is_empty());
/// ```
pub fn blocks(n: usize) -> Vec<std::ops::Range<usize>> {
    let size = n / BLOCKS;
    if size == 0 {
        return Vec::new();
    }
    (0..BLOCKS).map(|b| b * size..if b + 1 == BLOCKS { n } else { (b + 1) * size }).collect()
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
    /// The value's standard error, from the record's own blocks ([`batch_std_error`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub std_error: Option<f64>,
    /// The baseline value's, from the baseline record's blocks (absent from baselines learned
    /// before they were kept).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub baseline_std_error: Option<f64>,
    /// 95 % interval of the ratio, from both standard errors.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interval: Option<[f64; 2]>,
    /// Whether the interval leaves 1 out: a change beyond what the two records' own spread
    /// explains. `false` is the finding "no change beyond noise".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beyond_noise: Option<bool>,
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
            std_error: None,
            baseline_std_error: None,
            interval: None,
            beyond_noise: None,
        }
    }

    /// With the standard errors of the value and of the baseline's (either may be unknown:
    /// NaN or `None`, the baseline's then counted as exact): the ratio's 95 % interval, on the
    /// log scale (`r·e^{±t·√((σ/v)² + (σ_b/b)²)}`, which stays positive), and whether it
    /// leaves 1 out.
    ///
    /// ```
    /// use edgekf_sim::residual_loop::baseline::Comparison;
    /// // ×5 with 10 % and 5 % standard errors: the interval is ×3.88 to ×6.44.
    /// let c = Comparison::new("unbalance", "disk 6", None, "kg m", 5.0, 1.0).with_errors(Some(0.5), Some(0.05));
    /// let [lo, hi] = c.interval.unwrap();
    /// assert!((lo - 3.883).abs() < 1e-3 && (hi - 6.439).abs() < 1e-3 && c.beyond_noise == Some(true));
    /// // ×1.2 with a 20 % standard error: no change beyond noise.
    /// let same = Comparison::new("order_level", "n1_ay", Some(1), "m/s^2", 1.2, 1.0).with_errors(Some(0.24), None);
    /// assert_eq!(same.beyond_noise, Some(false));
    /// ```
    pub fn with_errors(mut self, std_error: Option<f64>, baseline_std_error: Option<f64>) -> Self {
        let known = |v: Option<f64>| v.filter(|s| s.is_finite() && *s >= 0.0);
        self.std_error = known(std_error);
        self.baseline_std_error = known(baseline_std_error);
        let (v, b, r) = (self.value, self.baseline_value, self.ratio_to_baseline);
        if let (Some(se), true) = (self.std_error, v > 0.0 && b > 0.0 && r.is_finite()) {
            let rel = ((se / v).powi(2) + (self.baseline_std_error.unwrap_or(0.0) / b).powi(2)).sqrt();
            let interval = [r * (-T_95 * rel).exp(), r * (T_95 * rel).exp()];
            self.beyond_noise = Some(!(interval[0]..=interval[1]).contains(&1.0));
            self.interval = Some(interval);
        }
        self
    }

    /// `disk 6: unbalance 2.50e-4 kg m, ×5.00 the baseline's`.
    pub fn describe(&self) -> String {
        let what = match self.order {
            Some(o) => format!("{o}x level"),
            None => self.kind.clone(),
        };
        format!(
            "{}: {what} {:.3e} {}, ×{:.2} the baseline's ({:.3e}){}",
            self.location,
            self.value,
            self.unit,
            self.ratio_to_baseline,
            self.baseline_value,
            self.spread()
        )
    }

    /// `; 95 %: ×3.88–×6.44` after a ratio, with `, no change beyond noise` where the interval
    /// holds 1; empty without an interval.
    pub fn spread(&self) -> String {
        match (self.interval, self.beyond_noise) {
            (Some([lo, hi]), Some(beyond)) => {
                let noise = if beyond { "" } else { ", no change beyond noise" };
                format!("; 95 %: ×{lo:.2}–×{hi:.2}{noise}")
            }
            _ => String::new(),
        }
    }
}
