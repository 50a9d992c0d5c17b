//! `edgekf uuv …`: the underwater vehicle's commands.
//!
//! ```text
//! edgekf uuv simulate [--config C] --scenario paper|vertical|healthy [--duration 300] [--seed 1]
//!                     [--rate 50] --out data.csv
//! edgekf uuv estimate [--config C] --data data.csv --out est.csv [--plot health.svg] [--json]
//! edgekf uuv export [--config C] --out uuv.rs
//! ```

use super::config::UuvConfig;
use super::estimate::{estimate, EstimateTable, REQUIRED};
use super::scenario::Scenario;
use super::simulate::{simulate, TRUTH};
use crate::cli::request::{EstimateFiles, ScenarioRun};
use crate::io::data::DataFile;
use crate::io::output::{check, write_atomic};
use crate::io::timeline::TimelineOptions;
use crate::report::summary::{truth, Prose, Quantity, Stats};
use crate::residual_loop::LoopReport;
use anyhow::Context as _;
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};

/// Underwater vehicle thruster health (REMUS 100 with a vertical tunnel thruster).
#[derive(Debug, Subcommand)]
pub enum UuvCommand {
    /// Fly a scenario closed loop with the 6-DOF reference model into a data CSV.
    ///
    /// Columns: t, acc_x, acc_y, acc_z (m/s², specific force, body), gyro_x, gyro_y, gyro_z
    /// (rad/s), depth (m), heading (rad), dvl_u, dvl_v, dvl_w (m/s, body, over ground; empty
    /// between DVL updates), cmd_n_t, cmd_n_v (rpm), cmd_rudder, cmd_elevator (rad; in force
    /// until the next row), and truth_ columns (health factors, position, attitude, velocity,
    /// current, sensor biases).
    #[command(mut_arg("config", |a| a.help("Configuration (default: host-sim/configs/uuv_remus100.toml's values)")))]
    #[command(mut_arg("seed", |a| a.help("Seed of the current and of the sensors' noise and biases")))]
    #[command(mut_arg("scenario", |a| a.help("Health timeline")))]
    #[command(mut_arg("duration", |a| a.required(false).default_value("300")))]
    Simulate(SimulateArgs),
    /// Estimate the thrusters' health and the vehicle's state from a data CSV into an
    /// estimate CSV: t, k_t, k_v, k_t_std, k_v_std, status_t, status_v (healthy, degraded,
    /// failed), x, y, z, phi, theta, psi, u, v, w, p, q, r, then the nuisance states. A
    /// thruster without a health state has empty k and status columns.
    #[command(mut_arg("config", |a| a.help("Configuration (default: host-sim/configs/uuv_remus100.toml's values)")))]
    #[command(mut_arg("json", |a| a.help(
        "Print one JSON object on stdout (the text goes to stderr): per health factor and speed its statistics, \
         final value and error against truth, per thruster its alarms"
    )))]
    Estimate(EstimateArgs),
    /// Write the node's vehicle and estimator (`[vehicle]`, `[estimator]`, `[sensors] rate`)
    /// as Rust constants.
    ///
    /// The vehicle image compiles such a file in with `include!`: the committed
    /// firmware/src/systems/uuv/generated/uuv.rs, or the file the environment variable
    /// EDGEKF_UUV_MODEL names (how a corrected configuration reaches the chip: rebuild and
    /// flash).
    Export(crate::cli::request::ExportArgs),
}

/// Arguments of `edgekf uuv simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// `--config`, `--out`, `--seed`, `--scenario`, `--duration` (their help: [`UuvCommand::Simulate`]'s).
    #[command(flatten)]
    pub run: ScenarioRun<Scenario>,
    /// Sample rate, Hz (default: the configuration's `sensors.rate`).
    #[arg(long, value_name = "HZ")]
    pub rate: Option<f64>,
}

/// Arguments of `edgekf uuv estimate`.
#[derive(Debug, Args)]
pub struct EstimateArgs {
    /// `--config`, `--data`, `--out`, `--json` (their help: [`UuvCommand::Estimate`]'s).
    #[command(flatten)]
    pub files: EstimateFiles,
    /// Also draw the health factors (against truth where the data has it) into this SVG; with
    /// no health factor in the configuration, the speeds u, v, w.
    #[arg(long, value_name = "SVG")]
    pub plot: Option<PathBuf>,
}

/// Runs one `edgekf uuv` command.
pub fn run(command: UuvCommand) -> anyhow::Result<()> {
    match command {
        UuvCommand::Simulate(a) => simulate_command(a),
        UuvCommand::Estimate(a) => estimate_command(a),
        UuvCommand::Export(a) => {
            a.write(load, super::export::node_constants, |_| "the node's vehicle and estimator".into())
        }
    }
}

fn load(path: Option<&Path>) -> anyhow::Result<UuvConfig> {
    Ok(match path {
        Some(p) => UuvConfig::load(p)?,
        None => UuvConfig::default(),
    })
}

fn simulate_command(args: SimulateArgs) -> anyhow::Result<()> {
    check(&[Some(&args.run.files.out)], &[args.run.files.config.as_deref()])?;
    let mut config = load(args.run.files.config.as_deref())?;
    if let Some(rate) = args.rate {
        config.sensors.rate = rate;
        config.validate()?;
    }
    let options = args.run.options();
    let rec = simulate(&config, &options, &mut args.run.progress())?;
    let text = rec.to_csv(&args.run.files.out)?;
    let u = rec.column("truth_u").unwrap_or_default();
    let mean_u = u.iter().sum::<f64>() / u.len().max(1) as f64;
    args.run.write(text, rec.t.len(), config.sensors.rate, &format!("mean speed {mean_u:.3} m/s"))
}

fn estimate_command(args: EstimateArgs) -> anyhow::Result<()> {
    check(&[Some(&args.files.out), args.plot.as_deref()], &[Some(&args.files.data), args.files.config.as_deref()])?;
    if args.plot.as_ref() == Some(&args.files.out) {
        anyhow::bail!("{}: --out and --plot are the same file", args.files.out.display());
    }
    let prose = args.files.prose();
    let config = load(args.files.config.as_deref())?;
    let known: Vec<&str> = REQUIRED.iter().chain(TRUTH.iter()).copied().collect();
    let (file, restarts) =
        crate::io::recording::read_estimator_data(&args.files.data, &REQUIRED, &known, config.sensors.rate)?;
    let table = estimate(&config, &file, &restarts)?;
    write_atomic(&args.files.out, table.to_csv())
        .with_context(|| format!("cannot write {}", args.files.out.display()))?;
    prose.say(format_args!("{}: {} rows", args.files.out.display(), table.t.len()));
    if let Some(path) = &args.plot {
        plot(prose, path, &table, &file)
            .with_context(|| format!("{} written, but not the plot", args.files.out.display()))?;
    }
    let thrusters = summarise(prose, &table, &file);
    if args.files.json {
        let mut j = args.files.summary("uuv", &file.t);
        for k in ["k_t", "k_v", "u", "v", "w"] {
            let Some(est) = table.column(k) else { continue };
            let unit = if k.starts_with("k_") { "1" } else { "m/s" };
            let q = Quantity::of(unit, est).map(|q| q.against(est, truth(file.column(&format!("truth_{k}")))));
            j.quantity(k, q);
        }
        j.detail("thrusters", thrusters);
        j.detail("filter_repairs", table.repairs);
        j.plot = args.plot;
        j.print()?;
    }
    Ok(())
}

/// `--plot`: the health factors against their truth, or the speeds where the filter carries no
/// health factor; a notice when the recording has no truth to draw against.
///
/// Without a health factor the speeds are drawn rather than the command refused: the user
/// asked for a figure of the run, the filter still estimates the vehicle's motion, and a
/// script that plots every configuration's run should not fail on one of them.
fn plot(prose: Prose, path: &Path, table: &EstimateTable, file: &DataFile) -> anyhow::Result<()> {
    // Truth row for row with the estimate, or none (an empty column is none too).
    let aligned = |name: &str| truth(file.column(name)).filter(|c| c.len() == table.t.len());
    let health_truth = [aligned("truth_k_t"), aligned("truth_k_v")];
    let (svg, what, against) = match super::plot::health_figure(table, health_truth)? {
        Some(svg) => (svg, "health factors", health_truth.iter().any(Option::is_some)),
        None => {
            let speed_truth = ["truth_u", "truth_v", "truth_w"].map(aligned);
            let svg = super::plot::speed_figure(table, speed_truth)?;
            eprintln!("notice: no health state in the configuration: {} draws the speeds u, v, w", path.display());
            (svg, "speeds", speed_truth.iter().any(Option::is_some))
        }
    };
    write_atomic(path, svg).with_context(|| format!("cannot write {}", path.display()))?;
    if !against {
        eprintln!("notice: {}: no truth_ columns in the recording: the estimates are drawn alone", path.display());
    }
    prose.say(format_args!("{}: {what}{}", path.display(), if against { " against truth" } else { "" }));
    Ok(())
}

/// Per thruster: alarms, time declared and, with truth, the RMS error of its factor; returned
/// for the JSON object as `{thruster: {alarms, declared_s}}`.
fn summarise(prose: Prose, table: &EstimateTable, data: &DataFile) -> serde_json::Value {
    let mut thrusters = serde_json::Map::new();
    for (j, (name, k, truth)) in
        [("main", "k_t", "truth_k_t"), ("vertical", "k_v", "truth_k_v")].into_iter().enumerate()
    {
        let Some(est) = table.column(k) else { continue };
        if est.iter().all(|v| v.is_nan()) {
            prose.say(format_args!("{name} thruster: no health state"));
            continue;
        }
        let declared = table.status[j].iter().filter(|s| s.is_some_and(|s| s.declared())).count();
        let dt = if table.t.len() > 1 { table.t[1] - table.t[0] } else { 0.0 };
        let mut line = format!(
            "{name} thruster: {} CUSUM alarm(s), declared for {:.2} s, final {k} = {:.3}",
            table.alarms[j],
            declared as f64 * dt,
            est.last().copied().unwrap_or(f64::NAN)
        );
        if let Some(error) = data.column(truth).and_then(|tr| Stats::of_error(est, tr)) {
            line += &format!(", RMS error {:.4}", error.rms);
        }
        prose.say(line);
        thrusters
            .insert(name.into(), serde_json::json!({ "alarms": table.alarms[j], "declared_s": declared as f64 * dt }));
    }
    if table.repairs != (0, 0) {
        prose.say(format_args!(
            "filter repairs: {} covariance reset(s), {} refused update(s)",
            table.repairs.0, table.repairs.1
        ));
    }
    serde_json::Value::Object(thrusters)
}

/// `edgekf loop uuv`: the vehicle's configuration and data, the loop closed on them.
pub fn close_loop(request: &crate::cli::request::LoopRequest, _: &clap::ArgMatches) -> anyhow::Result<LoopReport> {
    let (config, file) = loop_inputs(&request.config, &request.data)?;
    request.close("uuv", file.sha256.clone(), |o| super::loop_system::close_loop(&config, &file, o))
}

/// `edgekf baseline uuv`: what the configured vehicle leaves unexplained on a healthy
/// recording, and its innovation levels there.
pub fn baseline(request: &crate::cli::request::BaselineRequest, _: &clap::ArgMatches) -> anyhow::Result<String> {
    let args = &request.args;
    let (config, file) = loop_inputs(&args.config, &args.data)?;
    let b = super::loop_system::learn_baseline(&config, &file, args.condition.clone(), &request.options)?;
    b.with_source(&request.source, file.sha256.as_deref()).to_toml()
}

/// The configuration and the recording a loop or a baseline reads.
fn loop_inputs(config: &Path, data: &Path) -> anyhow::Result<(UuvConfig, crate::io::data::DataFile)> {
    let config = UuvConfig::load(config)?;
    let known: Vec<&str> = REQUIRED.iter().chain(TRUTH.iter()).copied().collect();
    let file = crate::io::recording::read_data(data, &known, config.sensors.rate, &TimelineOptions::default())?;
    Ok((config, file))
}
