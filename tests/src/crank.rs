//! Slider-crank joint clearance on the node: the firmware's crank image run on the host over the
//! same CSV text the QEMU image reads, the parsing of its output (the image's or the host
//! run's), and the original two-pass host features as an oracle for the streaming ones.

use crate::faulty::FaultPlan;
use crate::report::frames;
use anyhow::{anyhow, bail, Result};
use edgekf::systems::crank::{ClearanceEstimate, FEATURES};
use edgekf_firmware::hil::FileEnd;
use edgekf_firmware::systems::crank::{CrankEnd, CrankImage, FeaturesFrame, WindowFrame, WindowReport};

/// What a run of the node's estimator reports: every window's estimate, then the whole
/// recording's.
#[derive(Debug, Clone, PartialEq)]
pub struct CrankRun {
    /// One report per completed window.
    pub windows: Vec<WindowReport>,
    /// The recording's features (`ln` of the window means).
    pub features: [f32; FEATURES],
    /// The estimate for the whole recording.
    pub estimate: ClearanceEstimate<f32>,
    /// The end-of-run frame as the image sent it, the firmware's own struct: its counters of
    /// windows and of samples stepped and skipped.
    pub end: CrankEnd,
    /// What the image met in its input file: bad, untimed and missing lines and time jumps.
    pub file: FileEnd,
}

/// Runs the firmware's crank image over CSV text exactly as `edgekf-crank-qemu` does.
pub fn run_host(csv: &[u8]) -> Result<CrankRun> {
    parse(&crate::host::lines::<CrankImage>(csv)?)
}

/// The `win`, `feat` and `crank` frames of a run's lines.
pub fn parse(lines: &[String]) -> Result<CrankRun> {
    let joint = || anyhow!("a joint other than 0, 1, 2");
    let windows: Vec<WindowReport> =
        frames::<WindowFrame>(lines)?.iter().map(|w| w.report().ok_or_else(joint)).collect::<Result<_>>()?;
    let features = frames::<FeaturesFrame>(lines)?.pop().ok_or_else(|| anyhow!("no `feat` line"))?;
    let end = frames::<CrankEnd>(lines)?.pop().ok_or_else(|| anyhow!("no `crank` line: the run did not finish"))?;
    let file = crate::host::file_end(lines)?;
    if end.windows as usize != windows.len() {
        bail!("{} window lines but the end line says {}", windows.len(), end.windows);
    }
    Ok(CrankRun { windows, features: features.values(), estimate: end.estimate().ok_or_else(joint)?, end, file })
}

/// The HIL input: `t, crank_alpha` in shortest round-trip form.
pub fn csv(t: &[f64], alpha: &[f64]) -> String {
    let mut s = String::from("t,crank_alpha\n");
    for (t, a) in t.iter().zip(alpha) {
        s.push_str(&format!("{t:?},{a:?}\n"));
    }
    s
}

/// The host's original feature computation (two passes over each stored window, `f64`, as
/// `edgekf-sim` had it before it moved to the streaming [`edgekf::systems::crank::CrankFeatures`]):
/// kept only as the oracle the streaming version is checked against.
pub fn reference_features(x: &[f64], rate: f64, window_s: f64) -> ([f64; FEATURES], usize) {
    let n = ((window_s * rate).round() as usize).max(16);
    let mut acc = [0.0; FEATURES];
    let mut windows = 0usize;
    for w in x.chunks_exact(n) {
        let m = n as f64;
        let mean = w.iter().sum::<f64>() / m;
        let s2: f64 = w.iter().map(|v| (v - mean).powi(2)).sum();
        let s4: f64 = w.iter().map(|v| (v - mean).powi(4)).sum();
        let d: Vec<f64> = w.windows(2).map(|p| p[1] - p[0]).collect();
        let dd: Vec<f64> = w.windows(3).map(|p| p[2] - 2.0 * p[1] + p[0]).collect();
        let hp: Vec<f64> = (4..n - 4).map(|k| w[k] - w[k - 4..k + 4].iter().sum::<f64>() / 8.0).collect();
        let sq = |v: &[f64]| v.iter().map(|e| e * e).sum::<f64>();
        let (d2, d4, dd2, hp2) = (sq(&d), d.iter().map(|e| e.powi(4)).sum::<f64>(), sq(&dd), sq(&hp));
        let mut sorted: Vec<f64> = d.iter().map(|v| v.abs()).collect();
        sorted.sort_by(f64::total_cmp);
        let median = sorted[sorted.len() / 2];
        let thr = 6.0 * median;
        // Runs of |Δα| above the threshold: count, samples above, sum of run peaks.
        let (mut count, mut above_n, mut peak_sum) = (0usize, 0usize, 0.0);
        for run in d.iter().map(|v| v.abs()).collect::<Vec<_>>().split(|&a| a <= thr).filter(|r| !r.is_empty()) {
            count += 1;
            above_n += run.len();
            peak_sum += run.iter().copied().fold(0.0, f64::max);
        }
        let md = d.len() as f64;
        let vals = [
            (s2 / m).sqrt(),
            (d2 / md).sqrt(),
            (dd2 / (m - 2.0)).sqrt(),
            (hp2 / (m - 8.0)).sqrt(),
            (d4 / md) / (d2 / md).powi(2).max(1e-300),
            (s4 / m) / (s2 / m).powi(2).max(1e-300),
            count as f64 * rate / m,
            if count > 0 { peak_sum / count as f64 / median.max(1e-12) } else { 6.0 },
            if count > 0 { above_n as f64 / count as f64 } else { 1.0 },
            median,
        ];
        for (a, v) in acc.iter_mut().zip(vals) {
            *a += v;
        }
        windows += 1;
    }
    let k = windows.max(1) as f64;
    (acc.map(|v| (v / k).max(1e-12).ln()), windows)
}

/// What [`faulty_csv`] does to a crank HIL file (the counts the node must report follow from
/// it).
pub const FAULTS: FaultPlan =
    FaultPlan { deleted: 5000..5010, garbage: 12_000, empty_cell: 7000, junk_after: 15_000, nan: 16_000 };

/// `text` (the output of [`csv`]) with the faults of [`FAULTS`].
pub fn faulty_csv(text: &str) -> String {
    FAULTS.apply(text)
}

/// Checks a run over [`faulty_csv`] of a recording of `samples` samples against the clean
/// run: the counts exactly (one step per sample of the recording: the missing lines were
/// stepped, the clock did not slip), every window closed where 2 500 usable samples end (the
/// shared estimator's windows count usable samples: a skipped one lengthens its window), the
/// same joint named as the clean run after as many windows, and the clearance within
/// `tolerance` (relative) of the clean run's then. Returns the clearance's relative difference.
pub fn check_faulty_run(run: &CrankRun, clean: &CrankRun, samples: usize, tolerance: f64) -> Result<f64> {
    let e = &run.end;
    let f = &run.file;
    let counts = (e.samples, e.skipped, f.bad_lines, f.untimed_lines, f.missing_lines, f.time_jumps);
    // Skipped: the missing lines, the empty cell and the NaN.
    let missing = FAULTS.missing_lines();
    let want = (samples as u32, missing + 2, FaultPlan::BAD_LINES, FaultPlan::UNTIMED_LINES, missing, 0);
    if counts != want {
        bail!("(samples, skipped, bad, untimed, missing, jumps) = {counts:?}, expected {want:?}");
    }
    let skipped = |k: usize| FAULTS.unusable(k);
    let window = edgekf_firmware::systems::crank::WINDOW;
    let mut usable = 0;
    let mut closes = Vec::new();
    for k in 0..samples {
        if !skipped(k) {
            usable += 1;
            if usable % window == 0 {
                closes.push(k as u32 + 1);
            }
        }
    }
    let got: Vec<u32> = run.windows.iter().map(|w| w.samples).collect();
    if got != closes {
        bail!("windows closed at {got:?}, expected {closes:?}");
    }
    let Some(reference) = clean.windows.get(run.windows.len().wrapping_sub(1)) else {
        bail!("{} windows, the clean run has {}", run.windows.len(), clean.windows.len());
    };
    let reference = reference.estimate;
    if run.estimate.joint != reference.joint {
        bail!("joint {} named, clean {}", run.estimate.joint, reference.joint);
    }
    let rel = f64::from(run.estimate.clearance) / f64::from(reference.clearance) - 1.0;
    if rel.is_nan() || rel.abs() > tolerance {
        bail!("clearance {} against {} clean ({rel:+.2e})", run.estimate.clearance, reference.clearance);
    }
    Ok(rel)
}
