//! `edgekf rotor …`: the rotor commands of the command line.
//!
//! * `modes`: natural frequencies, logarithmic decrements and whirl at a speed (`--json` for
//!   `{"speed": W, "modes": [{"frequency_hz": f, "log_dec": d, "whirl": w}, …]}`);
//! * `campbell`: the same over a range of speeds;
//! * `unbalance`: the steady unbalance response at the sensors;
//! * `simulate`: the time response from rest into a data CSV (see [`crate::systems::rotor::simulate`]).

use crate::systems::rotor::config::{Direction, RotorConfig, SensorKind};
use crate::systems::rotor::modal::ModalAnalysis;
use crate::systems::rotor::simulate::{Method, Progress, SimOptions};
use crate::systems::rotor::{Mode, RotorModel, Whirl};
pub mod estimate;

use anyhow::Context as _;
use clap::{Subcommand, ValueEnum};
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The `edgekf rotor` subcommands.
#[derive(Debug, Subcommand)]
pub enum RotorCommand {
    /// Natural frequencies (Hz), logarithmic decrements and whirl directions at a speed.
    Modes {
        /// Rotor configuration (e.g. host-sim/configs/rotor_paper.toml).
        #[arg(long, value_name = "TOML")]
        config: PathBuf,
        /// Speed, rad/s (default: the configuration's operation.speed).
        #[arg(long, value_name = "RAD_S", allow_negative_numbers = true)]
        speed: Option<f64>,
        /// Number of modes to list (0: all).
        #[arg(long, value_name = "N", default_value_t = 12)]
        count: usize,
        /// Print JSON: {"speed": W, "modes": [{"frequency_hz", "log_dec", "whirl"}, …]}.
        #[arg(long)]
        json: bool,
    },
    /// Campbell diagram: the first modes over a range of speeds.
    Campbell {
        /// Rotor configuration.
        #[arg(long, value_name = "TOML")]
        config: PathBuf,
        /// Highest speed, rad/s (the range starts at 0).
        #[arg(long, value_name = "RAD_S", default_value_t = 1000.0)]
        max_speed: f64,
        /// Number of speeds from 0 to max_speed (at least 2).
        #[arg(long, value_name = "N", default_value_t = 11, value_parser = crate::cli::values::at_least::<2>)]
        steps: usize,
        /// Number of modes per speed.
        #[arg(long, value_name = "N", default_value_t = 6)]
        count: usize,
        /// Print JSON: {"speeds": [...], "modes": [[{"frequency_hz", "log_dec", "whirl"}, …], …]}.
        #[arg(long)]
        json: bool,
    },
    /// Steady unbalance response (amplitude and phase) at the sensors and the largest orbit.
    Unbalance {
        /// Rotor configuration.
        #[arg(long, value_name = "TOML")]
        config: PathBuf,
        /// Speed, rad/s (default: the configuration's operation.speed).
        #[arg(long, value_name = "RAD_S", allow_negative_numbers = true)]
        speed: Option<f64>,
    },
    /// Time response from rest at constant speed, with sensor noise, into a data CSV.
    ///
    /// Columns: t; the sensors (`n<node>_<x|y>` in m, `n<node>_a<x|y>` in m/s²,
    /// `n<node>_a<x|y>_volts` in V); truth: `truth_n<k>_x`, `truth_n<k>_y` for every node (m),
    /// `truth_f<k>_x`, `truth_f<k>_y` per unbalanced node (N), `truth_<channel>` the noise-free
    /// output of each accelerometer channel.
    Simulate {
        /// Rotor configuration.
        #[arg(long, value_name = "TOML")]
        config: PathBuf,
        /// Length of the run, s.
        #[arg(long, value_name = "S", allow_negative_numbers = true, value_parser = crate::cli::values::positive_seconds)]
        duration: f64,
        /// Data file to write.
        #[arg(long, value_name = "CSV")]
        out: PathBuf,
        /// Seed of the sensor noise.
        #[arg(long, value_name = "N", default_value_t = 1)]
        seed: u64,
        /// Integration: the exact matrix exponential, or Newmark average acceleration.
        #[arg(long, value_enum, default_value_t = MethodArg::Exact)]
        method: MethodArg,
        /// Newmark steps per output sample (with --method newmark).
        #[arg(long, value_name = "N", default_value_t = 20)]
        substeps: u32,
    },
    /// Virtual sensing: every node's displacement and the unbalance forces from the sensors.
    ///
    /// Runs the augmented Kalman filter of the modally reduced rotor (unbalance forces as
    /// rotating phasors at the running speed) over the data file's sensor channels. Writes `t`,
    /// `n<k>_x`, `n<k>_y` for every node (m) and `f<k>_x`, `f<k>_y` per unbalance node (N). With
    /// `truth_` columns in the data, prints the error at the sensors and the force nodes.
    Estimate {
        /// Rotor configuration (the estimator reads only the unbalance nodes, not their size).
        #[arg(long, value_name = "TOML")]
        config: PathBuf,
        /// Data file (channels named like the configured sensors).
        #[arg(long, value_name = "CSV")]
        data: PathBuf,
        /// Estimates to write.
        #[arg(long, value_name = "CSV")]
        out: Option<PathBuf>,
        /// The chip's arithmetic (f32) instead of f64.
        #[arg(long)]
        f32: bool,
        /// Modes kept in the reduced model.
        #[arg(long, value_name = "N", default_value_t = 8)]
        modes: usize,
        /// The paper's force model (independent random walks) instead of rotating phasors.
        #[arg(long)]
        random_walk: bool,
        /// The robust tuning (faster force random walk, more modal noise): tolerates ~1 %
        /// stiffness or 0.05 % speed error in the model at some cost when the model is right.
        #[arg(long)]
        robust: bool,
        /// Switch to the steady-state gain at this time, s (default: time-varying throughout).
        #[arg(long, value_name = "S")]
        steady_after: Option<f64>,
        /// Print one JSON object on stdout (the text goes to stderr): per reported node its
        /// displacement's statistics and RMS errors, per unbalance node its force.
        #[arg(long)]
        json: bool,
    },
    /// Tune the virtual-sensing filter's noise parameters on a reference simulation.
    ///
    /// Simulates a training record (`--seed`, `--duration`) from the configuration, tunes
    /// `log10` of the force and modal noise densities and of the measurement-noise scale, and
    /// reports the tuning with its error and NIS on three held-out seeds (4 s each). `de`: the
    /// paper's compromise objective Σ(1 − |R²|) under differential evolution; `ml`: the
    /// innovations' maximum likelihood under Nelder–Mead.
    Tune {
        /// Rotor configuration.
        #[arg(long, value_name = "TOML")]
        config: PathBuf,
        /// Objective and optimiser.
        #[arg(long, value_enum, default_value_t = TuneMethodArg::Ml)]
        method: TuneMethodArg,
        /// Seed of the training record (held out: the next three seeds).
        #[arg(long, value_name = "N", default_value_t = 1)]
        seed: u64,
        /// Length of the training record, s.
        #[arg(long, value_name = "S", default_value_t = 2.0, value_parser = crate::cli::values::positive_seconds)]
        duration: f64,
        /// Objective evaluations allowed (at least 16; DE: a population of 12 over budget/12
        /// generations).
        #[arg(long, value_name = "N", default_value_t = 108, value_parser = crate::cli::values::at_least::<16>)]
        budget: usize,
        /// Modes kept in the reduced model.
        #[arg(long, value_name = "N", default_value_t = 8)]
        modes: usize,
    },
    /// Write the reduced model and its steady-state gain as Rust constants for the firmware.
    Export {
        /// Rotor configuration.
        #[arg(long, value_name = "TOML")]
        config: PathBuf,
        /// Rust file to write.
        #[arg(long, value_name = "RS")]
        out: PathBuf,
        /// Modes kept in the reduced model.
        #[arg(long, value_name = "N", default_value_t = 8)]
        modes: usize,
        /// Export the robust tuning (faster force random walk, more modal process noise), the
        /// one the accelerometer node runs
        #[arg(long)]
        robust: bool,
    },
}

/// `--method` of `rotor tune`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TuneMethodArg {
    /// The paper's compromise objective under differential evolution.
    De,
    /// Maximum likelihood of the innovations under Nelder–Mead.
    Ml,
}

/// `--method` of `rotor simulate`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Exact discretisation (matrix exponential of the augmented system).
    Exact,
    /// Newmark average acceleration at `--substeps` steps per sample.
    Newmark,
}

fn load(path: &Path) -> anyhow::Result<(RotorConfig, RotorModel)> {
    let cfg = RotorConfig::load(path)?;
    let model = RotorModel::from_config(&cfg).with_context(|| format!("{}: cannot build the model", path.display()))?;
    Ok((cfg, model))
}

fn mode_json(m: &Mode) -> serde_json::Value {
    serde_json::json!({ "frequency_hz": m.frequency_hz, "log_dec": m.log_dec, "whirl": m.whirl.as_str() })
}

fn take(n: usize, count: usize) -> usize {
    if count == 0 {
        n
    } else {
        count.min(n)
    }
}

/// The modes as the text table `edgekf rotor modes` prints.
pub fn modes_table(modal: &ModalAnalysis, count: usize) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:>4}  {:>14}  {:>13}  {:>10}  {:>9}  {:<8}",
        "mode", "frequency [Hz]", "undamped [Hz]", "log dec", "zeta [%]", "whirl"
    );
    for (i, m) in modal.modes.iter().take(take(modal.modes.len(), count)).enumerate() {
        let _ = writeln!(
            s,
            "{:>4}  {:>14.4}  {:>13.4}  {:>10.3e}  {:>9.4}  {:<8}",
            i + 1,
            m.frequency_hz,
            m.undamped_hz,
            m.log_dec,
            100.0 * m.damping_ratio,
            m.whirl
        );
    }
    s
}

/// Runs one `edgekf rotor` subcommand.
pub fn run(command: RotorCommand) -> anyhow::Result<()> {
    match command {
        RotorCommand::Estimate { config, data, out, f32, modes, random_walk, robust, steady_after, json } => {
            let options = estimate::EstimateOptions { f32, modes, random_walk, robust, steady_after, json };
            estimate::estimate(&config, &data, out.as_deref(), &options)
        }
        RotorCommand::Tune { config, method, seed, duration, budget, modes } => {
            estimate::tune(&config, method == TuneMethodArg::Ml, seed, duration, budget, modes)
        }
        RotorCommand::Export { config, out, modes, robust } => estimate::export(&config, &out, modes, robust),
        RotorCommand::Modes { config, speed, count, json } => modes(&config, speed, count, json),
        RotorCommand::Campbell { config, max_speed, steps, count, json } => {
            campbell(&config, max_speed, steps, count, json)
        }
        RotorCommand::Unbalance { config, speed } => unbalance(&config, speed),
        RotorCommand::Simulate { config, duration, out, seed, method, substeps } => {
            simulate(&config, duration, &out, seed, method, substeps)
        }
    }
}

/// Prints the modes at a speed (a table, or JSON).
fn modes(config: &std::path::Path, speed: Option<f64>, count: usize, json: bool) -> anyhow::Result<()> {
    let (cfg, model) = load(config)?;
    let speed = speed.unwrap_or(cfg.operation.speed);
    let modal = model.modes(speed)?;
    let n = take(modal.modes.len(), count);
    if json {
        let modes: Vec<_> = modal.modes.iter().take(n).map(mode_json).collect();
        println!("{}", serde_json::json!({ "speed": speed, "modes": modes }));
    } else {
        println!(
            "{}: {} nodes, {} DOFs, at {speed} rad/s ({:.4} Hz)",
            config.display(),
            model.n_nodes(),
            model.n_dofs(),
            speed / (2.0 * PI)
        );
        print!("{}", modes_table(&modal, count));
    }
    Ok(())
}

/// Prints the Campbell diagram (a table, or JSON).
fn campbell(config: &std::path::Path, max_speed: f64, steps: usize, count: usize, json: bool) -> anyhow::Result<()> {
    let (_, model) = load(config)?;
    if !(max_speed.is_finite() && max_speed >= 0.0) || steps < 2 {
        anyhow::bail!("--max-speed must be ≥ 0 and --steps at least 2");
    }
    let speeds: Vec<f64> = (0..steps).map(|i| max_speed * i as f64 / (steps - 1) as f64).collect();
    let c = model.campbell(&speeds, count)?;
    if json {
        let modes: Vec<Vec<_>> = c.modes.iter().map(|ms| ms.iter().map(mode_json).collect()).collect();
        println!("{}", serde_json::json!({ "speeds": c.speeds, "modes": modes }));
    } else {
        println!("{}: frequencies in Hz (F forward, B backward, P planar whirl)", config.display());
        let mut head = format!("{:>10}", "speed");
        for i in 0..count {
            let _ = write!(head, "  {:>11}", format!("mode {}", i + 1));
        }
        println!("{head}");
        for (w, ms) in c.speeds.iter().zip(&c.modes) {
            let mut line = format!("{w:>10.2}");
            for m in ms {
                let tag = match m.whirl {
                    Whirl::Forward => 'F',
                    Whirl::Backward => 'B',
                    Whirl::Planar => 'P',
                };
                let _ = write!(line, "  {:>9.3} {tag}", m.frequency_hz);
            }
            println!("{line}");
        }
    }
    Ok(())
}

/// Prints the steady unbalance response at the sensors and the largest orbit.
fn unbalance(config: &std::path::Path, speed: Option<f64>) -> anyhow::Result<()> {
    let (cfg, model) = load(config)?;
    let speed = speed.unwrap_or(cfg.operation.speed);
    let r = model.unbalance_response(speed)?;
    println!("{}: steady unbalance response at {speed} rad/s", config.display());
    println!("{:>6}  {:>4}  {:>15}  {:>10}", "node", "dir", "amplitude [um]", "phase [deg]");
    let mut seen = Vec::new();
    for s in &cfg.sensors {
        if seen.contains(&(s.node, s.direction)) {
            continue;
        }
        seen.push((s.node, s.direction));
        println!(
            "{:>6}  {:>4}  {:>15.4}  {:>10.2}",
            s.node,
            s.direction.as_str(),
            1e6 * r.amplitude(s.node, s.direction),
            r.phase_deg(s.node, s.direction)
        );
    }
    let (node, a) =
        (0..model.n_nodes())
            .map(|k| (k, r.major_axis(k)))
            .fold((0, 0.0), |best, c| if c.1 > best.1 { c } else { best });
    println!(
        "largest orbit: node {node}, semi-major axis {:.4} um (x {:.4} um, y {:.4} um)",
        1e6 * a,
        1e6 * r.amplitude(node, Direction::X),
        1e6 * r.amplitude(node, Direction::Y)
    );
    Ok(())
}

/// Simulates the configuration and writes the recording, with progress on long runs.
fn simulate(
    config: &std::path::Path,
    duration: f64,
    out: &std::path::Path,
    seed: u64,
    method: MethodArg,
    substeps: u32,
) -> anyhow::Result<()> {
    crate::io::output::check(&[Some(out)], &[Some(config)])?;
    let (_, model) = load(config)?;
    let method = match method {
        MethodArg::Exact => Method::Exact,
        MethodArg::Newmark => Method::Trapezoidal { substeps },
    };
    let opts = SimOptions { duration, seed, noise: true, method, speed: None, steady_start: false };
    let start = Instant::now();
    let mut last_decile = 0;
    let rec = model
        .simulate_with_progress(&opts, &mut |p| match p {
            Progress::Discretised { states } => {
                eprintln!("rotor simulate: {states} states discretised in {:.2} s", start.elapsed().as_secs_f64());
            }
            Progress::Samples { done, total } => {
                let decile = 10 * done / total;
                if total >= 10_000 && decile > last_decile {
                    last_decile = decile;
                    eprintln!("rotor simulate: {}% ({done}/{total} samples)", 10 * decile);
                }
            }
        })
        .with_context(|| format!("{}: cannot simulate", config.display()))?;
    let sim_s = start.elapsed().as_secs_f64();
    rec.write_csv(out)?;
    let total_s = start.elapsed().as_secs_f64();
    let channels: Vec<String> = rec
        .channels
        .iter()
        .map(|c| match c.sensor.kind {
            SensorKind::Displacement { .. } => format!("{} (σ {:.3e} m)", c.name, c.noise_std),
            SensorKind::Acceleration(a) if a.sensitivity.is_some() => {
                format!("{} (σ {:.3e} V)", c.name, c.noise_std)
            }
            SensorKind::Acceleration(_) => format!("{} (σ {:.3e} m/s²)", c.name, c.noise_std),
        })
        .collect();
    println!(
        "wrote {}: {} samples at {} Hz, {} rad/s, seed {seed}; sensors: {}; truth: {} nodes, forces at nodes {:?}",
        out.display(),
        rec.len(),
        rec.sample_rate,
        rec.speed,
        if channels.is_empty() { "none".to_string() } else { channels.join(", ") },
        model.n_nodes(),
        rec.forces.iter().map(|f| f.node).collect::<Vec<_>>()
    );
    println!("wall time: {sim_s:.3} s to simulate, {total_s:.3} s with the CSV");
    Ok(())
}

/// `edgekf loop rotor`'s own flags (beside the ones every loop has).
#[derive(Debug, Clone, clap::Args)]
pub struct RotorLoopArgs {
    /// Read the running speed from the data, within this fraction of the configured
    /// (nominal) speed (default 0.1 when given without a value): for a motor that slips.
    #[arg(long, value_name = "FRACTION", num_args = 0..=1, default_missing_value = "0.1", value_parser = fraction)]
    pub estimate_speed: Option<f64>,
}

/// A fraction strictly between 0 and 1 (clap's usage error, exit 2, otherwise).
fn fraction(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(f) if f > 0.0 && f < 1.0 => Ok(f),
        Ok(f) => Err(format!("{f} is not a fraction between 0 and 1 (0.1 is ±10 %)")),
        Err(e) => Err(format!("{text:?}: {e}")),
    }
}

/// `edgekf loop rotor`: the rotor's configuration and data, the loop closed on them.
pub fn close_loop(
    request: &crate::cli::request::LoopRequest,
    m: &clap::ArgMatches,
) -> anyhow::Result<crate::residual_loop::LoopReport> {
    use clap::FromArgMatches as _;
    let args = RotorLoopArgs::from_arg_matches(m).map_err(|e| anyhow::anyhow!("{e}"))?;
    let config = &request.config;
    let cfg = RotorConfig::load(config).with_context(|| format!("{}: cannot load the rotor", config.display()))?;
    let model = RotorModel::from_config(&cfg)?;
    let channels: Vec<String> = cfg.sensors.iter().map(|s| s.channel_name()).collect();
    let known: Vec<&str> = channels.iter().map(String::as_str).collect();
    let file = crate::io::recording::read_data(&request.data, &known, cfg.operation.sample_rate, &cfg.timeline)?;
    let rotor = super::loop_system::RotorLoopOptions { speed_band: args.estimate_speed, ..Default::default() };
    let mut report = match &request.baseline {
        Some(path) => {
            let baseline = super::loop_system::baseline::RotorBaseline::load(path)?;
            super::loop_system::close_loop_from(&model, &file, &request.options, &rotor, &baseline)?
        }
        None => super::loop_system::close_loop(&model, &file, &request.options, &rotor)?,
    };
    report.source.data_sha256 = file.sha256.clone();
    Ok(report)
}

/// `edgekf baseline rotor`'s own flag (beside the ones every baseline has).
#[derive(Debug, Clone, clap::Args)]
pub struct RotorBaselineArgs {
    /// At most this many resonances and synchronous forces.
    #[arg(long, value_name = "N", default_value_t = 12)]
    pub max_parts: usize,
}

/// `edgekf baseline rotor`: the configuration and the healthy recording, the baseline learned
/// from them (the running speed read from the data within ±10 % of the configured one).
pub fn baseline(request: &crate::cli::request::BaselineRequest, m: &clap::ArgMatches) -> anyhow::Result<String> {
    use super::loop_system::baseline::{learn, BaselineOptions};
    use clap::FromArgMatches;
    let own = RotorBaselineArgs::from_arg_matches(m).map_err(|e| anyhow::anyhow!("{e}"))?;
    let args = &request.args;
    let cfg =
        RotorConfig::load(&args.config).with_context(|| format!("{}: cannot load the rotor", args.config.display()))?;
    let model = RotorModel::from_config(&cfg)?;
    let channels: Vec<String> = cfg.sensors.iter().map(|s| s.channel_name()).collect();
    let known: Vec<&str> = channels.iter().map(String::as_str).collect();
    let file = crate::io::recording::read_data(&args.data, &known, cfg.operation.sample_rate, &cfg.timeline)?;
    let options = BaselineOptions { max_parts: own.max_parts, condition: args.condition.clone(), ..Default::default() };
    let mut b = learn(&model, &file, &request.options, &Default::default(), &options)?;
    b.source = request.source.clone();
    b.source.data_sha256 = file.sha256.clone().unwrap_or_default();
    b.to_toml()
}

/// The rotor's part of `edgekf demo`: the paper rotor with an undeclared heavier disk, the loop
/// closed on the declared model; `--out DIR` writes `loop/data.csv` and the report there.
pub fn demo(args: &crate::cli::request::DemoArgs) -> anyhow::Result<()> {
    use super::demo::LoopDemo;
    use crate::report::text::{summary_table, write_report};
    if let Some(dir) = &args.out {
        let files = crate::report::text::REPORT_FILES.map(|f| format!("loop/{f}"));
        let files: Vec<&str> = files.iter().map(String::as_str).chain(["loop/data.csv", "loop/config.toml"]).collect();
        crate::io::output::check_folder(dir, &files, &[args.config.as_deref()])?;
    }
    println!("closing the loop — {}", LoopDemo::describe());
    let demo = LoopDemo::run(true)?;
    print!("{}", summary_table(&demo.report));
    if let Some(dir) = &args.out {
        let dir = dir.join("loop");
        std::fs::create_dir_all(&dir).with_context(|| format!("{}: cannot make the folder", dir.display()))?;
        let mut report = demo.report;
        report.source = rerunnable(&demo.data, &dir)?;
        write_report(&report, &dir)?;
        println!("wrote the data, the declared model and the report in {}", dir.display());
        println!("rerun: {}", report.source.command.as_deref().unwrap_or_default());
    }
    Ok(())
}

/// Writes the demo's recording and declared model into `dir` (`data.csv`, `config.toml`) and
/// returns the report's `source` naming them, with the `edgekf loop rotor` command that makes
/// the same report from them.
fn rerunnable(d: &crate::io::data::DataFile, dir: &std::path::Path) -> anyhow::Result<crate::residual_loop::Source> {
    let (data, config) = (dir.join("data.csv"), dir.join("config.toml"));
    let text = d.to_csv_string()?;
    crate::io::output::write_atomic(&data, &text).with_context(|| format!("cannot write {}", data.display()))?;
    let declared = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml"));
    crate::io::output::write_atomic(&config, declared).with_context(|| format!("cannot write {}", config.display()))?;
    let command =
        format!("edgekf loop rotor --config {} --data {} --report {}", config.display(), data.display(), dir.display());
    Ok(crate::residual_loop::Source {
        data: Some(data.display().to_string()),
        data_sha256: Some(crate::io::data::hex_sha256(text.as_bytes())),
        config: Some(config.display().to_string()),
        command: Some(command),
        version: env!("CARGO_PKG_VERSION").into(),
        ..Default::default()
    })
}
