//! The boom's part of `edgekf demo`: a luffing run of the shipped 30 m ladder whose root
//! inclinometer lags by 0.3 s while the configuration declares no lag. The lag turns the
//! inclinometer's correction into a wrong one after every move; the loop has to name it and
//! bring the tip's peak error back down.

use super::{simulate, BoomConfig, Scenario, SimOptions};
use crate::cli::demo_loop::{check, close, say, ErrorOf, LoopInputs};
use crate::cli::request::DemoArgs;
use anyhow::{Context, Result};

/// The inclinometer's true lag, s.
pub const LAG: f64 = 0.3;
/// Length of the run, s.
pub const DURATION: f64 = 60.0;
/// Noise seed.
pub const SEED: u64 = 1;

/// The configuration the part writes: the shipped boom declaring no inclinometer lag, the
/// simulator's inclinometer (`[sim.inclinometer]`) lagging by [`LAG`], so that `edgekf boom
/// simulate` on it makes the same recording.
pub fn config() -> BoomConfig {
    let mut c = BoomConfig::default();
    c.inclinometer.lag = 0.0;
    c.sim.inclinometer.lag = Some(LAG);
    c
}

/// One line saying what was simulated.
pub fn describe() -> String {
    format!(
        "telescoping boom (boom_ladder30.toml), {DURATION} s of luffing at 100 Hz, seed {SEED}; undeclared: the \
         root inclinometer lags by {LAG} s"
    )
}

/// Runs the part: simulate the run and the static record, close the loop, print the finding
/// and the tip's peak error before and after; `--out DIR` writes `boom/` with the inputs and
/// the report.
pub fn demo(args: &DemoArgs) -> Result<()> {
    check(args, "boom", &["static.csv"])?;
    println!("boom — {}", describe());
    let config = config();
    let rec =
        simulate(&config, &SimOptions { scenario: Scenario::Luffing, duration: DURATION, seed: SEED }, &mut |_| {})?;
    let statics = super::cli::static_csv(&config, SEED, std::path::Path::new("static.csv"))?;
    let inputs = LoopInputs {
        system: "boom",
        run: super::cli::close_loop,
        args: <super::cli::BoomLoopArgs as clap::Args>::augment_args,
        config: toml::to_string(&config).context("the boom's configuration as TOML")?,
        data: rec.to_csv(std::path::Path::new("data.csv"))?,
        extra: vec![("--static", "static.csv", statics)],
    };
    let report = close(args, &inputs)?;
    let peak = ErrorOf { label: "tip peak error", unit: " %", of: |s| s.metrics.get("peak_error_pct").copied() };
    say(args, &report, &peak);
    Ok(())
}
