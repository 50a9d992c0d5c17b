//! What the command line asks of a system: the requests its registry row's functions take
//! (`edgekf loop`, `edgekf baseline`, `edgekf demo`) and the arguments systems' commands share
//! (`export`, and the files of `estimate` and `simulate`), apart from the commands that build them,
//! so that a system and the registry depend on these types and on nothing else of `cli`.

use crate::report::summary::{EstimateSummary, Prose};
use crate::residual_loop::baseline::BaselineSource;
use crate::residual_loop::{LoopOptions, LoopReport};
use crate::systems::common::SimOptions;
use clap::Args;
use std::path::{Path, PathBuf};

/// The flags of every `edgekf loop <system>`.
#[derive(Debug, Clone, Args)]
pub struct LoopArgs {
    /// The system's configuration (model, sensors, operating point, sample rate).
    #[arg(long, value_name = "TOML")]
    pub config: PathBuf,
    /// Data file (channels named like the configured sensors; `truth_` columns optional), or a
    /// folder of them, or a quoted pattern ('runs/2026-12-*.csv'): every recording is run, its
    /// report written to `DIR/<name>/`, and the machine's history to `DIR/trend.csv` and
    /// `DIR/trend.html`.
    #[arg(long, value_name = "CSV|FOLDER|PATTERN")]
    pub data: PathBuf,
    /// Directory for report.json and report.html (with a folder of data: for each recording's
    /// report folder and the history).
    #[arg(long, value_name = "DIR")]
    pub report: PathBuf,
    /// A healthy baseline (`edgekf baseline <system>`): the loop asks what changed since.
    /// Refused on a system that has no baselines.
    #[arg(long, value_name = "TOML")]
    pub baseline: Option<PathBuf>,
    /// Also write the configuration with every added model or calibration effect made a
    /// declared part of it (its own keys, a comment per change); faults stay out of the model.
    #[arg(long, value_name = "TOML")]
    pub corrected_config: Option<PathBuf>,
    /// At most this many effects.
    #[arg(long, value_name = "N", default_value_t = 4)]
    pub max_effects: usize,
    /// Do not print each candidate as it is tried (with a folder of data: no progress bar).
    #[arg(long)]
    pub quiet: bool,
}

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

impl LoopRequest {
    /// Runs `close` (a system's loop on its one read of the data) with the levels of the
    /// request's baseline if it names one, and stamps the report with the data's SHA-256.
    pub fn close(
        &self,
        system: &str,
        data_sha256: Option<String>,
        close: impl FnOnce(&LoopOptions) -> anyhow::Result<LoopReport>,
    ) -> anyhow::Result<LoopReport> {
        let mut report =
            crate::residual_loop::levels::close_with(self.baseline.as_deref(), system, &self.options, close)?;
        report.source.data_sha256 = data_sha256;
        Ok(report)
    }
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

/// Fills the report's `source`: the files and the command line (the system's run gave the
/// data's SHA-256, taken in the one read of the data).
pub fn fill_source(report: &mut LoopReport, data: &Path, config: &Path, command_line: &str) {
    report.source.data = Some(data.display().to_string());
    report.source.config = Some(config.display().to_string());
    report.source.command = Some(command_line.to_string());
}

/// Arguments of `edgekf boom export` and `edgekf uuv export`: a node's constants from a
/// configuration, as Rust source its image compiles in.
#[derive(Debug, Clone, Args)]
pub struct ExportArgs {
    /// Configuration (default: the system's shipped one, in host-sim/configs/).
    #[arg(long, value_name = "TOML")]
    pub config: Option<PathBuf>,
    /// Rust file to write.
    #[arg(long, value_name = "RS")]
    pub out: PathBuf,
}

impl ExportArgs {
    /// The command: checks the files, loads the configuration (`load`, the default without
    /// `--config`), writes the Rust source `constants` makes of it, and says what it wrote
    /// (`what`: `the node's …`).
    pub fn write<C>(
        &self,
        load: impl FnOnce(Option<&Path>) -> anyhow::Result<C>,
        constants: impl FnOnce(&C) -> anyhow::Result<String>,
        what: impl FnOnce(&C) -> String,
    ) -> anyhow::Result<()> {
        use anyhow::Context as _;
        crate::io::output::check(&[Some(&self.out)], &[self.config.as_deref()])?;
        let config = load(self.config.as_deref())?;
        let text = constants(&config)?;
        crate::io::output::write_atomic(&self.out, text)
            .with_context(|| format!("cannot write {}", self.out.display()))?;
        println!("wrote {}: {}", self.out.display(), what(&config));
        Ok(())
    }
}

/// The files of every system's `estimate`: the configuration and the recording it reads, the
/// estimate file it writes, and whether it prints a JSON summary. Each system's arguments
/// flatten it first; where a system says more of a file (its columns, its default), its
/// command sets that help (`mut_arg`), so `--help` reads as the system's own.
#[derive(Debug, Clone, Args)]
pub struct EstimateFiles {
    /// Configuration (default: the system's shipped one, in host-sim/configs/).
    #[arg(long, value_name = "TOML")]
    pub config: Option<PathBuf>,
    /// Data file to read.
    #[arg(long, value_name = "CSV")]
    pub data: PathBuf,
    /// Estimate file to write.
    #[arg(long, value_name = "CSV")]
    pub out: PathBuf,
    /// Print one JSON object on stdout (the text goes to stderr): the estimate's statistics.
    #[arg(long)]
    pub json: bool,
}

impl EstimateFiles {
    /// Where the text goes: stderr under `--json`, else stdout.
    pub fn prose(&self) -> Prose {
        Prose { json: self.json }
    }

    /// The JSON summary of `system`'s estimate over the samples at times `t`, naming these files.
    pub fn summary(&self, system: &'static str, t: &[f64]) -> EstimateSummary {
        let mut j = EstimateSummary::new(system, &self.data, self.config.as_deref(), t);
        j.out = Some(self.out.clone());
        j
    }
}

/// The files and the seed of every system's `simulate`: the configuration it reads, the data
/// file it writes and the seed of its noise. Flattened first, with the system's own help
/// where it says more (as [`EstimateFiles`]).
#[derive(Debug, Clone, Args)]
pub struct SimulateFiles {
    /// Configuration (default: the system's shipped one, in host-sim/configs/).
    #[arg(long, value_name = "TOML")]
    pub config: Option<PathBuf>,
    /// Data file to write.
    #[arg(long, value_name = "CSV")]
    pub out: PathBuf,
    /// Seed of the sensors' noise.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub seed: u64,
}

/// The run of a system that simulates a named scenario (the boom, the vehicle): its files and
/// seed, the scenario and the length, read as the shared [`SimOptions`]. The length's default
/// and limit are the system's (`mut_arg("duration", …)` on its command).
#[derive(Debug, Clone, Args)]
pub struct ScenarioRun<S: clap::ValueEnum + Clone + Send + Sync + 'static> {
    /// `--config`, `--out`, `--seed`.
    #[command(flatten)]
    pub files: SimulateFiles,
    /// The run.
    #[arg(long, value_enum)]
    pub scenario: S,
    /// Length, s.
    #[arg(long, value_name = "S", value_parser = crate::cli::values::positive_seconds)]
    pub duration: f64,
}

impl<S: clap::ValueEnum + Copy + Send + Sync + 'static> ScenarioRun<S> {
    /// The simulator's options.
    pub fn options(&self) -> SimOptions<S> {
        SimOptions { scenario: self.scenario, duration: self.duration, seed: self.files.seed }
    }

    /// The simulator's progress on stderr: `t` seconds simulated of `--duration`.
    pub fn progress(&self) -> impl FnMut(f64) + '_ {
        move |t| eprintln!("simulated {t:.0} s of {:.0} s", self.duration)
    }

    /// Writes a simulated recording's CSV `text` to `--out` (whole, or not at all) and prints
    /// the line every scenario run ends with: rows, rate, scenario, seed, then `headline` (what
    /// the system's run is about, e.g. its largest tip vibration).
    pub fn write(
        &self,
        text: String,
        rows: usize,
        rate_hz: impl std::fmt::Display,
        headline: &str,
    ) -> anyhow::Result<()> {
        use anyhow::Context;
        let out = &self.files.out;
        crate::io::output::write_atomic(out, text).with_context(|| format!("cannot write {}", out.display()))?;
        let scenario = self.scenario.to_possible_value().map(|v| v.get_name().to_owned()).unwrap_or_default();
        let seed = self.files.seed;
        println!("{}: {rows} rows at {rate_hz} Hz, scenario {scenario}, seed {seed}; {headline}", out.display());
        Ok(())
    }
}
