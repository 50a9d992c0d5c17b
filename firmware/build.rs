//! Link scripts for the Cortex-M images: `memory.x` lives at the workspace root (one memory map
//! for every image), cortex-m-rt provides `link.x`, defmt provides `defmt.x`. Host builds (the
//! library and its tests) get no linker arguments.
//!
//! The model constants of the oscillator, the boom and the vehicle: each system's committed
//! `src/systems/<system>/generated/<file>.rs`, or the file its variable names
//! (`EDGEKF_OSCILLATOR_MODEL`, `EDGEKF_BOOM_MODEL`, `EDGEKF_UUV_MODEL`: an `edgekf <system>
//! export` output, e.g. a round trip's corrected model under `target/`), copied to
//! `OUT_DIR/<file>.rs` where the crate `include!`s it: a corrected model reaches the chip
//! without touching the committed file.

use std::{env, fs, path::PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=../memory.x");
    println!("cargo:rerun-if-changed=build.rs");
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    model(&out, "EDGEKF_OSCILLATOR_MODEL", "oscillator", "harmonic.rs");
    model(&out, "EDGEKF_BOOM_MODEL", "boom", "boom.rs");
    model(&out, "EDGEKF_UUV_MODEL", "uuv", "uuv.rs");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    fs::copy("../memory.x", out.join("memory.x")).expect("memory.x at the workspace root");
    println!("cargo:rustc-link-search={}", out.display());
    // Only the binaries are linked; the arguments apply to them.
    println!("cargo:rustc-link-arg-bins=--nmagic");
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}

/// Copies `system`'s model constants (its committed `file`, or the one `var` names) to
/// `out/file`.
fn model(out: &std::path::Path, var: &str, system: &str, file: &str) {
    println!("cargo:rerun-if-env-changed={var}");
    let chosen = match env::var_os(var) {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => PathBuf::from(format!("src/systems/{system}/generated/{file}")),
    };
    println!("cargo:rerun-if-changed={}", chosen.display());
    if let Err(e) = fs::copy(&chosen, out.join(file)) {
        panic!("the {system}'s model constants {}: {e}", chosen.display());
    }
}
