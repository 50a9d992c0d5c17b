//! What the command line asks of a system: the requests its registry row's functions take
//! (`edgekf loop`, `edgekf baseline`, `edgekf demo`), apart from the commands that build them,
//! so that a system and the registry depend on these types and on nothing else of `cli`.

use crate::residual_loop::baseline::BaselineSource;
use crate::residual_loop::LoopOptions;
use clap::Args;
use std::path::PathBuf;

/// What a system's loop is asked to do.
#[derive(Debug, Clone)]
pub struct LoopRequest {
    /// `--config`.
    pub config: PathBuf,
    /// `--data`.
    pub data: PathBuf,
    /// `--baseline`.
    pub baseline: Option<PathBuf>,
    /// The engine's options from the common flags.
    pub options: LoopOptions,
}

/// The flags of every `edgekf baseline <system>`.
#[derive(Debug, Clone, Args)]
pub struct BaselineArgs {
    /// The system's configuration (the same the loop will use).
    #[arg(long, value_name = "TOML")]
    pub config: PathBuf,
    /// A recording of the healthy machine (channels named like the configured sensors).
    #[arg(long, value_name = "CSV")]
    pub data: PathBuf,
    /// The baseline to write (TOML).
    #[arg(long, value_name = "TOML")]
    pub out: PathBuf,
    /// The operating condition it belongs to (e.g. "0 hp"), written into the baseline.
    #[arg(long, value_name = "TEXT")]
    pub condition: Option<String>,
    /// Do not print each part as it is tried.
    #[arg(long)]
    pub quiet: bool,
}

/// What a system's baseline is asked to learn from.
#[derive(Debug, Clone)]
pub struct BaselineRequest {
    /// The flags.
    pub args: BaselineArgs,
    /// The engine's options (progress, signatures, acceptance).
    pub options: LoopOptions,
    /// Where it is learned, for the file's `[source]`.
    pub source: BaselineSource,
}

/// The flags of `edgekf demo`.
#[derive(Debug, Clone, Default, Args)]
pub struct DemoArgs {
    /// Also write each part's data and estimates into this directory.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Use this oscillator scenario instead of the built-in demo.
    #[arg(long, value_name = "TOML")]
    pub config: Option<PathBuf>,
    /// Skip the parts that close a residual loop (the rotor's, the boom's and the vehicle's: most of
    /// the demo's time).
    #[arg(long)]
    pub skip_loop: bool,
}
