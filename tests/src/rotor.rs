//! Rotor virtual sensing: the firmware's rotor image run on the host over a data file, the
//! parsing of its output (the image's or the host run's), and the accuracy measure shared by
//! the tests.

use crate::report::frames;
use anyhow::{anyhow, Result};
use edgekf_firmware::line_feed::ChannelReader;
use edgekf_firmware::node::Node;
use edgekf_firmware::systems::rotor::{
    channel_source, RotorEnd, RotorEstimator, RotorFrame, RotorImage, RotorNode, RotorReport, CHANNELS, DISK_NODES,
};
use edgekf_sim::systems::rotor::Recording;

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
