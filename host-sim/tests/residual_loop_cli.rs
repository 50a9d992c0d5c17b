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

/// Runs `edgekf` with `args`.
fn edgekf(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_edgekf")).args(args).output().expect("run edgekf")
}

/// `edgekf baseline oscillator` learns a healthy record's floor and innovation level; `loop
/// oscillator --baseline` on another healthy record adds nothing and finds its innovations at
/// the baseline's level, on a record with an accelerometer bias finds the bias and innovations
/// grown; a baseline of another system is refused before a report is written.
#[test]
fn a_baseline_of_the_oscillator_is_learned_and_judged_against() {
    use edgekf_sim::systems::oscillator::scenario::Scenario;
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("residual-loop-cli-baseline");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let demo = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/oscillator_demo.toml");
    let declared = Scenario::load(Path::new(demo)).unwrap();
    let write = |name: &str, s: &Scenario| {
        let path = dir.join(name);
        std::fs::write(&path, s.simulate().to_data_file().to_csv_string().unwrap()).unwrap();
        path.to_str().unwrap().to_string()
    };
    let healthy = write("healthy.csv", &Scenario { seed: 11, ..declared.clone() });
    let other = write("other.csv", &Scenario { seed: 12, ..declared.clone() });
    let mut biased = Scenario { seed: 13, ..declared.clone() };
    biased.sensor.bias_m_s2[0] = 0.05;
    let biased = write("biased.csv", &biased);
    let b = dir.join("b.toml");
    let b = b.to_str().unwrap();
    let out = edgekf(&["baseline", "oscillator", "--config", demo, "--data", &healthy, "--out", b, "--quiet"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let learned = edgekf_sim::residual_loop::levels::LevelBaseline::load(Path::new(b), "oscillator").unwrap();
    assert!(learned.gain_floor.is_finite() && learned.gain_floor >= 0.0, "{learned:?}");
    assert_eq!(learned.source.data, healthy);
    assert_eq!(learned.source.data_sha256.len(), 64);
    let close = |data: &str, baseline: &str, report: &Path| {
        let report = report.to_str().unwrap();
        let args = ["loop", "oscillator", "--config", demo, "--data", data, "--baseline", baseline, "--report", report];
        edgekf(&[&args[..], &["--quiet"]].concat())
    };
    let level = |data: &str, name: &str| {
        let report = dir.join(name);
        let out = close(data, b, &report);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(report.join("report.json")).unwrap()).unwrap();
        let c = &v["baseline_comparison"][0];
        assert_eq!((c["kind"].as_str(), c["location"].as_str()), (Some("innovation_rms"), Some("ax")), "{v}");
        assert_eq!(v["baseline"]["data"].as_str(), Some(healthy.as_str()));
        (c["ratio_to_baseline"].as_f64().unwrap(), v["effects_added"].clone())
    };
    let (ratio, added) = level(&other, "other");
    assert!((ratio - 1.0).abs() < 0.1 && added.as_array().unwrap().is_empty(), "×{ratio}: {added}");
    let (ratio, added) = level(&biased, "biased");
    eprintln!("biased: innovations ×{ratio} the baseline's, added {added}");
    assert!(ratio > 1.3, "×{ratio}");
    assert_eq!((added[0]["kind"].as_str(), added[0]["location"].as_str()), (Some("sensor_bias"), Some("ax")));
    assert!((added[0]["value"].as_f64().unwrap() / 0.05 - 1.0).abs() < 0.05, "{added}");
    // A baseline of another system: refused, no report.
    let foreign = dir.join("foreign.toml");
    std::fs::write(
        &foreign,
        std::fs::read_to_string(b).unwrap().replace("system = \"oscillator\"", "system = \"boom\""),
    )
    .unwrap();
    let report = dir.join("refused");
    let out = close(&other, foreign.to_str().unwrap(), &report);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && stderr.contains("a baseline of `boom`, not of `oscillator`"), "{stderr}");
    assert!(!report.exists());
}

/// `edgekf baseline boom` takes the loop's `--static` record (a usage error without it); under
/// its baseline, `loop boom` on another healthy run adds nothing and reads the gyro's
/// innovations at the healthy level, and on a run with 100 kg on the platform reports the load as a
/// tie with the sections it moves like (nothing added, the mass fitted at its true factor).
#[test]
fn a_baseline_of_the_boom_takes_its_static_record() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("residual-loop-cli-boom-baseline");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let config = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/boom_ladder30.toml");
    let loaded = dir.join("loaded.toml");
    let text = std::fs::read_to_string(config).unwrap();
    let declared = edgekf_sim::systems::boom::BoomConfig::from_toml_str(&text).unwrap();
    let mut heavy = declared.clone();
    heavy.tip.mass += 100.0;
    heavy.tip.rotary_inertia *= heavy.tip.mass / declared.tip.mass;
    std::fs::write(&loaded, toml::to_string(&heavy).unwrap()).unwrap();
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let simulate = |config: &str, seed: &str, name: &str| {
        let (data, statics) = (path(&format!("{name}.csv")), path(&format!("{name}_static.csv")));
        let args =
            ["boom", "simulate", "--config", config, "--scenario", "luffing", "--duration", "60", "--seed", seed];
        let out = edgekf(&[&args[..], &["--out", &data, "--static", &statics]].concat());
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        (data, statics)
    };
    let (healthy, healthy_static) = simulate(config, "11", "healthy");
    let (other, other_static) = simulate(config, "12", "other");
    let (load, load_static) = simulate(loaded.to_str().unwrap(), "13", "load");
    let b = path("b.toml");
    let learn = ["baseline", "boom", "--config", config, "--data", &healthy, "--out", &b, "--quiet"];
    let out = edgekf(&learn);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    let out = edgekf(&[&learn[..], &["--static", &healthy_static]].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let judged = |data: &str, statics: &str, name: &str| {
        let report = path(name);
        let args = ["loop", "boom", "--config", config, "--data", data, "--static", statics, "--baseline", &b];
        let out = edgekf(&[&args[..], &["--report", &report, "--quiet"]].concat());
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let text = std::fs::read_to_string(Path::new(&report).join("report.json")).unwrap();
        serde_json::from_str::<serde_json::Value>(&text).unwrap()
    };
    let v = judged(&other, &other_static, "other");
    let gyro = v["baseline_comparison"].as_array().unwrap().iter().find(|c| c["location"] == "gyro_rate").cloned();
    let ratio = gyro.and_then(|c| c["ratio_to_baseline"].as_f64()).unwrap();
    assert!((ratio - 1.0).abs() < 0.1 && v["effects_added"].as_array().unwrap().is_empty(), "×{ratio}: {v}");
    // A heavier platform and a softer section move the first mode alike on this run: the
    // load is reported as a tie of the two quantities, nothing added, with the platform's mass
    // fitted at its true factor among them.
    let v = judged(&load, &load_static, "load");
    assert!(v["effects_added"].as_array().unwrap().is_empty(), "{v}");
    let unseen = v["not_identifiable"].as_array().unwrap();
    let mass = unseen.iter().find(|n| n["location"] == "tip" && n["parameter"] == "mass").expect("the tip's mass");
    eprintln!("load under the baseline: {mass}");
    assert!(mass["rivals"].as_array().unwrap().iter().any(|r| r.as_str().unwrap().contains("section")), "{mass}");
    let fitted: f64 = mass["reason"].as_str().unwrap().split("fitted as ×").nth(1).unwrap()[..6].parse().unwrap();
    assert!((fitted / (heavy.tip.mass / declared.tip.mass) - 1.0).abs() < 0.1, "{mass}");
}
