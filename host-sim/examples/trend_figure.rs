//! The README's trend figure (`docs/trend_history.svg`): the synthetic machine history of
//! `host-sim/tests/trend.rs` (30 recordings of the oscillator, a second harmonic growing by
//! 0.02 N per recording, an accelerometer offset from recording 20) run through `edgekf loop
//! oscillator --data FOLDER`, and the figure its `trend.html` embeds written on its own.
//!
//! ```text
//! cargo run --release -p edgekf-sim --example trend_figure [-- OUT.svg]
//! ```

use anyhow::{Context, Result};
use edgekf_sim::trend::synthetic::{write_history, RECORDINGS};
use edgekf_sim::{cli, systems};
use std::path::PathBuf;

fn main() -> Result<()> {
    let out = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/trend_history.svg")));
    let root = std::env::temp_dir().join(format!("edgekf-trend-figure-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let (data, config) = write_history(&root, RECORDINGS)?;
    let report = root.join("history");
    let mut args = vec!["edgekf".into(), "loop".into(), "oscillator".into(), "--quiet".into()];
    for (flag, path) in [("--config", &config), ("--data", &data), ("--report", &report)] {
        args.extend([flag.into(), path.clone().into_os_string()]);
    }
    let args: Vec<std::ffi::OsString> = args;
    cli::run_with(systems::REGISTRY, args)?;
    let page = std::fs::read_to_string(report.join("trend.html")).context("the history's page")?;
    let svg = match (page.find("<svg"), page.rfind("</svg>")) {
        (Some(a), Some(b)) if a < b => &page[a..b + "</svg>".len()],
        _ => anyhow::bail!("trend.html has no figure"),
    };
    std::fs::write(&out, format!("{svg}\n")).with_context(|| format!("cannot write {}", out.display()))?;
    let _ = std::fs::remove_dir_all(&root);
    println!("wrote {} ({} bytes)", out.display(), svg.len() + 1);
    Ok(())
}
