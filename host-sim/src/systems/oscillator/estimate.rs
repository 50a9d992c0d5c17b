//! Runs the harmonic-force estimator of `edgekf` over a data file, exactly as the sensor node
//! would run it over its samples, and measures it against the truth columns when a simulator
//! wrote them.
//!
//! Input handling, all counted in [`InputCounts`]:
//! * an empty/NaN `ax` cell is a missing sample: the filter predicts across it;
//! * a gap in the time column is bridged by the shared timeline ([`crate::io::timeline`]): its
//!   lost samples become rows the filter predicts through, and the estimates have a row for each;
//!   after a gap longer than `max_gap_s` the filter starts again;
//! * with [`EstimateOptions::clip_level`] set, a reading at or beyond it (a clipped sensor) is
//!   missing too, rather than a wrong number;
//! * the `fault_*` columns are instructions for the virtual device of the hardware-in-the-loop
//!   tests and are not used here.
//!
//! ```
//! use edgekf_sim::systems::oscillator::estimate::{run, EstimateOptions};
//! use edgekf_sim::systems::oscillator::scenario::Scenario;
//! let s = Scenario { duration_s: 4.0, ..Default::default() };
//! let data = s.simulate().to_data_file();
//! let est = run::<f64>(&data, &s.estimator_params(), &EstimateOptions::default()).unwrap();
//! assert!((est.mean_force_amplitude(3.0, 4.0).unwrap() - 5.0).abs() < 0.05);
//! assert!(est.error_rms.force_amplitude.unwrap() < 0.05);
//! ```

use crate::io::data::{self, DataError, DataFile};
use crate::io::timeline::{bridge, TimelineOptions};
use edgekf::residual::{NisBounds, RunningStats};
use edgekf::systems::oscillator::{EstimatorCounters, HarmonicForceEstimator, HarmonicForceParams};
use edgekf::Real;
use std::path::Path;

/// The channels the estimator's input may hold (besides `t` and `truth_*`): the accelerometer
/// axes and the virtual-device fault columns. Only `ax` is used.
pub const KNOWN_CHANNELS: [&str; 9] =
    ["ax", "ay", "az", "fault_nack", "fault_timeout", "fault_garbage", "fault_stuck", "fault_drop", "fault_reset"];

/// How to run and judge the estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimateOptions {
    /// Statistics (error RMS, innovation RMS, NIS) start this long after the first sample, s: the
    /// filter starts knowing nothing and its convergence is not what is being measured.
    pub settle_s: f64,
    /// Readings with `|ax|` at or above this are treated as missing (clipped sensor), m/s².
    pub clip_level: Option<f64>,
    /// Largest accepted relative difference between the file's sample rate and the filter's.
    pub rate_tolerance: f64,
    /// How gaps in the time column are bridged.
    pub timeline: TimelineOptions,
}

impl Default for EstimateOptions {
    /// 2 s settling (five decay time constants of the demo mode), no clip level, 1 % rate
    /// tolerance.
    fn default() -> Self {
        Self { settle_s: 2.0, clip_level: None, rate_tolerance: 0.01, timeline: TimelineOptions::default() }
    }
}

/// What happened to the input samples before the filter saw them.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct InputCounts {
    /// `ax` cells that were empty or NaN.
    pub nan: usize,
    /// Readings at or beyond the clip level.
    pub clipped: usize,
    /// Predict-only steps for samples lost in gaps of the time column
    /// ([`bridge`](crate::io::timeline::bridge)).
    pub gap_steps: usize,
    /// Restarts of the filter after gaps longer than `timeline.max_gap_s`.
    pub restarts: usize,
}

/// RMS errors against the truth columns, over `t ≥ from_t` (`None` when the file has no such
/// truth column).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorRms {
    /// Start of the statistics, s.
    pub from_t: f64,
    /// Of `force_amplitude` against `truth_force_amplitude`, N.
    pub force_amplitude: Option<f64>,
    /// Of `displacement` against `truth_x`, m.
    pub displacement: Option<f64>,
}

/// Per-sample estimates (one entry per data row, in `f64` whatever the filter's precision) and
/// run statistics.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimates {
    /// Time, s.
    pub t: Vec<f64>,
    /// Force amplitude `|F|`, N.
    pub force_amplitude: Vec<f64>,
    /// In-phase force component `F cos(Ωt + φ)`, N.
    pub force_cos: Vec<f64>,
    /// Quadrature force component, N.
    pub force_sin: Vec<f64>,
    /// Modal displacement, m.
    pub displacement: Vec<f64>,
    /// Modal velocity, m/s.
    pub velocity: Vec<f64>,
    /// Innovation, m/s² (NaN for a missing sample).
    pub innovation: Vec<f64>,
    /// Normalised innovation squared (NaN for a missing sample).
    pub nis: Vec<f64>,
    /// Whether the sample updated the filter (false when missing or rejected by the gate).
    pub accepted: Vec<bool>,
    /// The estimator's own counters.
    pub counters: EstimatorCounters,
    /// What was done to the input.
    pub input: InputCounts,
    /// RMS of the accepted innovations after settling, m/s².
    pub innovation_rms: f64,
    /// Mean NIS of the accepted samples after settling (1 for a consistent filter).
    pub nis_mean: f64,
    /// Number of samples in `nis_mean`.
    pub nis_count: usize,
    /// Errors against the truth.
    pub error_rms: ErrorRms,
}

impl Estimates {
    /// Columns of the estimate CSV after `t`.
    pub const COLUMNS: [&'static str; 7] =
        ["force_amplitude", "force_cos", "force_sin", "displacement", "velocity", "innovation", "nis"];

    /// Mean of the force amplitude over `t0 ≤ t < t1`, N (`None` if no sample lies there).
    pub fn mean_force_amplitude(&self, t0: f64, t1: f64) -> Option<f64> {
        window_mean(&self.t, &self.force_amplitude, t0, t1)
    }

    /// Statistics over `t0 ≤ t < t1`: a stretch of constant force shows what the filter does in
    /// steady state, without the transient of a change.
    pub fn window(&self, t0: f64, t1: f64) -> WindowStats {
        let (mut amp, mut inn, mut nis) = (RunningStats::new(), RunningStats::new(), RunningStats::new());
        for k in 0..self.t.len() {
            if self.t[k] >= t0 && self.t[k] < t1 {
                amp.push(self.force_amplitude[k]);
                if self.accepted[k] {
                    inn.push(self.innovation[k]);
                    nis.push(self.nis[k]);
                }
            }
        }
        WindowStats {
            t0,
            t1,
            force_amplitude: (amp.count() > 0).then(|| amp.mean()),
            force_amplitude_std: amp.variance().sqrt(),
            innovation_rms: inn.rms(),
            nis_mean: nis.mean(),
            nis_count: nis.count() as usize,
        }
    }

    /// 99 % acceptance band of [`Estimates::nis_mean`] for a consistent filter.
    pub fn nis_bounds(&self) -> NisBounds {
        NisBounds::new(1, self.nis_count.max(1), 0.01)
    }

    /// The estimates as a data file with [`Estimates::COLUMNS`].
    pub fn to_data_file(&self) -> DataFile {
        let columns = vec![
            self.force_amplitude.clone(),
            self.force_cos.clone(),
            self.force_sin.clone(),
            self.displacement.clone(),
            self.velocity.clone(),
            self.innovation.clone(),
            self.nis.clone(),
        ];
        DataFile {
            sha256: None,
            names: Self::COLUMNS.iter().map(|s| s.to_string()).collect(),
            t: self.t.clone(),
            columns,
        }
    }

    /// Writes `t,force_amplitude,force_cos,force_sin,displacement,velocity,innovation,nis`.
    pub fn write_csv(&self, path: &Path) -> Result<(), DataError> {
        let cols = [
            &self.force_amplitude[..],
            &self.force_cos,
            &self.force_sin,
            &self.displacement,
            &self.velocity,
            &self.innovation,
            &self.nis,
        ];
        data::write(path, &Self::COLUMNS, &self.t, &cols)
    }
}

/// Statistics of an [`Estimates`] over a time window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowStats {
    /// Start, s.
    pub t0: f64,
    /// End (exclusive), s.
    pub t1: f64,
    /// Mean force amplitude, N (`None` for an empty window).
    pub force_amplitude: Option<f64>,
    /// Its standard deviation over the window, N.
    pub force_amplitude_std: f64,
    /// RMS of the accepted innovations, m/s².
    pub innovation_rms: f64,
    /// Mean NIS of the accepted samples.
    pub nis_mean: f64,
    /// Accepted samples.
    pub nis_count: usize,
}

impl WindowStats {
    /// 99 % acceptance band of the mean NIS for a consistent filter.
    pub fn nis_bounds(&self) -> NisBounds {
        NisBounds::new(1, self.nis_count.max(1), 0.01)
    }
}

/// Mean of the finite `values` whose time lies in `[t0, t1)`.
pub fn window_mean(t: &[f64], values: &[f64], t0: f64, t1: f64) -> Option<f64> {
    let mut s = RunningStats::<f64>::new();
    for (&tk, &v) in t.iter().zip(values) {
        if tk >= t0 && tk < t1 {
            s.push(v);
        }
    }
    (s.count() > 0).then(|| s.mean())
}

/// Runs the estimator in precision `T` (`f32` as on the chip, `f64` as a reference) over the
/// `ax` channel of `data`.
///
/// Fails when the file has no `ax` channel (or fewer than two samples), when its sample rate differs from
/// `params.sample_rate_hz` by more than the tolerance (the filter is discretised for one rate),
/// or when the filter cannot be built from `params`.
pub fn run<T: Real>(
    data: &DataFile,
    params: &HarmonicForceParams,
    opts: &EstimateOptions,
) -> anyhow::Result<Estimates> {
    let ax = data
        .column("ax")
        .ok_or_else(|| anyhow::anyhow!("the data have no `ax` column (columns: t, {})", data.names.join(", ")))?;
    if data.len() < 2 || ax.len() != data.len() {
        anyhow::bail!("the data need at least 2 samples and an `ax` column as long as `t`");
    }
    let timing = data.timing();
    let rate_error = timing.sample_rate / params.sample_rate_hz - 1.0;
    if rate_error.is_nan() || rate_error.abs() > opts.rate_tolerance {
        anyhow::bail!(
            "the data are sampled at {:.6} Hz but the filter is built for {} Hz (sensor.odr_hz)",
            timing.sample_rate,
            params.sample_rate_hz
        );
    }
    let (bridged, timeline) = bridge(data, &timing, &opts.timeline);
    let data = &bridged;
    let ax = data.column("ax").unwrap_or_default();
    let new_estimator = || {
        HarmonicForceEstimator::<T>::new(params)
            .map_err(|e| anyhow::anyhow!("cannot build the harmonic-force estimator: {e:?}"))
    };
    let mut est = new_estimator()?;
    let mut counters = EstimatorCounters::default();
    let filled = timeline.filled_mask(ax.len());

    let n = data.len();
    let mut out = Estimates {
        t: data.t.clone(),
        force_amplitude: Vec::with_capacity(n),
        force_cos: Vec::with_capacity(n),
        force_sin: Vec::with_capacity(n),
        displacement: Vec::with_capacity(n),
        velocity: Vec::with_capacity(n),
        innovation: Vec::with_capacity(n),
        nis: Vec::with_capacity(n),
        accepted: Vec::with_capacity(n),
        counters: EstimatorCounters::default(),
        input: InputCounts::default(),
        innovation_rms: f64::NAN,
        nis_mean: f64::NAN,
        nis_count: 0,
        error_rms: ErrorRms { from_t: data.t[0] + opts.settle_s, force_amplitude: None, displacement: None },
    };
    let from_t = out.error_rms.from_t;
    let (mut innovations, mut nis) = (RunningStats::<f64>::new(), RunningStats::<f64>::new());
    for (k, &a) in ax.iter().enumerate() {
        if timeline.restarts_at(k) {
            counters = sum(counters, est.counters());
            est = new_estimator()?;
            out.input.restarts += 1;
        }
        let input = if filled[k] {
            out.input.gap_steps += 1;
            None
        } else if a.is_nan() {
            out.input.nan += 1;
            None
        } else if opts.clip_level.is_some_and(|c| a.abs() >= c) {
            out.input.clipped += 1;
            None
        } else {
            Some(T::of_f64(a))
        };
        let gated_before = est.counters().gated;
        let r = est.step(input);
        let accepted = input.is_some() && est.counters().gated == gated_before;
        if accepted && data.t[k] >= from_t {
            if let (Some(i), Some(q)) = (r.innovation, r.nis) {
                innovations.push(i.as_f64());
                nis.push(q.as_f64());
            }
        }
        out.force_amplitude.push(r.force_amplitude.as_f64());
        out.force_cos.push(r.force_cos.as_f64());
        out.force_sin.push(r.force_sin.as_f64());
        out.displacement.push(r.displacement.as_f64());
        out.velocity.push(r.velocity.as_f64());
        out.innovation.push(r.innovation.map_or(f64::NAN, Real::as_f64));
        out.nis.push(r.nis.map_or(f64::NAN, Real::as_f64));
        out.accepted.push(accepted);
    }
    out.counters = sum(counters, est.counters());
    out.innovation_rms = innovations.rms();
    out.nis_mean = nis.mean();
    out.nis_count = nis.count() as usize;
    out.error_rms.force_amplitude =
        data.column("truth_force_amplitude").and_then(|tr| rms_error(&out.t, &out.force_amplitude, tr, from_t));
    out.error_rms.displacement = data.column("truth_x").and_then(|tr| rms_error(&out.t, &out.displacement, tr, from_t));
    Ok(out)
}

/// The counters of two runs of the estimator (before and after a restart) together.
fn sum(a: EstimatorCounters, b: EstimatorCounters) -> EstimatorCounters {
    let mut filter = a.filter;
    filter.covariance_resets += b.filter.covariance_resets;
    filter.refused_updates += b.filter.refused_updates;
    EstimatorCounters { steps: a.steps + b.steps, missing: a.missing + b.missing, gated: a.gated + b.gated, filter }
}

/// RMS of `est − truth` over `t ≥ from_t`, skipping NaN truth.
fn rms_error(t: &[f64], est: &[f64], truth: &[f64], from_t: f64) -> Option<f64> {
    let mut s = RunningStats::<f64>::new();
    for ((&tk, &e), &tr) in t.iter().zip(est).zip(truth) {
        if tk >= from_t && tr.is_finite() {
            s.push(e - tr);
        }
    }
    (s.count() > 0).then(|| s.rms())
}

#[cfg(test)]
mod tests;
