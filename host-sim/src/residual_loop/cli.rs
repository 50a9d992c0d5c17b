//! `edgekf loop rotor --config C --data data.csv --report DIR`.

use super::search::{close_loop, LoopOptions, LoopReport, RunSummary};
use crate::io::data;
use crate::rotor::{RotorConfig, RotorModel};
use anyhow::{bail, Context, Result};
use clap::Subcommand;
use std::path::{Path, PathBuf};

/// `edgekf loop …`.
#[derive(Debug, Subcommand)]
pub enum LoopCommand {
    /// Rotor: run the virtual-sensing filter on a data file, read its innovations, add the
    /// effects (sensor bias, harmonic force at k× running speed) that the data asks for and
    /// that pay for their parameters (BIC), and report before/after.
    Rotor {
        /// Rotor configuration (model, sensors, unbalance nodes, speed, sample rate).
        #[arg(long, value_name = "TOML")]
        config: PathBuf,
        /// Data file (channels named like the configured sensors; `truth_` columns optional).
        #[arg(long, value_name = "CSV")]
        data: PathBuf,
        /// Directory for report.json.
        #[arg(long, value_name = "DIR")]
        report: PathBuf,
        /// At most this many effects.
        #[arg(long, value_name = "N", default_value_t = 4)]
        max_effects: usize,
    },
}

/// Runs a `loop` command.
pub fn run(command: LoopCommand) -> Result<()> {
    match command {
        LoopCommand::Rotor { config, data, report, max_effects } => rotor(&config, &data, &report, max_effects),
    }
}

fn rotor(config: &Path, data_path: &Path, dir: &Path, max_effects: usize) -> Result<()> {
    let cfg = RotorConfig::load(config).with_context(|| format!("{}: cannot load the rotor", config.display()))?;
    let model = RotorModel::from_config(&cfg)?;
    let channels: Vec<String> = cfg.sensors.iter().map(|s| s.channel_name()).collect();
    let known: Vec<&str> = channels.iter().map(String::as_str).collect();
    let (file, notes) = data::read(data_path, &known)?;
    eprintln!("{}: {notes}", data_path.display());
    let rate = cfg.operation.sample_rate;
    if (notes.timing.sample_rate - rate).abs() > 0.01 * rate {
        bail!(
            "{}: sampled at {:.3} Hz, the configuration says {rate} Hz",
            data_path.display(),
            notes.timing.sample_rate
        );
    }
    let report = close_loop(&model, &file, &LoopOptions { max_effects, ..LoopOptions::default() })?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join("report.json");
    std::fs::write(&path, serde_json::to_string_pretty(&report)?)
        .with_context(|| format!("writing {}", path.display()))?;
    print!("{}", summary_table(&report));
    println!("wrote {}", path.display());
    Ok(())
}

/// The summary the CLI prints: effects, then a before/after table.
pub fn summary_table(r: &LoopReport) -> String {
    let mut s = String::new();
    s.push_str(&format!("{}: {} effect(s) added; {}\n", r.system, r.effects_added.len(), r.stopped));
    for e in &r.effects_added {
        let order = e.order.map(|o| format!(" at {o}x")).unwrap_or_default();
        let what = e.parameter.as_ref().or(e.line.as_ref()).map(|p| format!(" {p}")).unwrap_or_default();
        s.push_str(&format!(
            "  + {}{} at {}{}: {:.4e} {} (Δ log-likelihood {:.1}, BIC cost {:.1})\n",
            e.kind, order, e.location, what, e.value, e.unit, e.delta_log_likelihood, e.bic_penalty
        ));
    }
    let row = |name: &str, f: &dyn Fn(&RunSummary) -> String| {
        format!("  {name:<28} {:>14} {:>14}\n", f(&r.before), f(&r.after))
    };
    s.push_str(&format!("  {:<28} {:>14} {:>14}\n", "", "before", "after"));
    s.push_str(&row("log-likelihood", &|x| format!("{:.1}", x.log_likelihood)));
    s.push_str(&row("NIS mean / channel", &|x| format!("{:.3}", x.nis_mean)));
    s.push_str(&row("whiteness p (min)", &|x| format!("{:.2e}", x.whiteness_p)));
    for k in r.before.innovation_rms.keys() {
        s.push_str(&row(&format!("innovation RMS {k} µm"), &|x| format!("{:.3}", x.innovation_rms[k] * 1e6)));
    }
    for k in r.before.error_rms.keys() {
        s.push_str(&row(&format!("error RMS {k} µm"), &|x| {
            x.error_rms.get(k).map_or("-".into(), |v| format!("{:.3}", v * 1e6))
        }));
    }
    for u in &r.not_identifiable {
        let what = u.parameter.as_ref().map(|p| format!(" {p}")).unwrap_or_default();
        s.push_str(&format!("  not identifiable: {} {}{}: {}\n", u.kind, u.location, what, u.reason));
    }
    for u in &r.unexplained {
        s.push_str(&format!("  unexplained: {}: {}\n", u.channel, u.description));
    }
    s
}
