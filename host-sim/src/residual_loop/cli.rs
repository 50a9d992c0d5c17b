//! `edgekf loop rotor --config C --data data.csv --report DIR`.

use super::rotor_system::close_loop;
use super::search::{LoopOptions, LoopReport, RunSummary};
use crate::io::data;
use crate::rotor::{RotorConfig, RotorModel};
use anyhow::{bail, Context, Result};
use clap::Subcommand;
use std::path::{Path, PathBuf};

/// `edgekf loop …`.
#[derive(Debug, Subcommand)]
pub enum LoopCommand {
    /// Rotor: run the virtual-sensing filter on a data file, read its innovations, add the
    /// effects the data asks for (sensor bias, scale or delay; a force at k× the running speed;
    /// a wrong disk, shaft or bearing parameter; an extra mode; a bearing defect line; an unknown
    /// input) and that pay for their parameters (BIC) in both halves of the run, and report
    /// before/after (report.json, report.html).
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
        /// Do not print each candidate as it is tried.
        #[arg(long)]
        quiet: bool,
        /// Read the running speed from the data, within this fraction of the configured
        /// (nominal) speed (default 0.1 when given without a value): for a motor that slips.
        #[arg(long, value_name = "FRACTION", num_args = 0..=1, default_missing_value = "0.1")]
        estimate_speed: Option<f64>,
    },
}

/// Runs a `loop` command.
pub fn run(command: LoopCommand) -> Result<()> {
    match command {
        LoopCommand::Rotor { config, data, report, max_effects, quiet, estimate_speed } => {
            let options =
                LoopOptions { max_effects, progress: !quiet, speed_band: estimate_speed, ..LoopOptions::default() };
            rotor(&config, &data, &report, &options)
        }
    }
}

fn rotor(config: &Path, data_path: &Path, dir: &Path, options: &LoopOptions) -> Result<()> {
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
    let report = close_loop(&model, &file, options)?;
    print!("{}", summary_table(&report));
    write_report(&report, dir)?;
    println!("wrote {0}/report.json and {0}/report.html", dir.display());
    Ok(())
}

/// Writes `dir/report.json` and `dir/report.html`, creating `dir` if needed.
pub fn write_report(report: &LoopReport, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join("report.json");
    std::fs::write(&path, serde_json::to_string_pretty(report)?)
        .with_context(|| format!("writing {}", path.display()))?;
    let path = dir.join("report.html");
    std::fs::write(&path, super::html::render(report)?).with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// The summary the CLI prints: effects, then a before/after table.
pub fn summary_table(r: &LoopReport) -> String {
    let mut s = String::new();
    s.push_str(&format!("{}: {} effect(s) added; {}\n", r.system, r.effects_added.len(), r.stopped));
    if let Some(sp) = &r.running_speed {
        s.push_str(&format!("  running speed {}\n", super::html::speed_text(sp)));
    }
    for e in &r.effects_added {
        let order = e.order.map(|o| format!(" at {o}x")).unwrap_or_default();
        let what = e.parameter.as_ref().or(e.line.as_ref()).map(|p| format!(" {p}")).unwrap_or_default();
        s.push_str(&format!(
            "  + {}{} at {}{}: {} (Δ log-likelihood {:.1}, BIC cost {:.1})\n",
            e.kind,
            order,
            e.location,
            what,
            show_value(e.value, &e.unit),
            e.delta_log_likelihood,
            e.bic_penalty
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
        let (scale, unit) = super::html::channel_unit(k);
        s.push_str(&row(&format!("innovation RMS {k} {unit}"), &|x| {
            let v = x.innovation_rms[k] * scale;
            if unit == "µm" {
                format!("{v:.3}")
            } else {
                format!("{v:.3e}")
            }
        }));
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

/// A value with its unit as people read it: factors as `×1.0500 (+5.00 %)`, metres in µm,
/// seconds in ms.
pub fn show_value(v: f64, unit: &str) -> String {
    match unit {
        "1" => format!("×{v:.4} ({:+.2} %)", (v - 1.0) * 100.0),
        "m" => format!("{:.3} µm", v * 1e6),
        "s" => format!("{:.3} ms", v * 1e3),
        _ => format!("{v:.4} {unit}"),
    }
}
