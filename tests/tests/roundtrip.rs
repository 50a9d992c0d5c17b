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
//! uploaded recording) and the vehicle's (`edgekf_tests::roundtrip_uuv`: a sideways DVL
//! offset, likewise) run with `EDGEKF_LONG=1` (`cargo xtask test --long`, which also sets
//! `EDGEKF_BOOM_ELF` and `EDGEKF_UUV_ELF`): their recordings and loops take minutes (72 s and
//! 134 s here), more than CI's share.
#![cfg(feature = "hil")]

use edgekf_tests::roundtrip::{oscillator, Setup};
use edgekf_tests::roundtrip_boom::{boom, BoomSetup};
use edgekf_tests::roundtrip_uuv::{uuv, UuvSetup};
use edgekf_tests::{cross, qemu};
use std::path::{Path, PathBuf};

/// The shipped image `bin` (the ELF `cargo xtask test` built), a build of it with the model
/// file the variable `var` names, and the folder `name` under `target/roundtrip/`.
fn rebuilds(bin: &str, var: &'static str, name: &str) -> (PathBuf, impl Fn(&Path) -> anyhow::Result<PathBuf>, PathBuf) {
    let shipped = qemu::image_elf(bin).unwrap_or_else(|e| panic!("{e:#}"));
    let image = edgekf_firmware::systems::IMAGES.iter().find(|i| i.bin == bin).expect("the image's row");
    let features = format!("{},no-panic-proof", image.features);
    let build = move |model: &Path| cross::build(image.bin, &features, &[(var, model.as_os_str())]);
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| cross::workspace_root().join("target"));
    (shipped, build, target.join("roundtrip").join(name))
}

#[test]
fn the_oscillator_round_trip_closes_on_the_node() {
    let (shipped, build, dir) = rebuilds("edgekf-qemu", "EDGEKF_OSCILLATOR_MODEL", "oscillator-test");
    let setup = Setup::oscillator(dir);
    let figures = oscillator(&setup, &shipped, &build).unwrap_or_else(|e| panic!("{e:#}"));
    eprintln!("{figures}");
    figures.check(setup.offset_m_s2).unwrap_or_else(|e| panic!("{e:#}"));
}

#[test]
fn the_vehicle_round_trip_closes_on_the_node() {
    if std::env::var_os("EDGEKF_LONG").is_none() {
        eprintln!("the vehicle's round trip runs with EDGEKF_LONG=1 (cargo xtask test --long)");
        return;
    }
    let (shipped, build, dir) = rebuilds("edgekf-uuv-qemu", "EDGEKF_UUV_MODEL", "uuv-test");
    let figures = uuv(&UuvSetup::new(dir), &shipped, &build).unwrap_or_else(|e| panic!("{e:#}"));
    eprintln!("{figures}");
    figures.check().unwrap_or_else(|e| panic!("{e:#}"));
}

#[test]
fn the_boom_round_trip_closes_on_the_node() {
    if std::env::var_os("EDGEKF_LONG").is_none() {
        eprintln!("the boom's round trip runs with EDGEKF_LONG=1 (cargo xtask test --long)");
        return;
    }
    let (shipped, build, dir) = rebuilds("edgekf-boom-qemu", "EDGEKF_BOOM_MODEL", "boom-test");
    let figures = boom(&BoomSetup::new(dir), &shipped, &build).unwrap_or_else(|e| panic!("{e:#}"));
    eprintln!("{figures}");
    figures.check().unwrap_or_else(|e| panic!("{e:#}"));
}
