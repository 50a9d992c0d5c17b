//! `edgekf sdof …`: simulate the mount, estimate its relative motion.

use super::estimate::{self, rms_error, CHANNEL, KNOWN};
use super::sim::{simulate, SimOptions};
use crate::io::output::check;
use crate::report::summary::{EstimateSummary, Prose, Quantity};
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
        /// Print one JSON object on stdout (the text goes to stderr): the displacement's and
        /// the velocity's statistics and RMS errors after settling.
        #[arg(long)]
        json: bool,
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
        SdofCommand::Estimate { data, out, precision, json } => {
            let prose = Prose { json };
            check(&[Some(&out)], &[Some(&data)])?;
            let (file, restarts) =
                crate::io::recording::read_estimator_data(&data, &[CHANNEL], &KNOWN, params.sample_rate_hz)?;
            let est = match precision {
                Precision::F64 => estimate::run::<f64>(&file, &params, &restarts),
                Precision::F32 => estimate::run::<f32>(&file, &params, &restarts),
            }
            .with_context(|| format!("{}: cannot estimate", data.display()))?;
            let c = est.counters;
            prose.say(format_args!(
                "{}: {} samples, {} missing, {} refused, {} covariance resets, {} restarts",
                data.display(),
                c.steps,
                c.missing,
                c.filter.refused_updates,
                c.filter.covariance_resets,
                restarts.len()
            ));
            let from = (SETTLE_S * params.sample_rate_hz) as usize;
            let mut summary = EstimateSummary::new("sdof", &data, None, &file.t);
            for (name, unit, estimate) in [("displacement", "m", &est.displacement), ("velocity", "m/s", &est.velocity)]
            {
                let mut q = Quantity::of(unit, estimate).map(Quantity::without_final);
                if let Some(truth) = file.column(&format!("truth_{name}")) {
                    let (e, t) = rms_error(estimate, truth, from);
                    prose.say(format_args!(
                        "  {name}: RMS error {e:.3e} ({:.3} % of the truth's RMS {t:.3e})",
                        100.0 * e / t
                    ));
                    q = q.map(|q| q.with_error("rms", e).with_error("rms_pct", 100.0 * e / t));
                }
                summary.quantity(name, q);
            }
            est.write(&out)?;
            prose.say(format_args!("wrote {}", out.display()));
            if json {
                summary.detail("settle_s", SETTLE_S);
                summary.out = Some(out);
                summary.print()?;
            }
            Ok(())
        }
    }
}
