//! The `edgekf` binary as a user runs it.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[path = "common/svg_check.rs"]
mod svg_check;

const DEMO_CONFIG: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/oscillator_demo.toml");

fn edgekf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_edgekf")).args(args).env_remove("RUST_BACKTRACE").output().expect("run edgekf")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A fresh directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cli-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The table row starting with `label`, split into cells.
fn row(stdout: &str, label: &str) -> Vec<String> {
    let line = stdout.lines().find(|l| l.starts_with(label)).unwrap_or_else(|| panic!("no `{label}` in\n{stdout}"));
    line[label.len()..].split_whitespace().map(str::to_owned).collect()
}

#[test]
fn demo_prints_the_summary_and_writes_files() {
    let dir = scratch("demo");
    let out = edgekf(&["demo", "--out", path(&dir)]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    // Truth, f64 and f32 columns; the f64 estimate before the step is within 1 mN of 5 N.
    let before = row(&stdout, "force amplitude, mean 3–6 s [N]");
    assert_eq!(before[0], "5.0000");
    let f64_before: f64 = before[1].parse().unwrap();
    assert!((f64_before - 5.0).abs() < 1e-3, "{stdout}");
    assert_eq!(row(&stdout, "force amplitude, mean 9–12 s [N]")[0], "3.0000");
    assert_eq!(row(&stdout, "steps"), ["—", "12000", "12000"]);
    assert!(stdout.contains("noise σ = 4.857 mm/s²"));

    let data = std::fs::read_to_string(dir.join("data.csv")).unwrap();
    assert!(data.starts_with(
        "t,ax,ay,az,fault_nack,fault_timeout,fault_garbage,fault_stuck,fault_drop,fault_reset,truth_x,truth_v,\
         truth_force,truth_force_amplitude,truth_accel\n0,"
    ));
    assert_eq!(data.lines().count(), 12_001);
    let est = std::fs::read_to_string(dir.join("est.csv")).unwrap();
    assert!(est.starts_with("t,force_amplitude,force_cos,force_sin,displacement,velocity,innovation,nis\n"));
    assert_eq!(est.lines().count(), 12_001);
    assert!(dir.join("est_f32.csv").exists());

    // The second part: the residual loop finds the disk the demo made 10 % heavier without
    // saying so, and the error drops from tens of µm to under one.
    assert!(stdout.contains("closing the loop"), "{stdout}");
    assert!(stdout.contains("+ parameter at disk 12 mass: ×1.1"), "{stdout}");
    let err = row(&stdout, "  error RMS n12_y µm");
    let (before, after): (f64, f64) = (err[0].parse().unwrap(), err[1].parse().unwrap());
    assert!(before > 10.0 && after < 1.0, "{before} → {after}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("loop/report.json")).unwrap()).unwrap();
    let factor = report["effects_added"][0]["value"].as_f64().unwrap();
    assert!((factor - 1.10).abs() < 0.02, "{factor}");
    assert!(dir.join("loop/data.csv").exists());
    // The report says where it came from: its command, rerun as printed, makes the same finding.
    let command = report["source"]["command"].as_str().unwrap();
    assert!(report["source"]["data_sha256"].as_str().is_some_and(|h| h.len() == 64), "{}", report["source"]);
    let args: Vec<&str> = command.split_whitespace().skip(1).collect();
    assert_eq!(args[..2], ["loop", "rotor"]);
    let rerun = edgekf(&[&args[..], &["--quiet"]].concat());
    assert!(
        text(&rerun.stdout).contains(&format!("+ parameter at disk 12 mass: ×{factor:.4}")),
        "{}",
        text(&rerun.stdout)
    );

    // The third part: the fast clearance estimator names joint B and sizes its 0.3 mm within
    // ±3 % from the first contact after release; the window features alone are further off.
    assert!(stdout.contains("slider-crank: 0.30 mm of clearance at joint B"), "{stdout}");
    let line = stdout.lines().find(|l| l.trim_start().starts_with("estimate: joint")).expect("the crank estimate line");
    assert!(line.contains("estimate: joint B, 0.29") || line.contains("estimate: joint B, 0.30"), "{line}");
    assert!(line.contains("from the first contact after release"), "{line}");
    let est = std::fs::read_to_string(dir.join("crank/est.csv")).unwrap();
    assert!(est.starts_with("t,clearance_A,clearance_B,clearance_C\n"));
    assert_eq!(est.lines().count(), 1 + 40 + 1);
    assert!(dir.join("crank/data.csv").exists());

    // The fourth and fifth: the boom's undeclared 0.3 s inclinometer lag named within a tenth,
    // the tip's peak error brought under half a percent; the vehicle's undeclared 0.05 m/s²
    // offset on acc_z named within a tenth, the vertical thruster's health error cut tenfold.
    let line = |part: &str| part_line(&stdout, part);
    let lag = number_after(&line("boom —"), "loop adds: sensor_lag at incl_angle ");
    assert!((lag / 300.0 - 1.0).abs() < 0.1, "{lag} ms");
    let peak = numbers_after(&line("boom —"), "tip peak error ");
    assert!(peak[0] > 1.0 && peak[1] < 0.5, "{peak:?}");
    let offset = number_after(&line("vehicle —"), "loop adds: sensor_bias at acc_z ");
    assert!((offset / 0.05 - 1.0).abs() < 0.1, "{offset} m/s²");
    let k_v = numbers_after(&line("vehicle —"), "k_v RMS error ");
    assert!(k_v[0] > 10.0 * k_v[1], "{k_v:?}");
    // Every report the demo writes says where it came from, with files that exist and the
    // data's hash, so it can be rerun; the boom's is, and makes the same finding.
    for part in ["loop", "boom", "uuv"] {
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join(part).join("report.json")).unwrap()).unwrap();
        let source = &report["source"];
        for key in ["data", "config", "command"] {
            assert!(source[key].is_string(), "{part}: source.{key} is {}", source[key]);
        }
        assert!(Path::new(source["config"].as_str().unwrap()).is_file(), "{part}: {source}");
        let data = std::fs::read(source["data"].as_str().unwrap()).unwrap();
        assert_eq!(source["data_sha256"].as_str(), Some(sha256(&data).as_str()), "{part}");
    }
    // Their pages' figures: no empty axes, every series inside its axes, no label on another.
    for part in ["loop", "boom", "uuv"] {
        let defects = svg_check::svg_defects(&std::fs::read_to_string(dir.join(part).join("report.html")).unwrap());
        assert!(defects.is_empty(), "{part}: {}", defects.join("\n"));
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("boom/report.json")).unwrap()).unwrap();
    let args: Vec<&str> = report["source"]["command"].as_str().unwrap().split_whitespace().skip(1).collect();
    let rerun = text(&edgekf(&[&args[..], &["--quiet"]].concat()).stdout);
    assert!(rerun.contains(&format!("+ sensor_lag at incl_angle: {lag:.3} ms")), "{rerun}");
}

/// The lines of the demo's part that starts with `head`, up to the next blank line, as one.
fn part_line(stdout: &str, head: &str) -> String {
    let start = stdout.find(head).unwrap_or_else(|| panic!("no `{head}` part in\n{stdout}"));
    stdout[start..].split("\n\n").next().unwrap_or_default().to_string()
}

/// The numbers right after `label` in `text` (split at spaces, arrows and units).
fn numbers_after(text: &str, label: &str) -> Vec<f64> {
    let at = text.find(label).unwrap_or_else(|| panic!("no `{label}` in\n{text}"));
    let rest = text[at + label.len()..].lines().next().unwrap_or_default();
    rest.split([' ', ';', ','])
        .map_while(|w| if w == "→" || w == "%" { Some(None) } else { w.parse().ok().map(Some) })
        .flatten()
        .collect()
}

/// The first number right after `label` in `text`.
fn number_after(text: &str, label: &str) -> f64 {
    numbers_after(text, label).first().copied().unwrap_or_else(|| panic!("no number after `{label}` in\n{text}"))
}

/// The SHA-256 of `bytes`, hex (as the reports write it).
fn sha256(bytes: &[u8]) -> String {
    edgekf_sim::io::data::hex_sha256(bytes)
}

#[test]
fn simulate_then_estimate_round_trip_with_faults() {
    let dir = scratch("roundtrip");
    let data = dir.join("data.csv");
    let est = dir.join("est.csv");
    let out = edgekf(&["oscillator", "simulate", "--config", DEMO_CONFIG, "--out", path(&data), "--faults"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("12000 samples, seed 1, 7 fault(s)"), "{}", text(&out.stdout));

    let out = edgekf(&["oscillator", "estimate", "--config", DEMO_CONFIG, "--data", path(&data), "--out", path(&est)]);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("12000 rows, sample rate 1000.000000 Hz"), "{stderr}");
    assert!(!stderr.contains("notice"), "a simulator file is clean: {stderr}");
    // The 20 ms of 3 g saturation read as full scale and are bridged as missing samples.
    assert_eq!(row(&stdout, "missing samples (NaN + clipped + gap)"), ["—", "0+20+0"]);
    let before: f64 = row(&stdout, "force amplitude, mean 3–6 s [N]")[1].parse().unwrap();
    assert!((before - 5.0).abs() < 1e-3, "{stdout}");

    let est_text = std::fs::read_to_string(&est).unwrap();
    let mut lines = est_text.lines();
    assert_eq!(lines.next().unwrap(), "t,force_amplitude,force_cos,force_sin,displacement,velocity,innovation,nis");
    // Row for t = 9.005 s: the innovation and NIS of a clipped sample are empty (NaN).
    let clipped: Vec<&str> = lines.nth(9_005).unwrap().split(',').collect();
    assert_eq!((clipped[0], clipped[6], clipped[7]), ("9.005", "NaN", "NaN"));

    // The same data in f32.
    let out = edgekf(&["oscillator", "estimate", "--data", path(&data), "--precision", "f32"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("harmonic-force estimate (f32) with the model of the demo scenario"));
}

#[test]
fn data_notices_go_to_stderr() {
    let dir = scratch("notices");
    let data = dir.join("data.csv");
    // 1.5 s at 1 kHz of a 14 Hz vibration, with a temperature column, two empty cells and 10 ms lost.
    let mut csv = String::from("t,ax,temperature\n");
    for k in (0..1500).filter(|k| !(700..710).contains(k)) {
        let t = k as f64 / 1000.0;
        let ax = if k == 100 || k == 900 { String::new() } else { format!("{}", 4.8 * (87.96 * t).cos()) };
        csv.push_str(&format!("{t},{ax},21.5\n"));
    }
    std::fs::write(&data, csv).unwrap();
    let out = edgekf(&["oscillator", "estimate", "--data", path(&data), "--settle", "0.5"]);
    let stderr = text(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("notice: ignored column `temperature`"), "{stderr}");
    assert!(stderr.contains("notice: column `ax`: 2 empty/NaN cell(s) of 1490"), "{stderr}");
    assert!(stderr.contains("1 gap(s)") && stderr.contains("10 sample(s) missing"), "{stderr}");
    assert_eq!(row(&text(&out.stdout), "missing samples (NaN + clipped + gap)"), ["—", "2+0+10"]);
}

#[test]
fn malformed_files_fail_with_one_clear_line() {
    let dir = scratch("malformed");
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "t,ax\n0,0.1\n0.001,0.2,0.3\n0.002,0.1\n").unwrap();
    let out = edgekf(&["oscillator", "estimate", "--data", path(&bad)]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert_eq!(stderr, format!("error: {}:3: 3 field(s), but the header has 2\n", bad.display()));
    assert!(out.stdout.is_empty());

    std::fs::write(&bad, "time,ax\n0,1\n").unwrap();
    let stderr = text(&edgekf(&["oscillator", "estimate", "--data", path(&bad)]).stderr);
    assert!(stderr.contains("the first column must be `t`"), "{stderr}");

    // Data at 500 Hz against a 1 kHz sensor.
    std::fs::write(&bad, "t,ax\n0,1\n0.002,1\n0.004,1\n").unwrap();
    let stderr = text(&edgekf(&["oscillator", "estimate", "--data", path(&bad)]).stderr);
    // The data report comes first, then the error.
    let last = stderr.lines().last().unwrap();
    assert!(
        last.starts_with("error: ") && last.contains("sampled at 500.000000 Hz but the filter is built for 1000 Hz")
    );

    let missing = dir.join("nope.csv");
    let out = edgekf(&["oscillator", "estimate", "--data", path(&missing)]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("nope.csv: cannot read"));
}

#[test]
fn bad_scenarios_name_the_file_and_field() {
    let dir = scratch("badconfig");
    let cfg = dir.join("c.toml");
    std::fs::write(&cfg, "[sensor]\nodr_hz = 1200.0\n").unwrap();
    let out = edgekf(&["oscillator", "simulate", "--config", path(&cfg), "--out", path(&dir.join("d.csv"))]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(
        stderr.starts_with(&format!("error: {}: invalid scenario: sensor.odr_hz = 1200", cfg.display())),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(!stderr.contains("panicked"));

    std::fs::write(&cfg, "[mode]\nnatural_freq = 20.0\n").unwrap();
    let stderr = text(&edgekf(&["demo", "--config", path(&cfg)]).stderr);
    assert!(stderr.contains("unknown field `natural_freq`"), "{stderr}");
}

#[test]
fn help_explains_the_commands() {
    let out = edgekf(&["--help"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success());
    for word in ["demo", "oscillator", "first column `t` in seconds", "edgekf oscillator estimate --config"] {
        assert!(stdout.contains(word), "{word}: {stdout}");
    }
    let out = edgekf(&["oscillator", "simulate", "--help"]);
    assert!(text(&out.stdout).contains("--faults"));
    // A usage error is clap's: exit 2.
    assert_eq!(edgekf(&["oscillator", "estimate"]).status.code(), Some(2));
    // Each system's loop and baseline says what it does, not the doc of the flags it shares.
    for args in [["loop", "--help"], ["baseline", "--help"]] {
        let help = text(&edgekf(&args).stdout);
        assert!(
            help.contains("rotor  ") && !help.contains("The flags of every") && !help.contains("own flag"),
            "{help}"
        );
    }
    let help = text(&edgekf(&["rotor", "export", "--help"]).stdout);
    assert!(help.contains("the one the accelerometer node runs"), "{help}");
}

#[test]
fn uuv_simulate_then_estimate_writes_the_issues_columns() {
    let dir = scratch("uuv");
    let data = dir.join("paper.csv");
    let est = dir.join("est.csv");
    let out =
        edgekf(&["uuv", "simulate", "--scenario", "paper", "--duration", "225", "--seed", "4", "--out", path(&data)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let csv = std::fs::read_to_string(&data).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(
        header[..16],
        [
            "t",
            "acc_x",
            "acc_y",
            "acc_z",
            "gyro_x",
            "gyro_y",
            "gyro_z",
            "depth",
            "heading",
            "dvl_u",
            "dvl_v",
            "dvl_w",
            "cmd_n_t",
            "cmd_n_v",
            "cmd_rudder",
            "cmd_elevator"
        ]
    );
    // The DVL is a 5 Hz channel in 50 Hz rows: empty between its readings.
    let second: Vec<&str> = csv.lines().nth(2).unwrap().split(',').collect();
    assert_eq!((second[9], second[10], second[11]), ("", "", ""));
    // Health states switched off for the vertical thruster: its columns stay empty.
    let config = dir.join("main_only.toml");
    std::fs::write(&config, "[estimator]\nhealth = [\"main\"]\n").unwrap();
    let out = edgekf(&["uuv", "estimate", "--config", path(&config), "--data", path(&data), "--out", path(&est)]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    // The DVL's three channels are one sensor at a fifth of the rate: said once, and their
    // empty cells between updates are not counted as missing.
    let stderr = text(&out.stderr);
    assert!(stderr.contains("`dvl_u`, `dvl_v`, `dvl_w` are updated every 10 rows"), "{stderr}");
    assert!(!stderr.contains("dvl_u`: ") && stderr.matches("notice:").count() == 1, "{stderr}");
    assert!(stdout.contains("vertical thruster: no health state"), "{stdout}");
    let table = std::fs::read_to_string(&est).unwrap();
    let mut lines = table.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header[..19],
        [
            "t", "k_t", "k_v", "k_t_std", "k_v_std", "status_t", "status_v", "x", "y", "z", "phi", "theta", "psi", "u",
            "v", "w", "p", "q", "r"
        ]
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 225 * 50);
    // Healthy before the fault at 220 s, failed a second after it; k_v and status_v empty.
    let at = |t: f64| &rows[(t * 50.0) as usize];
    assert_eq!((at(219.0)[5], at(221.0)[5]), ("healthy", "failed"));
    assert_eq!((at(221.0)[2], at(221.0)[6]), ("", ""));
    let k_t: f64 = at(224.0)[1].parse().unwrap();
    assert!((k_t - 0.1).abs() < 0.1, "k_t = {k_t} at 224 s");
    // The recording is never an output.
    let out = edgekf(&["uuv", "estimate", "--data", path(&data), "--out", path(&data)]);
    assert!(!out.status.success());
    assert_eq!(std::fs::read_to_string(&data).unwrap(), csv);
}

#[test]
fn boom_simulate_then_estimate_writes_the_issues_columns() {
    let dir = scratch("boom");
    let (data, statics, est) = (dir.join("luffing.csv"), dir.join("static.csv"), dir.join("est.csv"));
    let out = edgekf(&[
        "boom",
        "simulate",
        "--scenario",
        "luffing",
        "--duration",
        "40",
        "--out",
        path(&data),
        "--static",
        path(&statics),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let csv = std::fs::read_to_string(&data).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(
        header,
        [
            "t",
            "gyro_rate",
            "incl_angle",
            "boom_length",
            "luff_rate_cmd",
            "truth_tip_angle",
            "truth_tip_deflection",
            "truth_tip_vibration",
            "truth_root_angle",
            "truth_root_rate",
            "truth_gyro_bias"
        ]
    );
    // The model-based filter is the default; the peak errors are printed against the truth.
    assert_eq!(std::fs::read_to_string(&statics).unwrap().lines().next(), Some("t,gyro_rate,incl_angle"));
    let svg = dir.join("vibration.svg");
    let args = ["boom", "estimate", "--data", path(&data), "--static", path(&statics), "--out", path(&est)];
    let out = edgekf(&[&args[..], &["--plot", path(&svg)]].concat());
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    let table = std::fs::read_to_string(&est).unwrap();
    let mut lines = table.lines();
    assert_eq!(lines.next().unwrap(), "t,tip_angle,tip_vibration,tip_deflection");
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), 4000);
    // At rest at 0.5 rad before the first move: the tip below the root's line by the sag.
    assert!((rows[150][1] - 0.5).abs() < 0.1 && rows[150][3] < -0.05 && rows[150][2].abs() < 0.005, "{:?}", rows[150]);
    let cells = row(&stdout, "peak error over");
    let mean: f64 = cells[cells.iter().position(|c| c == "mean").unwrap() + 1].parse().unwrap();
    assert!(mean < 2.0, "{stdout}");
    assert!(std::fs::read_to_string(&svg).unwrap().contains("Boom tip vibration against truth"));
    // Without the command column the model cannot run; the paper's method can.
    let no_cmd = dir.join("no_cmd.csv");
    let stripped: String = csv.lines().map(|l| l.splitn(6, ',').take(4).collect::<Vec<_>>().join(",") + "\n").collect();
    std::fs::write(&no_cmd, stripped).unwrap();
    let out = edgekf(&["boom", "estimate", "--data", path(&no_cmd), "--static", path(&statics), "--out", path(&est)]);
    assert!(!out.status.success() && text(&out.stderr).contains("luff_rate_cmd"), "{}", text(&out.stderr));
    // A recording without truth (every real one) is drawn alone, and its estimate written.
    let args = ["boom", "estimate", "--data", path(&no_cmd), "--static", path(&statics), "--method", "paper"];
    let _ = std::fs::remove_file(&est);
    let out = edgekf(&[&args[..], &["--out", path(&est), "--plot", path(&svg)]].concat());
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("(the recording has no truth_tip_vibration)"), "{}", text(&out.stdout));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("no truth in the recording") && est.exists());
    // The recording is never an output.
    let out = edgekf(&["boom", "estimate", "--data", path(&data), "--static", path(&statics), "--out", path(&data)]);
    assert!(!out.status.success());
    assert_eq!(std::fs::read_to_string(&data).unwrap(), csv);
}

#[test]
fn loop_boom_names_an_undeclared_inclinometer_lag() {
    let dir = scratch("loop-boom");
    let (data, statics, report) = (dir.join("luffing.csv"), dir.join("static.csv"), dir.join("report"));
    let out = edgekf(&[
        "boom",
        "simulate",
        "--scenario",
        "luffing",
        "--duration",
        "60",
        "--out",
        path(&data),
        "--static",
        path(&statics),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // The configuration says the inclinometer has no lag; the simulated one lags by 0.3 s.
    let config = dir.join("no_lag.toml");
    let shipped = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/boom_ladder30.toml")).unwrap();
    let no_lag = shipped
        .replace("lag = 0.30\n", "lag = 0.0\n")
        .replace("[sim.inclinometer]\n", "[sim.inclinometer]\nlag = 0.30\n");
    assert!(no_lag.contains("lag = 0.0\n") && no_lag != shipped);
    std::fs::write(&config, no_lag).unwrap();
    let c = path(&config);
    let fixed = dir.join("fixed.toml");
    let args = ["loop", "boom", "--config", c, "--data", path(&data), "--static", path(&statics), "--report"];
    let out = edgekf(&[&args[..], &[path(&report), "--quiet", "--corrected-config", path(&fixed)]].concat());
    assert!(out.status.success(), "{}\n{}", text(&out.stdout), text(&out.stderr));
    // The boom's own figure is on stdout, and the lag went into the corrected configuration.
    assert!(text(&out.stdout).contains("peak_error_pct") && text(&out.stdout).contains("1 of 1 effects carried"));
    let corrected: toml::Table = std::fs::read_to_string(&fixed).unwrap().parse().unwrap();
    let lag = corrected["inclinometer"]["lag"].as_float().unwrap();
    assert!((lag - 0.3).abs() < 0.06 && corrected["sim"]["inclinometer"]["lag"].as_float() == Some(0.3), "{lag}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("report.json")).unwrap()).unwrap();
    assert_eq!(json["system"], "boom");
    let added = &json["effects_added"][0];
    assert_eq!(
        (added["kind"].as_str(), added["location"].as_str()),
        (Some("sensor_lag"), Some("incl_angle")),
        "{json}"
    );
    assert!((added["value"].as_f64().unwrap() - 0.3).abs() < 0.06, "{added}");
    let (before, after) =
        (json["before"]["peak_error_pct"].as_f64().unwrap(), json["after"]["peak_error_pct"].as_f64().unwrap());
    assert!(after < 0.5 * before, "peak error {before} % → {after} %");
    // The loop again with the corrected configuration: nothing left to add.
    let again = dir.join("again");
    let args = ["loop", "boom", "--config", path(&fixed), "--data", path(&data), "--static", path(&statics)];
    let out = edgekf(&[&args[..], &["--report", path(&again), "--quiet"]].concat());
    assert!(out.status.success() && text(&out.stdout).contains("0 effect(s) added"), "{}", text(&out.stdout));
    // Without --static the loop says what it needs.
    let out = edgekf(&["loop", "boom", "--config", c, "--data", path(&data), "--report", path(&dir.join("r2"))]);
    assert!(!out.status.success() && text(&out.stderr).contains("--static"), "{}", text(&out.stderr));
}

#[test]
fn loop_uuv_names_an_undeclared_offset_and_reports_the_declared_model() {
    let dir = scratch("loop-uuv");
    let (config, data, report) = (dir.join("no_biases.toml"), dir.join("healthy.csv"), dir.join("report"));
    // An accelerometer offset on z that the estimator does not carry (it pulls k_v off).
    std::fs::write(
        &config,
        "[sensors]\nacc_bias = 0.0\ngyro_bias = 0.0\nacc_offset = [0.0, 0.0, 0.05]\n\n[estimator]\nsensor_biases = false\n",
    )
    .unwrap();
    let c = path(&config);
    let out = edgekf(&["uuv", "simulate", "--config", c, "--scenario", "healthy", "--duration", "60", "--seed", "5"]);
    assert!(!out.status.success(), "--out is required");
    let out = edgekf(&[
        "uuv",
        "simulate",
        "--config",
        c,
        "--scenario",
        "healthy",
        "--duration",
        "60",
        "--seed",
        "5",
        "--out",
        path(&data),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let fixed = dir.join("fixed.toml");
    let args = ["loop", "uuv", "--config", c, "--data", path(&data), "--report", path(&report), "--quiet"];
    let out = edgekf(&[&args[..], &["--corrected-config", path(&fixed)]].concat());
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    assert!(stdout.contains("+ sensor_bias at acc_z"), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("report.json")).unwrap()).unwrap();
    assert_eq!(json["system"], "uuv");
    assert_eq!(json["declared"][0], "actuator_health at thruster main");
    assert_eq!(json["effects_added"].as_array().map(Vec::len), Some(1), "{}", json["effects_added"]);
    let value = json["effects_added"][0]["value"].as_f64().unwrap();
    assert!((value - 0.05).abs() < 0.01, "{value}");
    // The vertical thruster's factor had taken up the offset.
    let k_v = |run: &str| json[run]["error_rms"]["k_v"].as_f64().unwrap();
    assert!(k_v("before") > 0.2 && k_v("after") < 0.05, "k_v RMS error {} → {}", k_v("before"), k_v("after"));
    assert!(report.join("report.html").exists());
    // The corrected configuration has the estimator carry the IMU's biases; with it the loop
    // adds nothing to the same recording.
    let corrected: toml::Table = std::fs::read_to_string(&fixed).unwrap().parse().unwrap();
    assert_eq!(corrected["estimator"]["sensor_biases"].as_bool(), Some(true));
    let again = dir.join("again");
    let out =
        edgekf(&["loop", "uuv", "--config", path(&fixed), "--data", path(&data), "--report", path(&again), "--quiet"]);
    assert!(out.status.success() && text(&out.stdout).contains("0 effect(s) added"), "{}", text(&out.stdout));
}
