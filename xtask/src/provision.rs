//! What the firmware half of the tests needs beyond rustup's host toolchain, and how to get it
//! on Debian. rustup's toolchains here carry only x86-64 `std` and `rustup target add` needs a
//! network, so the Cortex-M build uses Debian's Rust 1.96 with its library sources
//! (`-Zbuild-std=core`); the compiler must match those sources exactly, which only Debian's pair
//! guarantees (see README, "Toolchain").

use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::Command;

/// Debian packages that provide everything below.
pub const PACKAGES: [&str; 5] = ["rustc-web", "cargo-web", "rust-web-src", "qemu-system-arm", "binutils-arm-none-eabi"];

/// Debian's cargo and rustc (matching `rust-web-src`).
pub const DEBIAN_CARGO: &str = "/usr/bin/cargo";
const DEBIAN_RUSTC: &str = "/usr/bin/rustc";
const DEBIAN_CORE_SRC: &str = "/usr/lib/rustlib/src/rust/library/core";

fn missing() -> Vec<&'static str> {
    let mut m = Vec::new();
    let runs = |prog: &str| Command::new(prog).arg("--version").output().map(|o| o.status.success()).unwrap_or(false);
    if !runs("qemu-system-arm") {
        m.push("qemu-system-arm");
    }
    if !runs("arm-none-eabi-ld") || !runs("arm-none-eabi-size") {
        m.push("arm-none-eabi binutils");
    }
    if !Path::new(DEBIAN_CARGO).exists() || !Path::new(DEBIAN_RUSTC).exists() {
        m.push("Debian cargo/rustc");
    }
    if !Path::new(DEBIAN_CORE_SRC).exists() {
        m.push("Rust library sources");
    }
    m
}

fn is_root() -> bool {
    Command::new("id").arg("-u").output().map(|o| o.stdout.starts_with(b"0")).unwrap_or(false)
}

/// Checks the tools; installs them with apt-get when running as root, else says what to run.
pub fn ensure() -> Result<()> {
    let m = missing();
    if m.is_empty() {
        return Ok(());
    }
    let install = format!("apt-get install -y --no-install-recommends {}", PACKAGES.join(" "));
    if !is_root() || !Path::new("/usr/bin/apt-get").exists() {
        bail!("missing {}; install them with:\n  sudo apt-get update && sudo {install}", m.join(", "));
    }
    eprintln!("==> provisioning: missing {}; installing Debian packages {}", m.join(", "), PACKAGES.join(" "));
    let ok = Command::new("apt-get").args(["update", "-qq"]).status().context("apt-get update")?.success()
        && Command::new("apt-get")
            .args(["install", "-y", "-qq", "--no-install-recommends"])
            .args(PACKAGES)
            .env("DEBIAN_FRONTEND", "noninteractive")
            .status()
            .context("apt-get install")?
            .success();
    let still = missing();
    if !ok || !still.is_empty() {
        bail!("provisioning failed; still missing: {}. Try: {install}", still.join(", "));
    }
    Ok(())
}
