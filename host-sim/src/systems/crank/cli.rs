//! `edgekf crank …`: the slider-crank commands of the `edgekf` binary.
//!
//! ```text
//! edgekf crank simulate [--config C] [--clearance A=0.25e-3]… --duration S --out data.csv
//!                       [--seed N] [--integrator symplectic|adaptive] [--step H] [--tolerance TOL]
//! edgekf crank feature  --data data.csv [--window 0.25] [--column crank_alpha]
//! edgekf crank estimate --data data.csv --method ukf|fast [--config C] [--initial 0.1e-3]
//!                       [--window 0.25] [--model model.toml] --out est.csv
//! edgekf crank train    --out model.toml [--config C] [--clearances 0.08e-3,…] [--variants 8]
//!                       [--duration 10] [--threads 2] [--ridge 1e-4] [--linear] [--seed-base 1000]
//!                       [--test-variants 0] [--test-seed-base 900000] [--test-clearances …]
//!                       [--save-features F.csv] [--load-features F.csv] [--load-test-features T.csv]
//! ```

use super::config::CrankConfig;
use super::error::CrankError;
use super::feature::window_features;
use super::integrate::Integrator;
use super::simulate::{CrankRecording, SimOptions};
use super::{Joint, Mechanism};
use crate::io::data;
use crate::io::output::{check, check_folder};
use anyhow::Context as _;
use clap::{Args, Subcommand, ValueEnum};
use std::io::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// Planar slider-crank with revolute clearance joints (the clearance paper's mechanism).
#[derive(Debug, Subcommand)]
pub enum CrankCommand {
    /// Simulate the mechanism falling from rest under gravity into a data CSV.
    ///
    /// Columns: t, crank_alpha (measured, rad/s²), truth_crank_alpha, truth_crank_angle,
    /// truth_crank_rate, truth_slider_x, truth_contact_force_A/B/C (N), truth_eccentricity_A/B/C,
    /// truth_clearance_A/B/C (m, 0 = ideal joint), truth_energy, truth_dissipated,
    /// truth_balance (J). A summary goes to stdout, progress to stderr.
    Simulate(SimulateArgs),
    /// Print the spectral clearance feature (fit y = a·e^(b·f) of the FFT amplitude) of each
    /// window of a data CSV.
    Feature(FeatureArgs),
    /// Estimate the clearance from a recording's crank angular acceleration into an estimate
    /// CSV (t, clearance_A, clearance_B, clearance_C in m, 0 = tight; one row per window, the
    /// last row the estimate for the whole recording).
    Estimate(EstimateArgs),
    /// Learn the fast estimator's model (joint discriminant and per-joint clearance regression)
    /// from simulated runs, and write it as TOML (`--model` of `estimate --method fast`; the
    /// built-in model is host-sim/src/crank/estimate/fast_model.toml, written by this command
    /// with its defaults).
    Train(TrainArgs),
    /// Write the fast estimator's model as Rust constants for the firmware
    /// (firmware/src/systems/crank/generated/clearance.rs).
    Export(super::estimate::chip::ExportArgs),
}

/// Arguments of `edgekf crank train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    /// Configuration file of the mechanism (default: the paper's case).
    #[arg(long, value_name = "TOML")]
    pub config: Option<PathBuf>,
    /// Model file to write.
    #[arg(long, value_name = "TOML")]
    pub out: PathBuf,
    /// Training clearances, m, comma-separated (each simulated at every joint).
    #[arg(long, value_name = "M,…", value_delimiter = ',', default_values_t = [0.08e-3, 0.1e-3, 0.15e-3, 0.2e-3, 0.25e-3, 0.3e-3, 0.35e-3, 0.4e-3, 0.45e-3, 0.5e-3, 0.55e-3])]
    pub clearances: Vec<f64>,
    /// Runs per joint and clearance (release angle 20–40° and journal radius × 0.8–1.2 drawn
    /// at random, one noise seed each).
    #[arg(long, value_name = "N", default_value_t = 8)]
    pub variants: usize,
    /// Length of each run, s.
    #[arg(long, value_name = "S", default_value_t = 10.0)]
    pub duration: f64,
    /// Simulation threads.
    #[arg(long, value_name = "N", default_value_t = 2)]
    pub threads: usize,
    /// Ridge regularisation on the standardised features.
    #[arg(long, value_name = "L", default_value_t = 1e-4)]
    pub ridge: f64,
    /// First noise seed of the training grid (also seeds its random draws).
    #[arg(long, value_name = "N", default_value_t = 1000)]
    pub seed_base: u64,
    /// Runs per joint and clearance of an unseen test grid to score the model on (0: none).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub test_variants: usize,
    /// First noise seed of the test grid.
    #[arg(long, value_name = "N", default_value_t = 900_000)]
    pub test_seed_base: u64,
    /// Regress ln c on the standardised features only (default: on their squares too).
    #[arg(long)]
    pub linear: bool,
    /// Runs per joint and clearance of the release laws' own grid of 0.11 s runs
    /// (`estimate::release`); 0 leaves the release stage out.
    #[arg(long, value_name = "N", default_value_t = 300)]
    pub release_variants: usize,
    /// First noise seed of the release grid.
    #[arg(long, value_name = "N", default_value_t = 500_000)]
    pub release_seed_base: u64,
    /// Largest |ln c| step from the window features' clearance to a release law's that is taken.
    #[arg(long, value_name = "L", default_value_t = 0.3)]
    pub max_step: f64,
    /// Write the training runs' features to this CSV.
    #[arg(long, value_name = "CSV")]
    pub save_features: Option<PathBuf>,
    /// Fit to the runs and features of this CSV (from --save-features) instead of simulating.
    #[arg(long, value_name = "CSV")]
    pub load_features: Option<PathBuf>,
    /// Score on the runs and features of this CSV (the `.test.csv` that --save-features writes
    /// next to its file) instead of simulating the test grid.
    #[arg(long, value_name = "CSV")]
    pub load_test_features: Option<PathBuf>,
    /// Test clearances, m, comma-separated.
    #[arg(long, value_name = "M,…", value_delimiter = ',', default_values_t = [0.1e-3, 0.2e-3, 0.3e-3, 0.4e-3, 0.5e-3])]
    pub test_clearances: Vec<f64>,
}

/// Estimation method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// The paper's UKF: three sigma points, each a clearance simulation, one step per window.
    Ukf,
    /// The learned feature-to-clearance map (no simulation).
    Fast,
}

/// Arguments of `edgekf crank estimate`.
#[derive(Debug, Args)]
pub struct EstimateArgs {
    /// Configuration file of the mechanism (default: the paper's case); its `[timeline]
    /// max_gap_s` (default 2 s) is the longest gap in `t` bridged: the recording ends at a longer
    /// one.
    #[arg(long, value_name = "TOML")]
    pub config: Option<PathBuf>,
    /// Data file with `t` and `crank_alpha` (rad/s²). Rows lost from `t` are missing samples,
    /// like empty cells: `fast` steps through them, `ukf` and a legacy `--model` map refuse them.
    #[arg(long, value_name = "CSV")]
    pub data: PathBuf,
    /// Estimator.
    #[arg(long, value_enum)]
    pub method: MethodArg,
    /// UKF: initial clearance guess, m.
    #[arg(long, value_name = "M", default_value_t = 0.1e-3)]
    pub initial: f64,
    /// UKF: window (one filter step), s.
    #[arg(long, value_name = "S", default_value_t = 0.25)]
    pub window: f64,
    /// UKF: measurement standard deviation of the feature a (default: per window, from the
    /// spread of the sigma points' simulated ensembles).
    #[arg(long, value_name = "RAD_S2")]
    pub measurement_std: Option<f64>,
    /// UKF: simulations per sigma point (their mean is the predicted feature).
    #[arg(long, value_name = "N", default_value_t = 8)]
    pub members: usize,
    /// UKF: the filter as first written (one simulation per sigma point, R from the recording,
    /// windows in order, symplectic Euler, the last half of the windows averaged).
    #[arg(long)]
    pub paper: bool,
    /// Fast: the learned model from `edgekf crank train` (default: the built-in one); a legacy
    /// impact-rate map (`impact_rate`, `clearance`; joint A only) is also accepted.
    #[arg(long, value_name = "TOML")]
    pub model: Option<PathBuf>,
    /// Estimate file to write.
    #[arg(long, value_name = "CSV")]
    pub out: PathBuf,
}

/// Arguments of `edgekf crank simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Configuration file (default: the paper's case, as in host-sim/configs/crank_paper.toml).
    #[arg(long, value_name = "TOML")]
    pub config: Option<PathBuf>,
    /// Radial clearance of a joint, JOINT=METRES (JOINT is A, B or C; 0 means ideal).
    /// Repeat for several joints; joints not named are ideal.
    #[arg(long = "clearance", value_name = "JOINT=M", value_parser = parse_clearance)]
    pub clearances: Vec<(Joint, f64)>,
    /// Simulated time, s.
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub duration: f64,
    /// Data file to write.
    #[arg(long, value_name = "CSV")]
    pub out: PathBuf,
    /// Seed of the sensor noise.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub seed: u64,
    /// Integrator (default: the configuration's, symplectic Euler in the paper's case).
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorArg>,
    /// Step of the symplectic Euler integrator, s (default: the configuration's).
    #[arg(long, value_name = "H")]
    pub step: Option<f64>,
    /// Relative tolerance of the adaptive integrator (default: the configuration's).
    #[arg(long, value_name = "TOL")]
    pub tolerance: Option<f64>,
}

/// Integrator choice on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum IntegratorArg {
    /// Symplectic Euler at a fixed step (the paper's).
    Symplectic,
    /// Dormand–Prince 5(4) with error control and located contact events.
    Adaptive,
}

/// Arguments of `edgekf crank feature`.
#[derive(Debug, Args)]
pub struct FeatureArgs {
    /// Data file to read.
    #[arg(long, value_name = "CSV")]
    pub data: PathBuf,
    /// Window length, s.
    #[arg(long, value_name = "S", default_value_t = 0.25)]
    pub window: f64,
    /// Column holding the crank angular acceleration.
    #[arg(long, value_name = "NAME", default_value = "crank_alpha")]
    pub column: String,
}

/// `JOINT=METRES`, e.g. `A=0.25e-3`.
fn parse_clearance(text: &str) -> Result<(Joint, f64), String> {
    let (joint, value) =
        text.split_once('=').ok_or_else(|| format!("`{text}`: expected JOINT=METRES, e.g. A=0.25e-3"))?;
    let joint: Joint = joint.trim().parse()?;
    let value: f64 =
        value.trim().parse().map_err(|_| format!("`{value}` is not a number (clearance in metres, e.g. 0.25e-3)"))?;
    if !(value.is_finite() && value >= 0.0) {
        return Err(format!("clearance {value} m must be a non-negative number"));
    }
    if value > 0.01 {
        return Err(format!("clearance {value} m is more than 1 cm: the value is in metres (0.25 mm = 0.25e-3)"));
    }
    Ok((joint, value))
}

/// Runs a `crank` command.
pub fn run(command: CrankCommand) -> anyhow::Result<()> {
    match command {
        CrankCommand::Simulate(args) => simulate(args),
        CrankCommand::Feature(args) => feature(args),
        CrankCommand::Estimate(args) => estimate(args),
        CrankCommand::Train(args) => train(args),
        CrankCommand::Export(args) => super::estimate::chip::export(args),
    }
}

fn describe_clearances(c: &[Option<f64>; 3]) -> String {
    Joint::ALL
        .iter()
        .map(|j| match c[j.index()] {
            Some(v) => format!("{j} {:.4} mm", v * 1e3),
            None => format!("{j} ideal"),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn simulate(args: SimulateArgs) -> anyhow::Result<()> {
    check(&[Some(&args.out)], &[args.config.as_deref()])?;
    let mut config = match &args.config {
        Some(path) => CrankConfig::load(path)?,
        None => CrankConfig::default(),
    };
    if let Some(step) = args.step {
        config.integrator.step = step;
    }
    if let Some(tol) = args.tolerance {
        config.integrator.tolerance = tol;
    }
    if let Some(i) = args.integrator {
        config.integrator.method = match i {
            IntegratorArg::Symplectic => super::config::Method::Symplectic,
            IntegratorArg::Adaptive => super::config::Method::Adaptive,
        };
    }
    config.validate().context("invalid --step or --tolerance")?;
    let mut clearances = [None; 3];
    let mut named = [false; 3];
    for (joint, c) in &args.clearances {
        let j = joint.index();
        if named[j] {
            anyhow::bail!("--clearance given twice for joint {joint}");
        }
        named[j] = true;
        clearances[j] = (*c > 0.0).then_some(*c);
    }
    let mech = Mechanism::new(&config, clearances)?;
    let mut opts = SimOptions::from_config(&config, args.duration);
    opts.seed = args.seed;
    let started = Instant::now();
    // Progress only for runs that take a while: at most one line per second of wall time.
    let mut last_shown = 0.0;
    let mut progress = |f: f64| {
        let elapsed = started.elapsed().as_secs_f64();
        if elapsed >= last_shown + 1.0 && f < 1.0 {
            last_shown = elapsed;
            eprintln!(
                "crank simulate: {:3.0} % ({:.2} of {} s simulated, {elapsed:.1} s elapsed)",
                f * 100.0,
                f * args.duration,
                args.duration,
            );
            let _ = std::io::stderr().flush();
        }
    };
    let rec = mech.simulate_with_progress(&opts, &mut progress)?;
    let wall = started.elapsed().as_secs_f64();
    // The data error already names its cause; flatten it so the cause is printed once.
    rec.write_csv(&args.out).map_err(|e| anyhow::anyhow!("{e}"))?;
    println!(
        "wrote {}: {} samples at {} Hz over {} s, seed {}",
        args.out.display(),
        rec.len(),
        opts.sample_rate,
        args.duration,
        opts.seed
    );
    print!("{}", summary(&mech, &rec, &opts.integrator, wall));
    Ok(())
}

/// The human-readable summary of a run.
pub fn summary(mech: &Mechanism, rec: &CrankRecording, integrator: &Integrator, wall_s: f64) -> String {
    let s = &rec.stats;
    let method = match integrator {
        Integrator::SymplecticEuler { step } => format!("symplectic Euler, step {step:e} s"),
        Integrator::Adaptive { tolerance, max_step } => {
            format!("adaptive Dormand–Prince 5(4), tolerance {tolerance:e}, max step {max_step:e} s")
        }
    };
    let mut out = format!("clearances: {}\n", describe_clearances(&mech.clearances()));
    out += &format!(
        "integrator: {method}: {} steps ({} rejected), {} evaluations, steps {:.3e}–{:.3e} s, wall {:.2} s\n",
        s.steps, s.rejected, s.evaluations, s.step_range.0, s.step_range.1, wall_s
    );
    for joint in Joint::ALL {
        let kind = if mech.clearance(joint).is_some() { "contact" } else { "pin reaction" };
        out += &format!(
            "joint {joint}: {} impacts, peak {kind} force {:.1} N\n",
            s.impacts[joint.index()],
            rec.peak_force(joint)
        );
    }
    let e0 = rec.truth_energy.first().copied().unwrap_or(0.0);
    let e1 = rec.truth_energy.last().copied().unwrap_or(0.0);
    let d1 = rec.truth_dissipated.last().copied().unwrap_or(0.0);
    out += &format!(
        "energy: start {e0:.6} J, end {e1:.6} J, dissipated {d1:.3e} J, balance error max {:.3e} J, largest climb {:.3e} J\n",
        rec.energy_balance_error(),
        rec.energy_rise()
    );
    out += &format!("constraints: largest residual {:.1e} m\n", rec.max_constraint_residual);
    let rms = (rec.truth_crank_alpha.iter().map(|v| v * v).sum::<f64>() / rec.len().max(1) as f64).sqrt();
    out += &format!(
        "crank: angle {:.2}° → {:.2}°, angular acceleration RMS {rms:.1} rad/s² (truth)\n",
        rec.truth_crank_angle.first().copied().unwrap_or(0.0).to_degrees(),
        rec.truth_crank_angle.last().copied().unwrap_or(0.0).to_degrees(),
    );
    out
}

fn feature(args: FeatureArgs) -> anyhow::Result<()> {
    let (file, report) = data::read(&args.data, &[args.column.as_str()])?;
    eprintln!("{}: {report}", args.data.display());
    // Lost rows are missing samples here too (not a shorter recording), and refused alike.
    let (file, bridged) = crate::io::timeline::bridge(&file, &report.timing, &Default::default());
    let x =
        file.column(&args.column).with_context(|| format!("{}: no column `{}`", args.data.display(), args.column))?;
    let first_missing = x.iter().position(|v| !v.is_finite()).map(|k| file.t[k]);
    // A gap too long to bridge: its samples are missing from one period after the row before.
    let unbridged = bridged.restarts.first().and_then(|r| file.t.get(r.row.checked_sub(1)?));
    let unbridged = unbridged.map(|t| t + report.timing.dt_median);
    if let Some(t) = first_missing.into_iter().chain(unbridged).reduce(f64::min) {
        anyhow::bail!(
            "{}: column `{}` has sample(s) missing from t = {t:.6} s (rows lost from the time column or empty cells); \
             the spectrum needs every sample",
            args.data.display(),
            args.column
        );
    }
    let rate = report.timing.sample_rate;
    let feats = window_features(x, rate, args.window);
    if feats.is_empty() {
        anyhow::bail!("{}: shorter than one {} s window", args.data.display(), args.window);
    }
    println!(
        "{}: spectral feature of `{}`, {} s windows at {rate:.1} Hz",
        args.data.display(),
        args.column,
        args.window
    );
    println!("{:>8} {:>10} {:>14} {:>14}", "window", "t0 [s]", "a", "b [1/Hz]");
    let mut a_values = Vec::new();
    for (i, f) in feats.iter().enumerate() {
        let t0 = file.t[0] + i as f64 * args.window;
        match f {
            Some(f) => {
                println!("{i:>8} {t0:>10.3} {:>14.6} {:>14.6e}", f.a, f.b);
                a_values.push(f.a);
            }
            None => println!("{i:>8} {t0:>10.3} {:>14} {:>14}", "—", "—"),
        }
    }
    let n = a_values.len() as f64;
    if n > 0.0 {
        let mean = a_values.iter().sum::<f64>() / n;
        let std = (a_values.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
        println!("a: mean {mean:.6}, std {std:.6} over {} window(s)", a_values.len());
    }
    Ok(())
}

fn estimate(args: EstimateArgs) -> anyhow::Result<()> {
    use super::estimate::{self, ukf, Recording};
    check(&[Some(&args.out)], &[Some(&args.data), args.config.as_deref(), args.model.as_deref()])?;
    let config = match &args.config {
        Some(path) => CrankConfig::load(path)?,
        None => CrankConfig::default(),
    };
    let (rec, notes) = Recording::read(&args.data, &config.timeline)?;
    for line in notes {
        eprintln!("{line}");
    }
    let on_data = |e: anyhow::Error| e.context(args.data.display().to_string());
    let truth = rec.truth_clearance.map(|c| describe_clearances(&c.map(|v| (v > 0.0).then_some(v))));
    let started = Instant::now();
    let rows = match args.method {
        MethodArg::Ukf => {
            if !(args.initial.is_finite() && args.initial > 0.0 && args.initial < 0.01) {
                anyhow::bail!("--initial {} m must be a clearance in metres (0.1 mm = 0.1e-3)", args.initial);
            }
            let base = if args.paper { ukf::UkfOptions::paper() } else { ukf::UkfOptions::default() };
            if args.members == 0 {
                anyhow::bail!("--members must be at least 1");
            }
            let opts = ukf::UkfOptions {
                initial: args.initial,
                window: args.window,
                measurement_std: args.measurement_std,
                members: if args.paper { base.members } else { args.members },
                ..base
            };
            let mut progress = |k: usize, s: &ukf::UkfStep| {
                eprintln!(
                    "window {k:>3} (t {:.2} s): a measured {:>8} predicted {:7.1}, sigma {:.4}/{:.4}/{:.4} mm → A {:.4} ± {:.4} mm",
                    s.t,
                    s.measured.map_or("—".to_string(), |a| format!("{a:.1}")),
                    s.predicted,
                    s.sigma[0] * 1e3,
                    s.sigma[1] * 1e3,
                    s.sigma[2] * 1e3,
                    s.clearance * 1e3,
                    s.std * 1e3
                );
            };
            let run = ukf::run(&config, &rec, &opts, &mut progress).map_err(|e| match e {
                CrankError::Data(_) => on_data(e.into()),
                e => e.into(),
            })?;
            println!(
                "ukf: {} windows of {} s, R std {:.1} rad/s², {} simulations, {} integration steps, wall {:.2} s",
                run.steps.len(),
                args.window,
                run.measurement_std,
                run.simulations,
                run.integration_steps,
                started.elapsed().as_secs_f64()
            );
            println!(
                "estimate: A {:.4} ± {:.4} mm (last window {:.4} mm){}",
                run.estimate * 1e3,
                run.estimate_std * 1e3,
                run.steps.last().map_or(f64::NAN, |s| s.clearance) * 1e3,
                truth.map_or(String::new(), |t| format!("; truth: {t}"))
            );
            run.rows()
        }
        MethodArg::Fast => {
            let model = match &args.model {
                Some(path) => match estimate::model::FastModel::load(path) {
                    Ok(m) => Some(m),
                    Err(e) => match estimate::fast::FeatureMap::load(path) {
                        Ok(map) => {
                            let est = map.estimate(&rec).map_err(on_data)?;
                            println!(
                                "fast (legacy impact-rate map, joint A): {} windows, {} feature operations",
                                est.windows, est.operations
                            );
                            println!(
                                "estimate: {}{}",
                                describe_clearances(&est.clearance.map(|v| (v > 0.0).then_some(v))),
                                truth.clone().map_or(String::new(), |t| format!("; truth: {t}"))
                            );
                            let rows = est.rows(&rec);
                            estimate::write_estimates(&args.out, &rows).map_err(|e| anyhow::anyhow!("{e}"))?;
                            println!("wrote {}: {} rows", args.out.display(), rows.len());
                            return Ok(());
                        }
                        Err(_) => return Err(e),
                    },
                },
                None => Some(estimate::model::FastModel::builtin()),
            };
            let model = model.expect("set above");
            if let Some(t) = &model.trained_for {
                for w in t.check(&config).map_err(anyhow::Error::msg)? {
                    eprintln!("warning: {w}");
                }
            }
            let est = model.estimate(&rec).map_err(on_data)?;
            println!(
                "fast: {} windows, {} operations, wall {:.3} s; joint scores A {:.2}, B {:.2}, C {:.2}{}",
                est.features.windows,
                est.operations,
                started.elapsed().as_secs_f64(),
                est.scores[0],
                est.scores[1],
                est.scores[2],
                match rec.missing() {
                    0 => String::new(),
                    m => format!("; {m} missing sample(s) skipped, their time counted by the release stage"),
                }
            );
            let features_only = est.per_joint[est.joint.index()] * 1e3;
            match (est.features.release, est.release) {
                (Some(r), Some(h)) => println!(
                    "release: first contact seen at {:.1} ms, crank acceleration before it {:.1} rad/s²; taken as contact {} after release: {} {:.4} mm (window features alone {features_only:.4} mm)",
                    r.contact * 1e3,
                    r.release_alpha,
                    h + 1,
                    est.joint,
                    est.clearance[est.joint.index()] * 1e3
                ),
                (Some(r), None) => println!(
                    "release: first contact seen at {:.1} ms, crank acceleration before it {:.1} rad/s²; no release law fits it, so the window features give the clearance ({features_only:.4} mm)",
                    r.contact * 1e3,
                    r.release_alpha
                ),
                (None, _) => println!(
                    "release: no contact seen in the first {} s; the window features give the clearance ({features_only:.4} mm)",
                    estimate::release::RELEASE_SPAN
                ),
            }
            println!(
                "estimate: joint {}: {}{}",
                est.joint,
                describe_clearances(&est.clearance.map(|v| (v > 0.0).then_some(v))),
                truth.map_or(String::new(), |t| format!("; truth: {t}"))
            );
            model.rows(&rec, &est)?
        }
    };
    estimate::write_estimates(&args.out, &rows).map_err(|e| anyhow::anyhow!("{e}"))?;
    println!("wrote {}: {} rows", args.out.display(), rows.len());
    Ok(())
}

fn train(args: TrainArgs) -> anyhow::Result<()> {
    use super::estimate::training::{self, TrainPlan};
    let test_features = args.save_features.as_ref().map(|p| p.with_extension("test.csv"));
    let inputs = [args.config.as_deref(), args.load_features.as_deref(), args.load_test_features.as_deref()];
    check(&[Some(&args.out), args.save_features.as_deref(), test_features.as_deref()], &inputs)?;
    let config = match &args.config {
        Some(path) => CrankConfig::load(path)?,
        None => CrankConfig::default(),
    };
    let plan = TrainPlan {
        clearances: args.clearances,
        variants: args.variants,
        duration: args.duration,
        threads: args.threads,
        ridge: args.ridge,
        seed_base: args.seed_base,
        squares: !args.linear,
        release_variants: args.release_variants,
        release_seed_base: args.release_seed_base,
        max_step: args.max_step,
        test_variants: args.test_variants,
        test_seed_base: args.test_seed_base,
        test_clearances: args.test_clearances,
        save_features: args.save_features,
        load_features: args.load_features,
        load_test_features: args.load_test_features,
    };
    plan.validate()?;
    let started = Instant::now();
    let progress = |line: String| eprintln!("crank train: {line} ({:.0} s elapsed)", started.elapsed().as_secs_f64());
    let trained = training::train(&config, &plan, &progress)?;
    let s = trained.training;
    println!(
        "training set: joint right in {:.1} % of {} runs; clearance error RMS {:.1} %, worst {:.1} %",
        s.joint_right * 100.0,
        s.runs,
        s.rms * 100.0,
        s.worst * 100.0
    );
    let model = trained.model;
    crate::io::output::write_atomic(&args.out, model.to_toml())
        .with_context(|| format!("{}: cannot write", args.out.display()))?;
    println!("wrote {}", args.out.display());
    if let Some(tested) = training::test(&config, &model, &plan)? {
        for (r, f) in &tested.runs {
            let e = model.estimate_features(*f);
            println!(
                "test {} {:.3} mm (release {:.1}°, radius ×{:.2}, seed {}): named {} {:.4} mm ({:+.1} %; first stage {:+.1} %{})",
                r.joint,
                r.clearance * 1e3,
                r.release_deg,
                r.radius,
                r.seed,
                e.joint,
                e.clearance[e.joint.index()] * 1e3,
                (e.clearance[e.joint.index()] / r.clearance - 1.0) * 100.0,
                (e.per_joint[r.joint.index()] / r.clearance - 1.0) * 100.0,
                match e.release {
                    Some(h) => format!(", release law {}", ["first contact", "second contact", "third contact", "fourth contact"][h.min(3)]),
                    None => String::new(),
                }
            );
        }
        let s = tested.score;
        println!(
            "test set (unseen seeds and draws): joint right in {:.1} % of {} runs; clearance error RMS {:.1} %, worst {:.1} %, within ±3 % in {}",
            s.joint_right * 100.0,
            s.runs,
            s.rms * 100.0,
            s.worst * 100.0,
            tested.within_3_percent
        );
    }
    println!("wall {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}

/// The crank's part of `edgekf demo`: a loose joint named and sized by the node's estimator;
/// `--out DIR` writes `crank/data.csv` and `crank/est.csv`.
pub fn demo(args: &crate::cli::request::DemoArgs) -> anyhow::Result<()> {
    use super::demo::CrankDemo;
    println!("{}", CrankDemo::describe());
    if let Some(dir) = &args.out {
        check_folder(dir, &["crank/data.csv", "crank/est.csv"], &[args.config.as_deref()])?;
    }
    let crank = CrankDemo::run()?;
    print!("{}", crank.summary());
    if let Some(dir) = &args.out {
        let dir = dir.join("crank");
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        crank.recording.write_csv(&dir.join("data.csv"))?;
        super::estimate::write_estimates(&dir.join("est.csv"), &crank.rows)?;
        println!("wrote {0}/data.csv and {0}/est.csv", dir.display());
    }
    Ok(())
}
