//! Plain-text summaries of estimator runs, as the CLI prints them.
//!
//! A summary compares one or more runs (e.g. the same filter in `f64` and `f32`) with the truth
//! where the data carry it: the force amplitude over steady stretches, RMS errors, innovations
//! against the sensor noise, the NIS against its 99 % band, and every counter, so a failing run
//! is visible at a glance rather than averaged away.

use crate::io::data::DataFile;
use crate::systems::oscillator::estimate::{window_mean, Estimates, WindowStats};
use crate::systems::oscillator::sim::ForceConfig;
use std::fmt::{self, Write as _};

/// Steady stretches of a run: the second half of each interval of constant force between
/// `t_start`, the force changes and `t_end`, so that the filter has had half the stretch to
/// settle. For the demo (step at 6 s, 12 s run) these are 3–6 s and 9–12 s.
///
/// ```
/// use edgekf_sim::systems::oscillator::sim::ForceConfig;
/// use edgekf_sim::systems::oscillator::report::steady_windows;
/// assert_eq!(steady_windows(&ForceConfig::default(), 0.0, 12.0), [(3.0, 6.0), (9.0, 12.0)]);
/// ```
pub fn steady_windows(force: &ForceConfig, t_start: f64, t_end: f64) -> Vec<(f64, f64)> {
    let mut bounds = vec![t_start];
    bounds.extend(force.changes.iter().map(|c| c.t).filter(|&t| t > t_start && t < t_end));
    bounds.push(t_end);
    bounds.windows(2).map(|w| (0.5 * (w[0] + w[1]), w[1])).filter(|(a, b)| b > a).collect()
}

/// A summary table of estimator runs over the same data.
#[derive(Debug, Clone)]
pub struct Summary<'a> {
    /// Heading lines.
    pub title: String,
    /// The data the runs used (its `truth_*` columns give the truth column of the table).
    pub data: &'a DataFile,
    /// Named runs, one table column each.
    pub runs: Vec<(&'a str, &'a Estimates)>,
    /// Windows for the window rows (see [`steady_windows`]).
    pub windows: Vec<(f64, f64)>,
    /// Per-sample sensor noise, m/s², shown next to the innovation RMS.
    pub noise_std: Option<f64>,
}

const LABEL: usize = 44;
const CELL: usize = 11;

impl Summary<'_> {
    fn row(&self, out: &mut String, label: &str, truth: Option<String>, cell: impl Fn(&Estimates) -> String) {
        let _ = write!(out, "{label:<LABEL$} {:>CELL$}", truth.unwrap_or_else(|| "—".into()));
        for (_, e) in &self.runs {
            let _ = write!(out, " {:>CELL$}", cell(e));
        }
        out.push('\n');
    }
}

impl Summary<'_> {
    /// Why a NIS row lies outside its band, where the windows tell (the first run's figures):
    /// a whole-run NIS above it while the steady windows are not comes from the catch-up after
    /// the force changes (the windows' ends but the last); steady windows below it mean the
    /// filter expects larger innovations than it gets, its process noise being set to follow a
    /// change that a steady force does not make.
    fn nis_notes(&self, out: &mut String) {
        let Some((_, e)) = self.runs.first() else { return };
        let windows: Vec<_> = self.windows.iter().map(|&(t0, t1)| e.window(t0, t1)).collect();
        if windows.is_empty() {
            return;
        }
        let changes: Vec<String> = windows[..windows.len() - 1].iter().map(|w| format!("{} s", w.t1)).collect();
        let steady: Vec<String> =
            windows.iter().map(|w| format!("{:.2} over {}–{} s", w.nis_mean, w.t0, w.t1)).collect();
        let whole = e.nis_bounds();
        let calm = windows.iter().all(|w| w.nis_mean <= w.nis_bounds().upper);
        if e.nis_mean > whole.upper && calm && !changes.is_empty() {
            let _ = writeln!(
                out,
                "note: the NIS over t ≥ {} s ({:.2}) is above its band because it takes in the filter catching up \
                 after the force changes at {}: its innovations grow until the estimate follows. Over the steady \
                 windows it is {}.",
                e.error_rms.from_t,
                e.nis_mean,
                changes.join(", "),
                steady.join(", ")
            );
        }
        let low: Vec<&WindowStats> = windows.iter().filter(|w| w.nis_mean < w.nis_bounds().lower).collect();
        if !low.is_empty() {
            let rms = low.iter().map(|w| w.innovation_rms).sum::<f64>() / low.len() as f64;
            let nis = low.iter().map(|w| w.nis_mean).sum::<f64>() / low.len() as f64;
            let _ = writeln!(
                out,
                "note: below its band over steady force the filter is conservative, not wrong: its innovations \
                 ({:.3} mm/s² RMS) are smaller than it expects (√S ≈ {:.3} mm/s²), its force process noise being \
                 set to follow changes that a steady force does not make.",
                rms * 1e3,
                rms / nis.sqrt() * 1e3
            );
        }
    }
}

/// A table cell: fixed decimals for ordinary magnitudes, scientific notation for values too large
/// to fit (a diverged filter must still print a readable table), a dash for NaN.
fn num(v: f64, decimals: usize) -> String {
    if v.is_nan() {
        "—".into()
    } else if v.is_finite() && v.abs() < 1e5 {
        format!("{v:.decimals$}")
    } else {
        format!("{v:.2e}")
    }
}

impl fmt::Display for Summary<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut out = String::new();
        out.push_str(&self.title);
        if !self.title.ends_with('\n') {
            out.push('\n');
        }
        out.push('\n');
        let _ = write!(out, "{:<LABEL$} {:>CELL$}", "", "truth");
        for (name, _) in &self.runs {
            let _ = write!(out, " {name:>CELL$}");
        }
        out.push('\n');

        let truth_amp = self.data.column("truth_force_amplitude");
        for &(t0, t1) in &self.windows {
            let truth = truth_amp.and_then(|c| window_mean(&self.data.t, c, t0, t1)).map(|v| num(v, 4));
            self.row(&mut out, &format!("force amplitude, mean {t0}–{t1} s [N]"), truth, |e| {
                e.window(t0, t1).force_amplitude.map_or("—".into(), |v| num(v, 4))
            });
        }
        for &(t0, t1) in &self.windows {
            self.row(&mut out, &format!("force amplitude, std {t0}–{t1} s [N]"), None, |e| {
                num(e.window(t0, t1).force_amplitude_std, 4)
            });
        }
        if let Some((_, first)) = self.runs.first() {
            let from = first.error_rms.from_t;
            self.row(&mut out, &format!("force amplitude, RMS error t ≥ {from} s [N]"), None, |e| {
                e.error_rms.force_amplitude.map_or("—".into(), |v| num(v, 4))
            });
            self.row(&mut out, &format!("displacement, RMS error t ≥ {from} s [µm]"), None, |e| {
                e.error_rms.displacement.map_or("—".into(), |v| num(v * 1e6, 3))
            });
        }
        let sigma = self.noise_std.map(|s| format!("σ {}", num(s * 1e3, 3)));
        for &(t0, t1) in &self.windows {
            self.row(&mut out, &format!("innovation RMS {t0}–{t1} s [mm/s²]"), sigma.clone(), |e| {
                num(e.window(t0, t1).innovation_rms * 1e3, 3)
            });
        }
        if let Some((_, first)) = self.runs.first() {
            let from = first.error_rms.from_t;
            self.row(&mut out, &format!("innovation RMS t ≥ {from} s [mm/s²]"), sigma.clone(), |e| {
                num(e.innovation_rms * 1e3, 3)
            });
        }
        for &(t0, t1) in &self.windows {
            let band = self.runs.first().map(|(_, e)| e.window(t0, t1).nis_bounds());
            let label = match band {
                Some(b) => format!("NIS mean {t0}–{t1} s (99 %: {:.2}–{:.2})", b.lower, b.upper),
                None => format!("NIS mean {t0}–{t1} s"),
            };
            self.row(&mut out, &label, Some("1".into()), |e| num(e.window(t0, t1).nis_mean, 3));
        }
        if let Some((_, first)) = self.runs.first() {
            let b = first.nis_bounds();
            let label = format!("NIS mean t ≥ {} s (99 %: {:.2}–{:.2})", first.error_rms.from_t, b.lower, b.upper);
            self.row(&mut out, &label, Some("1".into()), |e| num(e.nis_mean, 3));
        }
        self.row(&mut out, "steps", None, |e| e.counters.steps.to_string());
        self.row(&mut out, "missing samples (NaN + clipped + gap)", None, |e| {
            format!("{}+{}+{}", e.input.nan, e.input.clipped, e.input.gap_steps)
        });
        self.row(&mut out, "gated (NIS above the gate)", None, |e| e.counters.gated.to_string());
        self.row(&mut out, "covariance resets", None, |e| e.counters.filter.covariance_resets.to_string());
        self.row(&mut out, "refused updates", None, |e| e.counters.filter.refused_updates.to_string());
        self.nis_notes(&mut out);
        for (name, e) in &self.runs {
            let h = e.counters.filter;
            if h.covariance_resets > 0 || h.refused_updates > 0 {
                let _ = writeln!(
                    out,
                    "warning: {name}: the filter lost positive definiteness ({} covariance resets, {} refused \
                     updates); its estimates are not trustworthy while that happens",
                    h.covariance_resets, h.refused_updates
                );
            }
        }
        f.write_str(&out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::systems::oscillator::estimate::{run, EstimateOptions};
    use crate::systems::oscillator::scenario::Scenario;

    #[test]
    fn cells_stay_narrow_whatever_the_value() {
        assert_eq!(num(5.00018, 4), "5.0002");
        assert_eq!(num(f64::NAN, 4), "—");
        assert_eq!(num(2.5e22, 4), "2.50e22");
        assert_eq!(num(f64::INFINITY, 4), "inf");
    }

    #[test]
    fn windows_follow_the_force_changes() {
        let mut f = ForceConfig::default();
        assert_eq!(steady_windows(&f, 0.0, 12.0), [(3.0, 6.0), (9.0, 12.0)]);
        f.changes.clear();
        assert_eq!(steady_windows(&f, 1.0, 11.0), [(6.0, 11.0)]);
        // A change outside the data is ignored.
        assert_eq!(steady_windows(&ForceConfig::default(), 0.0, 4.0), [(2.0, 4.0)]);
    }

    #[test]
    fn the_table_shows_truth_estimates_and_counters() {
        let s = Scenario { duration_s: 4.0, ..Default::default() };
        let d = s.simulate().to_data_file();
        let e = run::<f64>(&d, &s.estimator_params(), &EstimateOptions::default()).unwrap();
        let table = Summary {
            title: "test".into(),
            data: &d,
            runs: vec![("f64", &e)],
            windows: steady_windows(&s.force, 0.0, 4.0),
            noise_std: Some(s.sensor.noise_std()),
        }
        .to_string();
        let line = |start: &str| table.lines().find(|l| l.starts_with(start)).unwrap_or_else(|| panic!("{table}"));
        let amp: Vec<&str> = line("force amplitude, mean 2–4 s").split_whitespace().collect();
        assert_eq!(amp[amp.len() - 2], "5.0000");
        assert!(amp[amp.len() - 1].starts_with("5.000"), "{table}");
        assert!(line("innovation RMS 2–4 s").contains("σ 4.857"), "{table}");
        assert!(line("steps").ends_with("4000"));
        assert!(line("missing samples").ends_with("0+0+0"));
    }

    #[test]
    fn the_demo_says_why_its_nis_leaves_the_band() {
        // The demo's 12 s: the force steps at 6 s; the whole run's NIS takes in the catch-up.
        let s = Scenario::default();
        let d = s.simulate().to_data_file();
        let e = run::<f64>(&d, &s.estimator_params(), &EstimateOptions::default()).unwrap();
        let t_end = d.t.last().copied().unwrap() + 1e-3;
        let table = Summary {
            title: "demo".into(),
            data: &d,
            runs: vec![("f64", &e)],
            windows: steady_windows(&s.force, 0.0, t_end),
            noise_std: Some(s.sensor.noise_std()),
        }
        .to_string();
        assert!(e.nis_mean > e.nis_bounds().upper, "{table}");
        assert!(
            table.contains(
                "is above its band because it takes in the filter catching up after the force changes at 6 s"
            ),
            "{table}"
        );
        assert!(table.contains("the filter is conservative, not wrong"), "{table}");
    }
}
