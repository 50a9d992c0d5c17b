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

pub mod chip;
pub mod fast;
pub mod model;
pub mod release;
pub mod train;
pub mod trained_for;
pub mod training;
pub mod ukf;

use super::simulate::CrankRecording;
use super::Joint;
use crate::io::data::{self, DataError};
use crate::io::timeline::{bridge, TimelineOptions};
use std::path::Path;

/// The measured channel of a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// Sample times, s (uniform).
    pub t: Vec<f64>,
    /// Measured crank angular acceleration, rad/s².
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

    /// Reads `t` and `crank_alpha` (and `truth_clearance_A/B/C` if present) from a data CSV.
    /// Missing samples are refused: the spectra need every sample.
    pub fn read(path: &Path) -> anyhow::Result<Self> {
        let names = ["crank_alpha", "truth_clearance_A", "truth_clearance_B", "truth_clearance_C"];
        // The data error already names its cause and file.
        let (file, report) = data::read(path, &names).map_err(|e| anyhow::anyhow!("{e}"))?;
        let (file, timeline) = bridge(&file, &report.timing, &TimelineOptions::default());
        if let Some(gap) = timeline.filled.first().map(|r| r.start).or(timeline.restarts.first().map(|r| r.row)) {
            anyhow::bail!(
                "{}: samples are lost in the time column before t = {:.6} s; the spectra need every sample",
                path.display(),
                file.t.get(gap).copied().unwrap_or(f64::NAN)
            );
        }
        let alpha =
            file.column("crank_alpha").ok_or_else(|| anyhow::anyhow!("{}: no column `crank_alpha`", path.display()))?;
        if alpha.iter().any(|v| !v.is_finite()) {
            anyhow::bail!("{}: column `crank_alpha` has missing samples; the spectra need them all", path.display());
        }
        let truth: Vec<Option<f64>> = Joint::ALL
            .iter()
            .map(|j| file.column(&format!("truth_clearance_{j}")).and_then(|c| c.first().copied()))
            .collect();
        let truth_clearance = truth.iter().all(Option::is_some).then(|| [0, 1, 2].map(|i| truth[i].unwrap_or(0.0)));
        Ok(Self {
            t: file.t.clone(),
            crank_alpha: alpha.to_vec(),
            sample_rate: report.timing.sample_rate,
            truth_clearance,
        })
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
