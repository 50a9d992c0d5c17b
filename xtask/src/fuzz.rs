//! `cargo xtask fuzz [--seconds N] [TARGET…]`: the coverage-guided fuzz targets of `fuzz/`
//! (cargo-fuzz, libFuzzer), each for a bounded time, on the stable toolchain.
//!
//! cargo-fuzz builds with `-s none` (no sanitizer): the sanitizers need nightly's `-Z` flags,
//! while the coverage instrumentation (`-Cpasses=sancov-module` and LLVM's sanitizer-coverage
//! options) is stable. Rust's own checks (bounds, overflow, debug assertions) find the panics.
//! cargo-fuzz is installed with `cargo install --locked` when missing.

use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// cargo-fuzz release that the project is tested with.
const CARGO_FUZZ: &str = "0.13.2";

/// A fuzz target: its extra seed corpus (besides `fuzz/seeds/<target>`), its libFuzzer
/// dictionary (under `fuzz/dicts/`) and its longest input, bytes.
struct Target {
    name: &'static str,
    seeds: Option<&'static str>,
    dict: Option<&'static str>,
    max_len: usize,
}

const TARGETS: [Target; 4] = [
    Target { name: "csv_reader", seeds: None, dict: Some("csv.dict"), max_len: 8192 },
    Target { name: "toml_configs", seeds: Some("host-sim/configs"), dict: None, max_len: 8192 },
    // Longer than the wide line buffer (4096 bytes), so that overlong lines are reached.
    Target { name: "line_reader", seeds: None, dict: Some("csv.dict"), max_len: 12_288 },
    Target { name: "fifo_decoder", seeds: None, dict: None, max_len: 1024 },
];

/// Runs the targets named in `args` (all when none is named) for `--seconds` each (default 20).
pub fn run(root: &Path, args: &[String]) -> Result<()> {
    let seconds = match args.iter().position(|a| a == "--seconds") {
        Some(i) => args.get(i + 1).and_then(|s| s.parse::<u64>().ok()).context("--seconds needs a whole number")?,
        None => 20,
    };
    let named: Vec<&String> = args
        .iter()
        .enumerate()
        .filter(|(i, a)| !a.starts_with("--") && *i != seconds_value(args))
        .map(|(_, a)| a)
        .collect();
    if let Some(unknown) = named.iter().find(|n| !TARGETS.iter().any(|t| t.name == n.as_str())) {
        bail!("no fuzz target `{unknown}`; the targets: {}", TARGETS.map(|t| t.name).join(", "));
    }
    ensure_cargo_fuzz()?;
    let fuzz_dir = root.join("fuzz");
    let started = Instant::now();
    let mut build = cargo();
    build.current_dir(root).args(["fuzz", "build", "-s", "none", "--fuzz-dir"]).arg(&fuzz_dir);
    crate::status(build, "cargo fuzz build")?;
    eprintln!("fuzz targets built in {:.0} s", started.elapsed().as_secs_f64());

    let mut summary = Vec::new();
    for t in TARGETS.iter().filter(|t| named.is_empty() || named.iter().any(|n| *n == t.name)) {
        let target = t.name;
        crate::step(&format!("fuzz {target} for {seconds} s"));
        let corpus = fuzz_dir.join("corpus").join(target);
        std::fs::create_dir_all(&corpus).with_context(|| format!("creating {}", corpus.display()))?;
        let mut cmd = cargo();
        cmd.current_dir(root).args(["fuzz", "run", "-s", "none", "--fuzz-dir"]).arg(&fuzz_dir).arg(target);
        cmd.arg(&corpus);
        let seeds = [Some(fuzz_dir.join("seeds").join(target)), t.seeds.map(|e| root.join(e))];
        cmd.args(seeds.into_iter().flatten().filter(|d| d.is_dir()));
        cmd.arg("--").arg(format!("-max_total_time={seconds}")).arg(format!("-max_len={}", t.max_len));
        if let Some(dict) = t.dict {
            cmd.arg(format!("-dict={}", fuzz_dir.join("dicts").join(dict).display()));
        }
        // An input that takes seconds is a finding too (a hang on bad input).
        cmd.args(["-timeout=10", "-print_final_stats=1"]);
        let out = cmd.output().with_context(|| format!("starting cargo fuzz run {target}"))?;
        let log = String::from_utf8_lossy(&out.stderr);
        if !out.status.success() {
            let tail: Vec<&str> = log.lines().rev().take(40).collect();
            eprintln!("{}", tail.into_iter().rev().collect::<Vec<_>>().join("\n"));
            bail!(
                "fuzz target {target} failed ({}); a failing input is saved under fuzz/artifacts/{target}/",
                out.status
            );
        }
        let runs = stat(&log, "stat::number_of_executed_units:").unwrap_or(0);
        let coverage = log.lines().rev().find_map(|l| l.split_whitespace().skip_while(|w| *w != "cov:").nth(1));
        eprintln!("{target}: {runs} executions in {seconds} s, coverage {} edges", coverage.unwrap_or("?"));
        summary.push((target, runs));
    }
    crate::step("fuzzing: no target panicked");
    for (target, runs) in summary {
        eprintln!("  {target:<14} {runs:>12} executions in {seconds} s");
    }
    Ok(())
}

/// Index of the value after `--seconds` (not a target name).
fn seconds_value(args: &[String]) -> usize {
    args.iter().position(|a| a == "--seconds").map_or(usize::MAX, |i| i + 1)
}

/// A `stat::…: N` line of libFuzzer's final statistics.
fn stat(log: &str, key: &str) -> Option<u64> {
    log.lines().find_map(|l| l.strip_prefix(key)).and_then(|v| v.trim().parse().ok())
}

/// `cargo` for the fuzz crate (its own workspace; artifacts in `fuzz/target` unless
/// `CARGO_TARGET_DIR` says otherwise, under the host triple, apart from the normal builds).
fn cargo() -> Command {
    crate::cargo_here()
}

/// Installs cargo-fuzz when `cargo fuzz` does not run (a fresh machine); a present one is kept.
fn ensure_cargo_fuzz() -> Result<()> {
    let present = cargo().args(["fuzz", "--version"]).output().map(|o| o.status.success()).unwrap_or(false);
    if present {
        return Ok(());
    }
    crate::step(&format!("provisioning: cargo install --locked cargo-fuzz --version {CARGO_FUZZ}"));
    let started = Instant::now();
    let mut install = cargo();
    install.args(["install", "--locked", "cargo-fuzz", "--version", CARGO_FUZZ]);
    crate::status(install, "cargo install cargo-fuzz")?;
    eprintln!("cargo-fuzz installed in {:.0} s", started.elapsed().as_secs_f64());
    Ok(())
}
