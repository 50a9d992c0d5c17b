//! The `edgekf` command line, built from a registry of systems: each row gives a system's
//! subcommands (`edgekf <system> …`), its residual loop (`edgekf loop <system>`) and its part of
//! `edgekf demo`. The dispatcher knows no system; [`crate::systems::REGISTRY`] is the table.
//!
//! * [`registry`]: the row type ([`SystemEntry`]) and the helpers that turn a system's clap
//!   `Subcommand` into one;
//! * [`looping`]: `edgekf loop <system>`: the flags every loop shares, the run, the report files;
//! * [`demo`]: `edgekf demo`: every system's demo part in the registry's order.
//!
//! ```
//! use edgekf_sim::{cli, systems};
//! // `edgekf --version` goes through the same dispatcher as every command.
//! let help = cli::command(systems::REGISTRY).render_long_help().to_string();
//! assert!(help.contains("rotor") && help.contains("loop") && help.contains("demo"));
//! ```

pub mod demo;
pub mod looping;
pub mod registry;

pub use registry::{DemoPart, LoopEntry, SystemEntry};

use anyhow::Result;
use std::ffi::OsString;
use std::process::ExitCode;

const EXAMPLES: &str = "Examples:
  edgekf demo --out out/
  edgekf oscillator simulate --config host-sim/configs/oscillator_demo.toml --out data.csv --faults
  edgekf oscillator estimate --config host-sim/configs/oscillator_demo.toml --data data.csv --out est.csv
  edgekf loop rotor --config host-sim/configs/rotor_paper.toml --data data.csv --report report/";

/// The whole command tree for `registry`.
pub fn command(registry: &[SystemEntry]) -> clap::Command {
    let mut cmd = clap::Command::new("edgekf")
        .version(env!("CARGO_PKG_VERSION"))
        .propagate_version(true)
        .about("Host tools of edgekf: Kalman filtering for an edge vibration sensor (ADXL355 + Cortex-M4F).")
        .long_about(
            "Host tools of edgekf: Kalman filtering for an edge vibration sensor (ADXL355 + Cortex-M4F).\n\n\
             Data files are CSV: a header, first column `t` in seconds, then channels in SI units \
             (`ax` in m/s², …), ground truth in `truth_*` columns. Configuration files are TOML; see \
             host-sim/configs/ for every field with its unit.",
        )
        .after_help(EXAMPLES)
        .subcommand_required(true)
        .arg_required_else_help(true)
        .subcommand(demo::command(registry));
    for s in registry {
        cmd = cmd.subcommand((s.command)().name(s.name).about(s.about));
    }
    cmd.subcommand(looping::command(registry))
}

/// Runs the command line `args` (the program's name first) against `registry`. Usage errors,
/// `--help` and `--version` print and exit as clap does (exit code 2 for usage errors, 0 for help).
pub fn run_with<I, T>(registry: &[SystemEntry], args: I) -> Result<()>
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let args: Vec<OsString> = args.into_iter().map(Into::into).collect();
    let command_line = args.iter().map(|a| a.to_string_lossy()).collect::<Vec<_>>().join(" ");
    let matches = command(registry).try_get_matches_from(&args).unwrap_or_else(|e| e.exit());
    let Some((name, sub)) = matches.subcommand() else { unreachable!("clap requires a subcommand") };
    match name {
        "demo" => demo::run(registry, sub),
        "loop" => looping::run(registry, sub, &command_line),
        _ => {
            let system = registry.iter().find(|s| s.name == name).expect("clap only accepts registered names");
            (system.run)(sub)
        }
    }
}

/// The `edgekf` binary: [`run_with`] on the process's arguments; errors print one line and
/// exit 1.
pub fn main(registry: &[SystemEntry]) -> ExitCode {
    match run_with(registry, std::env::args_os()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
