//! A demo part that closes a system's loop on a recording it simulated. Its inputs are written
//! as files (into `--out DIR/<system>/`, or a scratch folder removed afterwards) and the loop
//! runs on them through the system's own `edgekf loop <system>` function and flags, so the
//! report's `source` names real files and its `command` makes the same report again.

use super::request::{DemoArgs, LoopRequest};
use crate::io::output::{check_folder, write_atomic};
use crate::report::text::{show_value, write_report, REPORT_FILES};
use crate::residual_loop::{LoopOptions, LoopReport, RunSummary};
use anyhow::{Context, Result};
use clap::Args;
use std::path::{Path, PathBuf};

/// What a part hands to the loop: the declared model and the recording, as the files a user
/// would give `edgekf loop <system>`.
pub struct LoopInputs {
    /// The system's name: the `edgekf loop` subcommand and the folder under `--out`.
    pub system: &'static str,
    /// The system's `edgekf loop` run (its registry row's `close_loop.run`).
    pub run: fn(&LoopRequest, &clap::ArgMatches) -> Result<LoopReport>,
    /// Its own loop flags (its registry row's `close_loop.args`).
    pub args: fn(clap::Command) -> clap::Command,
    /// The declared configuration, TOML.
    pub config: String,
    /// The recording, CSV.
    pub data: String,
    /// Further inputs: `(flag, file name, CSV text)`, e.g. the boom's `--static static.csv`.
    pub extra: Vec<(&'static str, &'static str, String)>,
}

/// Checks, before any work, the files a part writes under `--out DIR/<system>/`: the report,
/// `data.csv`, `config.toml` and the `extra` file names.
pub fn check(args: &DemoArgs, system: &str, extra: &[&str]) -> Result<()> {
    let Some(out) = &args.out else { return Ok(()) };
    let names: Vec<String> =
        REPORT_FILES.iter().chain(&["data.csv", "config.toml"]).chain(extra).map(|f| format!("{system}/{f}")).collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    check_folder(out, &names, &[args.config.as_deref()])?;
    Ok(())
}

/// Writes the inputs, closes the loop on them as `edgekf loop` would (candidates printed to
/// standard error) and, with `--out`, writes the report beside them; returns the report.
pub fn close(args: &DemoArgs, inputs: &LoopInputs) -> Result<LoopReport> {
    let (dir, scratch) = match &args.out {
        Some(out) => (out.join(inputs.system), false),
        None => (scratch_folder(inputs.system), true),
    };
    std::fs::create_dir_all(&dir).with_context(|| format!("{}: cannot make the folder", dir.display()))?;
    let result = close_in(&dir, inputs, !scratch);
    if scratch {
        // A scratch folder left behind costs a little disk space, never a result.
        let _ = std::fs::remove_dir_all(&dir);
    }
    result
}

/// A fresh folder under the system's temporary directory for one process's part.
fn scratch_folder(system: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("edgekf-demo-{system}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// [`close`] in `dir`; `keep`: write the report there too.
fn close_in(dir: &Path, inputs: &LoopInputs, keep: bool) -> Result<LoopReport> {
    let (config, data) = (dir.join("config.toml"), dir.join("data.csv"));
    let mut files = vec![("--config", config.clone(), &inputs.config), ("--data", data.clone(), &inputs.data)];
    files.extend(inputs.extra.iter().map(|(flag, name, text)| (*flag, dir.join(name), text)));
    let mut words: Vec<String> = vec!["edgekf".into(), "loop".into(), inputs.system.into()];
    for (flag, path, text) in files {
        write_atomic(&path, text).with_context(|| format!("cannot write {}", path.display()))?;
        words.extend([flag.to_string(), path.display().to_string()]);
    }
    words.extend(["--report".to_string(), dir.display().to_string()]);
    let command = (inputs.args)(super::request::LoopArgs::augment_args(clap::Command::new(inputs.system)));
    let matches = command.try_get_matches_from(&words[2..]).context("the demo's own loop command")?;
    let request = LoopRequest {
        config: config.clone(),
        data: data.clone(),
        baseline: None,
        options: LoopOptions { progress: true, ..LoopOptions::default() },
    };
    let mut report = (inputs.run)(&request, &matches)?;
    super::request::fill_source(&mut report, &data, &config, &words.join(" "));
    if keep {
        write_report(&report, dir)?;
    }
    Ok(report)
}

/// An error figure of a part's result: its label, unit, and value before and after the loop.
pub type ErrorFigure<'a> = (&'a str, &'a str, f64, f64);

/// The error a part shows: its label, unit, and where a run's summary has it (`None` where the
/// recording has no truth).
pub struct ErrorOf {
    /// Its label (`tip peak error`).
    pub label: &'static str,
    /// Its unit after the number (`" %"`, or empty).
    pub unit: &'static str,
    /// Its value in a run's summary.
    pub of: fn(&RunSummary) -> Option<f64>,
}

/// Prints the part's result line (its `error` before and after) and, with `--out`, where its
/// files are and the command that reruns the report.
pub fn say(args: &DemoArgs, report: &LoopReport, error: &ErrorOf) {
    let figure =
        (error.of)(&report.before).zip((error.of)(&report.after)).map(|(b, a)| (error.label, error.unit, b, a));
    println!("  {}", result_line(report, figure));
    if let Some(out) = &args.out {
        println!("wrote the data, the declared model and the report in {}", out.join(&report.system).display());
        println!("rerun: {}", report.source.command.as_deref().unwrap_or_default());
    }
}

/// The part's one-line result: each effect the loop added with its value, and `error` before
/// and after the loop where the recording has the truth.
pub fn result_line(report: &LoopReport, error: Option<ErrorFigure<'_>>) -> String {
    let added: Vec<String> = report
        .effects_added
        .iter()
        .map(|e| format!("{} at {} {}", e.kind, e.location, show_value(e.value, &e.unit)))
        .collect();
    let added = if added.is_empty() { "nothing".to_string() } else { added.join(", ") };
    let error = error
        .map(|(label, unit, before, after)| format!("; {label} {before:.3}{unit} → {after:.3}{unit}"))
        .unwrap_or_default();
    format!("loop adds: {added}{error}")
}
