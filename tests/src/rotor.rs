//! Rotor virtual sensing: the firmware's estimator run on the host over a data file, the
//! parsing of the QEMU image's output, and the accuracy measure shared by the tests.

use anyhow::{anyhow, bail, Result};
use edgekf_firmware::line_feed::ChannelReader;
use edgekf_firmware::rotor::{RotorEstimator, RotorReport, CHANNELS, DISK_NODES};
use edgekf_sim::systems::rotor::Recording;

/// Runs the firmware's [`RotorEstimator`] over CSV text exactly as `edgekf-rotor-qemu` does.
pub fn run_host(csv: &[u8]) -> Result<Vec<RotorReport>> {
    run_host_with(csv, RotorEstimator::new())
}

/// Runs `est` over CSV text (for example [`RotorEstimator::with_switch_at`]`(None)`, the
/// time-varying filter throughout, to compare the node's switch against).
pub fn run_host_with(csv: &[u8], mut est: RotorEstimator) -> Result<Vec<RotorReport>> {
    let mut reader = ChannelReader::new(csv, CHANNELS).map_err(|e| anyhow!("header: {e:?}"))?;
    let mut out = Vec::new();
    while let Some(line) = reader.next_values() {
        out.push(est.step(line.ok()));
    }
    Ok(out)
}

/// The `rot` lines of a decoded firmware log.
pub fn parse(lines: &[String]) -> Result<Vec<RotorReport>> {
    let mut out = Vec::new();
    for line in lines {
        let Some(rest) = line.strip_prefix("rot ") else { continue };
        let v: Vec<&str> = rest.split_whitespace().collect();
        if v.len() != 10 {
            bail!("malformed line {line:?}");
        }
        let f = |i: usize| v[i].parse::<f32>().map_err(|_| anyhow!("bad value in {line:?}"));
        out.push(RotorReport { disk: [f(1)?, f(2)?, f(3)?, f(4)?], force: [f(5)?, f(6)?, f(7)?, f(8)?], nis: f(9)? });
    }
    Ok(out)
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
