//! `edgekf oscillator …`: simulate a scenario, estimate its harmonic force, export the model
//! for the firmware; and the oscillator's part of `edgekf demo`.

use super::demo::{describe, describe_run, Demo};
use super::estimate::{self, window_mean, EstimateOptions, KNOWN_CHANNELS};
use super::export::harmonic_constants;
use super::report::{steady_windows, Summary};
use super::scenario::{Fault, Scenario};
use crate::cli::request::DemoArgs;
use crate::io::data;
use crate::io::output::{check, check_folder};
use crate::report::summary::{truth as truth_column, EstimateSummary, Prose, Quantity};
use anyhow::Context as _;
use clap::{Subcommand, ValueEnum};
use std::path::{Path, PathBuf};

/// The `edgekf oscillator` subcommands.
#[derive(Debug, Subcommand)]
pub enum OscillatorCommand {
    /// Simulate a scenario into a data CSV.
    ///
    /// Columns: t, ax, ay, az, fault_nack, fault_timeout, fault_garbage, fault_stuck,
    /// fault_drop, fault_reset, truth_x, truth_v, truth_force, truth_force_amplitude,
    /// truth_accel.
    Simulate {
        /// Scenario file (default: the built-in demo scenario).
        #[arg(long, value_name = "TOML")]
        config: Option<PathBuf>,
        /// Data file to write.
        #[arg(long, value_name = "CSV")]
        out: PathBuf,
        /// Add one fault of each kind to the scenario's own: a 3-transaction I²C NACK burst at
        /// 25 % of the run, 2 timeouts at 30 %, 3 garbage reads at 35 %, registers stuck for
        /// 50 ms at 40 %, no samples for 20 ms at 50 %, a sensor reset at 60 %, 20 ms of 3 g on
        /// x at 75 %.
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
        /// Print one JSON object on stdout (the table goes to stderr): the force amplitude's
        /// statistics, its means over the steady stretches and its errors against truth.
        #[arg(long)]
        json: bool,
    },
    /// Write the scenario's discrete model and steady-state gain as Rust constants.
    ///
    /// The firmware compiles such a file in with `include!` instead of discretising and solving
    /// the Riccati equation at start-up. Constants: HARMONIC_A, _C, _Q, _R, _GAIN, _S and
    /// _ACCEL_OFFSET (the `[filter] accel_offset_m_s2` the node subtracts from each sample).
    /// Build an image with another file than the committed one through the environment
    /// variable EDGEKF_OSCILLATOR_MODEL (its path).
    Export {
        /// Scenario file (default: the built-in demo scenario).
        #[arg(long, value_name = "TOML")]
        config: Option<PathBuf>,
        /// Rust file to write.
        #[arg(long, value_name = "RS")]
        out: PathBuf,
    },
}

/// Arithmetic of the filter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Precision {
    /// As on the sensor node.
    F32,
    /// The host reference.
    F64,
}

fn scenario(config: Option<&Path>) -> anyhow::Result<Scenario> {
    config.map_or_else(|| Ok(Scenario::default()), Scenario::load)
}

/// Runs an `edgekf oscillator` command.
pub fn run(command: OscillatorCommand) -> anyhow::Result<()> {
    match command {
        OscillatorCommand::Simulate { config, out, faults } => {
            check(&[Some(&out)], &[config.as_deref()])?;
            let mut s = scenario(config.as_deref())?;
            if faults {
                s.faults.extend(Fault::demo_set(s.duration_s));
            }
            let rec = s.simulate();
            rec.write_csv(&out)?;
            println!("wrote {}: {}\n{}", out.display(), describe_run(&s), describe(&s));
            Ok(())
        }
        OscillatorCommand::Export { config, out } => {
            check(&[Some(&out)], &[config.as_deref()])?;
            let s = scenario(config.as_deref())?;
            let text = harmonic_constants(&s.estimator_params(), s.filter.accel_offset_m_s2)?;
            crate::io::output::write_atomic(&out, text).with_context(|| format!("writing {}", out.display()))?;
            println!("wrote {}: discrete model and steady-state gain of {}", out.display(), describe(&s));
            Ok(())
        }
        OscillatorCommand::Estimate { config, data, out, precision, settle, json } => {
            estimate_command(EstimateRequest { config, data, out, precision, settle, json })
        }
    }
}

/// `edgekf oscillator estimate`'s arguments.
struct EstimateRequest {
    config: Option<PathBuf>,
    data: PathBuf,
    out: Option<PathBuf>,
    precision: Precision,
    settle: f64,
    json: bool,
}

/// Runs the filter over the data: the table (stdout, or stderr under `--json`), the estimate
/// file, then the JSON object.
fn estimate_command(request: EstimateRequest) -> anyhow::Result<()> {
    let EstimateRequest { config, data: path, out, precision, settle, json } = request;
    let prose = Prose { json };
    check(&[out.as_deref()], &[Some(&path), config.as_deref()])?;
    let s = scenario(config.as_deref())?;
    let (mut data, report) = data::read(&path, &KNOWN_CHANNELS)?;
    subtract_offset(&mut data, s.filter.accel_offset_m_s2);
    eprintln!("{}: {report}", path.display());
    let opts = EstimateOptions {
        settle_s: settle,
        clip_level: Some(s.sensor.range_m_s2()),
        timeline: s.timeline,
        ..Default::default()
    };
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
    prose.say(&summary);
    if let Some(out) = &out {
        est.write_csv(out)?;
        prose.say(format_args!("wrote {}", out.display()));
    }
    if json {
        let mut j = EstimateSummary::new("oscillator", &path, config.as_deref(), &data.t);
        json_quantities(&mut j, &summary, &est);
        j.detail("precision", name);
        j.detail("settle_s", settle);
        j.out = out;
        j.print()?;
    }
    Ok(())
}

/// The declared accelerometer offset (`[filter] accel_offset_m_s2`) taken off `ax`, as the
/// loop's filter and the node do.
fn subtract_offset(data: &mut data::DataFile, offset: f64) {
    if let Some(i) = data.names.iter().position(|n| n == "ax") {
        data.columns[i].iter_mut().for_each(|a| *a -= offset);
    }
}

/// The force amplitude and the displacement in the JSON object, with the table's figures:
/// the RMS errors after settling, and per steady stretch the force amplitude's mean against
/// the truth's.
fn json_quantities(j: &mut EstimateSummary, summary: &Summary<'_>, est: &estimate::Estimates) {
    let amp = Quantity::of("N", &est.force_amplitude)
        .map(|q| q.with_error("rms", est.error_rms.force_amplitude.unwrap_or(f64::NAN)));
    j.quantity("force_amplitude", amp);
    let x = Quantity::of("m", &est.displacement)
        .map(|q| q.without_final().with_error("rms", est.error_rms.displacement.unwrap_or(f64::NAN)));
    j.quantity("displacement", x);
    let truth = truth_column(summary.data.column("truth_force_amplitude"));
    let windows: Vec<_> = summary
        .windows
        .iter()
        .map(|&(t0, t1)| {
            let w = est.window(t0, t1);
            serde_json::json!({
                "from_s": t0,
                "to_s": t1,
                "force_amplitude_mean": w.force_amplitude,
                "force_amplitude_std": w.force_amplitude_std,
                "truth": truth.and_then(|c| window_mean(&summary.data.t, c, t0, t1)),
                "nis_mean": w.nis_mean,
            })
        })
        .collect();
    j.detail("steady_windows", windows);
    j.detail("innovation_rms", est.innovation_rms);
    j.detail("nis_mean", est.nis_mean);
    j.detail("missing_samples", est.input.nan + est.input.clipped + est.input.gap_steps);
}

/// The oscillator's part of `edgekf demo`: the demo scenario (or `--config`'s) estimated in
/// `f64` and `f32`; `--out DIR` writes `data.csv`, `est.csv` and `est_f32.csv`.
pub fn demo(args: &DemoArgs) -> anyhow::Result<()> {
    if let Some(dir) = &args.out {
        check_folder(dir, &["data.csv", "est.csv", "est_f32.csv"], &[args.config.as_deref()])?;
    }
    let demo = Demo::run(&scenario(args.config.as_deref())?)?;
    println!("edgekf demo — {}", demo.summary());
    if let Some(dir) = &args.out {
        demo.write(dir)?;
        println!("wrote {0}/data.csv, {0}/est.csv and {0}/est_f32.csv", dir.display());
    }
    Ok(())
}

/// `edgekf loop oscillator`: the scenario file's model (mode, drive, sensor, filter tuning) on
/// the data's `ax` channel.
pub fn close_loop(
    request: &crate::cli::request::LoopRequest,
    _: &clap::ArgMatches,
) -> anyhow::Result<crate::residual_loop::LoopReport> {
    let s = Scenario::load(&request.config)?;
    let file = crate::io::recording::read_data(&request.data, &KNOWN_CHANNELS, s.sensor.odr_hz, &s.timeline)?;
    request.close("oscillator", file.sha256.clone(), |o| super::loop_system::close_loop(&s, &file, o))
}

/// `edgekf baseline oscillator`: what the scenario's model leaves unexplained on a healthy
/// recording, and its innovation level there.
pub fn baseline(request: &crate::cli::request::BaselineRequest, _: &clap::ArgMatches) -> anyhow::Result<String> {
    let args = &request.args;
    let s = Scenario::load(&args.config)?;
    let file = crate::io::recording::read_data(&args.data, &KNOWN_CHANNELS, s.sensor.odr_hz, &s.timeline)?;
    let b = super::loop_system::learn_baseline(&s, &file, args.condition.clone(), &request.options)?;
    b.with_source(&request.source, file.sha256.as_deref()).to_toml()
}
