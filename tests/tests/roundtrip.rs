//! The oscillator's round trip in QEMU (issue #36; `edgekf_tests::roundtrip`): an offset that
//! starts mid-run raises the shipped node's `mismatch`, its handed-over window goes through
//! `edgekf capture` and `edgekf loop oscillator --corrected-config`, the image rebuilt with the
//! exported constants raises nothing on a fresh recording with the offset from the start and
//! tracks within 1.5× a node built with the true configuration; the corrected configuration
//! adds nothing when the loop runs again. Run last by `cargo xtask test`, with `EDGEKF_FW_ELF`
//! the shipped image; it rebuilds the image twice (about 10 s each once the shipped one is
//! built) and took 39 s on 2 cores.
//!
//! The boom's round trip (`edgekf_tests::roundtrip_boom`: a heavier platform, the loop on the
//! uploaded recording) runs with `EDGEKF_LONG=1` (`cargo xtask test --long`, which also sets
//! `EDGEKF_BOOM_ELF`): two 120 s recordings and their loops take minutes, more than CI's share.
#![cfg(feature = "hil")]

use edgekf_tests::roundtrip::{oscillator, Setup};
use edgekf_tests::roundtrip_boom::{boom, BoomSetup};
use edgekf_tests::{cross, qemu};
use std::path::Path;

#[test]
fn the_oscillator_round_trip_closes_on_the_node() {
    let shipped = qemu::image_elf("edgekf-qemu").unwrap_or_else(|e| panic!("{e:#}"));
    let image = edgekf_firmware::systems::IMAGES.iter().find(|i| i.bin == "edgekf-qemu").expect("the oscillator's row");
    let features = format!("{},no-panic-proof", image.features);
    let build = |model: &Path| cross::build(image.bin, &features, &[("EDGEKF_OSCILLATOR_MODEL", model.as_os_str())]);
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| cross::workspace_root().join("target"));
    let setup = Setup::oscillator(target.join("roundtrip").join("oscillator-test"));
    let figures = oscillator(&setup, &shipped, &build).unwrap_or_else(|e| panic!("{e:#}"));
    eprintln!("{figures}");
    figures.check(setup.offset_m_s2).unwrap_or_else(|e| panic!("{e:#}"));
}

#[test]
fn the_boom_round_trip_closes_on_the_node() {
    if std::env::var_os("EDGEKF_LONG").is_none() {
        eprintln!("the boom's round trip runs with EDGEKF_LONG=1 (cargo xtask test --long)");
        return;
    }
    let shipped = qemu::image_elf("edgekf-boom-qemu").unwrap_or_else(|e| panic!("{e:#}"));
    let image = edgekf_firmware::systems::IMAGES.iter().find(|i| i.bin == "edgekf-boom-qemu").expect("the boom's row");
    let features = format!("{},no-panic-proof", image.features);
    let build = |model: &Path| cross::build(image.bin, &features, &[("EDGEKF_BOOM_MODEL", model.as_os_str())]);
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| cross::workspace_root().join("target"));
    let setup = BoomSetup::new(target.join("roundtrip").join("boom-test"));
    let figures = boom(&setup, &shipped, &build).unwrap_or_else(|e| panic!("{e:#}"));
    eprintln!("{figures}");
    figures.check().unwrap_or_else(|e| panic!("{e:#}"));
}
