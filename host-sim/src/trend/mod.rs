//! A machine's history: the loop's reports on many recordings of one machine, put in order of
//! their start, as indicators over time (`trend.csv`) with, for each effect, the first
//! recording where it appears and how fast it changes (`trend.html`).
//!
//! An engineer who watches a machine does not diagnose one file once: a node uploads a
//! recording every hour or day, and the question is what changed, since when, and how fast.
//! This module knows no system: it reads only what every [`LoopReport`] has (the effects
//! added, the NIS before and after, a baseline's `baseline_comparison` ratios).
//!
//! Recordings are ordered by their start. The data contract allows `t` to be absolute
//! (seconds since 1970-01-01 UTC): when every recording starts after [`ABSOLUTE_FROM_S`], the
//! history's `t` is that start and rates are also given per day. Otherwise (`t` from 0, as
//! simulators and most loggers write it) the recordings are ordered by file name and the
//! history's `t` is the recording's number in that order, 1, 2, …
//!
//! ```
//! use edgekf_sim::trend::{Clock, Point, Trend};
//! let point = |name: &str, growth: Option<f64>| Point {
//!     name: name.into(),
//!     start_s: 0.0,
//!     effects: growth.map(|g| ("harmonic_force_mode_2x".to_string(), g)).into_iter().collect(),
//!     nis: [2.0, 1.0],
//!     ..Point::default()
//! };
//! // Out of order, `t` from 0: ordered by name, numbered from 1.
//! let trend = Trend::new(vec![point("c", Some(0.3)), point("a", None), point("b", Some(0.2))]);
//! assert_eq!(trend.clock, Clock::Index);
//! assert_eq!(trend.t, [1.0, 2.0, 3.0]);
//! let e = &trend.effects[0];
//! assert_eq!((e.first, e.seen), (2, 2));
//! assert!((e.per_recording.unwrap() - 0.1).abs() < 1e-12);
//! assert!(trend.to_csv().unwrap().starts_with("t,harmonic_force_mode_2x,nis_before,nis_after\n1,,2,1\n"));
//! ```

mod html;
pub mod synthetic;

pub use html::render;

use crate::residual_loop::{AddedEffect, LoopReport};

/// Starts at or after this many seconds (1973-03-03 UTC) are read as absolute time: no
/// recording of a machine is made in the first three years after 1970, and no run that starts
/// from 0 lasts three years.
pub const ABSOLUTE_FROM_S: f64 = 1e8;

/// Seconds in a day, for the rates per day.
const DAY_S: f64 = 86_400.0;

/// One recording's indicators, as its loop report gives them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Point {
    /// The recording's name (its file name without `.csv`).
    pub name: String,
    /// Its first `t`, s.
    pub start_s: f64,
    /// Each added effect's column name ([`effect_column`]) and value, in the report's order.
    pub effects: Vec<(String, f64)>,
    /// Mean NIS per channel of the base model and of the final model.
    pub nis: [f64; 2],
    /// Each `baseline_comparison` entry's column name and `ratio_to_baseline`.
    pub ratios: Vec<(String, f64)>,
    /// Each effect's unit (its report's `unit`: SI, or `1` for a factor).
    pub units: Vec<(String, String)>,
    /// Each effect's 95 % interval, where its report gives one.
    pub intervals: Vec<(String, [f64; 2])>,
}

impl Point {
    /// The indicators of `report`, the loop's report on the recording `name`.
    pub fn from_report(name: &str, report: &LoopReport) -> Self {
        let (mut effects, mut units, mut intervals) = (Vec::new(), Vec::new(), Vec::new());
        for e in &report.effects_added {
            let column = unique(effect_column(e), &effects);
            units.push((column.clone(), e.unit.clone()));
            intervals.extend(e.interval.map(|i| (column.clone(), i)));
            effects.push((column, e.value));
        }
        let mut ratios: Vec<(String, f64)> = Vec::new();
        let comparison = report.section.fields.get("baseline_comparison").and_then(|v| v.as_array());
        for c in comparison.into_iter().flatten() {
            let text = |key: &str| c.get(key).and_then(|v| v.as_str()).unwrap_or("");
            let Some(ratio) = c.get("ratio_to_baseline").and_then(|v| v.as_f64()) else { continue };
            let order = c.get("order").and_then(|v| v.as_f64()).map(|o| format!("_{o}x")).unwrap_or_default();
            let column = unique(sanitise(&format!("ratio_{}_{}{order}", text("kind"), text("location"))), &ratios);
            ratios.push((column, ratio));
        }
        let start_s = report.traces.t.first().copied().unwrap_or(f64::NAN);
        let nis = [report.before.nis_mean, report.after.nis_mean];
        Self { name: name.into(), start_s, effects, nis, ratios, units, intervals }
    }
}

/// `column`, or with `_2`, `_3`, … if `taken` has it already (two effects of one name in one
/// report stay two columns).
fn unique(column: String, taken: &[(String, f64)]) -> String {
    let free = |c: &str| !taken.iter().any(|(t, _)| t == c);
    if free(&column) {
        return column;
    }
    (2..).map(|k| format!("{column}_{k}")).find(|c| free(c)).expect("a free name exists")
}

/// An effect's column in `trend.csv`: `<kind>_<location>[_<parameter or line>][_<order>x]`,
/// sanitised ([`sanitise`]); the order keeps a second and a third harmonic at one place apart.
///
/// ```
/// use edgekf_sim::residual_loop::{AddedEffect, EffectDetail, EffectKind};
/// let e = AddedEffect {
///     kind: EffectKind::HarmonicForce,
///     location: "node 12".into(),
///     value: 0.5,
///     unit: "N".into(),
///     detail: EffectDetail { order: Some(2.0), ..Default::default() },
///     explains: vec![],
///     delta_log_likelihood: 30.0,
///     bic_penalty: 5.0,
///     interval: None,
/// };
/// assert_eq!(edgekf_sim::trend::effect_column(&e), "harmonic_force_node_12_2x");
/// ```
pub fn effect_column(e: &AddedEffect) -> String {
    let what = e.detail.parameter.as_ref().or(e.detail.line.as_ref()).map(|p| format!("_{p}")).unwrap_or_default();
    let order = e.detail.order.map(|o| format!("_{o}x")).unwrap_or_default();
    sanitise(&format!("{}_{}{what}{order}", e.kind, e.location))
}

/// `name` as a data-contract column: lower case, every run of characters outside `[a-z0-9]`
/// one `_`, none at either end.
///
/// ```
/// assert_eq!(edgekf_sim::trend::sanitise("Parameter_Disk 12_mass"), "parameter_disk_12_mass");
/// assert_eq!(edgekf_sim::trend::sanitise("order_level_n5_x_1.5x"), "order_level_n5_x_1_5x");
/// ```
pub fn sanitise(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for c in name.chars().flat_map(char::to_lowercase) {
        if c.is_ascii_lowercase() || c.is_ascii_digit() {
            out.push(c);
        } else if !out.is_empty() && !out.ends_with('_') {
            out.push('_');
        }
    }
    out.trim_end_matches('_').to_string()
}

/// What the history's `t` is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Clock {
    /// Each recording's start, s since 1970-01-01 UTC.
    Absolute,
    /// The recording's number (1, 2, …) in the order of the file names.
    Index,
}

/// How one effect develops over the history.
#[derive(Debug, Clone, PartialEq)]
pub struct EffectTrend {
    /// Its column ([`effect_column`]).
    pub column: String,
    /// Its unit, as the reports give it.
    pub unit: String,
    /// The first recording (numbered from 1, in the history's order) where it was added.
    pub first: usize,
    /// How many recordings have it.
    pub seen: usize,
    /// Least-squares slope of its value against the recording's number, per recording, over
    /// the recordings that have it (None with fewer than two).
    pub per_recording: Option<f64>,
    /// The same against the recordings' start, per day (absolute time only).
    pub per_day: Option<f64>,
}

/// The history: the recordings in order, their `t`, the columns of `trend.csv` and each
/// effect's development.
#[derive(Debug, Clone, PartialEq)]
pub struct Trend {
    /// What `t` is.
    pub clock: Clock,
    /// The recordings, in order.
    pub recordings: Vec<Point>,
    /// Each recording's `t` (its start, or its number).
    pub t: Vec<f64>,
    /// The indicator columns after `t`: effects in order of first appearance, `nis_before`,
    /// `nis_after`, then the baseline ratios in order of first appearance.
    pub columns: Vec<String>,
    /// One per effect column, in the same order.
    pub effects: Vec<EffectTrend>,
}

impl Trend {
    /// The history of `points`, in order of their start (see the module's text).
    pub fn new(mut points: Vec<Point>) -> Self {
        let absolute = !points.is_empty() && points.iter().all(|p| p.start_s >= ABSOLUTE_FROM_S);
        let clock = if absolute { Clock::Absolute } else { Clock::Index };
        match clock {
            Clock::Absolute => points.sort_by(|a, b| a.start_s.total_cmp(&b.start_s).then(a.name.cmp(&b.name))),
            Clock::Index => points.sort_by(|a, b| a.name.cmp(&b.name)),
        }
        let t = match clock {
            Clock::Absolute => points.iter().map(|p| p.start_s).collect(),
            Clock::Index => (1..=points.len()).map(|k| k as f64).collect(),
        };
        let mut effect_columns: Vec<String> = Vec::new();
        let mut ratio_columns: Vec<String> = Vec::new();
        for p in &points {
            for (c, _) in &p.effects {
                if !effect_columns.contains(c) {
                    effect_columns.push(c.clone());
                }
            }
            for (c, _) in &p.ratios {
                if !ratio_columns.contains(c) {
                    ratio_columns.push(c.clone());
                }
            }
        }
        let effects = effect_columns.iter().map(|c| effect_trend(c, &points, clock)).collect();
        let mut columns = effect_columns;
        columns.extend(["nis_before".to_string(), "nis_after".to_string()]);
        columns.extend(ratio_columns);
        Self { clock, recordings: points, t, columns, effects }
    }

    /// The 95 % interval of the effect `column` in recording `row`, where its report gives one.
    pub fn interval(&self, row: usize, column: &str) -> Option<[f64; 2]> {
        let p = self.recordings.get(row)?;
        p.intervals.iter().find(|(c, _)| c == column).map(|(_, i)| *i)
    }

    /// The value of `column` in recording `row` (None where absent).
    pub fn value(&self, row: usize, column: &str) -> Option<f64> {
        let p = self.recordings.get(row)?;
        match column {
            "nis_before" => Some(p.nis[0]),
            "nis_after" => Some(p.nis[1]),
            c => p.effects.iter().chain(&p.ratios).find(|(name, _)| name == c).map(|(_, v)| *v),
        }
    }

    /// `trend.csv`: the header `t,<columns>`, then one row per recording, through the data
    /// contract's writer; an absent or non-finite value is an empty cell (a missing sample).
    pub fn to_csv(&self) -> Result<String, crate::io::data::DataError> {
        let names: Vec<&str> = self.columns.iter().map(String::as_str).collect();
        let columns: Vec<Vec<f64>> = self
            .columns
            .iter()
            .map(|c| {
                (0..self.t.len()).map(|row| self.value(row, c).filter(|v| v.is_finite()).unwrap_or(f64::NAN)).collect()
            })
            .collect();
        let views: Vec<&[f64]> = columns.iter().map(Vec::as_slice).collect();
        crate::io::data::to_csv_string_sparse(std::path::Path::new("trend.csv"), &names, &self.t, &views)
    }
}

/// The development of the effect `column` over `points` (in order).
fn effect_trend(column: &str, points: &[Point], clock: Clock) -> EffectTrend {
    let present: Vec<(usize, f64, f64)> = points
        .iter()
        .enumerate()
        .filter_map(|(k, p)| p.effects.iter().find(|(c, _)| c == column).map(|(_, v)| (k + 1, p.start_s, *v)))
        .collect();
    let per_recording = slope(&present.iter().map(|&(k, _, v)| (k as f64, v)).collect::<Vec<_>>());
    let per_day = match clock {
        Clock::Absolute => slope(&present.iter().map(|&(_, s, v)| (s / DAY_S, v)).collect::<Vec<_>>()),
        Clock::Index => None,
    };
    let unit = points.iter().flat_map(|p| &p.units).find(|(c, _)| c == column).map(|(_, u)| u.clone());
    EffectTrend {
        column: column.into(),
        unit: unit.unwrap_or_default(),
        first: present.first().map_or(0, |p| p.0),
        seen: present.len(),
        per_recording,
        per_day,
    }
}

/// The least-squares slope of `y` on `x` over `points` (None with fewer than two distinct `x`
/// or a non-finite value).
///
/// ```
/// let s = edgekf_sim::trend::slope(&[(1.0, 0.2), (2.0, 0.25), (3.0, 0.3)]).unwrap();
/// assert!((s - 0.05).abs() < 1e-12);
/// assert_eq!(edgekf_sim::trend::slope(&[(1.0, 0.2)]), None);
/// ```
pub fn slope(points: &[(f64, f64)]) -> Option<f64> {
    let n = points.len() as f64;
    if points.len() < 2 || points.iter().any(|(x, y)| !(x.is_finite() && y.is_finite())) {
        return None;
    }
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(name: &str, start_s: f64, effects: &[(&str, f64)]) -> Point {
        Point {
            name: name.into(),
            start_s,
            effects: effects.iter().map(|(c, v)| (c.to_string(), *v)).collect(),
            nis: [1.5, 1.0],
            ratios: vec![("ratio_innovation_rms_ax".into(), 1.2)],
            ..Point::default()
        }
    }

    #[test]
    fn absolute_starts_order_the_history_and_give_rates_per_day() {
        let day0 = 1.7e9;
        let points = vec![
            point("z", day0, &[("sensor_bias_ax", 0.1)]),
            point("a", day0 + 2.0 * DAY_S, &[("sensor_bias_ax", 0.3), ("harmonic_force_mode_2x", 0.5)]),
            point("m", day0 + DAY_S, &[("sensor_bias_ax", 0.2)]),
        ];
        let trend = Trend::new(points);
        assert_eq!(trend.clock, Clock::Absolute);
        let names: Vec<&str> = trend.recordings.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["z", "m", "a"]);
        assert_eq!(trend.t, [day0, day0 + DAY_S, day0 + 2.0 * DAY_S]);
        let bias = &trend.effects[0];
        assert_eq!((bias.column.as_str(), bias.first, bias.seen), ("sensor_bias_ax", 1, 3));
        assert!((bias.per_day.unwrap() - 0.1).abs() < 1e-9, "{bias:?}");
        let second = &trend.effects[1];
        assert_eq!((second.first, second.seen, second.per_recording), (3, 1, None));
        let csv = trend.to_csv().unwrap();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], "t,sensor_bias_ax,harmonic_force_mode_2x,nis_before,nis_after,ratio_innovation_rms_ax");
        assert_eq!(lines[1], "1700000000,0.1,,1.5,1,1.2");
        assert_eq!(lines.len(), 4);
    }

    #[test]
    fn starts_from_zero_are_numbered_in_name_order() {
        // One absolute start among relative ones does not make the clock absolute.
        let trend = Trend::new(vec![point("b", 0.0, &[]), point("a", 1.7e9, &[])]);
        assert_eq!(trend.clock, Clock::Index);
        assert_eq!(trend.recordings[0].name, "a");
        assert_eq!(trend.t, [1.0, 2.0]);
        assert!(trend.effects.is_empty());
        assert_eq!(trend.to_csv().unwrap().lines().next(), Some("t,nis_before,nis_after,ratio_innovation_rms_ax"));
    }

    #[test]
    fn a_missing_nis_is_an_empty_cell() {
        let mut p = point("a", 0.0, &[]);
        p.nis[1] = f64::NAN;
        assert_eq!(Trend::new(vec![p]).to_csv().unwrap().lines().nth(1), Some("1,1.5,,1.2"));
    }

    #[test]
    fn a_repeated_column_in_one_report_stays_apart() {
        let taken = vec![("x".to_string(), 1.0), ("x_2".to_string(), 2.0)];
        assert_eq!(unique("x".into(), &taken), "x_3");
        assert_eq!(unique("y".into(), &taken), "y");
    }
}
