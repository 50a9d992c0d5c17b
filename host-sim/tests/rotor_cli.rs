//! `edgekf rotor …` as a user runs it.

use edgekf_sim::io::data;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const PAPER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml");
const PAPER_ACCEL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper_accel.toml");
const RIG: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_rig_bearing.toml");

fn edgekf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_edgekf")).args(args).env_remove("RUST_BACKTRACE").output().expect("run edgekf")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("rotor-cli-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn modes_json_has_the_documented_shape() {
    let out = edgekf(&["rotor", "modes", "--config", PAPER, "--speed", "87.96", "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
    assert_eq!(v["speed"], 87.96);
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 12);
    for m in modes {
        let keys: Vec<&str> = m.as_object().unwrap().keys().map(String::as_str).collect();
        assert_eq!(keys, ["frequency_hz", "log_dec", "whirl"]);
        assert!(["forward", "backward", "planar"].contains(&m["whirl"].as_str().unwrap()));
    }
    assert!((modes[0]["frequency_hz"].as_f64().unwrap() - 22.36427).abs() < 1e-4);
    assert_eq!(modes[0]["whirl"], "backward");
    assert_eq!(modes[1]["whirl"], "forward");
}

#[test]
fn modes_table_defaults_to_the_configured_speed() {
    let out = edgekf(&["rotor", "modes", "--config", PAPER, "--count", "4"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(stdout.contains("at 87.96 rad/s"), "{stdout}");
    let rows: Vec<&str> = stdout.lines().filter(|l| l.trim_start().starts_with(char::is_numeric)).collect();
    assert_eq!(rows.len(), 4, "{stdout}");
    assert!(rows[0].contains("22.3643") && rows[0].ends_with("backward"), "{}", rows[0]);
}

#[test]
fn simulate_writes_the_data_contract() {
    let dir = scratch("simulate");
    let csv = dir.join("r.csv");
    let out = edgekf(&[
        "rotor",
        "simulate",
        "--config",
        PAPER,
        "--duration",
        "0.5",
        "--out",
        csv.to_str().unwrap(),
        "--seed",
        "3",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("500 samples at 1000 Hz"), "{}", text(&out.stdout));
    let known = ["n5_x", "n5_y", "n32_x", "n32_y"];
    let (file, report) = data::read(&csv, &known).unwrap();
    assert!(report.ignored_columns.is_empty() && report.nan_cells.is_empty());
    assert_eq!(file.len(), 500);
    assert_eq!(file.t[1], 0.001);
    assert_eq!(&file.names[..4], known);
    for k in 0..=37 {
        assert!(file.column(&format!("truth_n{k}_x")).is_some() && file.column(&format!("truth_n{k}_y")).is_some());
    }
    // Forces at the disks: |F| = U Ω² = 4.76e-4 · 87.96² N, at phase 70° (node 12) at t = 0.
    let (fx, fy) = (file.column("truth_f12_x").unwrap(), file.column("truth_f12_y").unwrap());
    let amp = 4.76e-4 * 87.96f64.powi(2);
    assert!((fx[0] - amp * 70f64.to_radians().cos()).abs() < 1e-12);
    assert!((fy[0] - amp * 70f64.to_radians().sin()).abs() < 1e-12);
    assert!(file.column("truth_f23_x").is_some());
    // Measured = truth + noise of about 1 µm.
    let (m, t) = (file.column("n5_x").unwrap(), file.column("truth_n5_x").unwrap());
    let std = (m.iter().zip(t).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / m.len() as f64).sqrt();
    assert!((std / 1e-6 - 1.0).abs() < 0.15, "{std}");
}

#[test]
fn simulate_accelerometers_names_channels_by_the_contract() {
    let dir = scratch("accel");
    let csv = dir.join("a.csv");
    let out =
        edgekf(&["rotor", "simulate", "--config", PAPER_ACCEL, "--duration", "0.1", "--out", csv.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let (file, _) = data::read(&csv, &["n5_ax", "n5_ay", "n32_ax", "n32_ay"]).unwrap();
    assert_eq!(&file.names[..4], ["n5_ax", "n5_ay", "n32_ax", "n32_ay"]);
    assert!(file.column("truth_n32_ay").is_some());
}

#[test]
fn bad_input_gives_one_line_and_exit_1() {
    let dir = scratch("bad");
    let cfg = dir.join("bad.toml");
    let text_in =
        std::fs::read_to_string(PAPER).unwrap().replacen("node = 12\nmass = 2.65", "node = 99\nmass = 2.65", 1);
    std::fs::write(&cfg, text_in).unwrap();
    let out = edgekf(&["rotor", "modes", "--config", cfg.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(err.starts_with("error: ") && err.contains("bad.toml") && err.contains("disk[0].node = 99"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");

    let out = edgekf(&["rotor", "simulate", "--config", PAPER, "--duration", "-1", "--out", "/tmp/never.csv"]);
    // A negative length is a usage error (exit 2), named by clap with its flag.
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("'--duration <S>': -1 s is not a positive length"), "{}", text(&out.stderr));
    assert!(!Path::new("/tmp/never.csv").exists());
}

#[test]
fn campbell_and_unbalance_commands() {
    let out = edgekf(&[
        "rotor",
        "campbell",
        "--config",
        PAPER,
        "--max-speed",
        "500",
        "--steps",
        "3",
        "--count",
        "4",
        "--json",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["speeds"], serde_json::json!([0.0, 250.0, 500.0]));
    let last = v["modes"][2].as_array().unwrap();
    assert_eq!(last.len(), 4);
    assert_eq!(last[2]["whirl"], "backward");
    assert_eq!(last[3]["whirl"], "forward");

    let out = edgekf(&["rotor", "unbalance", "--config", PAPER]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // ROSS: 11.56215 µm at 50.292° in x at node 5.
    let row = stdout.lines().find(|l| l.split_whitespace().take(2).eq(["5", "x"])).unwrap();
    assert!(row.contains("11.5621") && row.contains("50.29"), "{row}");
    assert!(stdout.contains("largest orbit: node 19"), "{stdout}");
}

/// The rig of rotor_rig_bearing.toml gives 22 states × 2 accelerometers, a size no build compiles
/// in: `rotor estimate` runs it with the dynamic-size filter (f64) and finds the disk's motion,
/// which no sensor measures; `--f32`, the chip's arithmetic, is refused with the chip's sizes.
#[test]
fn estimate_runs_a_size_no_build_compiles_in() {
    let dir = scratch("rig");
    let (csv, est) = (dir.join("rig.csv"), dir.join("est.csv"));
    let (csv_s, est_s) = (csv.to_str().unwrap(), est.to_str().unwrap());
    let out = edgekf(&["rotor", "simulate", "--config", RIG, "--duration", "2", "--out", csv_s, "--seed", "4"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = edgekf(&["rotor", "estimate", "--config", RIG, "--data", csv_s, "--out", est_s]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(stdout.contains("22 states"), "{stdout}");

    let (truth, _) = data::read(&csv, &[]).unwrap();
    let (estimate, _) = data::read(&est, &["n6_x", "n6_y"]).unwrap();
    for axis in ["x", "y"] {
        let (e, t) =
            (estimate.column(&format!("n6_{axis}")).unwrap(), truth.column(&format!("truth_n6_{axis}")).unwrap());
        let late = |k: &usize| truth.t[*k] >= 1.0;
        let rms = |f: &dyn Fn(usize) -> f64| {
            let v: Vec<f64> = (0..t.len()).filter(late).map(f).collect();
            (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
        };
        let (error, motion) = (rms(&|k| e[k] - t[k]), rms(&|k| t[k]));
        eprintln!("rig disk n6_{axis}: RMS error {:.3} µm of {:.3} µm RMS motion", error * 1e6, motion * 1e6);
        // The disk moves about 3 µm RMS; a broken filter (or none: an estimate of zero) is off
        // by about as much.
        assert!(motion > 2e-6 && error < 0.15 * motion, "n6_{axis}: error {error:e} for motion {motion:e}");
    }

    let out = edgekf(&["rotor", "estimate", "--config", RIG, "--data", csv_s, "--f32"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("the chip's sizes") && stderr.contains("22 states × 2 sensors"), "{stderr}");
}
