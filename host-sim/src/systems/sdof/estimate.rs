//! The node's estimator ([`edgekf::systems::sdof::SdofEstimator`]) over a data file, in `f64`
//! or `f32`, and its error against the file's truth when the file has one.

use crate::io::data::{self, DataError, DataFile};
use edgekf::systems::sdof::{SdofCounters, SdofEstimator, SdofParams};
use edgekf::Real;
use std::path::Path;

/// The channel the estimator reads: the mass's absolute acceleration along the mount, m/s².
pub const CHANNEL: &str = "ax";

/// The channels a data file may have besides the truth (the node's reader takes all three).
pub const KNOWN: [&str; 3] = ["ax", "ay", "az"];

/// The output file's channels.
pub const OUTPUT: [&str; 4] = ["displacement", "velocity", "innovation", "nis"];

/// The estimates of a run, one per row of the data.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Estimates {
    /// Time of each row, s.
    pub t: Vec<f64>,
    /// Relative displacement, m.
    pub displacement: Vec<f64>,
    /// Relative velocity, m/s.
    pub velocity: Vec<f64>,
    /// Innovation, m/s² (NaN where the sample was missing or refused).
    pub innovation: Vec<f64>,
    /// Its NIS (NaN likewise).
    pub nis: Vec<f64>,
    /// The estimator's counters, summed over its restarts.
    pub counters: SdofCounters,
}

impl Estimates {
    /// Writes the estimates (`t`, [`OUTPUT`]) through a temporary file renamed into place.
    pub fn write(&self, path: &Path) -> Result<(), DataError> {
        data::write(path, &OUTPUT, &self.t, &[&self.displacement, &self.velocity, &self.innovation, &self.nis])
    }
}

/// Runs the estimator in `T` over `file`'s [`CHANNEL`] (NaN cells are missing samples),
/// starting afresh at each row of `restarts` (where the timeline could not bridge a gap).
pub fn run<T: Real>(file: &DataFile, params: &SdofParams, restarts: &[usize]) -> anyhow::Result<Estimates> {
    let ax = file.column(CHANNEL).ok_or_else(|| anyhow::anyhow!("the data has no `{CHANNEL}` channel"))?;
    let fresh = || SdofEstimator::<T>::new(params).map_err(|e| anyhow::anyhow!("the mount's model: {e}"));
    let mut est = fresh()?;
    let mut out = Estimates { t: file.t.clone(), ..Estimates::default() };
    let mut counters = SdofCounters::default();
    for (k, &a) in ax.iter().enumerate() {
        if restarts.contains(&k) {
            add(&mut counters, est.counters());
            est = fresh()?;
        }
        let s = est.step(a.is_finite().then(|| T::of_f64(a)));
        out.displacement.push(s.displacement.as_f64());
        out.velocity.push(s.velocity.as_f64());
        out.innovation.push(s.innovation.map_or(f64::NAN, Real::as_f64));
        out.nis.push(s.nis.map_or(f64::NAN, Real::as_f64));
    }
    add(&mut counters, est.counters());
    out.counters = counters;
    Ok(out)
}

fn add(total: &mut SdofCounters, c: SdofCounters) {
    total.steps = total.steps.saturating_add(c.steps);
    total.missing = total.missing.saturating_add(c.missing);
    total.filter.covariance_resets = total.filter.covariance_resets.saturating_add(c.filter.covariance_resets);
    total.filter.refused_updates = total.filter.refused_updates.saturating_add(c.filter.refused_updates);
}

/// RMS error of `estimate` against `truth` over the rows from `from`, and the truth's RMS there.
pub fn rms_error(estimate: &[f64], truth: &[f64], from: usize) -> (f64, f64) {
    let (mut e2, mut t2, mut n) = (0.0, 0.0, 0usize);
    for (e, t) in estimate.iter().zip(truth).skip(from) {
        e2 += (e - t) * (e - t);
        t2 += t * t;
        n += 1;
    }
    let n = n.max(1) as f64;
    ((e2 / n).sqrt(), (t2 / n).sqrt())
}
