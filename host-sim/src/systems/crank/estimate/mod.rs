//! Clearance estimation from a recording of the crank angular acceleration.
//!
//! * [`ukf`]: the paper's estimator, a one-state unscented Kalman filter whose three sigma
//!   points are clearance simulations (8 per sigma point, their mean is the prediction), one
//!   step per 0.25 s window, measuring the spectral feature `a` ([`super::feature`]), the
//!   release window measured last. On recordings of 0.25 mm at A from an independent run
//!   (adaptive integrator at 1e-9): 4 s, all of 2 recordings × 3 starts (0.01, 0.1, 0.2 mm)
//!   within ±3.5 % (CI test: −3.0, +3.1, +1.4 %); 10 s, 4 of 9 within ±5 %, 8 of 9 within
//!   ±11 %, one at −35 % (`cargo run --release -p edgekf-sim --features studies --example crank_study -- ukf 10
//!   3`). Almost all the information is in the release window, whose `a` is many-branched in
//!   the clearance (see [`ukf`]); ~1 000 simulations of 0.25 s per 10 s;
//! * [`model`]: the fast estimator. Ten cheap time-domain features of the recording, a linear
//!   discriminant that names the joint with the clearance and a per-joint regression for its
//!   size; then the release stage ([`release`]): the time of the first contact seen after
//!   release and the crank acceleration before it give the clearance through per-joint laws
//!   (`c ∝ t₁²`). Learned on the host from the reference simulator ([`train`], ordered by
//!   [`training`] for `edgekf crank train`) and built in as `fast_model.toml`; no simulation at run time;
//! * [`fast`]: the earlier single-feature map (impact rate → clearance at A), kept for old
//!   `--model` files.
//!
//! Measured (built-in model; unseen seeds and draws of release 20–40° and journal radius
//! × 0.8–1.2, 10 s, adaptive integrator; `EDGEKF_LONG=1 cargo test --release -p edgekf-sim
//! --test crank_identify`): the joint is named right in all 108 test runs (A, B, C × 0.1–0.5
//! mm in 0.05 mm steps × 4). The clearance of the named joint is within RMS 0.8 %, 107 of 108
//! within ±3 %, worst +3.7 % (B at 0.1 mm, where one sample is 2.2 % of the clearance). The
//! window features alone reach RMS 8.5 %, worst 26 %: 10 s of chaotic impacts scatter them
//! (six runs at 0.3 mm released 30.00°, 30.01° … 30.05° give 0.269–0.321 mm at A). Two
//! clearances at once are outside the model: over A 0.15–0.35 mm × B 0.1–0.25 mm (30°, 10 s)
//! the window features name A and read 0.10–0.19 mm, while the discriminant score of A jumps
//! from ~150 (one clearance) to ~550–640 (the `studies` feature's `identify2`: a 10 s recording bounds
//! cA and cB at 0.25 + 0.15 mm to ~13 % and ~15 %, not ±10 %). The features cost 32 operations per
//! sample (3.2 M for 10 s, 1 ms), the release detector ~40 per sample until the contact; the
//! UKF integrates 30 steps of the full model per sample (3 M steps for 10 s, 0.96 s in
//! release).
//!
//! Both read a [`Recording`] (a data CSV with `t` and `crank_alpha`; `truth_clearance_*`
//! columns, when present, are only reported) and write one [`EstimateRow`] per window
//! ([`write_estimates`]: columns `t, clearance_A, clearance_B, clearance_C` in m, 0 for a
//! joint judged tight), the last row being the estimate for the whole recording.
//!
//! Lost samples, as on every system, are missing samples: [`Recording::read`] puts the rows lost
//! from the time column back as empty cells ([`crate::io::timeline`]), so a deleted row and an
//! emptied cell give the same estimate. [`model`] steps through them as the node does (the
//! window statistics skip them, the release detector counts their time). [`ukf`] and [`fast`]
//! compare spectra and impact statistics of whole windows, which a hole changes (a hole is not
//! an impact-free stretch), so they refuse a recording with a missing sample in a window they use
//! ([`Recording::require_every_sample`]), naming its time, rather than answer wrongly.

pub mod chip;
pub mod fast;
pub mod model;
pub mod release;
pub mod runs;
pub mod train;
pub mod trained_for;
pub mod training;
pub mod ukf;

use super::simulate::CrankRecording;
use super::Joint;
use crate::io::data::{self, DataError};
use crate::io::timeline::{bridge, Bridging, TimelineOptions};
use std::path::Path;

/// The measured channel of a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// Sample times, s (uniform).
    pub t: Vec<f64>,
    /// Measured crank angular acceleration, rad/s²; NaN for a missing sample.
    pub crank_alpha: Vec<f64>,
    /// Sample rate, Hz.
    pub sample_rate: f64,
    /// The true clearances (m, 0 = ideal) if the file carries `truth_clearance_*` columns.
    pub truth_clearance: Option<[f64; 3]>,
}

impl Recording {
    /// The measured channel of a simulated run.
    pub fn from_simulation(rec: &CrankRecording, sample_rate: f64) -> Self {
        Self {
            t: rec.t.clone(),
            crank_alpha: rec.crank_alpha.clone(),
            sample_rate,
            truth_clearance: Some(rec.clearances.map(|c| c.unwrap_or(0.0))),
        }
    }

    /// Reads `t` and `crank_alpha` (and `truth_clearance_A/B/C` if present) from a data CSV, on
    /// one timeline ([`bridge`]): rows lost from the time column come back as missing samples
    /// (NaN), exactly like empty cells, so the estimators see every sample at its time.
    ///
    /// A gap longer than `timeline.max_gap_s` (where the other systems restart their filters)
    /// ends the recording: the estimate is for one run from its release (the release stage times
    /// the first contact from the first sample, and the window features were learned on runs
    /// from release), so the rows after it are not used, and a notice says how many.
    ///
    /// Returns the recording and the lines to show the user: the file's report, then the
    /// timeline's notices.
    pub fn read(path: &Path, timeline: &TimelineOptions) -> anyhow::Result<(Self, Vec<String>)> {
        let names = ["crank_alpha", "truth_clearance_A", "truth_clearance_B", "truth_clearance_C"];
        // The data error already names its cause and file.
        let (file, report) = data::read(path, &names).map_err(|e| anyhow::anyhow!("{e}"))?;
        let (file, bridged) = bridge(&file, &report.timing, timeline);
        let end = bridged.restarts.first().map_or(file.len(), |r| r.row);
        let mut notes = vec![format!("{}: {report}", path.display())];
        notes.extend(Self::used(&bridged, end).notices().into_iter().map(|n| format!("notice: {n}")));
        if let Some(r) = bridged.restarts.first() {
            notes.push(format!(
                "notice: timeline: a {:.3} s gap before t = {:.6} s is longer than timeline.max_gap_s; the estimate is \
                 for one run from its release, so it ends there: {} row(s) from t = {:.6} s on are not used",
                r.gap_s,
                r.t,
                file.len() - end,
                r.t
            ));
        }
        let alpha =
            file.column("crank_alpha").ok_or_else(|| anyhow::anyhow!("{}: no column `crank_alpha`", path.display()))?;
        let truth: Vec<Option<f64>> = Joint::ALL
            .iter()
            .map(|j| {
                let column = file.column(&format!("truth_clearance_{j}"))?;
                column.iter().copied().find(|v| v.is_finite())
            })
            .collect();
        let truth_clearance = truth.iter().all(Option::is_some).then(|| [0, 1, 2].map(|i| truth[i].unwrap_or(0.0)));
        let rec = Self {
            t: file.t[..end].to_vec(),
            crank_alpha: alpha[..end].to_vec(),
            sample_rate: report.timing.sample_rate,
            truth_clearance,
        };
        Ok((rec, notes))
    }

    /// What the bridging did to the rows before `end` (the part of the file used).
    fn used(bridged: &Bridging, end: usize) -> Bridging {
        let filled: Vec<_> = bridged.filled.iter().filter(|r| r.end <= end).cloned().collect();
        Bridging {
            inserted: filled.iter().map(ExactSizeIterator::len).sum(),
            gaps: filled.len(),
            filled,
            restarts: Vec::new(),
            slow_channels: bridged.slow_channels.clone(),
        }
    }

    /// Missing samples (lost from the time column, or empty or NaN cells).
    pub fn missing(&self) -> usize {
        self.crank_alpha.iter().filter(|v| !v.is_finite()).count()
    }

    /// For an estimator that needs every one of the first `samples` samples: an error naming
    /// the first missing one's time, then `why` (why it needs them, and what to use instead).
    ///
    /// ```
    /// use edgekf_sim::systems::crank::estimate::Recording;
    /// let rec = Recording { t: vec![0.0, 0.1, 0.2, 0.3], crank_alpha: vec![1.0, 2.0, 3.0, f64::NAN],
    ///     sample_rate: 10.0, truth_clearance: None };
    /// assert!(rec.require_every_sample(3, "").is_ok()); // the 4th sample is not used
    /// let e = rec.require_every_sample(4, "the spectra need every sample").unwrap_err();
    /// assert!(e.contains("t = 0.300000 s") && e.ends_with("; the spectra need every sample"), "{e}");
    /// ```
    pub fn require_every_sample(&self, samples: usize, why: &str) -> Result<(), String> {
        let used = &self.crank_alpha[..samples.min(self.crank_alpha.len())];
        match used.iter().position(|v| !v.is_finite()) {
            None => Ok(()),
            Some(k) => Err(format!(
                "sample(s) missing from t = {:.6} s ({} in all: rows lost from the time column or empty cells); {why}",
                self.t.get(k).copied().unwrap_or(f64::NAN),
                self.missing()
            )),
        }
    }

    /// Samples in a window of `window_s` seconds (0 if not representable).
    pub fn window_len(&self, window_s: f64) -> usize {
        let n = (window_s * self.sample_rate).round();
        if (1.0..1e12).contains(&n) {
            n as usize
        } else {
            0
        }
    }
}

/// One line of an estimate file: the clearances after a window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimateRow {
    /// End of the window, s (for the last, whole-recording row: the end of the recording).
    pub t: f64,
    /// Clearance at A, B, C, m (0: judged tight).
    pub clearance: [f64; 3],
}

/// Writes estimate rows as a data CSV with columns `t, clearance_A, clearance_B, clearance_C`.
pub fn write_estimates(path: &Path, rows: &[EstimateRow]) -> Result<(), DataError> {
    let t: Vec<f64> = rows.iter().map(|r| r.t).collect();
    let cols: Vec<Vec<f64>> = (0..3).map(|j| rows.iter().map(|r| r.clearance[j]).collect()).collect();
    let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
    data::write(path, &["clearance_A", "clearance_B", "clearance_C"], &t, &refs)
}
