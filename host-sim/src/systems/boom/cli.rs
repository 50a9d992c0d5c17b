//! `edgekf boom …`: the boom's commands.
//!
//! ```text
//! edgekf boom simulate [--config C] --scenario luffing|extension [--duration 120] [--seed 1]
//!                      --out data.csv [--static static.csv]
//! edgekf boom estimate [--config C] --data data.csv --static static.csv [--method model|paper] --out est.csv
//!                      [--plot vibration.svg] [--json]
//! edgekf boom export [--config C] --out boom.rs
//! ```

use super::config::BoomConfig;
use super::estimate::{estimate_with, gyro_model, Method, INCLINOMETER_NOISE};
use super::peaks::peak_errors;
use super::plot::vibration_figure;
use super::runs::Scenario;
use super::simulate::{simulate, static_inclinometer, static_record};
use super::simulate::{MEASURED, TRUTH};
use crate::cli::request::{EstimateFiles, ScenarioRun};
use crate::io::output::{check, write_atomic};
use crate::io::timeline::TimelineOptions;
use crate::report::summary::{truth, EstimateSummary, Quantity};
use anyhow::Context as _;
use clap::{Args, Subcommand};
use std::path::PathBuf;

/// Seconds of the static record.
const STATIC_S: f64 = 60.0;

/// Tip vibration of a long telescoping boom (a fire-ladder truck).
#[derive(Debug, Subcommand)]
pub enum BoomCommand {
    /// Run the finite-element boom through a scenario into a data CSV.
    ///
    /// Columns: t, gyro_rate (rad/s, the tip gyro), incl_angle (rad, the root inclinometer),
    /// boom_length (m), luff_rate_cmd (rad/s, the operator's command), and truth_ columns
    /// (tip_angle from the horizontal, tip_deflection with the gravity sag, tip_vibration about
    /// the static equilibrium, root_angle, root_rate, gyro_bias).
    #[command(mut_arg("config", |a| a.help("Configuration (default: host-sim/configs/boom_ladder30.toml)")))]
    #[command(mut_arg("duration", |a| {
        let up_to_an_hour = crate::cli::values::up_to_an_hour;
        a.required(false).default_value("120").value_parser(up_to_an_hour).help("Length, s (up to an hour)")
    }))]
    Simulate(SimulateArgs),
    /// Estimate the tip's vibration from a data CSV and the static record into an estimate CSV:
    /// t, tip_angle (rad, from the horizontal), tip_vibration (m, about the static
    /// equilibrium), tip_deflection (m, with the model's sag; empty for the paper's method,
    /// which has no sag). With truth_tip_vibration in the data, prints the peak errors.
    #[command(mut_arg("config", |a| a.help("Configuration (default: host-sim/configs/boom_ladder30.toml)")))]
    #[command(mut_arg("data", |a| a.help(
        "Data file (t, gyro_rate, incl_angle, boom_length, luff_rate_cmd; truth_ columns optional)"
    )))]
    #[command(mut_arg("json", |a| a.help(
        "Print one JSON object on stdout (the text goes to stderr): the tip's vibration, angle and deflection with \
         their statistics, the peak vibration and the peak errors"
    )))]
    Estimate(EstimateArgs),
    /// Write the node's boom and sensors (sections, platform, damping, drive, the gyro's noise
    /// model, the inclinometer) as Rust constants.
    ///
    /// The boom image compiles such a file in with `include!`: the committed
    /// firmware/src/systems/boom/generated/boom.rs, or the file the environment variable
    /// EDGEKF_BOOM_MODEL names (how a corrected configuration reaches the chip: rebuild and
    /// flash). The gyro's AR(2), noise and bias are `[gyro]`'s where declared, else the
    /// simulator's (the node has no static record).
    Export(crate::cli::request::ExportArgs),
}

/// Arguments of `edgekf boom estimate`.
#[derive(Debug, Args)]
pub struct EstimateArgs {
    /// `--config`, `--data`, `--out`, `--json` (their help: [`BoomCommand::Estimate`]'s).
    #[command(flatten)]
    pub files: EstimateFiles,
    /// The sensors at rest (t, gyro_rate; incl_angle optional): the gyro's AR(2) noise and bias,
    /// the inclinometer's noise.
    #[arg(long = "static", value_name = "CSV")]
    pub static_data: PathBuf,
    /// The estimator (`model` needs luff_rate_cmd in the data).
    #[arg(long, value_enum, default_value_t = Method::Model)]
    pub method: Method,
    /// Also draw the tip's vibration (SVG), against truth_tip_vibration where the data have it.
    #[arg(long, value_name = "SVG")]
    pub plot: Option<PathBuf>,
}

/// Arguments of `edgekf boom simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// `--config`, `--out`, `--seed`, `--scenario`, `--duration` (their help: [`BoomCommand::Simulate`]'s).
    #[command(flatten)]
    pub run: ScenarioRun<Scenario>,
    /// Also write 60 s of the sensors with the boom at rest (t, gyro_rate, incl_angle): the
    /// static record.
    #[arg(long = "static", value_name = "CSV")]
    pub static_out: Option<PathBuf>,
}

/// Runs one `edgekf boom` command.
pub fn run(command: BoomCommand) -> anyhow::Result<()> {
    match command {
        BoomCommand::Simulate(args) => simulate_command(args),
        BoomCommand::Estimate(args) => estimate_command(args),
        BoomCommand::Export(args) => args.write(load, super::export::node_constants, |config| {
            format!("the node's boom ({} kg platform) and sensors", config.tip.mass)
        }),
    }
}

fn load(path: Option<&std::path::Path>) -> anyhow::Result<BoomConfig> {
    match path {
        Some(p) => BoomConfig::load(p),
        None => Ok(BoomConfig::default()),
    }
}

fn simulate_command(args: SimulateArgs) -> anyhow::Result<()> {
    check(&[Some(args.run.files.out.as_path()), args.static_out.as_deref()], &[args.run.files.config.as_deref()])?;
    if args.static_out.as_ref() == Some(&args.run.files.out) {
        anyhow::bail!("{}: --out and --static are the same file", args.run.files.out.display());
    }
    let config = load(args.run.files.config.as_deref())?;
    let options = args.run.options();
    let rec = simulate(&config, &options, &mut args.run.progress())?;
    let text = rec.to_csv(&args.run.files.out)?;
    let statics = match &args.static_out {
        Some(path) => Some((path, static_csv(&config, args.run.files.seed, path)?)),
        None => None,
    };
    let vib = rec.column("truth_tip_vibration").unwrap_or_default();
    let peak = vib.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let headline = format!("largest tip vibration {peak:.3} m");
    args.run.write(text, rec.t.len(), config.gyro.sample_rate, &headline)?;
    if let Some((path, text)) = statics {
        write_atomic(path, text).with_context(|| format!("cannot write {}", path.display()))?;
        println!("{}: {STATIC_S:.0} s of the gyro and the inclinometer at rest", path.display());
    }
    Ok(())
}

/// The static record's CSV text (`t`, `gyro_rate`, `incl_angle`): 60 s of the sensors with
/// the boom at rest, `path` for the error messages.
pub fn static_csv(config: &BoomConfig, seed: u64, path: &std::path::Path) -> anyhow::Result<String> {
    let (t, gyro) = static_record(config, STATIC_S, seed)?;
    let mut incl = static_inclinometer(config, STATIC_S, seed)?;
    incl.resize(t.len(), f64::NAN);
    Ok(crate::io::data::to_csv_string(path, &["gyro_rate", "incl_angle"], &t, &[&gyro, &incl])?)
}

fn estimate_command(args: EstimateArgs) -> anyhow::Result<()> {
    check(
        &[Some(args.files.out.as_path()), args.plot.as_deref()],
        &[Some(args.files.data.as_path()), Some(args.static_data.as_path()), args.files.config.as_deref()],
    )?;
    if args.plot.as_ref() == Some(&args.files.out) {
        anyhow::bail!("{}: --out and --plot are the same file", args.files.out.display());
    }
    let prose = args.files.prose();
    let config = load(args.files.config.as_deref())?;
    let known: Vec<&str> = MEASURED.iter().chain(TRUTH.iter()).copied().collect();
    let required = match args.method {
        Method::Model => &MEASURED[..],
        Method::Paper => &MEASURED[..3],
    };
    let (file, restarts) =
        crate::io::recording::read_estimator_data(&args.files.data, required, &known, config.gyro.sample_rate)?;
    let (statics, notes) =
        crate::io::data::read_required(&args.static_data, &["gyro_rate"], &["gyro_rate", "incl_angle"])?;
    eprintln!("{}: {notes}", args.static_data.display());
    let ar = gyro_model(&config, statics.column("gyro_rate").unwrap_or_default())?;
    let incl_noise = statics.column("incl_angle").and_then(spread).unwrap_or(INCLINOMETER_NOISE);
    let est = estimate_with(&config, &file, ar, incl_noise, args.method, &restarts)?;
    write_atomic(&args.files.out, est.to_csv(&args.files.out)?)
        .with_context(|| format!("cannot write {}", args.files.out.display()))?;
    prose.say(format_args!(
        "{}: {} rows by the {} method; gyro AR(2) [{:.4}, {:.5}], noise {:.2e} rad/s, bias {:.3e} rad/s",
        args.files.out.display(),
        est.t.len(),
        args.method.name(),
        ar.a[0],
        ar.a[1],
        ar.sigma,
        ar.mean
    ));
    // Truth row for row with the estimate, or none (an empty column is none too).
    let truth_vib = truth(file.column("truth_tip_vibration")).filter(|c| c.len() == est.t.len());
    if let Some(path) = &args.plot {
        vibration_figure(&est, args.method.name(), truth_vib, file.column(MEASURED[3]))
            .and_then(|svg| write_atomic(path, svg).with_context(|| format!("cannot write {}", path.display())))
            .with_context(|| format!("{} written, but not the plot", args.files.out.display()))?;
        let against =
            if truth_vib.is_some() { " against truth" } else { " (the recording has no truth_tip_vibration)" };
        if truth_vib.is_none() {
            eprintln!(
                "notice: {}: no truth_tip_vibration in the recording: the estimate is drawn alone",
                path.display()
            );
        }
        prose.say(format_args!("{}: the tip's vibration{against}", path.display()));
    }
    let peaks = match (truth_vib, truth(file.column("truth_root_rate")), est.column("tip_vibration")) {
        (Some(truth), Some(rate), Some(vib)) => Some(peak_errors(&est.t, vib, truth, rate)),
        _ => None,
    };
    if let Some(p) = &peaks {
        prose.say(format_args!(
            "peak error over {} peaks: mean {:.2} %, median {:.2} %; {} free-decay peaks: mean {:.2} %",
            p.peaks, p.mean_pct, p.median_pct, p.free_decay_peaks, p.free_decay_mean_pct
        ));
    }
    if args.files.json {
        json_summary(&args, &file, &est, peaks.as_ref()).print()?;
    }
    Ok(())
}

/// The JSON object: the tip's vibration (no `final`: its last swing means nothing) with the
/// text's peak errors as its error, its peak in `details`, and the tip's angle and deflection
/// against their truth.
fn json_summary(
    args: &EstimateArgs,
    file: &crate::io::data::DataFile,
    est: &super::estimate::BoomEstimate,
    peaks: Option<&super::peaks::PeakErrors>,
) -> EstimateSummary {
    let mut j = args.files.summary("boom", &file.t);
    for (name, unit) in [("tip_vibration", "m"), ("tip_angle", "rad"), ("tip_deflection", "m")] {
        let Some(values) = est.column(name) else { continue };
        let mut q = Quantity::of(unit, values).map(|q| q.against(values, truth(file.column(&format!("truth_{name}")))));
        if name == "tip_vibration" {
            j.detail("peak_tip_vibration", q.as_ref().map(|q| q.stats.peak()));
            q = q.map(Quantity::without_final);
            if let Some(p) = peaks {
                q = q.map(|q| {
                    q.with_error("peaks", p.peaks as f64)
                        .with_error("peak_mean_pct", p.mean_pct)
                        .with_error("peak_median_pct", p.median_pct)
                        .with_error("free_decay_peaks", p.free_decay_peaks as f64)
                        .with_error("free_decay_mean_pct", p.free_decay_mean_pct)
                });
            }
        }
        j.quantity(name, q);
    }
    j.detail("method", args.method.name());
    j.plot = args.plot.clone();
    j
}

/// Standard deviation of the finite values of `v` (at least 16 of them, not all equal).
fn spread(v: &[f64]) -> Option<f64> {
    let mut stats = edgekf::residual::RunningStats::<f64>::new();
    for x in v.iter().copied().filter(|x| x.is_finite()) {
        stats.push(x);
    }
    let sd = stats.variance().sqrt();
    (stats.count() >= 16 && sd > 0.0).then_some(sd)
}

/// `edgekf loop boom`'s and `edgekf baseline boom`'s own flag.
#[derive(Debug, Args)]
pub struct BoomLoopArgs {
    /// The sensors at rest (t, gyro_rate; incl_angle optional): the gyro's AR(2) noise and bias,
    /// the inclinometer's noise.
    #[arg(long = "static", value_name = "CSV")]
    pub static_data: PathBuf,
}

/// `edgekf loop boom --config C --data data.csv --static static.csv --report DIR`.
pub fn close_loop(
    request: &crate::cli::request::LoopRequest,
    m: &clap::ArgMatches,
) -> anyhow::Result<crate::residual_loop::LoopReport> {
    let (config, file, ar, incl_noise) = loop_inputs(&request.config, &request.data, m)?;
    request.close("boom", file.sha256.clone(), |o| super::loop_system::close_loop(&config, &file, ar, incl_noise, o))
}

/// `edgekf baseline boom --config C --data healthy.csv --static static.csv --out B`: what the
/// configured boom leaves unexplained on a healthy recording, and its innovation levels there.
pub fn baseline(request: &crate::cli::request::BaselineRequest, m: &clap::ArgMatches) -> anyhow::Result<String> {
    let args = &request.args;
    let (config, file, ar, incl_noise) = loop_inputs(&args.config, &args.data, m)?;
    let b =
        super::loop_system::learn_baseline(&config, &file, ar, incl_noise, args.condition.clone(), &request.options)?;
    b.with_source(&request.source, file.sha256.as_deref()).to_toml()
}

/// What a loop or a baseline reads: the configuration, the recording (every measured channel
/// required), the gyro's noise model and the inclinometer's noise from the static record.
fn loop_inputs(
    config: &std::path::Path,
    data: &std::path::Path,
    m: &clap::ArgMatches,
) -> anyhow::Result<(BoomConfig, crate::io::data::DataFile, edgekf::systems::boom::Ar2, f64)> {
    use clap::FromArgMatches;
    let args = BoomLoopArgs::from_arg_matches(m).map_err(|e| anyhow::anyhow!("{e}"))?;
    let config = BoomConfig::load(config)?;
    let known: Vec<&str> = MEASURED.iter().chain(TRUTH.iter()).copied().collect();
    let file = crate::io::recording::read_data(data, &known, config.gyro.sample_rate, &TimelineOptions::default())?;
    for name in MEASURED {
        if file.column(name).is_none() {
            anyhow::bail!("{}: no `{name}` column (the boom's loop needs {})", data.display(), MEASURED.join(", "));
        }
    }
    let (statics, notes) =
        crate::io::data::read_required(&args.static_data, &["gyro_rate"], &["gyro_rate", "incl_angle"])?;
    eprintln!("{}: {notes}", args.static_data.display());
    let ar = gyro_model(&config, statics.column("gyro_rate").unwrap_or_default())?;
    let incl_noise = statics.column("incl_angle").and_then(spread).unwrap_or(INCLINOMETER_NOISE);
    Ok((config, file, ar, incl_noise))
}
