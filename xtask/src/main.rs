//! `cargo xtask` — the commands that need more than `cargo`:
//!
//! * `cargo xtask test [--long]` — everything: provisioning, host tests, firmware cross-builds
//!   (QEMU and board images) with their footprint, then the hardware-in-the-loop tests in QEMU.
//! * `cargo xtask fw [--board | --rotor | --crank]` — cross-build an image (`edgekf-qemu`,
//!   `edgekf-board`, `edgekf-rotor-qemu` or `edgekf-crank-qemu`) and print its flash/RAM use.
//! * `cargo xtask run [--data FILE.csv]` — run the QEMU image on a data file (default: the demo
//!   scenario) and print the decoded defmt log, the stack high-water mark included.
//! * `cargo xtask bench` — per-step instruction counts of the filters on the Cortex-M4F under
//!   QEMU (an instruction-counting TCG plugin), checked against the budgets.
//! * `cargo xtask provision` — install what a fresh Debian machine lacks (as root), or say what.

mod bench;
mod firmware;
mod provision;

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
            let image = if flag("--board") {
                firmware::Image::Board
            } else if flag("--rotor") {
                firmware::Image::RotorQemu
            } else if flag("--crank") {
                firmware::Image::CrankQemu
            } else {
                firmware::Image::Qemu
            };
            let elf = firmware::build(image)?;
            firmware::print_footprint(image, &elf)
        }
        Some("run") => {
            provision::ensure()?;
            let data = args.iter().position(|a| a == "--data").and_then(|i| args.get(i + 1));
            let elf = firmware::build(firmware::Image::Qemu)?;
            firmware::run_and_print(&elf, data.map(std::path::Path::new))
        }
        Some("provision") => provision::ensure(),
        Some("bench") => {
            provision::ensure()?;
            bench::run(&firmware::workspace_root()).map(|_| ())
        }
        _ => {
            eprintln!("usage: cargo xtask <test [--long] | fw [--board | --rotor | --crank] | run [--data FILE.csv] | bench | provision>");
            std::process::exit(2);
        }
    }
}

/// The one command that runs every test.
fn test(long: bool) -> Result<()> {
    provision::ensure()?;
    step("host tests: cargo test --workspace");
    let mut host = cargo_here();
    host.args(["test", "--workspace"]);
    if long {
        host.env("EDGEKF_LONG", "1");
    }
    status(host, "host tests")?;

    step("firmware: cross-build the board image");
    let board = firmware::build(firmware::Image::Board)?;
    firmware::print_footprint(firmware::Image::Board, &board)?;
    step("firmware: cross-build the QEMU image");
    let qemu = firmware::build(firmware::Image::Qemu)?;
    firmware::print_footprint(firmware::Image::Qemu, &qemu)?;
    step("firmware: cross-build the rotor virtual-sensing QEMU image");
    let rotor = firmware::build(firmware::Image::RotorQemu)?;
    firmware::print_footprint(firmware::Image::RotorQemu, &rotor)?;
    step("firmware: cross-build the slider-crank clearance QEMU image");
    let crank = firmware::build(firmware::Image::CrankQemu)?;
    firmware::print_footprint(firmware::Image::CrankQemu, &crank)?;

    step("chip benchmarks: instruction counts per filter step in QEMU (deterministic, checked against budgets)");
    bench::run(&firmware::workspace_root())?;

    step("hardware-in-the-loop tests in QEMU");
    let mut hil = cargo_here();
    hil.args([
        "test",
        "-p",
        "edgekf-tests",
        "--features",
        "hil",
        "--test",
        "hil",
        "--test",
        "crank_node",
        "--",
        "--nocapture",
        "--test-threads",
        "1",
    ])
    .env("EDGEKF_FW_ELF", &qemu)
    .env("EDGEKF_ROTOR_ELF", &rotor)
    .env("EDGEKF_CRANK_ELF", &crank);
    status(hil, "HIL tests")?;
    step("all tests passed");
    Ok(())
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
