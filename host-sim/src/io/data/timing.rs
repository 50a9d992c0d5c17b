//! How regular a file's time column is.
//!
//! Every filter in `edgekf` is discretised once for a fixed sample period, so the time column is
//! checked rather than trusted: gaps (lost samples) and jitter are measured and reported, never
//! smoothed over.

use std::fmt;

/// An interval much longer than the typical one: samples were lost there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gap {
    /// Index (0-based data row) of the first sample after the gap.
    pub index: usize,
    /// Time of that sample, s.
    pub t: f64,
    /// The interval that ends at that sample, s.
    pub dt: f64,
}

/// Regularity of a time column.
///
/// ```
/// use edgekf_sim::io::data::TimingReport;
/// let t = [0.0, 0.001, 0.002, 0.005, 0.006];
/// let r = TimingReport::of(&t);
/// assert!((r.sample_rate - 1000.0).abs() < 1e-6);
/// assert_eq!(r.gaps.len(), 1);
/// assert_eq!(r.gaps[0].index, 3);
/// assert!(!r.uniform);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct TimingReport {
    /// Median interval between samples, s: the nominal sample period.
    pub dt_median: f64,
    /// `1 / dt_median`, Hz.
    pub sample_rate: f64,
    /// Largest `|dtᵢ − dt_median|` over the intervals that are not gaps, s. Gaps are listed in
    /// [`TimingReport::gaps`] instead, so one lost sample does not masquerade as jitter.
    pub max_jitter: f64,
    /// Intervals longer than [`GAP_FACTOR`] × `dt_median`.
    pub gaps: Vec<Gap>,
    /// `max_jitter < 1e-3 · dt_median` and no gaps: the file can be filtered as it is.
    pub uniform: bool,
}

/// An interval longer than this many median intervals is a gap.
pub const GAP_FACTOR: f64 = 1.5;

/// Relative jitter below which sampling counts as uniform.
pub const UNIFORM_JITTER: f64 = 1e-3;

impl TimingReport {
    /// Measures a strictly increasing time column of at least two samples (as
    /// [`read`](super::read) guarantees). With fewer samples every figure is NaN.
    pub fn of(t: &[f64]) -> Self {
        let mut dts: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        if dts.is_empty() {
            return Self {
                dt_median: f64::NAN,
                sample_rate: f64::NAN,
                max_jitter: f64::NAN,
                gaps: vec![],
                uniform: false,
            };
        }
        let intervals = dts.clone();
        dts.sort_by(f64::total_cmp);
        let n = dts.len();
        let dt_median = if n % 2 == 1 { dts[n / 2] } else { 0.5 * (dts[n / 2 - 1] + dts[n / 2]) };
        let mut gaps = Vec::new();
        let mut max_jitter: f64 = 0.0;
        for (i, &dt) in intervals.iter().enumerate() {
            if dt > GAP_FACTOR * dt_median {
                gaps.push(Gap { index: i + 1, t: t[i + 1], dt });
            } else {
                max_jitter = max_jitter.max((dt - dt_median).abs());
            }
        }
        let uniform = max_jitter < UNIFORM_JITTER * dt_median && gaps.is_empty();
        Self { dt_median, sample_rate: 1.0 / dt_median, max_jitter, gaps, uniform }
    }

    /// Number of samples missing in all the gaps together, each gap counted as
    /// `round(dt / dt_median) − 1` lost samples.
    pub fn missing_samples(&self) -> usize {
        // Saturating: a gap of 10⁴² periods (a corrupt `t`) counts as many as `usize` holds.
        self.gaps.iter().fold(0usize, |n, g| n.saturating_add(self.samples_lost_in(g)))
    }

    /// Samples lost in one gap: `round(dt / dt_median) − 1`, at least 1.
    pub fn samples_lost_in(&self, gap: &Gap) -> usize {
        ((gap.dt / self.dt_median).round() as usize).saturating_sub(1).max(1)
    }

    /// Human-readable notices about gaps and jitter (empty when sampling is uniform).
    pub fn notices(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !self.gaps.is_empty() {
            let largest = self.gaps.iter().map(|g| g.dt).fold(0.0, f64::max);
            let mut msg = format!(
                "timing: {} gap(s) in the time column (interval > {GAP_FACTOR} × the median {}), about {} \
                 sample(s) missing, largest {}",
                self.gaps.len(),
                ms(self.dt_median),
                self.missing_samples(),
                ms(largest)
            );
            for g in self.gaps.iter().take(5) {
                msg.push_str(&format!("; row {} at t = {:.6} s after {}", g.index, g.t, ms(g.dt)));
            }
            if self.gaps.len() > 5 {
                msg.push_str(&format!("; … {} more", self.gaps.len() - 5));
            }
            out.push(msg);
        }
        if self.max_jitter >= UNIFORM_JITTER * self.dt_median {
            out.push(format!(
                "timing: sample intervals jitter by up to {} ({:.2} % of the {} period); the data are \
                 processed as if uniformly sampled",
                ms(self.max_jitter),
                100.0 * self.max_jitter / self.dt_median,
                ms(self.dt_median)
            ));
        }
        out
    }
}

/// A duration in milliseconds with six significant-enough decimals (`1.000000 ms`).
fn ms(seconds: f64) -> String {
    format!("{:.6} ms", seconds * 1e3)
}

impl fmt::Display for TimingReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "sample rate {:.6} Hz (median interval {})", self.sample_rate, ms(self.dt_median))?;
        if self.uniform {
            write!(f, ", uniform")
        } else {
            write!(f, ", {} gap(s), max jitter {}", self.gaps.len(), ms(self.max_jitter))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize, dt: f64) -> Vec<f64> {
        (0..n).map(|k| k as f64 * dt).collect()
    }

    #[test]
    fn a_clean_1khz_grid_is_uniform() {
        let r = TimingReport::of(&grid(12_000, 1e-3));
        assert!((r.sample_rate - 1000.0).abs() < 1e-6, "{}", r.sample_rate);
        // k·dt rounding leaves only femtosecond-scale differences.
        assert!(r.max_jitter < 1e-12);
        assert!(r.uniform && r.gaps.is_empty() && r.notices().is_empty());
    }

    #[test]
    fn lost_samples_are_a_gap_not_jitter() {
        let mut t = grid(1000, 1e-3);
        t.drain(500..503); // three samples lost: one 4 ms interval
        let r = TimingReport::of(&t);
        assert_eq!(r.gaps.len(), 1);
        assert_eq!(r.gaps[0], Gap { index: 500, t: t[500], dt: t[500] - t[499] });
        assert!((r.gaps[0].dt - 4e-3).abs() < 1e-12);
        assert_eq!(r.missing_samples(), 3);
        // A corrupt time far beyond the others is counted, not overflowed (a fuzzer's find).
        let corrupt = TimingReport::of(&[0.0, 1.0, 2.0, 3.0, 6e42, 7e42]);
        assert_eq!(corrupt.missing_samples(), usize::MAX);
        assert!(r.max_jitter < 1e-12, "a gap must not count as jitter");
        assert!(!r.uniform);
        assert!(r.notices()[0].contains("3 sample(s)"), "{:?}", r.notices());
    }

    #[test]
    fn jitter_is_measured_against_the_median() {
        // 1 kHz with ±20 µs timestamp jitter on every other sample.
        let t: Vec<f64> = (0..201).map(|k| k as f64 * 1e-3 + if k % 2 == 1 { 20e-6 } else { 0.0 }).collect();
        let r = TimingReport::of(&t);
        assert!(r.gaps.is_empty());
        assert!((r.max_jitter - 20e-6).abs() < 1e-12, "{}", r.max_jitter);
        assert!(!r.uniform);
        assert_eq!(r.notices().len(), 1);
        assert!(r.notices()[0].contains("jitter"));
    }
}
