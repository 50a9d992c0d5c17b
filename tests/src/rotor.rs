//! Rotor virtual sensing: the firmware's rotor image run on the host over a data file, the
//! parsing of its output (the image's or the host run's), the bit-for-bit check of a rotor
//! image's QEMU run against the host's, and the accuracy measure shared by the tests.

use crate::faulty::FaultPlan;
use crate::host::file_end;
use crate::report::frames;
use anyhow::{anyhow, bail, Result};
use edgekf_firmware::frame::Frame;
use edgekf_firmware::hil::{FileEnd, HilImage};
use edgekf_firmware::line_feed::ChannelReader;
use edgekf_firmware::node::Node;
use edgekf_firmware::systems::rotor::{
    channel_source, RotorEnd, RotorEstimator, RotorFrame, RotorImage, RotorNode, RotorReport, CHANNELS, DISK_NODES,
};
use edgekf_sim::systems::rotor::Recording;
use std::fmt::Debug;
use std::path::Path;
use std::time::Duration;

/// Runs the firmware's rotor image over CSV text exactly as `edgekf-rotor-qemu` does.
pub fn run_host(csv: &[u8]) -> Result<Vec<RotorReport>> {
    parse(&crate::host::lines::<RotorImage>(csv)?)
}

/// Runs `est` over CSV text in the image's node (for example
/// [`RotorEstimator::with_switch_at`]`(None)`, the time-varying filter throughout, to compare
/// the node's switch against).
pub fn run_host_with(csv: &[u8], est: RotorEstimator) -> Result<Vec<RotorReport>> {
    let reader = ChannelReader::new(csv, CHANNELS).map_err(|e| anyhow!("header: {e:?}"))?;
    let mut node = Node::new(channel_source(reader), RotorNode::new(est), Default::default());
    parse(&crate::host::run_node::<RotorImage>(&mut node)?)
}

/// The `rot` frames of a run's lines, as reports.
pub fn parse(lines: &[String]) -> Result<Vec<RotorReport>> {
    Ok(frames::<RotorFrame>(lines)?.iter().map(RotorFrame::report).collect())
}

/// The `rot` frames of a run's lines as (sample number, report): a sample bridged for a line
/// missing from the file has no frame of its own.
pub fn parse_numbered(lines: &[String]) -> Result<Vec<(u32, RotorReport)>> {
    Ok(frames::<RotorFrame>(lines)?.iter().map(|f| (f.sample, f.report())).collect())
}

/// The run's end frame (its counts).
pub fn end(lines: &[String]) -> Result<RotorEnd> {
    frames::<RotorEnd>(lines)?.pop().ok_or_else(|| anyhow!("no `rotor` line: the run did not finish"))
}

/// A report's numbers as bits (NaN included), for bit-for-bit comparisons.
pub fn bits(r: &RotorReport) -> Vec<u32> {
    r.disk.iter().chain(&r.force).chain([&r.nis]).map(|v| v.to_bits()).collect()
}

/// Runs a rotor image's ELF `elf` (of image `I`, ending with frame `E`) in QEMU on the HIL file
/// `csv` and the same image on the host: every `rot` frame, its sample number and its report,
/// bit for bit, and the end frame the same. Returns the firmware run's lines (its `stack` frame
/// included).
pub fn qemu_matches_host<I: HilImage, E: Frame + PartialEq + Debug>(elf: &Path, csv: &[u8]) -> Result<Vec<String>> {
    let run = crate::qemu::run(elf, csv, Duration::from_secs(600))?;
    if let Some(msg) = run.failure() {
        bail!("{msg}");
    }
    let host = crate::host::lines::<I>(csv)?;
    let (fw, reference) = (parse_numbered(&run.lines)?, parse_numbered(&host)?);
    if fw.len() != reference.len() {
        bail!("firmware reported {} samples, the host {}", fw.len(), reference.len());
    }
    for ((k, a), (kh, b)) in fw.iter().zip(&reference) {
        if (k, bits(a)) != (kh, bits(b)) {
            bail!("sample {k} (host {kh}): firmware {a:?} host {b:?}");
        }
    }
    let (fw_end, host_end) = (frames::<E>(&run.lines)?, frames::<E>(&host)?);
    if fw_end.len() != 1 || fw_end != host_end {
        bail!("end frames: firmware {fw_end:?}, host {host_end:?}");
    }
    // The `file` frame, for an image that reads its channels from a file (not one that reads
    // virtual sensors).
    let (fw_file, host_file) = (frames::<FileEnd>(&run.lines)?, frames::<FileEnd>(&host)?);
    if fw_file != host_file {
        bail!("file frames: firmware {fw_file:?}, host {host_file:?}");
    }
    Ok(run.lines)
}

/// Worst RMS error over the disk nodes' x and y for samples with `t ≥ t0`, m.
pub fn disk_rms_error(reports: &[RotorReport], rec: &Recording, t0: f64) -> f64 {
    let mut worst = 0.0f64;
    for (j, &node) in DISK_NODES.iter().enumerate() {
        for (d, truth) in [(0, &rec.x[node]), (1, &rec.y[node])] {
            let (mut s, mut n) = (0.0, 0usize);
            for (k, r) in reports.iter().enumerate() {
                if rec.t[k] >= t0 {
                    s += (r.disk[2 * j + d] as f64 - truth[k]).powi(2);
                    n += 1;
                }
            }
            worst = worst.max((s / n.max(1) as f64).sqrt());
        }
    }
    worst
}

/// What [`faulty_csv`] does to a rotor HIL file (the counts the node must report follow from
/// it).
pub const FAULTS: FaultPlan =
    FaultPlan { deleted: 1500..1520, garbage: 2500, empty_cell: 1800, junk_after: 3000, nan: 3200 };

/// When the last fault of [`FAULTS`] is over, s.
pub const FAULTS_CLEAR_AT: f64 = 3.201;

/// The HIL file `csv` (a header and one line per sample) with the faults of [`FAULTS`].
pub fn faulty_csv(csv: &str) -> String {
    FAULTS.apply(csv)
}

/// Worst RMS error over the disk nodes' x and y for numbered reports with `t ≥ t0`, m.
pub fn disk_rms_error_numbered(reports: &[(u32, RotorReport)], rec: &Recording, t0: f64) -> f64 {
    let mut worst = 0.0f64;
    for (j, &node) in DISK_NODES.iter().enumerate() {
        for (d, truth) in [(0, &rec.x[node]), (1, &rec.y[node])] {
            let (mut s, mut n) = (0.0, 0usize);
            for (k, r) in reports {
                let k = *k as usize;
                if rec.t[k] >= t0 {
                    s += (r.disk[2 * j + d] as f64 - truth[k]).powi(2);
                    n += 1;
                }
            }
            worst = worst.max((s / n.max(1) as f64).sqrt());
        }
    }
    worst
}

/// Checks a run of the rotor image over [`faulty_csv`] of `rec`'s file against the clean run's
/// numbered reports: the end frame's counts exactly, a report for every sample but the bridged
/// ones (the clock did not slip), the disk error for t ≥ 1 s within the virtual-sensing target
/// (1 µm RMS), and from 0.5 s after the last fault every disk and force estimate within 1 % of
/// the clean run's RMS. Returns the disk error and that mismatch, for the log.
pub fn check_faulty_run(lines: &[String], clean: &[(u32, RotorReport)], rec: &Recording) -> Result<(f64, f64)> {
    let (end, file) = (end(lines)?, file_end(lines)?);
    let lines_read = rec.t.len() as u32 - FAULTS.deleted.len() as u32 + 1;
    if end.samples != lines_read {
        anyhow::bail!("end frame {end:?}, expected {lines_read} samples");
    }
    let expected = FileEnd {
        bad_lines: FaultPlan::BAD_LINES,
        untimed_lines: FaultPlan::UNTIMED_LINES,
        missing_lines: FAULTS.missing_lines(),
        time_jumps: 0,
    };
    if file != expected {
        anyhow::bail!("file frame {file:?}, expected {expected:?}");
    }
    let reports = parse_numbered(lines)?;
    let numbers: Vec<u32> = reports.iter().map(|(k, _)| *k).collect();
    let want: Vec<u32> = (0..rec.t.len()).filter(|k| !FAULTS.lost(*k)).map(|k| k as u32).collect();
    if numbers != want {
        anyhow::bail!("reported samples are not every sample but the bridged ones (the clock slipped)");
    }
    let err = disk_rms_error_numbered(&reports, rec, 1.0);
    if err > 1e-6 {
        anyhow::bail!("disk RMS error {err} m for t ≥ 1 s");
    }
    let after = FAULTS_CLEAR_AT + 0.5;
    let (mut d2, mut r2) = (0.0f64, 0.0f64);
    let kept = |(k, _): &&(u32, RotorReport)| !FAULTS.lost(*k as usize);
    for ((k, a), (kc, c)) in reports.iter().zip(clean.iter().filter(kept)) {
        if *k != *kc {
            anyhow::bail!("sample {k} against clean sample {kc}");
        }
        if rec.t[*k as usize] >= after {
            for (x, y) in a.disk.iter().chain(&a.force).zip(c.disk.iter().chain(&c.force)) {
                d2 += f64::from(x - y).powi(2);
                r2 += f64::from(*y).powi(2);
            }
        }
    }
    let mismatch = (d2 / r2).sqrt();
    if mismatch.is_nan() || mismatch > 0.01 {
        anyhow::bail!("from {after} s the estimates differ from the clean run by {mismatch} of its RMS");
    }
    Ok((err, mismatch))
}

/// The rotor node as it ran before its start-up term (stop 27), the reference that term is
/// judged against: the dense 20-state time-varying Kalman filter of the exported `P0` in `f32`
/// for the first [`STEADY_AFTER`] samples, then the steady-state filter of the exported gain
/// started from its state. Over the probes of a clean HIL file (every line present).
pub fn dense_start_run(csv: &str) -> Result<Vec<RotorReport>> {
    use edgekf::export::{matrix, model};
    use edgekf::filter::{KalmanFilter, SteadyStateFilter};
    use edgekf_firmware::systems::rotor::constants::*;
    use edgekf_firmware::systems::rotor::STEADY_AFTER;
    use nalgebra::SVector;
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().ok_or_else(|| anyhow!("empty file"))?.split(',').collect();
    let cols: Vec<usize> = CHANNELS
        .iter()
        .map(|c| header.iter().position(|h| h == c).ok_or_else(|| anyhow!("no column {c}")))
        .collect::<Result<_>>()?;
    let f64_model = model(&ROTOR_A, &ROTOR_C, &ROTOR_Q, &ROTOR_R);
    let f32_model = f64_model.cast::<f32>();
    let mut dense = KalmanFilter::new(f32_model.clone(), SVector::zeros(), matrix(&ROTOR_P0).map(|v| v as f32));
    let mut steady: Option<SteadyStateFilter<f32, 20, 4>> = None;
    let (disk, force) = (matrix(&ROTOR_DISK).map(|v| v as f32), matrix(&ROTOR_FORCE).map(|v| v as f32));
    let mut out = Vec::new();
    for (k, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        let y: Vec<f32> = cols.iter().map(|&c| cells.get(c).and_then(|v| v.parse().ok()).unwrap_or(f32::NAN)).collect();
        let y = SVector::<f32, 4>::from_column_slice(&y);
        if k == STEADY_AFTER as usize {
            let s = matrix(&ROTOR_S);
            steady = Some(
                SteadyStateFilter::from_parts(
                    &f32_model.a,
                    &f32_model.c,
                    &matrix(&ROTOR_GAIN).map(|v| v as f32),
                    &s,
                    *dense.state(),
                )
                .map_err(|e| anyhow!("{e:?}"))?,
            );
        }
        let (nis, x) = match steady.as_mut() {
            Some(f) => {
                let nis = f.update(&y).map_or(f32::NAN, |(_, n)| n);
                let x = *f.state();
                f.predict();
                (nis, x)
            }
            None => {
                let nis = dense.update(&y).map_or(f32::NAN, |i| i.nis);
                let x = *dense.state();
                dense.predict();
                (nis, x)
            }
        };
        let (d, f) = (disk * x, force * x);
        out.push(RotorReport { disk: [d[0], d[1], d[2], d[3]], force: [f[0], f[1], f[2], f[3]], nis });
    }
    Ok(out)
}
