//! `edgekf loop <system> --config C --data d.csv --report DIR`: the flags every system's loop
//! shares, the run through the system's [`LoopEntry`](super::LoopEntry), the printed summary and
//! the report files, with where the report came from (`source`).

use super::registry::{chosen_loop, SystemEntry};
use super::request::{fill_source, LoopArgs, LoopRequest};
use crate::io::output::{check, check_folder, write_atomic};
use crate::report::text::{summary_table, write_report, REPORT_FILES};
use crate::residual_loop::correction::corrected_config;
use crate::residual_loop::{Correction, LoopOptions, LoopReport};
use anyhow::{Context, Result};
use clap::{ArgMatches, Args, FromArgMatches};
use std::path::Path;

/// `edgekf loop` with one subcommand per system that has a loop.
pub fn command(registry: &[SystemEntry]) -> clap::Command {
    let mut cmd = clap::Command::new("loop")
        .about(
            "Close the loop with measured data: read the filter's innovations, add the model effects they \
             point at when they pay for their parameters, report before/after",
        )
        .subcommand_required(true)
        .arg_required_else_help(true);
    for s in registry {
        if let Some(l) = &s.close_loop {
            // The about last, the long about cleared: `augment_args` puts the flag structs' own
            // docs there, which `edgekf loop --help` would print as the subcommand's text.
            let sub = (l.args)(LoopArgs::augment_args(clap::Command::new(s.name)));
            cmd = cmd.subcommand(sub.about(l.about).long_about(None));
        }
    }
    cmd
}

/// Runs `edgekf loop <system> …` (`m`: the `loop` subcommand's matches); `command_line` goes
/// into the report's `source`.
pub fn run(registry: &[SystemEntry], m: &ArgMatches, command_line: &str) -> Result<()> {
    let (name, entry, sub) = chosen_loop(registry, m);
    let args = LoopArgs::from_arg_matches(sub).map_err(|e| anyhow::anyhow!("{e}"))?;
    if args.baseline.is_some() && entry.baseline.is_none() {
        let with: Vec<&str> = registry
            .iter()
            .filter(|s| s.close_loop.as_ref().is_some_and(|l| l.baseline.is_some()))
            .map(|s| s.name)
            .collect();
        anyhow::bail!(
            "edgekf loop {name}: --baseline would be ignored: {name} has no baselines yet (systems with baselines: {})",
            with.join(", ")
        );
    }
    if args.data.is_dir() || super::history::is_pattern(&args.data) {
        return history(registry, name, entry, &args, sub, command_line);
    }
    let inputs = [Some(args.data.as_path()), Some(args.config.as_path()), args.baseline.as_deref()];
    check_folder(&args.report, &REPORT_FILES, &inputs)?;
    check(&[args.corrected_config.as_deref()], &inputs)?;
    let request = LoopRequest {
        config: args.config.clone(),
        data: args.data.clone(),
        baseline: args.baseline.clone(),
        options: LoopOptions { max_effects: args.max_effects, progress: !args.quiet, ..LoopOptions::default() },
    };
    let mut report = (entry.run)(&request, sub)?;
    fill_source(&mut report, &args.data, &args.config, command_line);
    report.source.baseline = args.baseline.as_ref().map(|b| b.display().to_string());
    print!("{}", summary_table(&report));
    write_report(&report, &args.report)?;
    println!("wrote {0}/report.json and {0}/report.html", args.report.display());
    if let Some(path) = &args.corrected_config {
        write_corrected(&report, &args.config, &args.report, path)?;
    }
    Ok(())
}

/// `edgekf loop <system> --data FOLDER` (or a pattern): the machine's history ([`super::history`]). A folder
/// without recordings, or `--corrected-config` (one file cannot carry many recordings'
/// corrections), is a usage error (exit code 2, as clap's).
fn history(
    registry: &[SystemEntry],
    name: &str,
    entry: &super::LoopEntry,
    args: &LoopArgs,
    sub: &ArgMatches,
    command_line: &str,
) -> Result<()> {
    if args.corrected_config.is_some() {
        let message =
            "--corrected-config takes one recording, not a folder: run the recording whose corrections you want alone";
        usage_error(registry, name, message);
    }
    if super::history::recordings(&args.data)?.is_empty() {
        let what =
            if args.data.is_dir() { "the folder holds no *.csv recording" } else { "no file matches the pattern" };
        usage_error(registry, name, &format!("--data {}: {what}", args.data.display()));
    }
    super::history::run(name, entry, args, sub, command_line)
}

/// Prints `message` as clap prints a usage error of `edgekf loop <name>` and exits with its
/// code, 2.
fn usage_error(registry: &[SystemEntry], name: &str, message: &str) -> ! {
    let sub = command(registry).find_subcommand(name).cloned().expect("the system's loop is a subcommand");
    let mut sub = sub.bin_name(format!("edgekf loop {name}"));
    sub.error(clap::error::ErrorKind::InvalidValue, message).exit()
}

/// Writes `config` with the report's corrections to `out` (whole, or not at all), and says
/// which effects it could not carry.
fn write_corrected(report: &LoopReport, config: &Path, report_dir: &Path, out: &Path) -> Result<()> {
    let text = std::fs::read_to_string(config).with_context(|| format!("{}: cannot read", config.display()))?;
    let origin = report_dir.join("report.json").display().to_string();
    let fixed = corrected_config(&text, &report.corrections, &origin)
        .with_context(|| format!("{}: cannot write the corrections into it", config.display()))?;
    write_atomic(out, fixed).with_context(|| format!("{}: cannot write", out.display()))?;
    let carried = report.corrections.iter().filter(|c| matches!(c.correction, Correction::Model { .. })).count();
    println!("wrote {} ({carried} of {} effects carried into the model)", out.display(), report.corrections.len());
    for c in &report.corrections {
        match &c.correction {
            Correction::Indicator { note, .. } => println!("  {}: a fault, not modelled: {note}", c.effect),
            Correction::NotCarried { reason } => println!("  {}: not carried: {reason}", c.effect),
            Correction::Model { .. } => {}
        }
    }
    Ok(())
}
