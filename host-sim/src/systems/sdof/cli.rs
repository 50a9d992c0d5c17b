//! `edgekf sdof …`: simulate the mount, estimate its relative motion.

use super::estimate::{self, rms_error, CHANNEL, KNOWN};
use super::sim::{simulate, SimOptions};
use crate::io::output::check;
use anyhow::Context as _;
use clap::{Subcommand, ValueEnum};
use edgekf::systems::sdof::SdofParams;
use std::path::PathBuf;

/// The `edgekf sdof` subcommands.
#[derive(Debug, Subcommand)]
pub enum SdofCommand {
    /// Simulate the default mount on a randomly shaken base into a data CSV.
    ///
    /// Columns: t, ax, ay, az, truth_displacement, truth_velocity, truth_accel,
    /// truth_base_accel.
    Simulate {
        /// Data file to write.
        #[arg(long, value_name = "CSV")]
        out: PathBuf,
        /// Length of the run, s.
        #[arg(long, value_name = "S", default_value_t = 20.0)]
        duration: f64,
        /// Seed of the base motion and the sensor's noise.
        #[arg(long, value_name = "N", default_value_t = 1)]
        seed: u64,
    },
    /// Estimate the mount's relative displacement and velocity from the `ax` column.
    ///
    /// The file must be sampled at 1 kHz. Empty or NaN cells are missing samples, bridged by
    /// prediction; a gap too long to bridge restarts the filter. With truth columns the RMS
    /// errors are printed.
    Estimate {
        /// Data file to read.
        #[arg(long, value_name = "CSV")]
        data: PathBuf,
        /// Write the estimates here: t, displacement, velocity, innovation, nis.
        #[arg(long, value_name = "CSV")]
        out: PathBuf,
        /// Arithmetic of the filter: f32 as on the sensor node, f64 as a reference.
        #[arg(long, value_enum, default_value_t = Precision::F64)]
        precision: Precision,
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

/// Seconds before errors are counted: the filter's start from rest and the simulated mount's
/// own start-up (its decay time `1/(ζωn)` is 0.32 s).
pub const SETTLE_S: f64 = 1.0;

/// Runs an `edgekf sdof` command.
pub fn run(command: SdofCommand) -> anyhow::Result<()> {
    let params = SdofParams::default();
    match command {
        SdofCommand::Simulate { out, duration, seed } => {
            check(&[Some(&out)], &[])?;
            let rec = simulate(&params, &SimOptions { duration, seed })?;
            rec.write(&out)?;
            println!(
                "wrote {}: {} samples of a {} Hz mount (ζ = {}) on a base of {} (m/s²)²/Hz, seed {seed}",
                out.display(),
                rec.t.len(),
                params.natural_freq_hz,
                params.damping_ratio,
                params.base_psd
            );
            Ok(())
        }
        SdofCommand::Estimate { data, out, precision } => {
            check(&[Some(&out)], &[Some(&data)])?;
            let (file, restarts) =
                crate::io::recording::read_estimator_data(&data, &[CHANNEL], &KNOWN, params.sample_rate_hz)?;
            let est = match precision {
                Precision::F64 => estimate::run::<f64>(&file, &params, &restarts),
                Precision::F32 => estimate::run::<f32>(&file, &params, &restarts),
            }
            .with_context(|| format!("{}: cannot estimate", data.display()))?;
            let c = est.counters;
            println!(
                "{}: {} samples, {} missing, {} refused, {} covariance resets, {} restarts",
                data.display(),
                c.steps,
                c.missing,
                c.filter.refused_updates,
                c.filter.covariance_resets,
                restarts.len()
            );
            let from = (SETTLE_S * params.sample_rate_hz) as usize;
            for (name, estimate) in [("displacement", &est.displacement), ("velocity", &est.velocity)] {
                if let Some(truth) = file.column(&format!("truth_{name}")) {
                    let (e, t) = rms_error(estimate, truth, from);
                    println!("  {name}: RMS error {e:.3e} ({:.3} % of the truth's RMS {t:.3e})", 100.0 * e / t);
                }
            }
            est.write(&out)?;
            println!("wrote {}", out.display());
            Ok(())
        }
    }
}
