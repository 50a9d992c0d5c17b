//! A row of the systems' registry: what the command line needs to know of a system.

use crate::residual_loop::LoopReport;
use anyhow::Result;
use clap::{ArgMatches, FromArgMatches, Subcommand};
use std::path::Path;

/// One system as the command line sees it.
#[derive(Clone, Copy)]
pub struct SystemEntry {
    /// The subcommand's name (`rotor`): `edgekf rotor …`, `edgekf loop rotor`.
    pub name: &'static str,
    /// One line for `edgekf --help`.
    pub about: &'static str,
    /// Its subcommands (see [`subcommands`]).
    pub command: fn() -> clap::Command,
    /// Runs one of them.
    pub run: fn(&ArgMatches) -> Result<()>,
    /// Its residual loop, if it has one.
    pub close_loop: Option<LoopEntry>,
    /// Its part of `edgekf demo`, if it has one.
    pub demo: Option<DemoPart>,
}

/// `edgekf loop <system>`.
#[derive(Clone, Copy)]
pub struct LoopEntry {
    /// One line for `edgekf loop --help`.
    pub about: &'static str,
    /// Adds the system's own flags to the ones every loop has.
    pub args: fn(clap::Command) -> clap::Command,
    /// Loads the configuration, reads the data and closes the loop.
    pub run: fn(&super::looping::LoopRequest, &ArgMatches) -> Result<LoopReport>,
    /// Learns a healthy baseline (`edgekf baseline <system>`) and returns the file's text, if
    /// the system has baselines.
    pub baseline: Option<fn(&super::baseline::BaselineRequest) -> Result<String>>,
}

/// A system's part of `edgekf demo`.
#[derive(Clone, Copy)]
pub struct DemoPart {
    /// It closes a residual loop (`--skip-loop` skips it).
    pub closes_loop: bool,
    /// Runs it, prints what it found and writes its files under `out` if given.
    pub run: fn(&super::demo::DemoArgs) -> Result<()>,
}

/// A clap `Subcommand` enum as a registry's [`SystemEntry::command`]: `subcommands::<C>`.
pub fn subcommands<C: Subcommand>() -> clap::Command {
    C::augment_subcommands(clap::Command::new("system")).subcommand_required(true).arg_required_else_help(true)
}

/// Parses `m` into the system's `Subcommand` and runs it: `|m| dispatch(m, cli::run)`.
pub fn dispatch<C: FromArgMatches>(m: &ArgMatches, run: fn(C) -> Result<()>) -> Result<()> {
    run(C::from_arg_matches(m).map_err(|e| anyhow::anyhow!("{e}"))?)
}

/// Reads `path` as a data file whose channels are `known` (notices to standard error), checks
/// that it is sampled at `rate` Hz (within 1 %) and puts it on one timeline
/// ([`crate::io::timeline`]): lost samples become missing ones. The loop needs one stretch, so a
/// gap too long to bridge is an error.
pub fn read_data(
    path: &Path,
    known: &[&str],
    rate: f64,
    timeline: &crate::io::timeline::TimelineOptions,
) -> Result<crate::io::data::DataFile> {
    let (file, notes) = crate::io::data::read(path, known)?;
    let (file, restarts) = on_one_timeline(path, file, &notes, rate, timeline)?;
    if let Some(r) = restarts.first() {
        anyhow::bail!(
            "{}: a {:.3} s gap before t = {:.6} s is too long to bridge (timeline.max_gap_s); close the loop on each stretch",
            path.display(),
            r.gap_s,
            r.t
        );
    }
    Ok(file)
}

/// Reads `path` as a data file with its `required` channels among the `known` ones, checks its
/// rate and puts it on one timeline as [`read_data`] does; an estimator starts afresh at the
/// rows returned, where a gap too long to bridge restarts the timeline.
pub fn read_estimator_data(
    path: &Path,
    required: &[&str],
    known: &[&str],
    rate: f64,
) -> Result<(crate::io::data::DataFile, Vec<usize>)> {
    let (file, notes) = crate::io::data::read_required(path, required, known)?;
    let (file, restarts) = on_one_timeline(path, file, &notes, rate, &Default::default())?;
    Ok((file, restarts.iter().map(|r| r.row).collect()))
}

/// The notices, the rate check (within 1 % of `rate` Hz) and the bridging both readers share.
fn on_one_timeline(
    path: &Path,
    file: crate::io::data::DataFile,
    notes: &crate::io::data::DataReport,
    rate: f64,
    timeline: &crate::io::timeline::TimelineOptions,
) -> Result<(crate::io::data::DataFile, Vec<crate::io::timeline::Restart>)> {
    eprintln!("{}: {notes}", path.display());
    if (notes.timing.sample_rate - rate).abs() > 0.01 * rate {
        anyhow::bail!(
            "{}: sampled at {:.3} Hz, the configuration says {rate} Hz",
            path.display(),
            notes.timing.sample_rate
        );
    }
    let (file, bridged) = crate::io::timeline::bridge(&file, &notes.timing, timeline);
    for n in bridged.notices() {
        eprintln!("notice: {n}");
    }
    Ok((file, bridged.restarts))
}
