//! The host half of `cargo xtask bench`: edgekf against ROSS and filterpy on the same
//! problems, in one run on one machine (never in CI: it needs PyPI and a few minutes).
//!
//! It creates a Python virtual environment in `target/bench/venv` from the pinned
//! `tools/bench/requirements.txt` (once), runs `tools/bench/peers.py` there, runs edgekf's
//! `host-sim/examples/speed.rs` in release on the same problems, and prints the table of times
//! and ratios. Compute against compute: the peers' imports and model assembly are timed apart.

use anyhow::{bail, Context, Result};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The virtual environment with the pinned peers, created if it is missing.
fn venv(root: &Path) -> Result<PathBuf> {
    let dir = root.join("target/bench/venv");
    let python = dir.join("bin/python");
    let stamp = dir.join("requirements.txt");
    let requirements = root.join("tools/bench/requirements.txt");
    let wanted =
        std::fs::read_to_string(&requirements).with_context(|| format!("reading {}", requirements.display()))?;
    if python.exists() && std::fs::read_to_string(&stamp).is_ok_and(|s| s == wanted) {
        return Ok(python);
    }
    eprintln!("==> creating {} from {} (pip, a few minutes)", dir.display(), requirements.display());
    run(
        Command::new("python3").args(["-m", "venv", "--clear"]).arg(&dir),
        "python3 -m venv (apt-get install python3-venv)",
    )?;
    run(Command::new(&python).args(["-m", "pip", "install", "--quiet", "-r"]).arg(&requirements), "pip install")?;
    std::fs::write(&stamp, wanted)?;
    Ok(python)
}

fn run(cmd: &mut Command, what: &str) -> Result<()> {
    let st = cmd.status().with_context(|| format!("starting {what}"))?;
    if !st.success() {
        bail!("{what} failed ({st})");
    }
    Ok(())
}

/// The CPU's model name and the number of cores, for the table's header.
pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("model name").map(|v| v.trim_start_matches([' ', '\t', ':']).to_string()))
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    format!("{cpu}, {cores} cores")
}

/// Runs both sides and returns `{"edgekf": …, "peers": …, "ratios": …}` after printing the
/// table.
pub fn run_all(root: &Path) -> Result<Value> {
    let python = venv(root)?;
    let peers_json = root.join("target/bench/peers.json");
    // ROSS imports `ccp`, which trips over stray shared libraries in its working directory.
    let empty = root.join("target/bench/peers-cwd");
    std::fs::create_dir_all(&empty)?;
    eprintln!("==> the peers: tools/bench/peers.py (ROSS's time response, modes, Campbell diagram; filterpy's steps)");
    run(
        Command::new(&python).arg(root.join("tools/bench/peers.py")).arg(&peers_json).current_dir(&empty),
        "tools/bench/peers.py",
    )?;
    eprintln!("==> edgekf: cargo run --release -p edgekf-sim --example speed");
    let out = Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
        .args(["run", "--quiet", "--release", "-p", "edgekf-sim", "--example", "speed", "--"])
        .arg(&peers_json)
        .current_dir(root)
        .output()
        .context("running the speed example")?;
    if !out.status.success() {
        bail!("the speed example failed:\n{}", String::from_utf8_lossy(&out.stderr));
    }
    let ours: Value = serde_json::from_slice(&out.stdout).context("the speed example's JSON")?;
    let mut peers: Value = serde_json::from_str(&std::fs::read_to_string(&peers_json)?)?;
    if let Some(p) = peers.as_object_mut() {
        p.retain(|k, _| !k.ends_with("_disks"));
    }
    Ok(table(ours, peers))
}

/// The table of times and ratios (peer / edgekf) from both sides' figures.
fn table(ours: Value, peers: Value) -> Value {
    let f = |v: &Value, k: &str| v.get(k).and_then(Value::as_f64).unwrap_or(f64::NAN);
    let rows = [
        ("paper rotor time response, 4 s at 1 kHz", "response_4s_s", "ROSS"),
        ("paper rotor time response, 40 s at 1 kHz", "response_40s_s", "ROSS"),
        ("modal analysis at 87.96 rad/s (every mode)", "modal_s", "ROSS"),
        ("Campbell diagram, 6 modes × 51 speeds", "campbell_s", "ROSS"),
        ("Kalman predict + update, n = 4, m = 4 (f64)", "kf_step_s", "filterpy"),
        ("unscented predict + update, n = 14, m = 4 (f64)", "ukf_step_s", "filterpy"),
    ];
    let versions = peers.get("versions").cloned().unwrap_or(Value::Null);
    println!("\nhost speed against the peers on {} ({versions}), compute only, best of a few runs:", machine());
    println!("{:<52} {:>12} {:>12} {:>9}", "problem", "edgekf", "peer", "ratio");
    let mut ratios = serde_json::Map::new();
    for (what, key, peer) in rows {
        let (a, b) = (f(&ours, key), f(&peers, key));
        println!("{what:<52} {:>12} {:>12} {:>8.1}×  ({peer})", seconds(a), seconds(b), b / a);
        ratios.insert(key.to_string(), json!(b / a));
    }
    println!(
        "edgekf's 4 s response against ROSS's: {:.2e} relative RMS at 1 kHz, {:.2e} against ROSS at 10 kHz \
         (ROSS interpolates the force linearly between samples; the 1 kHz run converges to 6.4e-4 of its 10 kHz run: {:.2e})",
        f(&ours, "response_4s_vs_ross_1khz"),
        f(&ours, "response_4s_vs_ross_10khz"),
        f(&peers, "response_4s_fine_vs_1khz")
    );
    println!(
        "edgekf: writing the 4 s response as CSV {} ({:.1} MB) against simulating it {}; ROSS imports in {}; \
         rotor estimate {:.0} samples/s; the loop on 4 s at 1 kHz with an undeclared 2× force {} (adds {})",
        seconds(f(&ours, "csv_4s_s")),
        f(&ours, "csv_4s_bytes") / 1e6,
        seconds(f(&ours, "response_4s_s")),
        seconds(f(&peers, "import_s")),
        f(&ours, "estimate_samples_per_s"),
        seconds(f(&ours, "loop_4s_twox_s")),
        ours.get("loop_4s_twox_added").map_or("?".into(), Value::to_string)
    );
    println!(
        "edgekf: the loop on 10 s at 12 kHz from two housings with an outer-race defect, against a baseline \
         learnt from 2 s of the healthy twin in {}: {} (adds {})",
        seconds(f(&ours, "baseline_2s_12khz_s")),
        seconds(f(&ours, "loop_10s_12khz_s")),
        ours.get("loop_10s_12khz_added").map_or("?".into(), Value::to_string)
    );
    json!({ "machine": machine(), "edgekf": ours, "peers": peers, "ratios": ratios })
}

fn seconds(s: f64) -> String {
    if s >= 1.0 {
        format!("{s:.2} s")
    } else if s >= 1e-3 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{:.2} µs", s * 1e6)
    }
}
