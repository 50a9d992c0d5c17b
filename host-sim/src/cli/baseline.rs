//! `edgekf baseline <system> --config C --data healthy.csv --out baseline.toml`: learns what a
//! healthy machine of this kind shows that its model lacks, for `edgekf loop <system>
//! --baseline`. The flags, the file's safety (never over an input, written only when
//! complete) and its `source` are common; what a baseline holds is the system's.

use super::registry::{chosen_loop, SystemEntry};
use super::request::{BaselineArgs, BaselineRequest};
use crate::io::output::{check, write_atomic};
use crate::residual_loop::baseline::BaselineSource;
use crate::residual_loop::LoopOptions;
use anyhow::{Context, Result};
use clap::{ArgMatches, Args, FromArgMatches};

/// `edgekf baseline` with one subcommand per system that has baselines.
pub fn command(registry: &[SystemEntry]) -> clap::Command {
    let mut cmd = clap::Command::new("baseline")
        .about(
            "Learn a healthy baseline from a recording of a good machine (what its model leaves unexplained, its \
             innovation levels; the rotor's also its resonances and synchronous levels), for `edgekf loop <system> \
             --baseline`",
        )
        .subcommand_required(true)
        .arg_required_else_help(true);
    for s in registry {
        if let Some(b) = s.close_loop.as_ref().and_then(|l| l.baseline) {
            // The about last, the long about cleared: `augment_args` puts the flag structs' own
            // docs there, which `edgekf baseline --help` would print as the subcommand's text.
            let about = format!("{}: what a healthy {} shows that its model lacks, in a baseline file", s.name, s.name);
            let sub = (b.args)(BaselineArgs::augment_args(clap::Command::new(s.name)));
            cmd = cmd.subcommand(sub.about(about).long_about(None));
        }
    }
    cmd
}

/// Runs `edgekf baseline <system> …`; `command_line` goes into the baseline's `[source]`.
pub fn run(registry: &[SystemEntry], m: &ArgMatches, command_line: &str) -> Result<()> {
    let (_, chosen, sub) = chosen_loop(registry, m);
    let entry = chosen.baseline.expect("clap only accepts systems with baselines");
    let args = BaselineArgs::from_arg_matches(sub).map_err(|e| anyhow::anyhow!("{e}"))?;
    check(&[Some(&args.out)], &[Some(&args.data), Some(&args.config)])?;
    let source = BaselineSource {
        data: args.data.display().to_string(),
        // The system's baseline fills it from its one read of the data.
        data_sha256: String::new(),
        config: args.config.display().to_string(),
        command: command_line.to_string(),
        version: env!("CARGO_PKG_VERSION").to_string(),
    };
    let options = LoopOptions { progress: !args.quiet, ..LoopOptions::default() };
    let request = BaselineRequest { args: args.clone(), options, source };
    let text = (entry.learn)(&request, sub)?;
    write_atomic(&args.out, text).with_context(|| format!("{}: cannot write", args.out.display()))?;
    println!("wrote {}", args.out.display());
    Ok(())
}
