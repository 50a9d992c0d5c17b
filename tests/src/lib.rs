//! Support for edgekf's cross-crate and hardware-in-the-loop tests.
//!
//! * [`qemu`] runs the firmware image under `qemu-system-arm` on a data file and decodes its
//!   defmt stream;
//! * [`report`] turns the decoded lines into numbers with the frames' own parsers (block
//!   estimates, health counters, stack);
//! * [`host`] runs the very same image (driver, main loop, estimator, frames) on the host over
//!   the same data, which is what a firmware run is compared with;
//! * [`rotor`] and [`crank`] do the same for the rotor and slider-crank images;
//! * [`soak`] judges the numerical soak's figures, from the host or from QEMU;
//! * [`checks`] holds the scenarios and acceptance measures the host and HIL tests share;
//! * [`cross`] is the firmware's cross-build recipe (xtask's and the round trip's);
//! * [`roundtrip`] runs the oscillator's round trip: the alarm on the node, the captured window,
//!   the loop's corrected configuration, the rebuilt node; [`roundtrip_boom`] the boom's.
#![deny(missing_docs)]

pub mod checks;
pub mod crank;
pub mod cross;
pub mod faulty;
pub mod host;
pub mod monitor;
pub mod qemu;
pub mod report;
pub mod rotor;
pub mod roundtrip;
pub mod roundtrip_boom;
pub mod roundtrip_uuv;
pub mod soak;

/// Compares two runs block by block and returns a readable description of the first
/// difference, or `None` if every reported number is bit-identical.
pub fn first_difference(firmware: &report::RunReport, host: &report::RunReport) -> Option<String> {
    if firmware.blocks.len() != host.blocks.len() {
        return Some(format!("firmware reported {} blocks, host {}", firmware.blocks.len(), host.blocks.len()));
    }
    for (f, h) in firmware.blocks.iter().zip(&host.blocks) {
        let fv = report::block_values(f);
        let hv = report::block_values(h);
        for ((name, a), (_, b)) in fv.iter().zip(hv.iter()) {
            if a.to_bits() != b.to_bits() {
                return Some(format!(
                    "block {}: {name} firmware {a:e} host {b:e} ({} ulp apart)",
                    f.block,
                    (a.to_bits() as i64 - b.to_bits() as i64).abs()
                ));
            }
        }
        if (f.read, f.missing) != (h.read, h.missing) {
            return Some(format!(
                "block {}: read/missing firmware {:?} host {:?}",
                f.block,
                (f.read, f.missing),
                (h.read, h.missing)
            ));
        }
    }
    if firmware.health != host.health {
        return Some(format!("health differs: firmware {:?} host {:?}", firmware.health, host.health));
    }
    if firmware.mismatches != host.mismatches {
        return Some(format!("mismatch frames differ: firmware {:?} host {:?}", firmware.mismatches, host.mismatches));
    }
    None
}
