//! `edgekf loop rotor` as a user runs it: report.json has the documented shape.

use edgekf_sim::systems::rotor::loop_system::inject::inject_bias;
use edgekf_sim::systems::rotor::{RotorConfig, RotorModel, SimOptions};
use std::path::Path;
use std::process::Command;

const PAPER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml");

/// Runs `edgekf loop rotor --config config --data csv --report report` with `extra` flags.
fn edgekf_loop(config: &str, csv: &Path, report: &Path, extra: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_edgekf"))
        .args(["loop", "rotor", "--config", config, "--data"])
        .arg(csv)
        .arg("--report")
        .arg(report)
        .args(extra)
        .output()
        .expect("run edgekf")
}

#[test]
fn loop_rotor_writes_the_report() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("residual-loop-cli");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = RotorConfig::load(Path::new(PAPER)).unwrap();
    let model = RotorModel::from_config(&cfg).unwrap();
    let mut data =
        model.simulate(&SimOptions { duration: 3.0, seed: 7, ..SimOptions::default() }).unwrap().to_data_file();
    inject_bias(&mut data, "n32_y", -15e-6).unwrap();
    let csv = dir.join("data.csv");
    std::fs::write(&csv, data.to_csv_string().unwrap()).unwrap();
    let report = dir.join("report");
    // The corrected configuration may not be an input: refused before any work.
    let refused = edgekf_loop(PAPER, &csv, &report, &["--corrected-config", PAPER]);
    assert!(!refused.status.success() && !report.exists());
    let fixed = dir.join("fixed.toml");
    let out = edgekf_loop(PAPER, &csv, &report, &["--corrected-config", fixed.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // The rotor's model reads no sensor calibration: the bias is reported as not carried, and
    // the corrected file is the configuration as it was.
    assert!(stdout.contains("0 of 1 effects carried") && stdout.contains("not carried"), "{stdout}");
    assert_eq!(std::fs::read_to_string(&fixed).unwrap(), std::fs::read_to_string(PAPER).unwrap());
    assert!(stdout.contains("sensor_bias") && stdout.contains("before") && stdout.contains("after"), "{stdout}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("report.json")).unwrap()).unwrap();
    assert_eq!(v["system"], "rotor");
    let added = v["effects_added"].as_array().unwrap();
    assert_eq!(added.len(), 1, "{added:?}");
    assert_eq!(added[0]["kind"], "sensor_bias");
    assert_eq!(added[0]["location"], "n32_y");
    assert_eq!(added[0]["unit"], "m");
    assert!((added[0]["value"].as_f64().unwrap() + 15e-6).abs() < 3e-6);
    for side in ["before", "after"] {
        let s = &v[side];
        for key in ["nis_mean", "whiteness_p"] {
            assert!(s[key].is_number(), "{side}.{key}");
        }
        for ch in ["n5_x", "n5_y", "n32_x", "n32_y"] {
            assert!(s["innovation_rms"][ch].is_number(), "{side}.innovation_rms.{ch}");
        }
        for ch in ["n12_x", "n12_y", "n23_x", "n23_y"] {
            assert!(s["error_rms"][ch].is_number(), "{side}.error_rms.{ch}");
        }
    }
    assert!((v["after"]["nis_mean"].as_f64().unwrap() - 1.0).abs() < 0.1);
    assert!(v["before"]["nis_mean"].as_f64().unwrap() > 10.0);
    assert!(v["not_identifiable"].is_array() && v["unexplained"].is_array());
    assert_eq!(v["corrections"][0]["effect"], "sensor_bias at n32_y");
    assert_eq!(v["corrections"][0]["as"], "not_carried");
    let html = std::fs::read_to_string(report.join("report.html")).unwrap();
    assert!(html.contains("<html") && html.contains("sensor_bias"), "{}", &html[..200.min(html.len())]);
    assert!(html.matches("<svg").count() >= 3);
}

/// `--estimate-speed` on the rig: the speed in report.json is read from the data, and the
/// summary says so.
#[test]
fn loop_rotor_estimates_the_speed() {
    let rig = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_rig_bearing.toml");
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("residual-loop-cli-speed");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let model = RotorModel::from_config(&RotorConfig::load(Path::new(rig)).unwrap()).unwrap();
    // The motor runs 3 % slow.
    let speed = 0.97 * model.config().operation.speed;
    let opts = SimOptions { duration: 2.0, seed: 11, speed: Some(speed), ..SimOptions::default() };
    let csv = dir.join("data.csv");
    std::fs::write(&csv, model.simulate(&opts).unwrap().to_data_file().to_csv_string().unwrap()).unwrap();
    let report = dir.join("report");
    // A band that is not a fraction is a usage error (exit 2), before any work.
    let bad = edgekf_loop(rig, &csv, &report, &["--estimate-speed", "10"]);
    assert_eq!(bad.status.code(), Some(2), "{}", String::from_utf8_lossy(&bad.stderr));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("not a fraction") && !report.exists());
    let out = edgekf_loop(rig, &csv, &report, &["--quiet", "--estimate-speed"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("estimated from the data"), "{stdout}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("report.json")).unwrap()).unwrap();
    let s = &v["running_speed"];
    assert_eq!(s["source"], "estimated");
    let truth = speed / std::f64::consts::TAU;
    assert!((s["hz"].as_f64().unwrap() / truth - 1.0).abs() < 1e-3, "{s} against {truth} Hz");
    assert!((s["declared_hz"].as_f64().unwrap() - 30.0).abs() < 1e-3);
    assert_eq!(v["effects_added"].as_array().unwrap().len(), 0, "{}", v["effects_added"]);
}

/// `--baseline` on a system without baselines is a usage error before any work, not a flag
/// silently ignored and recorded in the report.
#[test]
fn a_baseline_is_refused_where_it_would_be_ignored() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("residual-loop-cli-baseline");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let demo = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/oscillator_demo.toml");
    let out = Command::new(env!("CARGO_BIN_EXE_edgekf"))
        .args(["loop", "oscillator", "--config", demo, "--data"])
        .arg(dir.join("no-such.csv"))
        .arg("--report")
        .arg(dir.join("report"))
        .arg("--baseline")
        .arg(dir.join("no-such.toml"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(stderr.contains("--baseline would be ignored") && stderr.contains("rotor"), "{stderr}");
    assert!(!dir.join("report").exists());
}
