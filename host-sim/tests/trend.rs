//! `edgekf loop <system> --data FOLDER` as a user runs it: a machine's history from a folder
//! of recordings (`trend.csv`, `trend.html`, one report per recording).
//!
//! The history is synthetic: 30 recordings of the oscillator's reference simulator (4 s each,
//! ADXL355 noise at a seed of its own, the load and its phase varying from one recording to
//! the next), with a second harmonic of the force growing by 0.02 N per recording and an
//! accelerometer offset that appears at recording 20. The trend must name recording 20 as
//! the offset's first and give the growth within 10 %.

use edgekf_sim::systems::oscillator::scenario::Scenario;
use edgekf_sim::trend::synthetic::{recording, DECLARED, HARMONIC, OFFSET, OFFSET_FROM, RECORDINGS};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Instant;

#[path = "common/svg_check.rs"]
mod svg_check;

/// A fresh folder under the test's scratch space.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The synthetic history's recordings `1..=n` in `root` (`trend::synthetic`).
fn write_history(root: &Path, n: usize) -> (PathBuf, PathBuf) {
    edgekf_sim::trend::synthetic::write_history(root, n).unwrap()
}

/// `edgekf loop oscillator --config config --data data --report report` with `extra` flags.
fn edgekf_loop(config: &Path, data: &Path, report: &Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_edgekf"))
        .args(["loop", "oscillator", "--config"])
        .arg(config)
        .arg("--data")
        .arg(data)
        .arg("--report")
        .arg(report)
        .args(extra)
        .output()
        .expect("run edgekf")
}

/// `trend.csv` as a header and rows of optional numbers.
fn read_trend(path: &Path) -> (Vec<String>, Vec<Vec<Option<f64>>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(str::to_string).collect();
    let rows = lines
        .map(|l| l.split(',').map(|c| if c.is_empty() { None } else { Some(c.parse().unwrap()) }).collect())
        .collect();
    (header, rows)
}

/// The least-squares slope of the points.
fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (mx, my) = (points.iter().map(|p| p.0).sum::<f64>() / n, points.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    sxy / points.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>()
}

#[test]
fn the_history_names_where_the_offset_appears_and_how_fast_the_harmonic_grows() {
    let root = scratch("trend-history");
    let (data, config) = write_history(&root, RECORDINGS);
    let report = root.join("out");
    let started = Instant::now();
    let out = edgekf_loop(&config, &data, &report, &["--quiet"]);
    let seconds = started.elapsed().as_secs_f64();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    let (header, rows) = read_trend(&report.join("trend.csv"));
    assert_eq!(rows.len(), RECORDINGS);
    let column = |name: &str| header.iter().position(|c| c == name).unwrap_or_else(|| panic!("{name}: {header:?}"));
    let (t, offset, harmonic) = (column("t"), column("sensor_bias_ax"), column("harmonic_force_mode_2x"));
    // The offset: absent before recording 20, present from it on, at its size.
    let first = rows.iter().position(|r| r[offset].is_some()).map(|i| rows[i][t].unwrap());
    assert_eq!(first, Some(OFFSET_FROM as f64), "{stdout}");
    for r in &rows[OFFSET_FROM - 1..] {
        assert!((r[offset].unwrap() / OFFSET - 1.0).abs() < 0.1, "{r:?}");
    }
    assert!(
        stdout.contains(&format!("sensor_bias_ax: first in recording {OFFSET_FROM} (day{OFFSET_FROM})")),
        "{stdout}"
    );
    // The harmonic: its growth per recording from the history's own columns.
    let points: Vec<(f64, f64)> = rows.iter().filter_map(|r| Some((r[t]?, r[harmonic]?))).collect();
    let growth = slope(&points);
    eprintln!(
        "offset first in recording {first:?}; harmonic in {} of {RECORDINGS} recordings, growth {growth:.5} N per recording \
         (truth {}, {:+.2} %); {seconds:.1} s for {RECORDINGS} recordings",
        points.len(),
        HARMONIC.1,
        (growth / HARMONIC.1 - 1.0) * 100.0
    );
    assert!(points.len() >= RECORDINGS - 2, "{points:?}");
    assert!((growth / HARMONIC.1 - 1.0).abs() < 0.1, "growth {growth} N per recording, truth {}", HARMONIC.1);
    // The page names the same, and every recording has its report.
    let html = std::fs::read_to_string(report.join("trend.html")).unwrap();
    let row = format!("<td>sensor_bias_ax</td><td>m/s^2</td><td>recording {OFFSET_FROM} (day{OFFSET_FROM})</td>");
    assert!(html.contains(&row), "{row}");
    for k in [1, OFFSET_FROM, RECORDINGS] {
        assert!(report.join(format!("day{k:02}")).join("report.json").is_file(), "day{k:02}");
    }
    // The history's figure and an oscillator report's: no empty axes, every series inside its
    // axes, no label on another.
    for page in [report.join("trend.html"), report.join(format!("day{OFFSET_FROM}/report.html"))] {
        let defects = svg_check::svg_defects(&std::fs::read_to_string(&page).unwrap());
        assert!(defects.is_empty(), "{}: {}", page.display(), defects.join("\n"));
    }
}

#[test]
fn a_small_folder_gives_a_trend_row_per_recording_and_names_the_file_that_failed() {
    let root = scratch("trend-cli");
    let (data, config) = write_history(&root, 3);
    let report = root.join("out");
    let out = edgekf_loop(&config, &data, &report, &["--quiet"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (header, rows) = read_trend(&report.join("trend.csv"));
    assert_eq!(header[0], "t");
    assert_eq!(&header[header.len() - 2..], ["nis_before", "nis_after"]);
    assert!(header.contains(&"harmonic_force_mode_2x".to_string()), "{header:?}");
    assert_eq!(rows.iter().map(|r| r[0]).collect::<Vec<_>>(), [Some(1.0), Some(2.0), Some(3.0)]);
    assert!(rows.iter().all(|r| r.len() == header.len()));
    // Each recording's report is the one a single run writes.
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("day02/report.json")).unwrap()).unwrap();
    assert!(v["source"]["data"].as_str().unwrap().ends_with("day02.csv"), "{}", v["source"]);
    // Its command reruns that recording alone, into its own folder.
    let command = v["source"]["command"].as_str().unwrap();
    let expected = format!("--data {} --report {}", data.join("day02.csv").display(), report.join("day02").display());
    assert!(command.contains(&expected), "{command}");
    assert!(report.join("day02/report.html").is_file());

    // A malformed file: the others still make the history, the command names it and fails.
    std::fs::write(data.join("day04.csv"), "t,ax\n0.0,0.1\n0.001,not-a-number\n").unwrap();
    let out = edgekf_loop(&config, &data, &report, &["--quiet"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("failed: day04: "),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(stderr.contains("1 of 4 recordings failed") && stderr.contains("day04"), "{stderr}");
    let (_, rows) = read_trend(&report.join("trend.csv"));
    assert_eq!(rows.len(), 3);
    assert!(std::fs::read_to_string(report.join("trend.html")).unwrap().contains("day04"));
}

/// Recordings whose `t` is absolute (s since 1970) are ordered by it, whatever their names,
/// and the growth is also given per day.
#[test]
fn absolute_starts_order_the_history_and_give_a_rate_per_day() {
    let root = scratch("trend-absolute");
    let data = root.join("data");
    std::fs::create_dir_all(&data).unwrap();
    let config = root.join("declared.toml");
    std::fs::write(&config, DECLARED).unwrap();
    // 2023-11-14 22:13:20 UTC, then one recording a day; the names sort against time.
    let day0 = 1.7e9;
    for (k, name) in [(1, "c"), (2, "b"), (3, "a")] {
        let mut file = recording(k).simulate().to_data_file();
        let start = day0 + 86_400.0 * (k - 1) as f64;
        file.t.iter_mut().for_each(|t| *t += start);
        std::fs::write(data.join(format!("{name}.csv")), file.to_csv_string().unwrap()).unwrap();
    }
    let report = root.join("out");
    let out = edgekf_loop(&config, &data, &report, &["--quiet"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (header, rows) = read_trend(&report.join("trend.csv"));
    assert_eq!(
        rows.iter().map(|r| r[0]).collect::<Vec<_>>(),
        [Some(day0), Some(day0 + 86_400.0), Some(day0 + 172_800.0)]
    );
    let harmonic = header.iter().position(|c| c == "harmonic_force_mode_2x").unwrap();
    let values: Vec<f64> = rows.iter().map(|r| r[harmonic].unwrap()).collect();
    assert!(values.windows(2).all(|w| w[1] > w[0]), "ordered by time, the harmonic grows: {values:?}");
    let per_day = stdout.split("per recording, ").nth(1).and_then(|s| s.split(" per day").next());
    let per_day: f64 = per_day.unwrap_or_else(|| panic!("{stdout}")).parse().unwrap();
    assert!((per_day / HARMONIC.1 - 1.0).abs() < 0.1, "{per_day} N per day, truth {}", HARMONIC.1);
    assert!(stdout.contains("first in recording 1 (c)"), "{stdout}");
}

/// With a healthy baseline, the history carries each level's ratio to it: the growing second
/// harmonic, which the baseline's recording lacks, raises the declared model's innovations.
#[test]
fn with_a_baseline_the_history_carries_the_ratios_to_it() {
    let root = scratch("trend-baseline");
    let (data, config) = write_history(&root, 3);
    let healthy = root.join("healthy.csv");
    std::fs::write(&healthy, Scenario { duration_s: 4.0, seed: 999, ..Scenario::default() }.simulate().to_csv_string())
        .unwrap();
    let baseline = root.join("healthy.toml");
    let learnt = Command::new(env!("CARGO_BIN_EXE_edgekf"))
        .args(["baseline", "oscillator", "--quiet", "--config"])
        .arg(&config)
        .arg("--data")
        .arg(&healthy)
        .arg("--out")
        .arg(&baseline)
        .output()
        .unwrap();
    assert!(learnt.status.success(), "{}", String::from_utf8_lossy(&learnt.stderr));
    let report = root.join("out");
    let out = edgekf_loop(&config, &data, &report, &["--quiet", "--baseline", baseline.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (header, rows) = read_trend(&report.join("trend.csv"));
    let ratio = header.iter().position(|c| c == "ratio_innovation_rms_ax").unwrap_or_else(|| panic!("{header:?}"));
    assert_eq!(rows.len(), 3);
    for r in &rows {
        assert!(r[ratio].is_some_and(|v| v > 1.0), "{r:?}");
    }
}

#[test]
fn a_folder_without_recordings_is_a_usage_error() {
    let root = scratch("trend-empty");
    let (data, config) = (root.join("data"), root.join("declared.toml"));
    std::fs::create_dir_all(&data).unwrap();
    std::fs::write(data.join("notes.txt"), "not a recording").unwrap();
    std::fs::write(&config, DECLARED).unwrap();
    let out = edgekf_loop(&config, &data, &root.join("out"), &[]);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("no *.csv recording") && stderr.contains("Usage: edgekf loop oscillator"), "{stderr}");
    assert!(!root.join("out").exists(), "nothing written");
    // One file cannot carry many recordings' corrections: a usage error too.
    std::fs::write(data.join("a.csv"), recording(1).simulate().to_csv_string()).unwrap();
    let out = edgekf_loop(&config, &data, &root.join("out"), &["--corrected-config", "fixed.toml"]);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    // The report folder may not be the data folder (the history would be read back as a recording).
    let out = edgekf_loop(&config, &data, &data, &[]);
    assert_eq!(out.status.code(), Some(1));
    assert!(!data.join("trend.csv").exists());
    // A pattern picks the recordings: none matched is a usage error; a report folder holding
    // the recordings is refused; `a*.csv` runs a.csv and not the others.
    let out = edgekf_loop(&config, &data.join("z*.csv"), &root.join("out"), &[]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no file matches the pattern"));
    let out = edgekf_loop(&config, &data.join("*.csv"), &data, &[]);
    assert_eq!(out.status.code(), Some(1));
    assert!(!data.join("trend.csv").exists());
    std::fs::write(data.join("b.csv"), "t,ax\nnot a recording").unwrap();
    let out = edgekf_loop(&config, &data.join("a*.csv"), &root.join("out"), &["--quiet"]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let trend = std::fs::read_to_string(root.join("out/trend.csv")).unwrap();
    assert_eq!(trend.lines().count(), 2, "{trend}");
    assert!(root.join("out/a/report.json").exists() && !root.join("out/b").exists());
}
