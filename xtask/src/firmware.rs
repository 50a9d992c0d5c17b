//! Cross-building the firmware images and reporting their footprint.

use crate::images::{Image, Role};
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

pub use edgekf_tests::cross::workspace_root;

/// Whether a build carries the no-panic proof (feature `no-panic-proof` of `edgekf-firmware`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Proof {
    /// `panic-never`'s handler: the link fails if a panic path survives.
    NoPanic,
    /// The ordinary handler (a message over semihosting or defmt), panic paths kept.
    Ordinary,
}

/// Builds `image`, proves it panic-free at link time (feature `no-panic-proof`: every image
/// reads its input with the shared crate's panic-free parser, not `core`'s) and returns the ELF
/// path. A failed proof lists the panic paths that survived ([`crate::panics`]).
pub fn build(image: &Image) -> Result<PathBuf> {
    match build_with(image, Proof::NoPanic) {
        Ok(elf) => Ok(elf),
        Err(e) => {
            eprintln!(
                "\nxtask: {} did not build with the no-panic proof (feature no-panic-proof). If the \
                 link failed with `undefined reference to ... panic-never ...`, a panic path \
                 survived optimisation; building the ordinary image to find it",
                image.bin
            );
            let elf = build_with(image, Proof::Ordinary).context("the ordinary build failed too")?;
            let sites = crate::panics::sites(&elf)?;
            if sites.is_empty() {
                Err(e)
            } else {
                surviving(image, &elf, &sites)
            }
        }
    }
}

/// The failed proof's message, with the panic paths that survived.
fn surviving(image: &Image, elf: &Path, sites: &[crate::panics::Site]) -> Result<PathBuf> {
    eprintln!("panic paths in {} (source line, panic, function):", elf.display());
    crate::panics::print(sites);
    bail!(
        "{}: {} panic path(s) survived, listed above (the no-panic proof, see the README): remove \
         them (checked or `get` indexing, explicit wrapping/saturating/checked arithmetic, handled \
         errors); `cargo xtask panics{}` lists them again",
        image.bin,
        sites.len(),
        image.flag.map(|f| format!(" {f}")).unwrap_or_default()
    )
}

/// Builds `image` with Debian's cargo (`-Zbuild-std=core`, the recipe of
/// [`edgekf_tests::cross::build`]) and returns the ELF path.
pub fn build_with(image: &Image, proof: Proof) -> Result<PathBuf> {
    build_env(image, proof, &[])
}

/// [`build_with`] with the environment `env` added (e.g. `EDGEKF_OSCILLATOR_MODEL`).
pub fn build_env(image: &Image, proof: Proof, env: &[(&str, &std::ffi::OsStr)]) -> Result<PathBuf> {
    // The soak and bench images gather every system's rows: they are built with the features
    // of the systems behind one that this xtask's table holds (the firmware manifest's
    // `FEATURES`), so that they run the same systems as the table. A system's own image names
    // its feature in its row; the others (a user's) carry no test system.
    let mut features = vec![image.features];
    if image.role == Role::Bench || image.bin == crate::images::SOAK_IMAGE {
        features.extend(edgekf_firmware::systems::FEATURES);
    }
    if proof == Proof::NoPanic {
        features.push("no-panic-proof");
    }
    edgekf_tests::cross::build(image.bin, &features.join(","), env)
}

/// Flash and static RAM of an ELF, from its allocated sections.
pub fn footprint(elf: &Path) -> Result<(u64, u64)> {
    let out = Command::new("arm-none-eabi-size").arg("-A").arg(elf).output().context("arm-none-eabi-size")?;
    if !out.status.success() {
        bail!("arm-none-eabi-size failed on {}", elf.display());
    }
    let (mut flash, mut ram) = (0u64, 0u64);
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        let [name, size, addr] = f[..] else { continue };
        let (Ok(size), Ok(addr)) = (size.parse::<u64>(), addr.parse::<u64>()) else { continue };
        if (0x0800_0000..0x0810_0000).contains(&addr) {
            flash += size;
        } else if (0x2000_0000..0x2002_0000).contains(&addr) {
            ram += size;
            if name == ".data" {
                flash += size; // initial values live in flash
            }
        }
    }
    Ok((flash, ram))
}

/// Prints the footprint line the README quotes.
pub fn print_footprint(image: &Image, elf: &Path) -> Result<()> {
    let (flash, ram) = footprint(elf)?;
    println!(
        "footprint {}: flash {} B ({:.1} KiB of 512 KiB), static RAM {} B ({:.1} KiB of 128 KiB) — {}",
        image.bin,
        flash,
        flash as f64 / 1024.0,
        ram,
        ram as f64 / 1024.0,
        elf.display()
    );
    Ok(())
}

/// Runs the QEMU image on `data` (default: the demo scenario) and prints the decoded log.
pub fn run_and_print(elf: &Path, data: Option<&Path>) -> Result<()> {
    let input = match data {
        Some(p) => std::fs::read(p).with_context(|| format!("reading {}", p.display()))?,
        None => edgekf_sim::systems::oscillator::scenario::Scenario::default().simulate().to_csv_string().into_bytes(),
    };
    let run = edgekf_tests::qemu::run(elf, &input, Duration::from_secs(120))?;
    for line in &run.lines {
        println!("{line}");
    }
    if !run.stderr.trim().is_empty() {
        eprintln!("{}", run.stderr.trim());
    }
    if let Some(msg) = run.failure() {
        bail!(msg);
    }
    let report = edgekf_tests::report::RunReport::parse(run.lines.iter().map(String::as_str))?;
    if let Some(s) = report.stack {
        println!(
            "stack high-water: {} B during start-up, {} B in the main loop, {} B available",
            s.boot, s.used, s.total
        );
    }
    Ok(())
}
