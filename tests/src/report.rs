//! The numbers a node run reports, parsed from decoded defmt lines (a firmware run's, or a host
//! run's written the same way) with the frames' own parsers ([`edgekf_firmware::frame`]).

use anyhow::{anyhow, Result};
use edgekf_firmware::frame::{Done, Frame, StackFrame};
use edgekf_firmware::monitor::MismatchFrame;
use edgekf_firmware::node::Health;
use edgekf_firmware::systems::oscillator::{BlockReport, EstimatorFrame, FeedFrame, VirtualFrame};

/// `line` as a frame of kind `F`: `None` if it is of another kind, an error if it is of this
/// kind but malformed.
pub fn frame<F: Frame>(line: &str) -> Result<Option<F>> {
    F::parse(line).transpose().map_err(|e| anyhow!("{e} in {line:?}"))
}

/// Every frame of kind `F` in `lines`, in order.
pub fn frames<F: Frame>(lines: &[String]) -> Result<Vec<F>> {
    lines.iter().filter_map(|l| frame::<F>(l).transpose()).collect()
}

/// Everything one oscillator run reported.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunReport {
    /// One entry per poll.
    pub blocks: Vec<BlockReport>,
    /// Health counters at the end.
    pub health: Health,
    /// Estimator counters at the end.
    pub estimator: EstimatorFrame,
    /// Input lines read, bad lines, ignored columns.
    pub feed: FeedFrame,
    /// Virtual device: samples loaded, NACKs sent, FIFO entries overwritten.
    pub virtual_device: VirtualFrame,
    /// Model mismatches the node's monitor reported, in order.
    pub mismatches: Vec<MismatchFrame>,
    /// Stack bytes used by start-up, by the main loop, and available (firmware runs only).
    pub stack: Option<StackFrame>,
    /// Whether the run reached its end.
    pub done: bool,
}

/// The named floating-point values of a block, in a fixed order.
pub fn block_values(b: &BlockReport) -> [(&'static str, f32); 7] {
    [
        ("displacement", b.displacement),
        ("velocity", b.velocity),
        ("force_cos", b.force_cos),
        ("force_sin", b.force_sin),
        ("force_amplitude", b.force_amplitude),
        ("innovation_rms", b.innovation_rms),
        ("nis_mean", b.nis_mean),
    ]
}

impl RunReport {
    /// Parses decoded defmt messages (one per line). Lines of other kinds (start, errors) are
    /// skipped; malformed lines of a known kind are an error.
    pub fn parse<'a>(lines: impl IntoIterator<Item = &'a str>) -> Result<Self> {
        let mut r = RunReport::default();
        for line in lines {
            if let Some(b) = frame::<BlockReport>(line)? {
                r.blocks.push(b);
            } else if let Some(h) = frame::<Health>(line)? {
                r.health = h;
            } else if let Some(e) = frame::<EstimatorFrame>(line)? {
                r.estimator = e;
            } else if let Some(f) = frame::<FeedFrame>(line)? {
                r.feed = f;
            } else if let Some(v) = frame::<VirtualFrame>(line)? {
                r.virtual_device = v;
            } else if let Some(m) = frame::<MismatchFrame>(line)? {
                r.mismatches.push(m);
            } else if let Some(s) = frame::<StackFrame>(line)? {
                r.stack = Some(s);
            } else if frame::<Done>(line)?.is_some() {
                r.done = true;
            }
        }
        Ok(r)
    }

    /// Block reports whose block started at or after `t` seconds, given the block length.
    pub fn blocks_from(&self, t: f64, block_seconds: f64) -> impl Iterator<Item = &BlockReport> {
        self.blocks.iter().filter(move |b| b.block as f64 * block_seconds >= t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_kind_and_rejects_short_lines() {
        let lines = [
            "start odr=1000 watermark=48",
            "blk 3 16 1 1e-5 -0.002 4.5 -2.25 5.0311 0.004 0.98",
            "health 10 160 2 2 0 0 1 0 0 0 0 1 0 0 0 0",
            "estimator 160 1 0 0 0",
            "feed 160 0 5",
            "virtual 160 2 0 0 0 0 0 0",
            "stack 9000 1200 131000",
            "done",
        ];
        let r = RunReport::parse(lines).unwrap();
        assert_eq!(r.blocks.len(), 1);
        assert_eq!(r.blocks[0].missing, 1);
        assert_eq!(r.blocks[0].force_amplitude, 5.0311);
        assert_eq!(r.health.stuck, 1);
        assert_eq!(r.feed.ignored_columns, 5);
        assert_eq!(r.stack, Some(StackFrame { boot: 9000, used: 1200, total: 131000 }));
        assert!(r.done);
        assert!(RunReport::parse(["blk 1 2 3 0.5"]).is_err());
    }
}
