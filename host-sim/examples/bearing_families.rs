//! The bearing diagnosis by fault family ([`family`](edgekf_sim::diagnostics::bearings::family))
//! on recordings given on the command line, with the bearings of a rotor configuration: FFTs
//! only, no filter, a fraction of a second per record.
//!
//! ```sh
//! cargo run --release -p edgekf-sim --example bearing_families -- \
//!     [--config host-sim/configs/rotor_cwru.toml] [--per-channel] 105.csv 130.csv …
//! ```
//!
//! Each CSV has a time column `t` and one column per channel; every column but `t` is read.
//! Prints, per record (and per channel with `--per-channel`): the refined speed, the verdict
//! (the family named first, its rival when they cannot be told apart, or nothing), and the
//! members' strengths of the first two families.

use anyhow::{anyhow, Context, Result};
use edgekf_sim::diagnostics::bearings::family::{diagnose, BearingSpec, Diagnosis, FamilyFit, Verdict};
use edgekf_sim::systems::rotor::RotorConfig;
use std::path::Path;

/// Named columns.
type Channels = Vec<(String, Vec<f64>)>;

/// The sample rate and every column but `t` of a CSV.
fn read_csv(path: &Path) -> Result<(f64, Channels)> {
    let mut rdr = csv::Reader::from_path(path).with_context(|| path.display().to_string())?;
    let headers: Vec<String> = rdr.headers()?.iter().map(str::to_string).collect();
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); headers.len()];
    for rec in rdr.records() {
        for (c, v) in cols.iter_mut().zip(rec?.iter()) {
            c.push(v.trim().parse().unwrap_or(f64::NAN));
        }
    }
    let t = headers.iter().position(|h| h == "t").ok_or_else(|| anyhow!("{}: no `t` column", path.display()))?;
    let fs = 1.0 / ((cols[t][cols[t].len() - 1] - cols[t][0]) / (cols[t].len() - 1) as f64);
    let channels = headers.into_iter().zip(cols).enumerate().filter(|(i, _)| *i != t).map(|(_, c)| c).collect();
    Ok((fs, channels))
}

fn members(f: &FamilyFit) -> String {
    let shown: Vec<String> = f
        .members
        .iter()
        .map(|m| {
            let db = if m.strength_db.is_finite() { format!("{:.1}", m.strength_db) } else { "—".into() };
            format!("{} {db}{}", m.label, if m.on_order { "(order)" } else { "" })
        })
        .collect();
    format!(
        "{} at {} [{:.1}, ch {}, band {:.0}–{:.0}, s {:+.2} %{}]: {}",
        f.family.name(),
        f.bearing,
        f.score,
        f.channel,
        f.band.low_hz,
        f.band.high_hz,
        100.0 * f.slip,
        if f.carried { ", carried" } else { "" },
        shown.join(", ")
    )
}

fn print(name: &str, d: &Diagnosis) {
    let verdict = match &d.verdict {
        Verdict::Named(f) => format!("{} at {}", f.family.name(), f.bearing),
        Verdict::CannotTell(a, b) => {
            format!("cannot tell: {} at {} or {} at {}", a.family.name(), a.bearing, b.family.name(), b.bearing)
        }
        Verdict::Nothing => "no bearing defect the data can show".to_string(),
    };
    println!(
        "{name}: {verdict}  (shaft {:.3} Hz ± {:.2e}, {} orders)",
        d.shaft.hz, d.shaft.uncertainty_hz, d.shaft.orders
    );
    for f in d.families.iter().take(3) {
        println!("    {}", members(f));
    }
}

fn main() -> Result<()> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut config = "host-sim/configs/rotor_cwru.toml".to_string();
    if let Some(i) = args.iter().position(|a| a == "--config") {
        config = args.get(i + 1).cloned().ok_or_else(|| anyhow!("--config needs a path"))?;
        args.drain(i..=i + 1);
    }
    let per_channel = args.iter().any(|a| a == "--per-channel");
    args.retain(|a| a != "--per-channel");
    let cfg = RotorConfig::from_toml_str(&std::fs::read_to_string(&config).with_context(|| config.clone())?)?;
    let bearings: Vec<BearingSpec> = cfg
        .bearings
        .iter()
        .filter_map(|b| b.geometry.map(|g| BearingSpec { name: format!("bearing {}", b.node), orders: g.kinematics() }))
        .collect();
    let nominal = cfg.operation.speed / std::f64::consts::TAU;
    for path in &args {
        let (fs, channels) = read_csv(Path::new(path))?;
        let name = Path::new(path).file_stem().map_or(path.clone(), |s| s.to_string_lossy().into_owned());
        let all: Vec<&[f64]> = channels.iter().map(|c| c.1.as_slice()).collect();
        match diagnose(&all, fs, nominal, &bearings) {
            Some(d) => print(&name, &d),
            None => println!("{name}: no running speed in the data"),
        }
        if per_channel && channels.len() > 1 {
            for (label, c) in &channels {
                if let Some(d) = diagnose(&[c.as_slice()], fs, nominal, &bearings) {
                    print(&format!("{name} {label}"), &d);
                }
            }
        }
    }
    Ok(())
}
