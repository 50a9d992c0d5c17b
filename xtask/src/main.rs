//! `cargo xtask` — the commands that need more than `cargo`:
//!
//! * `cargo xtask test [--long]` — everything: provisioning, host tests, firmware cross-builds
//!   (QEMU and board images) with their footprint, then the hardware-in-the-loop tests in QEMU.
//! * `cargo xtask fw [FLAG]` — cross-build an image (`edgekf-qemu` without a flag; the flags
//!   are the image table's, `--board`, `--rotor`, …, and `cargo xtask` alone lists them), prove
//!   it panic-free and print its flash/RAM use.
//! * `cargo xtask panics [FLAG]` — build an image without the proof and list its panic paths
//!   (source line, panic function, enclosing function).
//! * `cargo xtask run [--data FILE.csv]` — run the QEMU image on a data file (default: the demo
//!   scenario) and print the decoded defmt log, the stack high-water mark included.
//! * `cargo xtask bench [--check]` — per-step instruction counts of the filters on the
//!   Cortex-M4F under QEMU (an instruction-counting TCG plugin), checked against the budgets,
//!   and every image's real-time table; then (not with `--check`, which is what `test` runs) the
//!   host's speed against ROSS and filterpy in a Python environment it creates
//!   ([`peers`]). Both go to `target/bench/results.json`.
//! * `cargo xtask soak` — the long numerical soak in QEMU: every filter of
//!   `edgekf_firmware::soak` for about 10¹⁰ instructions, its instruction count measured by the
//!   TCG plugin, bit-identical to the host's run and checked (`tests/tests/soak_qemu.rs`).
//! * `cargo xtask fuzz [--seconds N] [TARGET…]` — the coverage-guided fuzz targets of `fuzz/`
//!   for N seconds each (default 20), on stable (cargo-fuzz without a sanitizer; installed when
//!   missing).
//! * `cargo xtask loop-matrix [SYSTEM…]` — the residual loop's effect matrices (every case run
//!   in parallel, scored by one rule) written into the README's tables between its
//!   `<!-- loop-matrix SYSTEM -->` markers.
//! * `cargo xtask roundtrip oscillator` — issue #36's round trip in QEMU: an offset that starts
//!   mid-run → the node's `mismatch` → its window → `edgekf capture` → `edgekf loop
//!   --corrected-config` → `edgekf oscillator export` → the rebuilt node on a fresh recording;
//!   prints the figures and checks them (files in `target/roundtrip/oscillator/`).
//! * `cargo xtask roundtrip boom` — the boom's: a heavier platform → the node's `mismatch` →
//!   `edgekf loop boom --corrected-config` on the uploaded recording → `edgekf boom export` →
//!   the rebuilt node on a fresh recording (files in `target/roundtrip/boom/`).
//! * `cargo xtask roundtrip uuv` — the vehicle's: a sideways DVL offset → the node's
//!   `mismatch` → `edgekf loop uuv --corrected-config` on the uploaded flight → `edgekf uuv
//!   export` → the rebuilt node on a fresh flight (files in `target/roundtrip/uuv/`).
//! * `cargo xtask cwru --dir D [--jobs N] [--loads 0,1,2,3] [--out FILE.md] [--keep DIR]` — issue
//!   #35's benchmark: the 0 hp baseline from `D/097a.csv`, then `edgekf loop rotor --baseline` on
//!   every 12 kHz drive-end fault record of the Case Western Reserve University data in D, and the
//!   table record → expected → named → right/wrong → Smith & Randall's grade with the counts
//!   ([`cwru`]).
//! * `cargo xtask provision` — install what a fresh Debian machine lacks (as root), or say what.
//!
//! Every build proves its image panic-free at link time (feature `no-panic-proof`); a failed
//! proof lists where the panic paths are ([`panics`]).
//!
//! The images, their flags, HIL tests and instruction budgets are one table, [`images::IMAGES`]:
//! the systems' rows come from the firmware's manifest (`edgekf_firmware::systems::IMAGES`).

mod bench;
mod cwru;
mod firmware;
mod fuzz;
mod images;
mod panics;
mod peers;
mod provision;

use images::{Role, IMAGES};

use anyhow::{bail, Context, Result};
use std::process::Command;

fn main() {
    if let Err(e) = run() {
        eprintln!("xtask: error: {e:#}");
        std::process::exit(1);
    }
}

fn run() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let flag = |f: &str| args.iter().any(|a| a == f);
    match args.first().map(String::as_str) {
        Some("test") => test(flag("--long")),
        Some("fw") => {
            provision::ensure()?;
            let image = images::select(&args);
            let elf = firmware::build(image)?;
            firmware::print_footprint(image, &elf)
        }
        Some("run") => {
            provision::ensure()?;
            let data = args.iter().position(|a| a == "--data").and_then(|i| args.get(i + 1));
            let elf = firmware::build(images::default_image())?;
            firmware::run_and_print(&elf, data.map(std::path::Path::new))
        }
        Some("panics") => {
            provision::ensure()?;
            let elf = firmware::build_with(images::select(&args), firmware::Proof::Ordinary)?;
            let sites = panics::sites(&elf)?;
            println!("{} panic path(s) in {}", sites.len(), elf.display());
            panics::print(&sites);
            Ok(())
        }
        Some("provision") => provision::ensure(),
        Some("fuzz") => fuzz::run(&firmware::workspace_root(), &args[1..]),
        Some("soak") => {
            provision::ensure()?;
            soak()
        }
        Some("bench") => {
            provision::ensure()?;
            bench::run(&firmware::workspace_root(), !flag("--check")).map(|_| ())
        }
        Some("loop-matrix") => loop_matrix(&args[1..]),
        Some("cwru") => cwru::main(&firmware::workspace_root(), &args[1..]),
        Some("roundtrip") => {
            provision::ensure()?;
            roundtrip(args.get(1).map(String::as_str))
        }
        _ => {
            eprintln!(
                "usage: cargo xtask <test [--long] | fw [{0}] | panics [{0}] | run [--data FILE.csv] | bench [--check] | soak | fuzz [--seconds N] [TARGET…] | loop-matrix [SYSTEM…] | cwru --dir D [--jobs N] [--loads 0,1,2,3] [--out FILE.md] [--keep DIR] | roundtrip oscillator|boom|uuv | provision>",
                images::flags()
            );
            std::process::exit(2);
        }
    }
}

/// The one command that runs every test.
fn test(long: bool) -> Result<()> {
    provision::ensure()?;
    // The studies (crank identifiability) are behind a feature; their tests run here.
    step("host tests: cargo test --workspace --features edgekf-sim/studies");
    let mut host = cargo_here();
    host.args(["test", "--workspace", "--features", "edgekf-sim/studies"]);
    if long {
        host.env("EDGEKF_LONG", "1");
    }
    status(host, "host tests")?;

    // Every image except the bench one (built by the bench step), with its footprint; the HIL
    // images' ELF paths go to their tests.
    let mut hil = cargo_here();
    hil.args(["test", "-p", "edgekf-tests", "--features", "hil"]);
    let mut tests: Vec<&str> = Vec::new();
    // The images whose round trips run with --long: their variables and ELFs.
    let (mut oscillator, mut long_images) = (None, Vec::new());
    for image in IMAGES.iter().filter(|i| i.role != Role::Bench) {
        step(&format!("firmware: cross-build {} and prove it panic-free", image.what));
        let elf = firmware::build(image)?;
        firmware::print_footprint(image, &elf)?;
        if image.bin == images::default_image().bin {
            oscillator = Some(elf.clone());
        }
        if let Role::Hil { env, tests: these } = image.role {
            hil.env(env, &elf);
            if ["EDGEKF_BOOM_ELF", "EDGEKF_UUV_ELF"].contains(&env) {
                long_images.push((env, elf.clone()));
            }
            for t in these {
                if !tests.contains(t) {
                    tests.push(t);
                }
            }
        }
    }

    step("chip benchmarks: instruction counts per filter step in QEMU (deterministic, checked against budgets)");
    bench::run(&firmware::workspace_root(), false)?;

    step("hardware-in-the-loop tests in QEMU");
    for t in tests {
        hil.args(["--test", t]);
    }
    hil.args(["--", "--nocapture", "--test-threads", "1"]);
    status(hil, "HIL tests")?;

    // Last: it rebuilds the oscillator's image with other constants (the ELF the HIL tests
    // read is then the corrected model's until the next build).
    // With --long, the boom's and the vehicle's too (they rebuild their images the same way).
    step("the round trips in QEMU (tests/roundtrip.rs: the oscillator's; the boom's and the vehicle's with --long)");
    let mut rt = cargo_here();
    rt.args(["test", "-p", "edgekf-tests", "--features", "hil", "--test", "roundtrip"]);
    rt.args(["--", "--nocapture", "--test-threads", "1"]);
    rt.env("EDGEKF_FW_ELF", oscillator.context("no oscillator image was built")?);
    if long {
        if long_images.len() != 2 {
            bail!("the boom's and the vehicle's images were not both built");
        }
        rt.env("EDGEKF_LONG", "1").envs(long_images);
    }
    status(rt, "the round trip")?;
    step("all tests passed");
    Ok(())
}

/// The effect matrices of `systems` (all without one) into the README.
fn loop_matrix(systems: &[String]) -> Result<()> {
    let root = firmware::workspace_root();
    step("the residual loop's effect matrices (every case in parallel)");
    let mut run = cargo_here();
    run.current_dir(&root).args(["run", "--release", "-p", "edgekf-sim", "--example", "loop_matrix", "--"]);
    run.args(systems).arg("--readme").arg(root.join("README.md"));
    status(run, "the effect matrices")
}

/// `cargo xtask roundtrip <system>`: the oscillator's, the boom's and the vehicle's (see
/// `edgekf_tests::roundtrip`, `edgekf_tests::roundtrip_boom` and `edgekf_tests::roundtrip_uuv`).
fn roundtrip(system: Option<&str>) -> Result<()> {
    use edgekf_tests::{roundtrip, roundtrip_boom, roundtrip_uuv};
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| firmware::workspace_root().join("target"))
        .join("roundtrip");
    // The image `bin` built as shipped, and a build of it with the model file `var` names.
    let rebuilds = |bin: &str, var: &'static str, dir: &std::path::Path| {
        let image = IMAGES.iter().find(|i| i.bin == bin).with_context(|| format!("{bin} is not in the table"))?;
        let shipped = firmware::build(image)?;
        step(&format!("the round trip of {bin} in QEMU, files in {}", dir.display()));
        let build = move |model: &std::path::Path| {
            firmware::build_env(image, firmware::Proof::NoPanic, &[(var, model.as_os_str())])
        };
        Ok::<_, anyhow::Error>((shipped, build))
    };
    match system {
        Some("oscillator") => {
            let setup = roundtrip::Setup::oscillator(target.join("oscillator"));
            let (shipped, build) = rebuilds(images::default_image().bin, "EDGEKF_OSCILLATOR_MODEL", &setup.dir)?;
            let figures = roundtrip::oscillator(&setup, &shipped, &build)?;
            println!("{figures}");
            figures.check(setup.offset_m_s2)
        }
        Some("boom") => {
            let setup = roundtrip_boom::BoomSetup::new(target.join("boom"));
            let (shipped, build) = rebuilds("edgekf-boom-qemu", "EDGEKF_BOOM_MODEL", &setup.dir)?;
            let figures = roundtrip_boom::boom(&setup, &shipped, &build)?;
            println!("{figures}");
            figures.check()
        }
        Some("uuv") => {
            let setup = roundtrip_uuv::UuvSetup::new(target.join("uuv"));
            let (shipped, build) = rebuilds("edgekf-uuv-qemu", "EDGEKF_UUV_MODEL", &setup.dir)?;
            let figures = roundtrip_uuv::uuv(&setup, &shipped, &build)?;
            println!("{figures}");
            figures.check()
        }
        _ => bail!("roundtrip: give the system; the round trip exists for: oscillator, boom, uuv"),
    }
}

/// The long QEMU soak: the soak image on every filter's `qemu_long_steps`, with the
/// instruction-counting plugin, through its HIL test.
fn soak() -> Result<()> {
    let root = firmware::workspace_root();
    let image = IMAGES.iter().find(|i| i.bin == images::SOAK_IMAGE).context("the soak image is not in the table")?;
    let elf = firmware::build(image)?;
    let plugin = bench::plugin(&root)?;
    step("the long numerical soak in QEMU (about 1e10 instructions a filter)");
    let mut test = cargo_here();
    test.args(["test", "--release", "-p", "edgekf-tests", "--features", "hil", "--test", "soak_qemu"])
        .args(["--", "--nocapture"])
        .env("EDGEKF_SOAK_ELF", &elf)
        .env("EDGEKF_LONG", "1")
        .env("EDGEKF_QEMU_PLUGIN", &plugin);
    status(test, "the long QEMU soak")
}

fn step(what: &str) {
    eprintln!("\n==> {what}");
}

/// The cargo that runs this xtask (rustup's, usually), for host builds.
fn cargo_here() -> Command {
    Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
}

fn status(mut cmd: Command, what: &str) -> Result<()> {
    let st = cmd.status().with_context(|| format!("starting {what}"))?;
    if !st.success() {
        bail!("{what} failed ({st})");
    }
    Ok(())
}
