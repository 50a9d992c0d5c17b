//! `edgekf boom …`: the boom's commands.
//!
//! ```text
//! edgekf boom simulate [--config C] --scenario luffing|extension [--duration 120] [--seed 1]
//!                      --out data.csv [--static static.csv]
//! ```

use super::config::BoomConfig;
use super::runs::Scenario;
use super::simulate::{simulate, static_record, SimOptions};
use crate::io::output::{check, write_atomic};
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
    Simulate(SimulateArgs),
}

/// Arguments of `edgekf boom simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Configuration (default: host-sim/configs/boom_ladder30.toml).
    #[arg(long, value_name = "TOML")]
    pub config: Option<PathBuf>,
    /// The run.
    #[arg(long, value_enum)]
    pub scenario: Scenario,
    /// Length, s.
    #[arg(long, value_name = "S", default_value_t = 120.0)]
    pub duration: f64,
    /// Seed of the sensors' noise.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub seed: u64,
    /// Data file to write.
    #[arg(long, value_name = "CSV")]
    pub out: PathBuf,
    /// Also write 60 s of the gyro with the boom at rest (t, gyro_rate): the static record.
    #[arg(long = "static", value_name = "CSV")]
    pub static_out: Option<PathBuf>,
}

/// Runs one `edgekf boom` command.
pub fn run(command: BoomCommand) -> anyhow::Result<()> {
    match command {
        BoomCommand::Simulate(args) => simulate_command(args),
    }
}

fn load(path: Option<&std::path::Path>) -> anyhow::Result<BoomConfig> {
    match path {
        Some(p) => BoomConfig::load(p),
        None => Ok(BoomConfig::default()),
    }
}

fn simulate_command(args: SimulateArgs) -> anyhow::Result<()> {
    check(&[Some(args.out.as_path()), args.static_out.as_deref()], &[args.config.as_deref()])?;
    if args.static_out.as_ref() == Some(&args.out) {
        anyhow::bail!("{}: --out and --static are the same file", args.out.display());
    }
    let config = load(args.config.as_deref())?;
    let options = SimOptions { scenario: args.scenario, duration: args.duration, seed: args.seed };
    let rec = simulate(&config, &options, &mut |t| eprintln!("simulated {t:.0} s of {:.0} s", args.duration))?;
    let text = rec.to_csv(&args.out)?;
    let statics = match &args.static_out {
        Some(path) => {
            let (t, gyro) = static_record(&config, STATIC_S, args.seed)?;
            Some((path, crate::io::data::to_csv_string(path, &["gyro_rate"], &t, &[&gyro])?))
        }
        None => None,
    };
    write_atomic(&args.out, text).with_context(|| format!("cannot write {}", args.out.display()))?;
    let vib = rec.column("truth_tip_vibration").unwrap_or_default();
    let peak = vib.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    println!(
        "{}: {} rows at {} Hz, run {}, seed {}; largest tip vibration {peak:.3} m",
        args.out.display(),
        rec.t.len(),
        config.gyro.sample_rate,
        args.scenario.name(),
        args.seed
    );
    if let Some((path, text)) = statics {
        write_atomic(path, text).with_context(|| format!("cannot write {}", path.display()))?;
        println!("{}: {STATIC_S:.0} s of the gyro at rest", path.display());
    }
    Ok(())
}
