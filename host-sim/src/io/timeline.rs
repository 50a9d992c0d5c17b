//! One timeline for every system: lost samples become missing samples.
//!
//! Every filter in edgekf is discretised for one sample period, so a row is a sample. A file
//! whose recorder dropped rows (a gap in `t`) must not be read as if no time had passed: that
//! turns a 21 ms gap into an apparent jump of the rotor and the loop into four spurious effects.
//! [`bridge`] puts the lost samples back as rows of empty cells, on the file's own clock, so
//! every estimator predicts through them exactly as it does through empty cells; a gap longer
//! than [`TimelineOptions::max_gap_s`] is not filled (it could be hours) but marked as a
//! restart, where the filters start again from their prior. Jitter is reported, not corrected.
//!
//! Channels may have their own rates (a 5 Hz DVL among 50 Hz IMU columns): a channel whose
//! values come every `k` rows is reported as such ([`ChannelRate`]), and its empty cells
//! between updates are not dropouts.

use super::data::{DataFile, TimingReport};
use serde::{Deserialize, Serialize};

/// `[timeline]` of a configuration.
///
/// ```toml
/// [timeline]
/// max_gap_s = 2.0   # longer gaps restart the filters instead of being bridged
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct TimelineOptions {
    /// Gaps up to this long are bridged by prediction, longer ones restart the filters, s.
    pub max_gap_s: f64,
}

impl Default for TimelineOptions {
    fn default() -> Self {
        Self { max_gap_s: 2.0 }
    }
}

impl TimelineOptions {
    /// Checks the figure; the message names the key.
    pub fn validate(&self) -> Result<(), String> {
        if self.max_gap_s.is_finite() && self.max_gap_s > 0.0 {
            Ok(())
        } else {
            Err(format!("timeline.max_gap_s = {} must be a positive number of seconds", self.max_gap_s))
        }
    }
}

/// A gap too long to bridge: the filters restart at `row`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Restart {
    /// Row of the bridged file where the filters start again.
    pub row: usize,
    /// Its time, s.
    pub t: f64,
    /// The gap before it, s.
    pub gap_s: f64,
}

/// A channel updated every `every` rows (a slower sensor among faster ones).
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelRate {
    /// The channel.
    pub name: String,
    /// Rows between its values.
    pub every: usize,
    /// Its rate, Hz.
    pub rate_hz: f64,
}

/// What [`bridge`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Bridging {
    /// Rows of empty cells inserted for lost samples.
    pub inserted: usize,
    /// Gaps bridged.
    pub gaps: usize,
    /// The inserted rows of the bridged file, one range per gap bridged.
    pub filled: Vec<std::ops::Range<usize>>,
    /// Gaps longer than `max_gap_s`, where the filters restart.
    pub restarts: Vec<Restart>,
    /// Channels slower than the file's rate.
    pub slow_channels: Vec<ChannelRate>,
}

impl Bridging {
    /// One line per thing a user should know (empty when the timeline needed nothing).
    pub fn notices(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.inserted > 0 {
            out.push(format!(
                "timeline: {} gap(s) bridged: {} lost sample(s) predicted through as missing samples",
                self.gaps, self.inserted
            ));
        }
        for r in &self.restarts {
            out.push(format!(
                "timeline: a {:.3} s gap before t = {:.6} s is longer than timeline.max_gap_s: the filters restart there",
                r.gap_s, r.t
            ));
        }
        // Channels of one sensor (the same spacing) described once.
        let mut described: Vec<usize> = Vec::new();
        for c in &self.slow_channels {
            if described.contains(&c.every) {
                continue;
            }
            described.push(c.every);
            let names: Vec<String> =
                self.slow_channels.iter().filter(|o| o.every == c.every).map(|o| format!("`{}`", o.name)).collect();
            let (verb, its) = if names.len() == 1 { ("is", "its") } else { ("are", "their") };
            out.push(format!(
                "timeline: {} {verb} updated every {} rows ({:.3} Hz); {its} empty cells between updates are not dropouts",
                names.join(", "),
                c.every,
                c.rate_hz
            ));
        }
        out
    }

    /// Whether `count` empty cells of channel `name` in `rows` rows are no more than its
    /// updates leave between them (a slow channel with no dropout of its own).
    pub fn only_between_updates(&self, name: &str, count: usize, rows: usize) -> bool {
        self.slow_channels.iter().any(|c| c.name == name && count <= rows - rows.div_ceil(c.every))
    }

    /// For each of the bridged file's `rows`, whether it was inserted for a lost sample (one
    /// pass, for estimators that ask per sample).
    pub fn filled_mask(&self, rows: usize) -> Vec<bool> {
        let mut mask = vec![false; rows];
        for r in &self.filled {
            if let Some(m) = mask.get_mut(r.clone()) {
                m.fill(true);
            }
        }
        mask
    }

    /// Whether the filters restart at `row`.
    pub fn restarts_at(&self, row: usize) -> bool {
        self.restarts.iter().any(|r| r.row == row)
    }

    /// The stretches of rows between restarts, as `start..end`.
    ///
    /// ```
    /// use edgekf_sim::io::timeline::{Bridging, Restart};
    /// let b = Bridging { restarts: vec![Restart { row: 40, t: 9.0, gap_s: 5.0 }], ..Bridging::default() };
    /// assert_eq!(b.stretches(100), [0..40, 40..100]);
    /// ```
    pub fn stretches(&self, rows: usize) -> Vec<std::ops::Range<usize>> {
        let mut starts: Vec<usize> = std::iter::once(0).chain(self.restarts.iter().map(|r| r.row)).collect();
        starts.dedup();
        let ends = starts.iter().skip(1).copied().chain(std::iter::once(rows));
        starts.iter().zip(ends).map(|(&a, b)| a..b).collect()
    }
}

/// The most rows one gap may add when the file is shorter (more than the file's own rows
/// otherwise); a longer gap restarts the filters instead.
pub const MAX_FILL: usize = 100_000;

/// `data` on one timeline: each gap of `timing` up to `max_gap_s` filled with rows of empty
/// cells (`round(dt / dt_median) − 1` of them, evenly spaced between its ends), longer gaps
/// (and gaps of more than [`MAX_FILL`] samples and of the file's length) marked as restarts;
/// and the channels slower than the file's rate.
///
/// ```
/// use edgekf_sim::io::data::{DataFile, TimingReport};
/// use edgekf_sim::io::timeline::{bridge, TimelineOptions};
/// let data = DataFile { sha256: None, names: vec!["ax".into()], t: vec![0.0, 0.001, 0.004, 0.005], columns: vec![vec![1.0, 2.0, 5.0, 6.0]] };
/// let (b, what) = bridge(&data, &TimingReport::of(&data.t), &TimelineOptions::default());
/// assert_eq!(what.inserted, 2);
/// assert_eq!(b.t.len(), 6);
/// assert!((b.t[2] - 0.002).abs() < 1e-12 && b.columns[0][2].is_nan() && b.columns[0][4] == 5.0);
/// ```
pub fn bridge(data: &DataFile, timing: &TimingReport, options: &TimelineOptions) -> (DataFile, Bridging) {
    let mut what = Bridging { slow_channels: slow_channels(data, timing), ..Bridging::default() };
    if timing.gaps.is_empty() {
        return (data.clone(), what);
    }
    let mut out = DataFile {
        sha256: data.sha256.clone(),
        names: data.names.clone(),
        t: Vec::new(),
        columns: vec![Vec::new(); data.columns.len()],
    };
    let mut gaps = timing.gaps.iter().peekable();
    for k in 0..data.t.len() {
        if let Some(gap) = gaps.next_if(|g| g.index == k) {
            // A gap of more samples than the file holds (a corrupt `t` or a tiny period) is not
            // filled: the rows it would add could exhaust the memory.
            let too_many = timing.samples_lost_in(gap) > data.t.len().max(MAX_FILL);
            if gap.dt > options.max_gap_s || too_many {
                what.restarts.push(Restart { row: out.t.len(), t: gap.t, gap_s: gap.dt });
            } else {
                let lost = timing.samples_lost_in(gap);
                what.filled.push(out.t.len()..out.t.len() + lost);
                let t0 = data.t[k - 1];
                for j in 1..=lost {
                    out.t.push(t0 + gap.dt * j as f64 / (lost + 1) as f64);
                    for c in &mut out.columns {
                        c.push(f64::NAN);
                    }
                }
                what.inserted += lost;
                what.gaps += 1;
            }
        }
        out.t.push(data.t[k]);
        for (o, c) in out.columns.iter_mut().zip(&data.columns) {
            o.push(c[k]);
        }
    }
    (out, what)
}

/// Channels (not `truth_`) whose values come at a fixed spacing of two rows or more: at least
/// nine in ten of the spacings between their values are the same.
fn slow_channels(data: &DataFile, timing: &TimingReport) -> Vec<ChannelRate> {
    let mut out = Vec::new();
    for (name, col) in data.names.iter().zip(&data.columns) {
        if name.starts_with(super::data::TRUTH_PREFIX) {
            continue;
        }
        let rows: Vec<usize> = (0..col.len()).filter(|&k| col[k].is_finite()).collect();
        if rows.len() < 3 {
            continue;
        }
        let spacings: Vec<usize> = rows.windows(2).map(|w| w[1] - w[0]).collect();
        let mut sorted = spacings.clone();
        sorted.sort_unstable();
        let every = sorted[sorted.len() / 2];
        let regular = spacings.iter().filter(|&&s| s == every).count();
        if every >= 2 && regular * 10 >= spacings.len() * 9 {
            out.push(ChannelRate { name: name.clone(), every, rate_hz: timing.sample_rate / every as f64 });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(t: Vec<f64>) -> DataFile {
        let x = t.iter().map(|v| v * 10.0).collect();
        DataFile { sha256: None, names: vec!["x".into()], t, columns: vec![x] }
    }

    #[test]
    fn deleted_rows_come_back_as_empty_cells_on_the_same_clock() {
        let full: Vec<f64> = (0..2000).map(|k| k as f64 * 1e-3).collect();
        let mut t = full.clone();
        t.drain(500..521); // a 21 ms gap
        let data = file(t);
        let (b, what) = bridge(&data, &TimingReport::of(&data.t), &TimelineOptions::default());
        assert_eq!((what.inserted, what.gaps, b.t.len()), (21, 1, 2000));
        let filled = what.filled_mask(b.t.len());
        assert!(filled[500] && filled[520] && !filled[521] && !filled[499]);
        assert_eq!(filled.iter().filter(|f| **f).count(), 21);
        for (a, e) in b.t.iter().zip(&full) {
            assert!((a - e).abs() < 1e-12, "{a} vs {e}");
        }
        assert!(b.columns[0][500..521].iter().all(|v| v.is_nan()));
        assert_eq!(b.columns[0][521], full[521] * 10.0);
    }

    #[test]
    fn a_gap_longer_than_the_limit_is_a_restart_not_a_million_rows() {
        let mut t: Vec<f64> = (0..100).map(|k| k as f64 * 1e-3).collect();
        t.extend((0..100).map(|k| 3600.0 + k as f64 * 1e-3));
        let data = file(t);
        let (b, what) = bridge(&data, &TimingReport::of(&data.t), &TimelineOptions::default());
        assert_eq!(b.t.len(), 200);
        assert_eq!(what.restarts.len(), 1);
        assert_eq!(what.restarts[0].row, 100);
        assert_eq!(what.stretches(200), [0..100, 100..200]);
        assert!(what.notices()[0].contains("restart"));
    }

    /// A 1 s gap is within `max_gap_s`, but at a 1 ns period it is 10⁹ samples: more than the
    /// file and [`MAX_FILL`] allow, so it is a restart and the memory is safe.
    #[test]
    fn a_gap_of_more_samples_than_allowed_is_a_restart() {
        let mut t: Vec<f64> = (0..100).map(|k| k as f64 * 1e-9).collect();
        t.extend((0..100).map(|k| 1.0 + k as f64 * 1e-9));
        let data = file(t);
        let (b, what) = bridge(&data, &TimingReport::of(&data.t), &TimelineOptions::default());
        assert_eq!((b.t.len(), what.inserted, what.restarts.len()), (200, 0, 1));
    }

    #[test]
    fn a_slow_channel_is_a_rate_not_dropouts() {
        let t: Vec<f64> = (0..500).map(|k| k as f64 * 0.02).collect();
        let imu: Vec<f64> = t.clone();
        let dvl: Vec<f64> = (0..500).map(|k| if k % 10 == 0 { 1.0 } else { f64::NAN }).collect();
        let data = DataFile { sha256: None, names: vec!["imu".into(), "dvl".into()], t, columns: vec![imu, dvl] };
        let (_, what) = bridge(&data, &TimingReport::of(&data.t), &TimelineOptions::default());
        assert_eq!(what.slow_channels.len(), 1, "{:?}", what.slow_channels);
        let dvl = &what.slow_channels[0];
        assert_eq!((dvl.name.as_str(), dvl.every), ("dvl", 10));
        assert!((dvl.rate_hz - 5.0).abs() < 1e-9, "{}", dvl.rate_hz);
    }
}
