//! `edgekf`: simulate, estimate and report on the host.

use anyhow::Context as _;
use clap::{Parser, Subcommand, ValueEnum};
use edgekf_sim::demo::{describe, describe_run, Demo};
use edgekf_sim::estimate::{self, EstimateOptions, KNOWN_CHANNELS};
use edgekf_sim::io::data;
use edgekf_sim::report::{steady_windows, Summary};
use edgekf_sim::scenario::{Fault, Scenario};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Host tools of edgekf: Kalman filtering for an edge vibration sensor (ADXL355 + Cortex-M4F).
///
/// Data files are CSV: a header, first column `t` in seconds, then channels in SI units
/// (`ax` in m/s², …), ground truth in `truth_*` columns. Scenario files are TOML; see
/// host-sim/configs/oscillator_demo.toml for every field with its unit.
#[derive(Debug, Parser)]
#[command(name = "edgekf", version, propagate_version = true, after_help = EXAMPLES)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

const EXAMPLES: &str = "Examples:
  edgekf demo --out out/
  edgekf oscillator simulate --config host-sim/configs/oscillator_demo.toml --out data.csv --faults
  edgekf oscillator estimate --config host-sim/configs/oscillator_demo.toml --data data.csv --out est.csv";

#[derive(Debug, Subcommand)]
enum Command {
    /// Simulate the demo scenario and estimate its harmonic force in f64 and f32.
    ///
    /// A 20 Hz mode (ζ = 0.02, 1 kg) driven at 87.96 rad/s by 5 N stepping to 3 N at 6 s, read
    /// by an ADXL355 at 1 kHz for 12 s. Prints the force amplitude against the truth over the
    /// steady stretches, RMS errors, innovations against the sensor noise, the NIS and every
    /// counter.
    Demo {
        /// Also write data.csv, est.csv (f64) and est_f32.csv into this directory.
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// Use this scenario instead of the built-in demo.
        #[arg(long, value_name = "TOML")]
        config: Option<PathBuf>,
        /// Skip the second part, the residual loop on the paper rotor with an undeclared
        /// effect (about half a minute); the third, the slider-crank, still runs.
        #[arg(long)]
        skip_loop: bool,
    },
    /// Single mode driven by a harmonic force: simulate data, estimate the force.
    #[command(subcommand)]
    Oscillator(Oscillator),
    /// Planar slider-crank with revolute clearance joints: simulate, spectral feature.
    #[command(subcommand)]
    Crank(edgekf_sim::crank::cli::CrankCommand),
    /// Flexible rotor (FE model): natural frequencies and whirl, time response with sensors.
    #[command(subcommand)]
    Rotor(edgekf_sim::rotor::cli::RotorCommand),
    /// Close the loop with measured data: read the filter's innovations, add the model effects
    /// they point at (sensor bias, harmonic force at k× running speed) when they pay for their
    /// parameters, report before/after.
    #[command(subcommand)]
    Loop(edgekf_sim::residual_loop::cli::LoopCommand),
}

#[derive(Debug, Subcommand)]
enum Oscillator {
    /// Simulate a scenario into a data CSV.
    ///
    /// Columns: t, ax, ay, az, fault_nack, fault_stuck, truth_x, truth_v, truth_force,
    /// truth_force_amplitude, truth_accel.
    Simulate {
        /// Scenario file (default: the built-in demo scenario).
        #[arg(long, value_name = "TOML")]
        config: Option<PathBuf>,
        /// Data file to write.
        #[arg(long, value_name = "CSV")]
        out: PathBuf,
        /// Add one fault of each kind to the scenario's own: a 3-transaction I²C NACK burst at
        /// 25 % of the run, registers stuck for 50 ms at 40 %, 20 ms of 3 g on x at 75 %.
        #[arg(long)]
        faults: bool,
    },
    /// Estimate the harmonic force from the `ax` column of a data CSV.
    ///
    /// Notices about the data (ignored columns, empty/NaN cells, gaps and jitter in t) go to
    /// stderr, the summary to stdout. Missing and clipped samples and gaps are bridged by
    /// prediction and counted. The sample rate must match the scenario's sensor.odr_hz.
    Estimate {
        /// Scenario file giving the mode, drive frequency, sensor and filter tuning (default:
        /// the built-in demo scenario).
        #[arg(long, value_name = "TOML")]
        config: Option<PathBuf>,
        /// Data file to read.
        #[arg(long, value_name = "CSV")]
        data: PathBuf,
        /// Write the estimates here: t, force_amplitude, force_cos, force_sin, displacement,
        /// velocity, innovation, nis.
        #[arg(long, value_name = "CSV")]
        out: Option<PathBuf>,
        /// Arithmetic of the filter: f32 as on the sensor node, f64 as a reference.
        #[arg(long, value_enum, default_value_t = Precision::F64)]
        precision: Precision,
        /// Seconds after the first sample before errors, innovations and NIS are counted.
        #[arg(long, value_name = "S", default_value_t = 2.0)]
        settle: f64,
    },
    /// Write the scenario's discrete model and steady-state gain as Rust constants.
    ///
    /// The firmware compiles such a file in with `include!` instead of discretising and solving
    /// the Riccati equation at start-up. Constants: HARMONIC_A, _C, _Q, _R, _GAIN, _S.
    Export {
        /// Scenario file (default: the built-in demo scenario).
        #[arg(long, value_name = "TOML")]
        config: Option<PathBuf>,
        /// Rust file to write.
        #[arg(long, value_name = "RS")]
        out: PathBuf,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Precision {
    F32,
    F64,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn scenario(config: Option<&Path>) -> anyhow::Result<Scenario> {
    config.map_or_else(|| Ok(Scenario::default()), Scenario::load)
}

fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Crank(c) => edgekf_sim::crank::cli::run(c),
        Command::Rotor(c) => edgekf_sim::rotor::cli::run(c),
        Command::Loop(c) => edgekf_sim::residual_loop::cli::run(c),
        Command::Demo { out, config, skip_loop } => {
            let demo = Demo::run(&scenario(config.as_deref())?)?;
            println!("edgekf demo — {}", demo.summary());
            if let Some(dir) = &out {
                demo.write(dir)?;
                println!("wrote {0}/data.csv, {0}/est.csv and {0}/est_f32.csv", dir.display());
            }
            if !skip_loop {
                use edgekf_sim::residual_loop::{cli, demo::LoopDemo};
                println!("\nclosing the loop — {}", LoopDemo::describe());
                let demo = LoopDemo::run(true)?;
                print!("{}", cli::summary_table(&demo.report));
                if let Some(dir) = &out {
                    let dir = dir.join("loop");
                    cli::write_report(&demo.report, &dir)?;
                    let d = &demo.data;
                    let names: Vec<&str> = d.names.iter().map(String::as_str).collect();
                    let cols: Vec<&[f64]> = d.columns.iter().map(Vec::as_slice).collect();
                    data::write(&dir.join("data.csv"), &names, &d.t, &cols)?;
                    println!("wrote {0}/data.csv and the report in {0}", dir.display());
                }
            }
            use edgekf_sim::crank::demo::CrankDemo;
            println!("\n{}", CrankDemo::describe());
            let crank = CrankDemo::run()?;
            print!("{}", crank.summary());
            if let Some(dir) = &out {
                let dir = dir.join("crank");
                std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
                crank.recording.write_csv(&dir.join("data.csv"))?;
                edgekf_sim::crank::estimate::write_estimates(&dir.join("est.csv"), &crank.rows)?;
                println!("wrote {0}/data.csv and {0}/est.csv", dir.display());
            }
            Ok(())
        }
        Command::Oscillator(Oscillator::Simulate { config, out, faults }) => {
            let mut s = scenario(config.as_deref())?;
            if faults {
                s.faults.extend(Fault::demo_set(s.duration_s));
            }
            let rec = s.simulate();
            rec.write_csv(&out)?;
            println!("wrote {}: {}\n{}", out.display(), describe_run(&s), describe(&s));
            Ok(())
        }
        Command::Oscillator(Oscillator::Export { config, out }) => {
            let s = scenario(config.as_deref())?;
            let text = edgekf_sim::export::harmonic_constants(&s.estimator_params())?;
            std::fs::write(&out, text).with_context(|| format!("writing {}", out.display()))?;
            println!("wrote {}: discrete model and steady-state gain of {}", out.display(), describe(&s));
            Ok(())
        }
        Command::Oscillator(Oscillator::Estimate { config, data: path, out, precision, settle }) => {
            let s = scenario(config.as_deref())?;
            let (data, report) = data::read(&path, &KNOWN_CHANNELS)?;
            eprintln!("{}: {report}", path.display());
            let opts =
                EstimateOptions { settle_s: settle, clip_level: Some(s.sensor.range_m_s2()), ..Default::default() };
            let params = s.estimator_params();
            let (name, est) = match precision {
                Precision::F64 => ("f64", estimate::run::<f64>(&data, &params, &opts)),
                Precision::F32 => ("f32", estimate::run::<f32>(&data, &params, &opts)),
            };
            let est = est.with_context(|| format!("{}: cannot estimate", path.display()))?;
            let t_end = data.t.last().copied().unwrap_or(0.0) + report.timing.dt_median;
            let summary = Summary {
                title: format!(
                    "{}: harmonic-force estimate ({name}) with the model of {}\n{}",
                    path.display(),
                    config.as_deref().map_or("the demo scenario".into(), |c| c.display().to_string()),
                    describe(&s)
                ),
                data: &data,
                runs: vec![(name, &est)],
                windows: steady_windows(&s.force, data.t.first().copied().unwrap_or(0.0), t_end),
                noise_std: Some(s.sensor.noise_std()),
            };
            println!("{summary}");
            if let Some(out) = out {
                est.write_csv(&out)?;
                println!("wrote {}", out.display());
            }
            Ok(())
        }
    }
}
