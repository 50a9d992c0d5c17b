//! The arguments of the `crank` commands, as clap reads them.

use super::super::Joint;
use crate::cli::request::{EstimateFiles, SimulateFiles};
use clap::{Args, ValueEnum};
use std::path::PathBuf;

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
    /// `--config`, `--data`, `--out`, `--json` (their help: [`CrankCommand::Estimate`](super::CrankCommand::Estimate)'s).
    #[command(flatten)]
    pub files: EstimateFiles,
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
}

/// Arguments of `edgekf crank simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// `--config`, `--out`, `--seed` (their help: [`CrankCommand::Simulate`](super::CrankCommand::Simulate)'s).
    #[command(flatten)]
    pub files: SimulateFiles,
    /// Radial clearance of a joint, JOINT=METRES (JOINT is A, B or C; 0 means ideal).
    /// Repeat for several joints; joints not named are ideal.
    #[arg(long = "clearance", value_name = "JOINT=M", value_parser = parse_clearance)]
    pub clearances: Vec<(Joint, f64)>,
    /// Simulated time, s.
    #[arg(long, value_name = "S", allow_hyphen_values = true, value_parser = crate::cli::values::positive_seconds)]
    pub duration: f64,
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
