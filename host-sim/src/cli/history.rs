//! `edgekf loop <system> --data DIR`: a machine's history. Every `*.csv` directly in `DIR` (or
//! every file a pattern such as `'runs/2026-12-*.csv'` matches) is one recording; each is run through the system's loop as `--data FILE` would run it (in
//! parallel over the cores), its report written under `--report OUT/<recording's stem>/`, and
//! the history of all of them written as `OUT/trend.csv` and `OUT/trend.html`
//! ([`crate::trend`]).
//!
//! A recording that cannot be read or run does not stop the others: the history is made from
//! those that ran, says which failed and why, and the command then exits 1. Every output is
//! checked before any work (none is an input) and written whole.

use super::registry::LoopEntry;
use super::request::LoopRequest;
use super::request::{fill_source, LoopArgs};
use crate::io::output::{check_folder, write_atomic};
use crate::report::text::{write_report, REPORT_FILES};
use crate::residual_loop::LoopOptions;
use crate::trend::{Clock, Point, Trend};
use anyhow::{Context, Result};
use clap::ArgMatches;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// The history's own files in the report folder.
pub const HISTORY_FILES: [&str; 2] = ["trend.csv", "trend.html"];

/// Whether `data` names a set of recordings by a pattern (`runs/2026-12-*.csv`: `*`, `?` or
/// `[…]` in it, as quoted on the command line) rather than one file or folder.
///
/// ```
/// use edgekf_sim::cli::history::is_pattern;
/// use std::path::Path;
/// assert!(is_pattern(Path::new("runs/day-*.csv")) && !is_pattern(Path::new("runs/day-1.csv")));
/// ```
pub fn is_pattern(data: &Path) -> bool {
    data.to_str().is_some_and(|s| s.contains(['*', '?', '[']))
}

/// The recordings `data` names: a folder's files named `*.csv` (any case; sub-folders are not
/// searched, so reports written inside it are never read back), or the files a pattern
/// ([`is_pattern`], the `glob` crate's syntax) matches; sorted by name.
///
/// ```
/// let dir = std::env::temp_dir().join("edgekf-doc-history-recordings");
/// std::fs::create_dir_all(&dir).unwrap();
/// for name in ["b.csv", "a.CSV", "notes.txt", "b2.csv"] {
///     std::fs::write(dir.join(name), "t,ax\n0,1\n").unwrap();
/// }
/// let names = |found: Vec<std::path::PathBuf>| -> Vec<String> {
///     found.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect()
/// };
/// let found = edgekf_sim::cli::history::recordings(&dir).unwrap();
/// assert_eq!(names(found), ["a.CSV", "b.csv", "b2.csv"]);
/// let found = edgekf_sim::cli::history::recordings(&dir.join("b*.csv")).unwrap();
/// assert_eq!(names(found), ["b.csv", "b2.csv"]);
/// ```
pub fn recordings(data: &Path) -> Result<Vec<PathBuf>> {
    if is_pattern(data) && !data.is_dir() {
        let pattern = data.to_string_lossy();
        let paths = glob::glob(&pattern).with_context(|| format!("--data {pattern}: not a usable pattern"))?;
        let mut out = Vec::new();
        for path in paths {
            let path = path.with_context(|| format!("--data {pattern}: cannot list a folder it reaches"))?;
            if path.is_file() {
                out.push(path);
            }
        }
        out.sort();
        return Ok(out);
    }
    let dir = data;
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).with_context(|| format!("{}: cannot list the folder", dir.display()))? {
        let path = entry.with_context(|| format!("{}: cannot list the folder", dir.display()))?.path();
        let is_csv = path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("csv"));
        if is_csv && path.is_file() {
            out.push(path);
        }
    }
    out.sort();
    Ok(out)
}

/// A recording's name: its file name without the extension (its report folder's name).
fn stem(path: &Path) -> String {
    path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

/// Checks, before any work, that the history's files and each recording's report folder can
/// be written without touching an input, and that no two recordings share a report folder.
fn check_outputs(args: &LoopArgs, files: &[PathBuf]) -> Result<()> {
    let folders: Vec<&Path> = files.iter().filter_map(|f| f.parent()).collect();
    let holds_recordings = folders.iter().any(|d| same_file::is_same_file(&args.report, d).unwrap_or(false));
    if same_file::is_same_file(&args.report, &args.data).unwrap_or(false) || holds_recordings {
        anyhow::bail!(
            "{}: the report folder is the data folder; choose another, so that the history's files are not read as recordings next time",
            args.report.display()
        );
    }
    let mut inputs: Vec<Option<&Path>> = files.iter().map(|f| Some(f.as_path())).collect();
    inputs.extend([Some(args.config.as_path()), args.baseline.as_deref()]);
    check_folder(&args.report, &HISTORY_FILES, &inputs)?;
    let mut stems: Vec<String> = files.iter().map(|f| stem(f)).collect();
    stems.sort();
    if let Some(w) = stems.windows(2).find(|w| w[0] == w[1]) {
        anyhow::bail!("{}: two recordings are named {}: their reports would share a folder", args.data.display(), w[0]);
    }
    if args.report.is_dir() {
        for s in &stems {
            check_folder(&args.report.join(s), &REPORT_FILES, &inputs)?;
        }
    }
    Ok(())
}

/// Runs the loop on the recording `path` and writes its report under `report/<stem>/`.
fn run_one(entry: &LoopEntry, args: &LoopArgs, sub: &ArgMatches, path: &Path, command_line: &str) -> Result<Point> {
    let request = LoopRequest {
        config: args.config.clone(),
        data: path.to_path_buf(),
        baseline: args.baseline.clone(),
        // One line per candidate from several recordings at once reads as noise: the bar says
        // how far the history is.
        options: LoopOptions { max_effects: args.max_effects, progress: false, ..LoopOptions::default() },
    };
    let mut report = (entry.run)(&request, sub)?;
    let name = stem(path);
    let single = single_command(command_line, args, path, &args.report.join(&name));
    fill_source(&mut report, path, &args.config, &single);
    report.source.baseline = args.baseline.as_ref().map(|b| b.display().to_string());
    write_report(&report, &args.report.join(&name))?;
    Ok(Point::from_report(&name, &report))
}

/// The command that makes one recording's report alone: `command_line` with the folder's
/// `--data` and `--report` replaced by the recording's (as given where they are not spelt
/// `--data DIR --report OUT`), so that every report's `source.command` reruns it.
///
/// ```
/// # use edgekf_sim::cli::history::single_command;
/// # use edgekf_sim::cli::request::LoopArgs;
/// # use std::path::{Path, PathBuf};
/// let args = LoopArgs {
///     config: "c.toml".into(),
///     data: "recs".into(),
///     report: "out".into(),
///     baseline: None,
///     corrected_config: None,
///     max_effects: 4,
///     quiet: true,
/// };
/// let line = "edgekf loop oscillator --config c.toml --data recs --report out --quiet";
/// let one = single_command(line, &args, Path::new("recs/day1.csv"), Path::new("out/day1"));
/// assert_eq!(one, "edgekf loop oscillator --config c.toml --data recs/day1.csv --report out/day1 --quiet");
/// ```
pub fn single_command(command_line: &str, args: &LoopArgs, data: &Path, report: &Path) -> String {
    let mut words: Vec<String> = command_line.split(' ').map(str::to_string).collect();
    for (flag, from, to) in [("--data", &args.data, data), ("--report", &args.report, report)] {
        for k in 1..words.len() {
            if words[k - 1] == flag && Path::new(&words[k]) == from.as_path() {
                words[k] = to.display().to_string();
            }
        }
    }
    words.join(" ")
}

/// A progress bar over `n` recordings on stderr (hidden with `quiet`, and by indicatif when
/// stderr is not a terminal).
fn progress_bar(n: usize, quiet: bool) -> indicatif::ProgressBar {
    if quiet {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(n as u64);
    if let Ok(style) = indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} recordings, {elapsed} {msg}") {
        bar.set_style(style);
    }
    bar
}

/// Runs every recording of the folder `args.data` (`files`, from [`recordings`]) and writes
/// their reports and the history; fails at the end, naming them, if any recording failed.
pub fn run(system: &str, entry: &LoopEntry, args: &LoopArgs, sub: &ArgMatches, command_line: &str) -> Result<()> {
    let files = recordings(&args.data)?;
    check_outputs(args, &files)?;
    std::fs::create_dir_all(&args.report).with_context(|| format!("creating {}", args.report.display()))?;
    let bar = progress_bar(files.len(), args.quiet);
    let results: Vec<(String, Result<Point>)> = files
        .par_iter()
        .map(|f| {
            // A recording the loop cannot take must not take the history down with it: a
            // panic (a defect, reported by the default hook) is that recording's failure.
            let run = std::panic::AssertUnwindSafe(|| run_one(entry, args, sub, f, command_line));
            let result = std::panic::catch_unwind(run)
                .unwrap_or_else(|_| Err(anyhow::anyhow!("the loop stopped on an internal error (reported above)")));
            bar.inc(1);
            bar.set_message(stem(f));
            (stem(f), result)
        })
        .collect();
    bar.finish_and_clear();
    let mut points = Vec::new();
    let mut failed = Vec::new();
    for (name, result) in results {
        match result {
            Ok(p) => points.push(p),
            Err(e) => failed.push((name, super::one_line(&e))),
        }
    }
    let trend = Trend::new(points);
    if trend.clock == Clock::Index && !trend.recordings.is_empty() {
        eprintln!(
            "notice: {}: the recordings' t does not start at an absolute time (s since 1970): they are ordered by file name, and trend.csv's t is each one's number (1, 2, …)",
            args.data.display()
        );
    }
    let csv = args.report.join(HISTORY_FILES[0]);
    let html = args.report.join(HISTORY_FILES[1]);
    let page = crate::trend::render(system, &trend, &failed)?;
    write_atomic(&csv, trend.to_csv()?).with_context(|| format!("writing {}", csv.display()))?;
    write_atomic(&html, page).with_context(|| format!("writing {}", html.display()))?;
    print!("{}", summary(&trend, &failed));
    println!(
        "wrote {} and {} ({} reports under {})",
        csv.display(),
        html.display(),
        trend.recordings.len(),
        args.report.display()
    );
    if !failed.is_empty() {
        let list: Vec<String> = failed.iter().map(|(n, why)| format!("{n}: {why}")).collect();
        anyhow::bail!("{} of {} recordings failed ({})", failed.len(), files.len(), list.join("; "));
    }
    Ok(())
}

/// The printed history: each effect's first recording and rate of change, then the
/// recordings that failed and why.
fn summary(trend: &Trend, failed: &[(String, String)]) -> String {
    let mut s = format!("history of {} recording(s):\n", trend.recordings.len());
    if trend.effects.is_empty() {
        s.push_str("  no effect added on any recording\n");
    }
    for e in &trend.effects {
        let first = trend.recordings.get(e.first.wrapping_sub(1)).map_or("-", |p| p.name.as_str());
        let rate = e.per_recording.map(|r| format!(", {r:.4e} per recording")).unwrap_or_default();
        let day = e.per_day.map(|r| format!(", {r:.4e} per day")).unwrap_or_default();
        s.push_str(&format!(
            "  {}: first in recording {} ({first}), in {} of {}{rate}{day}\n",
            e.column,
            e.first,
            e.seen,
            trend.recordings.len()
        ));
    }
    for (name, why) in failed {
        s.push_str(&format!("  failed: {name}: {why}\n"));
    }
    s
}
