//! What `edgekf <system> estimate --json` prints: one JSON object summing up the run, built
//! the same way for every system so that a script reads every estimator alike.
//!
//! * [`Stats`]: mean, RMS, extremes and last value of a column's finite samples;
//! * [`Quantity`]: an estimated quantity's [`Stats`] with its unit and its error against truth;
//! * [`EstimateSummary`]: the object (`system`, `data`, `config`, `samples`, `duration_s`,
//!   `quantities`, `details`, `out`, `plot`);
//! * [`Prose`]: where the text for people goes (stdout, or stderr when stdout is the JSON).

use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Display;
use std::path::{Path, PathBuf};

/// Statistics of a column's finite samples (NaN marks a missing one and is left out).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stats {
    /// Finite samples counted.
    pub count: usize,
    /// Their mean.
    pub mean: f64,
    /// Their root mean square.
    pub rms: f64,
    /// The smallest.
    pub min: f64,
    /// The largest.
    pub max: f64,
    /// The last one: the estimate at the end of the run, where that is what a user wants.
    #[serde(rename = "final", skip_serializing_if = "Option::is_none")]
    pub last: Option<f64>,
}

impl Stats {
    /// The statistics of `values`' finite samples; `None` when there is none.
    ///
    /// ```
    /// use edgekf_sim::report::summary::Stats;
    /// let s = Stats::of(&[1.0, f64::NAN, -3.0, 2.0]).unwrap();
    /// assert_eq!((s.count, s.mean, s.min, s.max, s.last), (3, 0.0, -3.0, 2.0, Some(2.0)));
    /// assert!((s.rms - (14.0f64 / 3.0).sqrt()).abs() < 1e-12);
    /// assert!(Stats::of(&[f64::NAN]).is_none());
    /// ```
    pub fn of(values: &[f64]) -> Option<Stats> {
        let finite = values.iter().copied().filter(|v| v.is_finite());
        let (mut count, mut sum, mut square) = (0usize, 0.0, 0.0);
        let (mut min, mut max, mut last) = (f64::INFINITY, f64::NEG_INFINITY, f64::NAN);
        for v in finite {
            count += 1;
            sum += v;
            square += v * v;
            min = min.min(v);
            max = max.max(v);
            last = v;
        }
        (count > 0).then(|| Stats {
            count,
            mean: sum / count as f64,
            rms: (square / count as f64).sqrt(),
            min,
            max,
            last: Some(last),
        })
    }

    /// The statistics of `estimate − truth` where both are finite.
    pub fn of_error(estimate: &[f64], truth: &[f64]) -> Option<Stats> {
        let error: Vec<f64> = estimate.iter().zip(truth).map(|(e, t)| e - t).collect();
        Stats::of(&error)
    }

    /// The largest magnitude, `max(|min|, |max|)`: a vibration's peak.
    pub fn peak(&self) -> f64 {
        self.min.abs().max(self.max.abs())
    }
}

/// One estimated quantity: its unit, its [`Stats`] and its error against truth (`null` when
/// the data have no truth for it: a real recording).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Quantity {
    /// SI unit (`1` for a factor).
    pub unit: &'static str,
    /// The statistics, flattened into the quantity's object.
    #[serde(flatten)]
    pub stats: Stats,
    /// Error figures against truth, by name (`rms`, `mean`, … as the command's text gives them).
    pub error: Option<BTreeMap<String, f64>>,
}

impl Quantity {
    /// `values`' statistics in `unit`; `None` when no sample is finite (nothing was estimated).
    pub fn of(unit: &'static str, values: &[f64]) -> Option<Quantity> {
        Stats::of(values).map(|stats| Quantity { unit, stats, error: None })
    }

    /// Without a `final` value, for a quantity whose last sample means nothing in particular
    /// (a vibration's last swing).
    pub fn without_final(mut self) -> Quantity {
        self.stats.last = None;
        self
    }

    /// Adds the error figure `name` (a finite `value` only: JSON has no NaN).
    pub fn with_error(mut self, name: &str, value: f64) -> Quantity {
        if value.is_finite() {
            self.error.get_or_insert_with(BTreeMap::new).insert(name.to_owned(), value);
        }
        self
    }

    /// Adds `rms`, `mean` (the bias) and `max_abs` of `estimate − truth` where `truth` is given
    /// and has finite samples where `estimate` has.
    pub fn against(self, estimate: &[f64], truth: Option<&[f64]>) -> Quantity {
        match truth.and_then(|t| Stats::of_error(estimate, t)) {
            Some(e) => self.with_error("rms", e.rms).with_error("mean", e.mean).with_error("max_abs", e.peak()),
            None => self,
        }
    }
}

/// A column of truth only if it has a finite sample: a `truth_` column left empty (a
/// recording's header copied from a simulated one) is no truth.
pub fn truth(column: Option<&[f64]>) -> Option<&[f64]> {
    column.filter(|c| c.iter().any(|v| v.is_finite()))
}

/// The JSON object of `edgekf <system> estimate --json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EstimateSummary {
    /// The system's name as on the command line.
    pub system: &'static str,
    /// The recording.
    pub data: PathBuf,
    /// The configuration file (`null`: the built-in one).
    pub config: Option<PathBuf>,
    /// Rows of the recording the estimator read.
    pub samples: usize,
    /// Time the recording spans, s: last − first `t` plus one mean sample interval, so that
    /// 4 000 rows at 100 Hz are 40 s.
    pub duration_s: f64,
    /// Whether the data carry truth (`truth_` columns with values).
    pub truth: bool,
    /// Per estimated quantity (named as in the estimate file): unit, statistics, error.
    pub quantities: BTreeMap<String, Quantity>,
    /// What else the command reports about the run (method, filter health, …), by name.
    pub details: BTreeMap<String, serde_json::Value>,
    /// The estimate file written (`null`: none asked for).
    pub out: Option<PathBuf>,
    /// The SVG written by `--plot` (`null`: none asked for).
    pub plot: Option<PathBuf>,
}

impl EstimateSummary {
    /// An empty summary of `system` on `data` (whose times are `t`) with `config`.
    pub fn new(system: &'static str, data: &Path, config: Option<&Path>, t: &[f64]) -> EstimateSummary {
        let duration_s = match (t.first(), t.last()) {
            (Some(a), Some(b)) if t.len() > 1 => (b - a) * t.len() as f64 / (t.len() - 1) as f64,
            _ => 0.0,
        };
        EstimateSummary {
            system,
            data: data.to_path_buf(),
            config: config.map(Path::to_path_buf),
            samples: t.len(),
            duration_s,
            truth: false,
            quantities: BTreeMap::new(),
            details: BTreeMap::new(),
            out: None,
            plot: None,
        }
    }

    /// Adds `quantity` as `name` if there is one (a quantity with no finite sample is left out).
    pub fn quantity(&mut self, name: impl Into<String>, quantity: Option<Quantity>) {
        if let Some(q) = quantity {
            self.truth |= q.error.is_some();
            self.quantities.insert(name.into(), q);
        }
    }

    /// Adds the detail `name`.
    pub fn detail(&mut self, name: &str, value: impl Serialize) {
        self.details.insert(name.to_owned(), serde_json::to_value(value).unwrap_or(serde_json::Value::Null));
    }

    /// Prints the object on stdout, alone (pretty-printed: one object, however many lines).
    pub fn print(&self) -> anyhow::Result<()> {
        use std::io::Write as _;
        let text = serde_json::to_string_pretty(self)?;
        let mut stdout = std::io::stdout().lock();
        writeln!(stdout, "{text}")?;
        stdout.flush()?;
        Ok(())
    }
}

/// Where an estimate command's text for people goes: stdout as always, or stderr under
/// `--json`, where stdout must carry the JSON object and nothing else.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Prose {
    /// Whether stdout is reserved for the JSON object.
    pub json: bool,
}

impl Prose {
    /// Prints `line` (a line break added) where the text goes.
    pub fn say(&self, line: impl Display) {
        if self.json {
            eprintln!("{line}");
        } else {
            println!("{line}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_object_has_the_issues_keys_and_no_nan() {
        let t = [0.0, 0.5, 1.0, 1.5];
        let mut s = EstimateSummary::new("uuv", Path::new("d.csv"), None, &t);
        let est = [1.0, 0.9, f64::NAN, 0.8];
        s.quantity("k_t", Quantity::of("1", &est).map(|q| q.against(&est, truth(Some(&[1.0, 1.0, 1.0, 1.0])))));
        s.quantity("k_v", Quantity::of("1", &[f64::NAN; 4]));
        s.quantity("u", Quantity::of("m/s", &est).map(|q| q.against(&est, truth(Some(&[f64::NAN; 4])))));
        let json = serde_json::to_value(&s).unwrap();
        assert_eq!((json["samples"].as_u64(), json["duration_s"].as_f64()), (Some(4), Some(2.0)));
        assert!(json["config"].is_null() && json["out"].is_null() && json["truth"] == true);
        let k = &json["quantities"]["k_t"];
        assert_eq!((k["final"].as_f64(), k["max"].as_f64(), k["unit"].as_str()), (Some(0.8), Some(1.0), Some("1")));
        assert!((k["error"]["mean"].as_f64().unwrap() + 0.1).abs() < 1e-12, "{k}");
        assert!(json["quantities"].get("k_v").is_none() && json["quantities"]["u"]["error"].is_null());
    }
}
