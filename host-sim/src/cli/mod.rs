//! The `edgekf` command line, built from a registry of systems: each row gives a system's
//! subcommands (`edgekf <system> …`), its residual loop (`edgekf loop <system>`) and its part of
//! `edgekf demo`. The dispatcher knows no system; [`crate::systems::REGISTRY`] is the table.
//!
//! * [`registry`]: the row type ([`SystemEntry`]) and the helpers that turn a system's clap
//!   `Subcommand` into one;
//! * [`request`]: what a row's functions are asked to do (the loop's, the baseline's, the
//!   demo's requests);
//! * [`looping`]: `edgekf loop <system>`: the flags every loop shares, the run, the report files;
//! * [`history`]: `edgekf loop <system> --data FOLDER`: every recording of a folder, and the
//!   machine's history (`trend.csv`, `trend.html`);
//! * [`baseline`]: `edgekf baseline <system>`: a healthy baseline learned from a recording;
//! * [`demo`]: `edgekf demo`: every system's demo part in the registry's order; [`demo_loop`],
//!   a part that closes a system's loop on files it can be rerun from;
//! * [`capture`]: `edgekf capture`: a node's handed-over window as a recording;
//! * [`values`]: flag values checked as clap parses them (out of range: a usage error).
//!
//! ```
//! use edgekf_sim::{cli, systems};
//! // `edgekf --version` goes through the same dispatcher as every command.
//! let help = cli::command(systems::REGISTRY).render_long_help().to_string();
//! assert!(help.contains("rotor") && help.contains("loop") && help.contains("demo"));
//! ```

pub mod baseline;
pub mod capture;
pub mod demo;
pub mod demo_loop;
pub mod history;
pub mod looping;
pub mod registry;
pub mod request;
pub mod values;

pub use registry::{DemoPart, LoopEntry, SystemEntry};

use anyhow::Result;
use std::ffi::OsString;
use std::process::ExitCode;

const EXAMPLES: &str = "Examples:
  edgekf demo --out out/
  edgekf oscillator simulate --config host-sim/configs/oscillator_demo.toml --out data.csv --faults
  edgekf oscillator estimate --config host-sim/configs/oscillator_demo.toml --data data.csv --out est.csv
  edgekf loop rotor --config host-sim/configs/rotor_paper.toml --data data.csv --report report/
  edgekf capture --log node.log --out window.csv";

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
    cmd.subcommand(looping::command(registry)).subcommand(baseline::command(registry)).subcommand(capture::command())
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
        "baseline" => baseline::run(registry, sub, &command_line),
        "capture" => capture::run(sub),
        _ => {
            let system = registry.iter().find(|s| s.name == name).expect("clap only accepts registered names");
            (system.run)(sub)
        }
    }
}

/// The `edgekf` binary: [`run_with`] on the process's arguments. Exit codes: 0 done (also
/// when the reader of standard output goes away, as `| head` does), 1 bad data, configuration
/// or output path (one line on standard error), 2 a usage error (clap's message).
pub fn main(registry: &[SystemEntry]) -> ExitCode {
    quiet_on_a_closed_pipe();
    match run_with(registry, std::env::args_os()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if is_closed_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", one_line(&e));
            ExitCode::FAILURE
        }
    }
}

/// `e` and its causes on one line (`: `-separated, inner line breaks folded).
fn one_line(e: &anyhow::Error) -> String {
    format!("{e:#}").split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Whether `e` is a write to a pipe whose reader has gone.
fn is_closed_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe))
}

/// `edgekf … | head -1` closes the pipe while edgekf still prints, and Rust's `print!` then
/// panics. The reader having seen enough is not an error: end quietly with exit 0 instead of a
/// panic message and exit 101. Every other panic keeps the default report.
fn quiet_on_a_closed_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let message = payload.downcast_ref::<String>().map(String::as_str).or(payload.downcast_ref::<&str>().copied());
        if message.is_some_and(|m| m.starts_with("failed printing to stdout") && m.contains("Broken pipe")) {
            std::process::exit(0);
        }
        default(info);
    }));
}
