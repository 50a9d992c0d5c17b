//! Link scripts for the Cortex-M images: `memory.x` lives at the workspace root (one memory map
//! for every image), cortex-m-rt provides `link.x`, defmt provides `defmt.x`. Host builds (the
//! library and its tests) get no linker arguments.
//!
//! The oscillator's model constants: the committed `src/systems/oscillator/generated/harmonic.rs`,
//! or the file `EDGEKF_OSCILLATOR_MODEL` names (an `edgekf oscillator export` output, e.g. the
//! round trip's corrected model under `target/`), copied to `OUT_DIR/harmonic.rs` where the
//! crate `include!`s it: a corrected model reaches the chip without touching the committed file.

use std::{env, fs, path::PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=../memory.x");
    println!("cargo:rerun-if-changed=build.rs");
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    oscillator_model(&out);
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

/// Copies the oscillator's model constants (the committed file, or `EDGEKF_OSCILLATOR_MODEL`'s)
/// to `out/harmonic.rs`.
fn oscillator_model(out: &std::path::Path) {
    const COMMITTED: &str = "src/systems/oscillator/generated/harmonic.rs";
    println!("cargo:rerun-if-env-changed=EDGEKF_OSCILLATOR_MODEL");
    let chosen = match env::var_os("EDGEKF_OSCILLATOR_MODEL") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => PathBuf::from(COMMITTED),
    };
    println!("cargo:rerun-if-changed={}", chosen.display());
    if let Err(e) = fs::copy(&chosen, out.join("harmonic.rs")) {
        panic!("the oscillator's model constants {}: {e}", chosen.display());
    }
}
