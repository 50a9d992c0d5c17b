//! The numbers a node run reports, parsed from the firmware's decoded defmt lines.
//!
//! The line formats are the ones `firmware/src/bin/qemu/main.rs` emits: `blk`, `health`,
//! `estimator`, `feed`, `virtual`, `stack`, `done`, each followed by its values in a fixed order.

use anyhow::{anyhow, bail, Context, Result};
use edgekf_firmware::node::{BlockReport, Health};

/// Everything one run reported.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunReport {
    /// One entry per poll.
    pub blocks: Vec<BlockReport>,
    /// Health counters at the end.
    pub health: Health,
    /// Estimator counters at the end: steps, missing, gated, covariance resets, refused updates.
    pub estimator: [u32; 5],
    /// Input lines read, bad lines, ignored columns.
    pub feed: [u32; 3],
    /// Virtual device: samples loaded, NACKs sent, FIFO entries overwritten.
    pub virtual_device: [u32; 3],
    /// Stack bytes used by start-up, by the main loop, and available (firmware runs only).
    pub stack: Option<[u32; 3]>,
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

fn numbers<T: std::str::FromStr>(fields: &[&str], n: usize, line: &str) -> Result<Vec<T>> {
    if fields.len() != n {
        bail!("expected {n} values in {line:?}, found {}", fields.len());
    }
    fields.iter().map(|f| f.parse::<T>().map_err(|_| anyhow!("bad value {f:?} in {line:?}"))).collect()
}

impl RunReport {
    /// Parses decoded defmt messages (one per line). Lines of other kinds (start, errors) are
    /// skipped; malformed lines of a known kind are an error.
    pub fn parse<'a>(lines: impl IntoIterator<Item = &'a str>) -> Result<Self> {
        let mut r = RunReport::default();
        for line in lines {
            let mut it = line.split_whitespace();
            let Some(kind) = it.next() else { continue };
            let rest: Vec<&str> = it.collect();
            match kind {
                "blk" => {
                    let ints = numbers::<u32>(&rest[..3.min(rest.len())], 3, line)?;
                    let f = numbers::<f32>(rest.get(3..).unwrap_or(&[]), 7, line)?;
                    r.blocks.push(BlockReport {
                        block: ints[0],
                        read: ints[1] as u16,
                        missing: ints[2] as u16,
                        displacement: f[0],
                        velocity: f[1],
                        force_cos: f[2],
                        force_sin: f[3],
                        force_amplitude: f[4],
                        innovation_rms: f[5],
                        nis_mean: f[6],
                    });
                }
                "health" => {
                    let v = numbers::<u32>(&rest, 11, line)?;
                    r.health = Health {
                        blocks: v[0],
                        samples: v[1],
                        bus_errors: v[2],
                        nacks: v[3],
                        recovered: v[4],
                        failed_polls: v[5],
                        fifo_overruns: v[6],
                        skipped_entries: v[7],
                        saturated: v[8],
                        stuck: v[9],
                        bridged: v[10],
                    };
                }
                "estimator" => r.estimator = numbers::<u32>(&rest, 5, line)?.try_into().expect("5 values"),
                "feed" => r.feed = numbers::<u32>(&rest, 3, line)?.try_into().expect("3 values"),
                "virtual" => r.virtual_device = numbers::<u32>(&rest, 3, line)?.try_into().expect("3 values"),
                "stack" => {
                    let v = numbers::<u32>(&rest, 3, line).context("stack line")?;
                    r.stack = Some([v[0], v[1], v[2]]);
                }
                "done" => r.done = true,
                _ => {}
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
            "health 10 160 2 2 1 0 0 0 0 1 0",
            "estimator 160 1 0 0 0",
            "feed 160 0 5",
            "virtual 160 2 0",
            "stack 9000 1200 131000",
            "done",
        ];
        let r = RunReport::parse(lines).unwrap();
        assert_eq!(r.blocks.len(), 1);
        assert_eq!(r.blocks[0].missing, 1);
        assert_eq!(r.blocks[0].force_amplitude, 5.0311);
        assert_eq!(r.health.stuck, 1);
        assert_eq!(r.stack, Some([9000, 1200, 131000]));
        assert!(r.done);
        assert!(RunReport::parse(["blk 1 2 3 0.5"]).is_err());
    }
}
