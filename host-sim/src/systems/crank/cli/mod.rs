//! `edgekf crank …`: the slider-crank commands of the `edgekf` binary.
//!
//! ```text
//! edgekf crank simulate [--config C] [--clearance A=0.25e-3]… --duration S --out data.csv
//!                       [--seed N] [--integrator symplectic|adaptive] [--step H] [--tolerance TOL]
//! edgekf crank feature  --data data.csv [--window 0.25] [--column crank_alpha]
//! edgekf crank estimate --data data.csv --method ukf|fast [--config C] [--initial 0.1e-3]
//!                       [--window 0.25] [--model model.toml] --out est.csv [--json]
//! edgekf crank train    --out model.toml [--config C] [--clearances 0.08e-3,…] [--variants 8]
//!                       [--duration 10] [--threads 2] [--ridge 1e-4] [--linear] [--seed-base 1000]
//!                       [--test-variants 0] [--test-seed-base 900000] [--test-clearances …]
//!                       [--save-features F.csv] [--load-features F.csv] [--load-test-features T.csv]
//! ```

mod args;
mod estimate;
mod feature;
mod simulate;
mod train;

pub use args::{EstimateArgs, FeatureArgs, IntegratorArg, MethodArg, SimulateArgs, TrainArgs};
pub use simulate::summary;

use super::{CrankConfig, Joint};
use crate::io::output::check_folder;
use anyhow::Context as _;
use clap::Subcommand;
use std::path::Path;

/// Planar slider-crank with revolute clearance joints (the clearance paper's mechanism).
#[derive(Debug, Subcommand)]
pub enum CrankCommand {
    /// Simulate the mechanism falling from rest under gravity into a data CSV.
    ///
    /// Columns: t, crank_alpha (measured, rad/s²), truth_crank_alpha, truth_crank_angle,
    /// truth_crank_rate, truth_slider_x, truth_contact_force_A/B/C (N), truth_eccentricity_A/B/C,
    /// truth_clearance_A/B/C (m, 0 = ideal joint), truth_energy, truth_dissipated,
    /// truth_balance (J). A summary goes to stdout, progress to stderr.
    #[command(mut_arg("config", |a| a.help(
        "Configuration file (default: the paper's case, as in host-sim/configs/crank_paper.toml)"
    )))]
    Simulate(SimulateArgs),
    /// Print the spectral clearance feature (fit y = a·e^(b·f) of the FFT amplitude) of each
    /// window of a data CSV.
    Feature(FeatureArgs),
    /// Estimate the clearance from a recording's crank angular acceleration into an estimate
    /// CSV (t, clearance_A, clearance_B, clearance_C in m, 0 = tight; one row per window, the
    /// last row the estimate for the whole recording).
    #[command(mut_arg("config", |a| a.help(
        "Configuration file of the mechanism (default: the paper's case); its `[timeline] max_gap_s` (default 2 s) \
         is the longest gap in `t` bridged: the recording ends at a longer one"
    )))]
    #[command(mut_arg("data", |a| a.help(
        "Data file with `t` and `crank_alpha` (rad/s²). Rows lost from `t` are missing samples, like empty cells: \
         `fast` steps through them, `ukf` and a legacy `--model` map refuse them"
    )))]
    #[command(mut_arg("json", |a| a.help(
        "Print one JSON object on stdout (the text goes to stderr): per joint the clearance's statistics over the \
         windows, its final value and its error against the truth"
    )))]
    Estimate(EstimateArgs),
    /// Learn the fast estimator's model (joint discriminant and per-joint clearance regression)
    /// from simulated runs, and write it as TOML (`--model` of `estimate --method fast`; the
    /// built-in model is host-sim/src/systems/crank/estimate/fast_model.toml, written by this command
    /// with its defaults).
    Train(TrainArgs),
    /// Write the fast estimator's model as Rust constants for the firmware
    /// (firmware/src/systems/crank/generated/clearance.rs).
    Export(super::estimate::chip::ExportArgs),
}

/// Runs a `crank` command.
pub fn run(command: CrankCommand) -> anyhow::Result<()> {
    match command {
        CrankCommand::Simulate(args) => simulate::simulate(args),
        CrankCommand::Feature(args) => feature::feature(args),
        CrankCommand::Estimate(args) => estimate::estimate(args),
        CrankCommand::Train(args) => train::train(args),
        CrankCommand::Export(args) => super::estimate::chip::export(args),
    }
}

/// How a recording's clearances read: `A 0.2500 mm, B ideal, C ideal`.
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

/// `--config`'s mechanism, or the paper's when none is given.
fn load_config(path: Option<&Path>) -> anyhow::Result<CrankConfig> {
    Ok(match path {
        Some(path) => CrankConfig::load(path)?,
        None => CrankConfig::default(),
    })
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
