//! `edgekf demo`: every registered system's demo part, in the registry's order, each printing
//! what it simulated and what the estimators or the loop found.

use super::registry::SystemEntry;
use super::request::DemoArgs;
use anyhow::Result;
use clap::{ArgMatches, Args, FromArgMatches};

/// The `demo` subcommand.
pub fn command(registry: &[SystemEntry]) -> clap::Command {
    let parts: Vec<&str> = registry.iter().filter(|s| s.demo.is_some()).map(|s| s.name).collect();
    DemoArgs::augment_args(clap::Command::new("demo"))
        .about("Run every system's demo: simulate, estimate, close the loop on an undeclared effect")
        .long_about(format!(
            "Run every system's demo ({}): each simulates a case with its reference simulator, runs the \
             estimators on it (in f64 and in f32 as on the node) and, where the system has a residual loop, \
             closes it on an effect nobody declared.",
            parts.join(", ")
        ))
}

/// Runs the demo parts, a blank line between them.
pub fn run(registry: &[SystemEntry], m: &ArgMatches) -> Result<()> {
    let args = DemoArgs::from_arg_matches(m).map_err(|e| anyhow::anyhow!("{e}"))?;
    if let Some(dir) = &args.out {
        crate::io::output::check_folder(dir, &[], &[args.config.as_deref()])?;
    }
    let mut first = true;
    for part in registry.iter().filter_map(|s| s.demo) {
        if part.closes_loop && args.skip_loop {
            continue;
        }
        if !first {
            println!();
        }
        first = false;
        (part.run)(&args)?;
    }
    Ok(())
}
