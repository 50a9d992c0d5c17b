//! The scenarios and acceptance measures shared by the host-loop and HIL tests, so both judge a
//! run by the same numbers.

use crate::report::RunReport;
use edgekf_sim::systems::oscillator::scenario::{Fault, Recording, Scenario};

/// Samples per block for `NodeConfig::default()` (48 FIFO entries / 3 axes).
pub const BLOCK_SAMPLES: usize = 16;

/// Time at which the last injected fault of [`fault_scenario`] has cleared, s.
pub const FAULTS_CLEAR_AT: f64 = 7.05;

/// The default scenario with every fault the node must survive: a NACK burst its retries
/// absorb, one long enough to lose whole polls and overrun the FIFO, a frozen sensor for 0.2 s,
/// and 50 ms of a saturated axis.
pub fn fault_scenario() -> Scenario {
    Scenario {
        faults: vec![
            Fault::NackBurst { t: 3.0, transactions: 3 },
            Fault::NackBurst { t: 4.0, transactions: 14 },
            Fault::Stuck { t_start: 5.0, t_end: 5.2 },
            Fault::Saturation { t_start: 7.0, t_end: FAULTS_CLEAR_AT, accel: 30.0 },
        ],
        ..Scenario::default()
    }
}

/// Worst relative force-amplitude error against truth over the blocks ending in `[t0, t1)`.
pub fn worst_amplitude_error(run: &RunReport, rec: &Recording, t0: f64, t1: f64) -> f64 {
    let mut worst = 0.0f64;
    for b in &run.blocks {
        let last = (b.block as usize + 1) * BLOCK_SAMPLES - 1;
        let Some(&t) = rec.t.get(last) else { continue };
        if t < t0 || t >= t1 {
            continue;
        }
        let truth = rec.truth_force_amplitude[last];
        worst = worst.max((b.force_amplitude as f64 - truth).abs() / truth);
    }
    worst
}

/// After `from` seconds: the RMS difference between two runs' estimates of each quantity, as a
/// fraction of the RMS of that quantity in `reference`; returns the worst quantity and value.
pub fn recovery_mismatch(reference: &RunReport, other: &RunReport, from: f64, dt: f64) -> (&'static str, f64) {
    type Pick = fn(&edgekf_firmware::systems::oscillator::BlockReport) -> f32;
    let pick: [(&'static str, Pick); 4] = [
        ("displacement", |b| b.displacement),
        ("velocity", |b| b.velocity),
        ("force_cos", |b| b.force_cos),
        ("force_amplitude", |b| b.force_amplitude),
    ];
    let block_s = BLOCK_SAMPLES as f64 * dt;
    let mut worst = ("none", 0.0f64);
    for (name, f) in pick {
        let (mut diff2, mut ref2, mut n) = (0.0f64, 0.0f64, 0usize);
        for (a, b) in reference.blocks_from(from, block_s).zip(other.blocks_from(from, block_s)) {
            let (x, y) = (f(a) as f64, f(b) as f64);
            diff2 += (x - y) * (x - y);
            ref2 += x * x;
            n += 1;
        }
        if n == 0 || ref2 == 0.0 {
            return (name, f64::INFINITY);
        }
        let rel = (diff2 / n as f64).sqrt() / (ref2 / n as f64).sqrt();
        if rel > worst.1 {
            worst = (name, rel);
        }
    }
    worst
}
