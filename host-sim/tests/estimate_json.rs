//! `edgekf <system> estimate --json` and `--plot` without truth, as a user runs them: stdout is
//! one JSON object whose figures match the text (now on stderr) and the data, and a plot of a
//! recording without `truth_` columns is drawn, with the estimate file written.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const CONFIGS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/configs");

fn edgekf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_edgekf")).args(args).env_remove("RUST_BACKTRACE").output().expect("run edgekf")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("estimate-json-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn config(name: &str) -> String {
    format!("{CONFIGS}/{name}")
}

/// Runs `args`, which must succeed, and parses the whole of stdout as one JSON object; returns
/// it with stderr.
fn json_run(args: &[&str]) -> (Value, String) {
    let out = edgekf(args);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{args:?}\n{stdout}\n{stderr}");
    let json: Value =
        serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("stdout is not one JSON object: {e}\n{stdout}"));
    assert!(json.is_object(), "{json}");
    (json, stderr)
}

/// `json[keys…]` as a number.
fn num(json: &Value, keys: &[&str]) -> f64 {
    let v = keys.iter().fold(json, |v, k| &v[*k]);
    v.as_f64().unwrap_or_else(|| panic!("no number at {keys:?} in {json:#}"))
}

/// The number following `before` in `text` (e.g. `RMS error ` → `0.0032`).
fn number_after(text: &str, before: &str) -> f64 {
    let at = text.find(before).unwrap_or_else(|| panic!("no `{before}` in\n{text}")) + before.len();
    let token: String = text[at..].chars().take_while(|c| c.is_ascii_digit() || matches!(c, '.' | '-' | 'e')).collect();
    token.parse().unwrap_or_else(|_| panic!("`{token}` after `{before}` in\n{text}"))
}

/// A CSV's column `name`, empty cells as NaN.
fn column(csv: &str, name: &str) -> Vec<f64> {
    let mut lines = csv.lines();
    let i = lines.next().unwrap().split(',').position(|c| c == name).unwrap_or_else(|| panic!("no column {name}"));
    lines.map(|l| l.split(',').nth(i).unwrap().parse().unwrap_or(f64::NAN)).collect()
}

/// `csv` without its `truth_` columns: a recording as a real sensor gives it.
fn strip_truth(csv: &str) -> String {
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let keep: Vec<usize> = (0..header.len()).filter(|&i| !header[i].starts_with("truth_")).collect();
    assert!(keep.len() < header.len(), "no truth_ columns to strip");
    csv.lines()
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            keep.iter().map(|&i| cells[i]).collect::<Vec<_>>().join(",") + "\n"
        })
        .collect()
}

/// Points of the estimate's lines (drawn in the plot kit's estimate blue) in an SVG file.
fn estimate_points(svg: &Path) -> usize {
    let svg = std::fs::read_to_string(svg).unwrap_or_else(|e| panic!("{}: {e}", svg.display()));
    svg.split("<polyline")
        .skip(1)
        .filter(|p| p.split('>').next().unwrap().contains("stroke=\"#1F64B4\""))
        .map(|p| p.split("points=\"").nth(1).map_or(0, |pts| pts.split('"').next().unwrap().split_whitespace().count()))
        .sum()
}

#[test]
fn oscillator_json_carries_the_tables_figures() {
    let dir = scratch("oscillator");
    let (data, est) = (dir.join("data.csv"), dir.join("est.csv"));
    let demo = config("oscillator_demo.toml");
    assert!(edgekf(&["oscillator", "simulate", "--config", &demo, "--out", path(&data)]).status.success());
    let args = ["oscillator", "estimate", "--config", &demo, "--data", path(&data), "--out", path(&est)];
    // Without --json stdout is the table, as scripts read it today.
    let plain = edgekf(&args);
    let table = text(&plain.stdout);
    assert!(table.contains("force amplitude, mean 3–6 s [N]") && table.contains("wrote"), "{table}");
    let (json, stderr) = json_run(&[&args[..], &["--json"]].concat());
    assert!(stderr.contains(&table), "the table moves to stderr whole:\n{stderr}");
    assert_eq!((json["system"].as_str(), json["samples"].as_u64()), (Some("oscillator"), Some(12_000)));
    assert!((num(&json, &["duration_s"]) - 12.0).abs() < 1e-9 && json["out"] == path(&est));
    let amp = &json["quantities"]["force_amplitude"];
    // The RMS error after settling is the table's, to its four decimals.
    let row = table.lines().find(|l| l.starts_with("force amplitude, RMS error t ≥ 2 s [N]")).unwrap();
    let printed: f64 = row.split_whitespace().last().unwrap().parse().unwrap();
    assert!((num(amp, &["error", "rms"]) - printed).abs() < 5e-5, "{amp} against {printed}");
    // The force steps from 5 N to 3 N: the steady stretches' means, the final value and the max.
    let windows = &json["details"]["steady_windows"];
    assert!((num(&windows[0], &["force_amplitude_mean"]) - 5.0).abs() < 1e-3, "{windows}");
    assert!((windows[1]["force_amplitude_mean"].as_f64().unwrap() - 3.0).abs() < 1e-3 && windows[1]["truth"] == 3.0);
    assert!((num(amp, &["final"]) - 3.0).abs() < 0.01 && (num(amp, &["max"]) - 5.0).abs() < 0.05, "{amp}");
}

#[test]
fn rotor_json_has_the_printed_errors_and_the_unbalance_forces() {
    let dir = scratch("rotor");
    let (data, est) = (dir.join("data.csv"), dir.join("est.csv"));
    let rotor = config("rotor_paper.toml");
    let out =
        edgekf(&["rotor", "simulate", "--config", &rotor, "--duration", "2", "--seed", "3", "--out", path(&data)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let (json, stderr) =
        json_run(&["rotor", "estimate", "--config", &rotor, "--data", path(&data), "--out", path(&est), "--json"]);
    let q = &json["quantities"];
    for node in ["n5_x", "n12_y", "n23_x", "n32_y"] {
        let printed = number_after(&stderr, &format!("{node}: RMS error "));
        assert!((num(q, &[node, "error", "rms_after_1s"]) * 1e6 - printed).abs() < 6e-4, "{node}: {}", q[node]);
    }
    // The force's error, computed here from the two files, and its final size against the truth's.
    let (d, e) = (std::fs::read_to_string(&data).unwrap(), std::fs::read_to_string(&est).unwrap());
    let (fx, truth_fx) = (column(&e, "f12_x"), column(&d, "truth_f12_x"));
    let rms = (fx.iter().zip(&truth_fx).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / fx.len() as f64).sqrt();
    assert!((num(q, &["f12_x", "error", "rms"]) - rms).abs() < 1e-9 * rms.max(1.0), "{} against {rms}", q["f12_x"]);
    let truth_size = truth_fx.last().unwrap().hypot(*column(&d, "truth_f12_y").last().unwrap());
    let size = num(q, &["f12_magnitude", "final"]);
    assert!((size - truth_size).abs() < 0.05 * truth_size, "{size} N against {truth_size} N");
    assert_eq!(json["details"]["force_nodes"], serde_json::json!([12, 23]));
}

#[test]
fn crank_json_sizes_the_loose_joint() {
    let dir = scratch("crank");
    let (data, est) = (dir.join("data.csv"), dir.join("est.csv"));
    let paper = config("crank_paper.toml");
    let out = edgekf(&[
        "crank",
        "simulate",
        "--config",
        &paper,
        "--clearance",
        "A=0.25e-3",
        "--duration",
        "2",
        "--out",
        path(&data),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let args = ["crank", "estimate", "--data", path(&data), "--method", "fast", "--out", path(&est), "--json"];
    let (json, stderr) = json_run(&args);
    assert!(stderr.contains("estimate: joint A") && stderr.contains("wrote"), "{stderr}");
    let a = &json["quantities"]["clearance_A"];
    // The fast estimator's joint-A tolerance on the paper's case: within 5 % (the text says 0.2486 mm).
    let final_a = num(a, &["final"]);
    assert!((final_a - 0.25e-3).abs() < 0.05 * 0.25e-3, "{a}");
    assert!((num(a, &["final"]) * 1e3 - number_after(&stderr, "estimate: joint A: A ")).abs() < 5e-5, "{a}");
    assert!(
        (num(a, &["error", "final"]) - (final_a - 0.25e-3)).abs() < 1e-15 && num(a, &["error", "truth"]) == 0.25e-3
    );
    for joint in ["clearance_B", "clearance_C"] {
        assert_eq!(num(&json["quantities"][joint], &["final"]), 0.0, "{json:#}");
    }
    assert_eq!(json["samples"].as_u64(), Some(20_000));
    assert!(std::fs::read_to_string(&est).unwrap().starts_with("t,clearance_A,clearance_B,clearance_C\n"));
}

#[test]
fn uuv_json_and_plots_without_truth_or_health_state() {
    let dir = scratch("uuv");
    let (data, bare, est, svg) = (dir.join("data.csv"), dir.join("bare.csv"), dir.join("est.csv"), dir.join("p.svg"));
    let out =
        edgekf(&["uuv", "simulate", "--scenario", "healthy", "--duration", "60", "--seed", "2", "--out", path(&data)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let (json, stderr) = json_run(&["uuv", "estimate", "--data", path(&data), "--out", path(&est), "--json"]);
    let k_t = &json["quantities"]["k_t"];
    // Healthy thrusters: k_t stays near the simulated 1; the RMS error is the one printed.
    assert!((num(k_t, &["mean"]) - 1.0).abs() < 0.02 && (num(k_t, &["final"]) - 1.0).abs() < 0.05, "{k_t}");
    let printed = number_after(&stderr, "main thruster: 0 CUSUM alarm(s), declared for 0.00 s, final k_t = ");
    assert!((num(k_t, &["final"]) - printed).abs() < 5e-4, "{k_t} against {printed}");
    let printed = number_after(&stderr[stderr.find("main thruster").unwrap()..], "RMS error ");
    assert!((num(k_t, &["error", "rms"]) - printed).abs() < 5e-5, "{k_t} against {printed}");
    let truth_u = column(&std::fs::read_to_string(&data).unwrap(), "truth_u");
    let mean_u = truth_u.iter().sum::<f64>() / truth_u.len() as f64;
    assert!((num(&json, &["quantities", "u", "mean"]) - mean_u).abs() < 0.01, "{mean_u}: {}", json["quantities"]["u"]);
    assert_eq!(json["details"]["thrusters"]["main"]["alarms"], 0);

    // A recording without truth: the health factors drawn alone, said so, the estimate written.
    std::fs::write(&bare, strip_truth(&std::fs::read_to_string(&data).unwrap())).unwrap();
    let args = ["uuv", "estimate", "--data", path(&bare), "--out", path(&est), "--plot", path(&svg), "--json"];
    let (json, stderr) = json_run(&args);
    assert!(stderr.contains("no truth_ columns in the recording"), "{stderr}");
    assert!(estimate_points(&svg) > 100 && est.exists(), "{}", std::fs::read_to_string(&svg).unwrap());
    assert!(!std::fs::read_to_string(&svg).unwrap().contains("against truth"));
    assert!(json["quantities"]["k_t"]["error"].is_null() && json["truth"] == false && json["plot"] == path(&svg));

    // No health state in the filter: the speeds are drawn instead (with and without truth).
    let none = dir.join("no_health.toml");
    std::fs::write(&none, "[estimator]\nhealth = []\n").unwrap();
    for recording in [&data, &bare] {
        let _ = std::fs::remove_file(&svg);
        let args = ["uuv", "estimate", "--config", path(&none), "--data", path(recording), "--out", path(&est)];
        let out = edgekf(&[&args[..], &["--plot", path(&svg)]].concat());
        assert!(out.status.success(), "{}", text(&out.stderr));
        assert!(text(&out.stderr).contains("draws the speeds u, v, w"), "{}", text(&out.stderr));
        assert!(estimate_points(&svg) > 100, "{}", std::fs::read_to_string(&svg).unwrap());
        assert!(std::fs::read_to_string(&svg).unwrap().contains("Vehicle speeds"));
    }
}

#[test]
fn boom_json_and_a_plot_without_truth() {
    let dir = scratch("boom");
    let (data, statics, est, svg) =
        (dir.join("data.csv"), dir.join("static.csv"), dir.join("est.csv"), dir.join("vibration.svg"));
    let args = ["boom", "simulate", "--scenario", "luffing", "--duration", "40", "--out", path(&data)];
    let out = edgekf(&[&args[..], &["--static", path(&statics)]].concat());
    assert!(out.status.success(), "{}", text(&out.stderr));
    let args = ["boom", "estimate", "--data", path(&data), "--static", path(&statics), "--out", path(&est)];
    let (json, stderr) = json_run(&[&args[..], &["--json"]].concat());
    let vib = &json["quantities"]["tip_vibration"];
    assert!((num(vib, &["error", "peak_mean_pct"]) - number_after(&stderr, "peaks: mean ")).abs() < 0.005, "{vib}");
    assert!(num(vib, &["error", "peak_mean_pct"]) < 2.0 && vib.get("final").is_none(), "{vib}");
    // The peak of the estimated vibration against the truth's, computed from the recording.
    let truth = column(&std::fs::read_to_string(&data).unwrap(), "truth_tip_vibration");
    let truth_peak = truth.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let peak = num(&json, &["details", "peak_tip_vibration"]);
    assert!((peak - truth_peak).abs() < 0.05 * truth_peak, "{peak} m against {truth_peak} m");
    assert!(num(&json, &["quantities", "tip_angle", "error", "rms"]) < 0.01, "{}", json["quantities"]["tip_angle"]);

    // The same recording without truth (the command column kept: the model method runs).
    let bare = dir.join("bare.csv");
    std::fs::write(&bare, strip_truth(&std::fs::read_to_string(&data).unwrap())).unwrap();
    let _ = std::fs::remove_file(&est);
    let args = ["boom", "estimate", "--data", path(&bare), "--static", path(&statics), "--out", path(&est)];
    let (json, stderr) = json_run(&[&args[..], &["--plot", path(&svg), "--json"]].concat());
    assert!(stderr.contains("no truth_tip_vibration in the recording"), "{stderr}");
    assert!(est.exists() && estimate_points(&svg) > 100, "{}", std::fs::read_to_string(&svg).unwrap());
    assert!(json["quantities"]["tip_vibration"]["error"].is_null() && json["truth"] == false, "{json:#}");
    assert!((num(&json, &["details", "peak_tip_vibration"]) - peak).abs() < 1e-12, "the same estimate without truth");
}

#[test]
fn json_runs_that_fail_print_no_json() {
    let dir = scratch("fail");
    let est = dir.join("est.csv");
    let missing = dir.join("none.csv");
    for system in ["oscillator", "uuv"] {
        let out = edgekf(&[system, "estimate", "--data", path(&missing), "--out", path(&est), "--json"]);
        assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
        assert!(out.stdout.is_empty() && !est.exists(), "{}", text(&out.stdout));
    }
    // --json takes no value: a usage error.
    let out = edgekf(&["uuv", "estimate", "--data", path(&missing), "--out", path(&est), "--json=yes"]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
}
