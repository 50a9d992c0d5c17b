//! `edgekf crank …` as a user runs it.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const PAPER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/crank_paper.toml");

fn edgekf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_edgekf")).args(args).env_remove("RUST_BACKTRACE").output().expect("run edgekf")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("crank-cli-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `edgekf crank simulate` of the paper's mechanism with 0.25 mm at A into `data`.
fn simulate_paper(data: &Path, duration: &str, extra: &[&str]) -> Output {
    let mut args = vec![
        "crank",
        "simulate",
        "--config",
        PAPER,
        "--clearance",
        "A=0.25e-3",
        "--duration",
        duration,
        "--out",
        path(data),
    ];
    args.extend_from_slice(extra);
    edgekf(&args)
}

#[test]
fn simulate_writes_the_data_contract_and_feature_reads_it() {
    let dir = scratch("simulate");
    let data = dir.join("data.csv");
    let out = simulate_paper(&data, "0.3", &["--seed", "7"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    assert!(stdout.contains("3000 samples at 10000 Hz over 0.3 s, seed 7"), "{stdout}");
    assert!(stdout.contains("clearances: A 0.2500 mm, B ideal, C ideal"), "{stdout}");
    assert!(stdout.contains("symplectic Euler, step 1e-5 s: 30000 steps"), "{stdout}");
    assert!(stdout.contains("constraints: largest residual"), "{stdout}");

    let csv = std::fs::read_to_string(&data).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header[..3], ["t", "crank_alpha", "truth_crank_alpha"]);
    for name in
        ["truth_crank_angle", "truth_contact_force_A", "truth_clearance_A", "truth_clearance_B", "truth_clearance_C"]
    {
        assert!(header.contains(&name), "{header:?}");
    }
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let first: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(first[0], "0");
    assert_eq!(first[col("truth_clearance_A")], "0.00025");
    assert_eq!(first[col("truth_clearance_B")], "0");
    assert_eq!(first[col("truth_crank_angle")], "0.5235987755982988"); // 30°
    assert_eq!(csv.lines().count(), 3001);
    // Measured = truth + noise of about 5 rad/s².
    let noise: Vec<f64> = csv
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
            c[1] - c[2]
        })
        .collect();
    let std = (noise.iter().map(|v| v * v).sum::<f64>() / noise.len() as f64).sqrt();
    assert!((std - 5.0).abs() < 0.3, "{std}");

    let out = edgekf(&["crank", "feature", "--data", path(&data), "--window", "0.1"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(stdout.contains("0.1 s windows at 10000.0 Hz"), "{stdout}");
    assert!(stdout.contains("a: mean") && stdout.contains("over 3 window(s)"), "{stdout}");
}

#[test]
fn adaptive_integrator_and_several_clearances() {
    let dir = scratch("adaptive");
    let data = dir.join("d.csv");
    let out = edgekf(&[
        "crank",
        "simulate",
        "--clearance",
        "B=0.1e-3",
        "--clearance",
        "c=0.1e-3",
        "--clearance",
        "A=0",
        "--duration",
        "0.05",
        "--out",
        path(&data),
        "--integrator",
        "adaptive",
    ]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    assert!(stdout.contains("clearances: A ideal, B 0.1000 mm, C 0.1000 mm"), "{stdout}");
    assert!(stdout.contains("adaptive Dormand–Prince 5(4), tolerance 1e-8"), "{stdout}");
    assert_eq!(std::fs::read_to_string(&data).unwrap().lines().count(), 501);
}

#[test]
fn mistakes_get_one_clear_line() {
    let dir = scratch("errors");
    let data = dir.join("d.csv");
    let d = path(&data);
    let cases: [(&[&str], &str); 5] = [
        (&["crank", "simulate", "--clearance", "D=1e-4", "--duration", "0.1", "--out", d], "is not a joint"),
        (&["crank", "simulate", "--clearance", "A=0.25", "--duration", "0.1", "--out", d], "in metres"),
        (&["crank", "simulate", "--clearance", "A", "--duration", "0.1", "--out", d], "JOINT=METRES"),
        (
            &["crank", "simulate", "--clearance", "A=1e-4", "--clearance", "A=2e-4", "--duration", "0.1", "--out", d],
            "given twice",
        ),
        (&["crank", "simulate", "--duration", "-1", "--out", d], "duration"),
    ];
    for (args, expect) in cases {
        let out = edgekf(args);
        let stderr = text(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(stderr.contains(expect), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "[contact]\nrestitusion = 0.9\n").unwrap();
    let out = edgekf(&["crank", "simulate", "--config", path(&bad), "--duration", "0.1", "--out", d]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr.contains("bad.toml") && stderr.contains("restitusion"), "{stderr}");
}

/// The fast model knows the mechanism it was trained for: another mechanism is refused with
/// what differs and how to train one, a release angle outside its training range is a warning,
/// and a recording at another sample rate is refused.
#[test]
fn fast_estimate_checks_the_mechanism_the_model_was_trained_for() {
    let dir = scratch("trained-for");
    let data = dir.join("data.csv");
    let out = simulate_paper(&data, "1", &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let paper = std::fs::read_to_string(PAPER).unwrap();
    let estimate = |config: &str, data: &Path| {
        let cfg = dir.join("c.toml");
        std::fs::write(&cfg, config).unwrap();
        let est = dir.join("est.csv");
        edgekf(&[
            "crank",
            "estimate",
            "--config",
            path(&cfg),
            "--data",
            path(data),
            "--method",
            "fast",
            "--out",
            path(&est),
        ])
    };
    let heavier = estimate(&paper.replace("mass = 0.14 ", "mass = 0.2 "), &data);
    let stderr = text(&heavier.stderr);
    assert!(!heavier.status.success());
    assert!(
        stderr.contains("slider mass 0.2 (the model's: 0.14)") && stderr.contains("edgekf crank train --config"),
        "{stderr}"
    );
    let steep = estimate(&paper.replace("crank_angle_deg = 30.0", "crank_angle_deg = 55.0"), &data);
    let stderr = text(&steep.stderr);
    assert!(steep.status.success(), "{stderr}");
    assert!(stderr.contains("warning: release angle 55° is outside the 20–40°"), "{stderr}");
    // The summary says where the clearance came from: 0.25 mm at A touches after 7.1 ms.
    let stdout = text(&steep.stdout);
    assert!(stdout.contains("release: first contact seen at 7.1 ms"), "{stdout}");
    assert!(stdout.contains("taken as contact 1 after release: A 0.2"), "{stdout}");
    // Every other sample: 5 kHz.
    let csv = std::fs::read_to_string(&data).unwrap();
    let mut lines = csv.lines();
    let mut half = format!("{}\n", lines.next().unwrap());
    for line in lines.step_by(2) {
        half.push_str(line);
        half.push('\n');
    }
    let slow = dir.join("slow.csv");
    std::fs::write(&slow, half).unwrap();
    let rate = estimate(&paper, &slow);
    let stderr = text(&rate.stderr);
    assert!(!rate.status.success());
    assert!(stderr.contains("sampled at 5000.0 Hz, the fast model at 10000.0 Hz"), "{stderr}");
}
