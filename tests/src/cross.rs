//! The firmware's cross-build recipe, once: Debian's cargo and rustc (`-Zbuild-std=core` on the
//! stable compiler) for the Cortex-M4F, the `firmware` profile. `cargo xtask` builds every
//! image through it, and the round trip ([`crate::roundtrip`]) rebuilds the oscillator's image
//! with another model file (`EDGEKF_OSCILLATOR_MODEL`) through it, from a test as from xtask.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The target triple of every image.
pub const TARGET: &str = "thumbv7em-none-eabihf";
/// The cargo profile of every image.
pub const PROFILE: &str = "firmware";
/// Debian's cargo, whose rustc matches the library sources `-Zbuild-std` compiles.
pub const DEBIAN_CARGO: &str = "/usr/bin/cargo";

/// The workspace's root (this crate's parent folder).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("."))
}

/// Builds binary `bin` of `edgekf-firmware` with `features` (comma-separated) and the
/// environment `env` added, and returns the ELF's path (under `$CARGO_TARGET_DIR`, or the
/// workspace's `target/`). The ELF of a later build with other settings lands on the same
/// path: copy it away to keep it.
pub fn build(bin: &str, features: &str, env: &[(&str, &std::ffi::OsStr)]) -> Result<PathBuf> {
    let root = workspace_root();
    let path = std::env::var("PATH").unwrap_or_default();
    let mut cmd = Command::new(DEBIAN_CARGO);
    cmd.current_dir(&root)
        .args(["build", "-p", "edgekf-firmware", "--bin", bin, "--features", features])
        .args(["--target", TARGET, "--profile", PROFILE, "-Zbuild-std=core"])
        .env("PATH", format!("/usr/bin:{path}"))
        .env("RUSTC_BOOTSTRAP", "1");
    // The host toolchain's settings (rustup's, or a `cargo test` that runs this) would pick
    // the wrong compiler.
    for var in
        ["RUSTC", "RUSTDOC", "RUSTC_WRAPPER", "RUSTUP_TOOLCHAIN", "CARGO", "RUSTFLAGS", "CARGO_ENCODED_RUSTFLAGS"]
    {
        cmd.env_remove(var);
    }
    cmd.envs(env.iter().copied());
    let st = cmd.status().context("running Debian's cargo for the cross build")?;
    if !st.success() {
        bail!("firmware build of {bin} failed ({st})");
    }
    let target_dir = std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| root.join("target"));
    let elf = target_dir.join(TARGET).join(PROFILE).join(bin);
    if !elf.is_file() {
        bail!("build succeeded but {} is missing", elf.display());
    }
    Ok(elf)
}
