//! A row of the systems' registry: what the command line needs to know of a system.

use crate::residual_loop::LoopReport;
use anyhow::Result;
use clap::{ArgMatches, FromArgMatches, Subcommand};

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
    pub run: fn(&super::request::LoopRequest, &ArgMatches) -> Result<LoopReport>,
    /// `edgekf baseline <system>`, if the system has baselines.
    pub baseline: Option<BaselineEntry>,
}

/// `edgekf baseline <system>`.
#[derive(Clone, Copy)]
pub struct BaselineEntry {
    /// Adds the system's own flags to the ones every baseline has.
    pub args: fn(clap::Command) -> clap::Command,
    /// Learns a healthy baseline and returns the file's text.
    pub learn: fn(&super::request::BaselineRequest, &ArgMatches) -> Result<String>,
}

/// A system's part of `edgekf demo`.
#[derive(Clone, Copy)]
pub struct DemoPart {
    /// It closes a residual loop (`--skip-loop` skips it).
    pub closes_loop: bool,
    /// Runs it, prints what it found and writes its files under `out` if given.
    pub run: fn(&super::request::DemoArgs) -> Result<()>,
}

/// The loop of the system `edgekf loop|baseline <system> …` names (`m`: the verb's matches),
/// with its name and its own matches; clap accepts only the names the verb registered.
pub fn chosen_loop<'a>(registry: &'a [SystemEntry], m: &'a ArgMatches) -> (&'a str, &'a LoopEntry, &'a ArgMatches) {
    let Some((name, sub)) = m.subcommand() else { unreachable!("clap requires a subcommand") };
    let entry = registry.iter().find(|s| s.name == name).and_then(|s| s.close_loop.as_ref());
    (name, entry.expect("clap only accepts registered names"), sub)
}

/// A clap `Subcommand` enum as a registry's [`SystemEntry::command`]: `subcommands::<C>`.
pub fn subcommands<C: Subcommand>() -> clap::Command {
    C::augment_subcommands(clap::Command::new("system")).subcommand_required(true).arg_required_else_help(true)
}

/// Parses `m` into the system's `Subcommand` and runs it: `|m| dispatch(m, cli::run)`.
pub fn dispatch<C: FromArgMatches>(m: &ArgMatches, run: fn(C) -> Result<()>) -> Result<()> {
    run(C::from_arg_matches(m).map_err(|e| anyhow::anyhow!("{e}"))?)
}
