//! The node's driver and main loop run on the host over the same input a firmware run gets:
//! the reference a QEMU run is compared with, bit for bit.

use crate::report::RunReport;
use anyhow::{anyhow, Result};
use edgekf_firmware::line_feed::LineFeed;
use edgekf_firmware::node::{Node, NodeConfig};
use edgekf_firmware::virtual_adxl355::VirtualAdxl355;

/// Runs `NodeConfig::default()` over CSV text exactly as `edgekf-qemu` does.
pub fn run(csv: &[u8]) -> Result<RunReport> {
    let feed = LineFeed::new(csv).map_err(|e| anyhow!("input header: {e:?}"))?;
    let mut node = Node::start(VirtualAdxl355::new(feed), NodeConfig::default())
        .map_err(|(e, _)| anyhow!("node start failed: {e:?}"))?;
    let mut report = RunReport::default();
    // One watermark period per poll, until the data has run out and the FIFO is drained.
    while node.bus_mut().advance_period() > 0 || !node.bus().is_exhausted() {
        report.blocks.push(node.poll());
    }
    report.health = node.health();
    let e = node.estimator_counters();
    report.estimator = [e.steps, e.missing, e.gated, e.filter.covariance_resets, e.filter.refused_updates];
    let bus = node.bus();
    report.feed = [bus.feed().lines(), bus.feed().bad_lines(), bus.feed().columns().ignored() as u32];
    let v = bus.counters();
    report.virtual_device = [v.samples_loaded, v.nacks_sent, v.overrun_entries];
    report.done = true;
    Ok(report)
}
