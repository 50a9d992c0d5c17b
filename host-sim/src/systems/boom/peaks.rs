//! The peak error as the paper's Table 1 gives it: in each half-cycle of the true vibration
//! (between its zero crossings), the true extreme and the estimate's extreme on the same side
//! in the same window, `|est − true| / |true|`, over the peaks with `|true| ≥ 0.05 m`; with the
//! mean, the median, and the same over the free-decay peaks (the root at rest for the 2 s
//! before).

use serde::Serialize;

/// Smallest true peak counted, m.
pub const MIN_PEAK: f64 = 0.05;
/// The root counts as at rest below this rate, rad/s.
pub const REST_RATE: f64 = 1e-4;
/// How long the root must have been at rest before a free-decay peak, s.
pub const REST_BEFORE: f64 = 2.0;

/// The peak errors of one estimate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeakErrors {
    /// Peaks compared.
    pub peaks: usize,
    /// Mean error, %.
    pub mean_pct: f64,
    /// Median error, %.
    pub median_pct: f64,
    /// Free-decay peaks compared.
    pub free_decay_peaks: usize,
    /// Their mean error, % (NaN if none).
    pub free_decay_mean_pct: f64,
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The peak errors of `estimate` against `truth` (both m, on `t`), with `root_rate` telling
/// the free decays.
///
/// ```
/// use edgekf_sim::systems::boom::peaks::peak_errors;
/// let t: Vec<f64> = (0..1000).map(|k| k as f64 * 0.01).collect();
/// let truth: Vec<f64> = t.iter().map(|t| 0.2 * (2.0 * std::f64::consts::PI * t).sin()).collect();
/// let est: Vec<f64> = truth.iter().map(|v| 1.1 * v).collect();
/// let e = peak_errors(&t, &est, &truth, &vec![0.0; 1000]);
/// assert!(e.peaks >= 18 && (e.mean_pct - 10.0).abs() < 1e-9 && (e.median_pct - 10.0).abs() < 1e-9);
/// assert!(e.free_decay_peaks > 0 && e.free_decay_peaks < e.peaks); // not in the first 2 s
/// ```
pub fn peak_errors(t: &[f64], estimate: &[f64], truth: &[f64], root_rate: &[f64]) -> PeakErrors {
    let n = t.len().min(estimate.len()).min(truth.len()).min(root_rate.len());
    let mut crossings: Vec<usize> = (1..n).filter(|&i| (truth[i - 1] < 0.0) != (truth[i] < 0.0)).collect();
    crossings.insert(0, 0);
    crossings.push(n);
    let (mut all, mut free) = (Vec::new(), Vec::new());
    for w in crossings.windows(2) {
        let (a, b) = (w[0], w[1]);
        if b <= a {
            continue;
        }
        let Some(k) =
            (a..b).filter(|&k| truth[k].is_finite()).max_by(|&x, &y| truth[x].abs().total_cmp(&truth[y].abs()))
        else {
            continue;
        };
        let top = truth[k];
        if top.abs() < MIN_PEAK {
            continue;
        }
        let side = top.signum();
        let est =
            (a..b).map(|i| estimate[i]).filter(|v| v.is_finite()).map(|v| v * side).fold(f64::NEG_INFINITY, f64::max);
        if !est.is_finite() {
            continue;
        }
        let err = 100.0 * (est * side - top).abs() / top.abs();
        all.push(err);
        let since = t[k] - REST_BEFORE;
        let resting = t[k] - t[0] >= REST_BEFORE
            && (0..=k).rev().take_while(|&i| t[i] >= since).all(|i| root_rate[i].abs() < REST_RATE);
        if resting {
            free.push(err);
        }
    }
    let mean = |v: &[f64]| if v.is_empty() { f64::NAN } else { v.iter().sum::<f64>() / v.len() as f64 };
    PeakErrors {
        peaks: all.len(),
        mean_pct: mean(&all),
        median_pct: median(&mut all.clone()),
        free_decay_peaks: free.len(),
        free_decay_mean_pct: mean(&free),
    }
}
