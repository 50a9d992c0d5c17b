//! One timeline for every path: rows deleted from a recording (a 21 ms gap, a 0.5 s gap and 1 %
//! of the rows at random) give the same estimates as the same recording with those samples
//! left as empty cells, on the rotor, the oscillator and the crank's fast estimator (whose
//! estimate stays that of the clean recording); the crank's UKF, legacy map and spectral feature,
//! which need every sample, refuse both alike. The rotor's loop adds nothing to the damaged clean
//! recording.

use edgekf_sim::io::data::{self, DataFile};
use rand::{Rng, SeedableRng};
use std::path::{Path, PathBuf};
use std::process::Command;

const CONFIGS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/configs");

fn edgekf(args: &[&str]) -> std::process::Output {
    let o = Command::new(env!("CARGO_BIN_EXE_edgekf")).args(args).output().unwrap();
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    o
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("edgekf-timeline-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The rows lost: 21 ms from 0.5 s, 500 ms from 1.2 s, those at the times `also` holds, and 1 %
/// of the others at random.
fn lost_rows(t: &[f64], also: fn(f64) -> bool) -> Vec<bool> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    t.iter()
        .enumerate()
        .map(|(k, &tk)| {
            (0.5..0.521).contains(&tk) || (1.2..1.7).contains(&tk) || also(tk) || (k > 0 && rng.gen_bool(0.01))
        })
        .collect()
}

/// `path` twice: with the lost rows ([`lost_rows`]) deleted, and with their channels (not
/// `truth_`) emptied.
fn damaged(path: &Path, dir: &Path) -> (PathBuf, PathBuf) {
    damaged_also(path, dir, |_| false)
}

/// [`damaged`], the rows at the times `also` holds lost too.
fn damaged_also(path: &Path, dir: &Path, also: fn(f64) -> bool) -> (PathBuf, PathBuf) {
    let file = read_all(path);
    let lost = lost_rows(&file.t, also);
    let deleted = rows_of(&file, &(0..file.len()).filter(|&k| !lost[k]).collect::<Vec<_>>());
    let mut emptied = file.clone();
    for (name, c) in emptied.names.iter().zip(&mut emptied.columns) {
        if !name.starts_with("truth_") {
            for (v, &l) in c.iter_mut().zip(&lost) {
                if l {
                    *v = f64::NAN;
                }
            }
        }
    }
    (write_all(&deleted, dir.join("deleted.csv")), write_all(&emptied, dir.join("emptied.csv")))
}

/// Every column of a data CSV.
fn read_all(path: &Path) -> DataFile {
    data::read(path, &header(path).iter().map(String::as_str).collect::<Vec<_>>()).unwrap().0
}

/// The rows `keep` of `f`.
fn rows_of(f: &DataFile, keep: &[usize]) -> DataFile {
    DataFile {
        sha256: None,
        names: f.names.clone(),
        t: keep.iter().map(|&k| f.t[k]).collect(),
        columns: f.columns.iter().map(|c| keep.iter().map(|&k| c[k]).collect()).collect(),
    }
}

/// Writes `f` as a data CSV at `path`, and returns `path`.
fn write_all(f: &DataFile, path: PathBuf) -> PathBuf {
    let names: Vec<&str> = f.names.iter().map(String::as_str).collect();
    let cols: Vec<&[f64]> = f.columns.iter().map(Vec::as_slice).collect();
    data::write(&path, &names, &f.t, &cols).unwrap();
    path
}

/// The column names of a CSV's header.
fn header(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines().next().unwrap().split(',').map(str::to_owned).collect()
}

/// The two estimate files hold the same values on the same clock.
fn same_estimates(a: &Path, b: &Path) {
    let names = header(a);
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let (ea, _) = data::read(a, &names).unwrap();
    let (eb, _) = data::read(b, &names).unwrap();
    assert_eq!(ea.names, eb.names);
    assert_eq!(ea.len(), eb.len(), "one row per sample, lost ones included");
    for (x, y) in ea.t.iter().zip(&eb.t) {
        assert!((x - y).abs() < 1e-9, "{x} vs {y}");
    }
    for ((name, x), y) in ea.names.iter().zip(&ea.columns).zip(&eb.columns) {
        for (k, (u, v)) in x.iter().zip(y).enumerate() {
            assert!(u == v || (u.is_nan() && v.is_nan()), "{name} row {k}: {u} vs {v}");
        }
    }
}

#[test]
fn the_rotor_bridges_deleted_rows_as_empty_cells() {
    let dir = scratch("rotor");
    let config = format!("{CONFIGS}/rotor_paper.toml");
    let clean = dir.join("clean.csv");
    edgekf(&["rotor", "simulate", "--config", &config, "--duration", "2.5", "--out", clean.to_str().unwrap()]);
    let (deleted, emptied) = damaged(&clean, &dir);
    let run = |data: &Path, out: &str| {
        let out = dir.join(out);
        let o = edgekf(&[
            "rotor",
            "estimate",
            "--config",
            &config,
            "--data",
            data.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        (out, String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (a, _, notices) = run(&deleted, "a.csv");
    let (b, _, _) = run(&emptied, "b.csv");
    assert!(notices.contains("gap(s) bridged"), "{notices}");
    same_estimates(&a, &b);
    // The loop reads the gaps as missing samples too, not as something the model lacks.
    let report = dir.join("report");
    let args = ["loop", "rotor", "--config", &config, "--data", deleted.to_str().unwrap(), "--report"];
    edgekf(&[&args[..], &[report.to_str().unwrap(), "--quiet"]].concat());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("report.json")).unwrap()).unwrap();
    assert_eq!(json["effects_added"].as_array().map(Vec::len), Some(0), "{}", json["effects_added"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_oscillator_bridges_deleted_rows_as_empty_cells() {
    let dir = scratch("oscillator");
    let clean = dir.join("clean.csv");
    edgekf(&["oscillator", "simulate", "--out", clean.to_str().unwrap()]);
    let (deleted, emptied) = damaged(&clean, &dir);
    for (data, out) in [(&deleted, "a.csv"), (&emptied, "b.csv")] {
        edgekf(&["oscillator", "estimate", "--data", data.to_str().unwrap(), "--out", dir.join(out).to_str().unwrap()]);
    }
    same_estimates(&dir.join("a.csv"), &dir.join("b.csv"));
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs `edgekf args…` expecting exit 1 and no file at `out`; returns the error line.
fn refused(args: &[&str], out: &Path) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_edgekf")).args(args).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    assert!(!out.exists(), "{args:?} wrote {}", out.display());
    let line = err.lines().last().unwrap_or_default().to_owned();
    assert!(line.starts_with("error: "), "{err}");
    line
}

/// The crank's clearance from its fast estimator's estimate file: (named joint, clearance, m)
/// of the last row, the whole recording's (read as text: when the recording ends with a
/// window, that row repeats the window's `t`).
fn crank_estimate(path: &Path) -> (usize, f64) {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.starts_with("t,clearance_A,clearance_B,clearance_C\n"), "{text}");
    let last: Vec<f64> = text.lines().last().unwrap().split(',').skip(1).map(|c| c.parse().unwrap()).collect();
    let joint = (0..3).find(|&j| last[j] > 0.0).expect("a joint named");
    (joint, last[joint])
}

/// The fast estimator (the node's): deleted rows and emptied cells give identical estimate
/// files, and the clearance stays the clean recording's. 3 s at A = 0.25 mm (12 windows), the
/// rows of 2.0–2.5 ms lost too: before the first contact (~7 ms), whose time the release stage
/// reads, so a detector that lost the time of missing samples would read the clearance ~11 %
/// low (measured by hand).
#[test]
fn the_crank_bridges_deleted_rows_as_empty_cells() {
    let dir = scratch("crank");
    let clean = dir.join("clean.csv");
    edgekf(&["crank", "simulate", "--clearance", "A=0.25e-3", "--duration", "3", "--out", clean.to_str().unwrap()]);
    let (deleted, emptied) = damaged_also(&clean, &dir, |t| (0.002..0.0025).contains(&t));
    let run = |data: &Path, out: &str| {
        let out = dir.join(out);
        let args = ["crank", "estimate", "--method", "fast", "--data", data.to_str().unwrap(), "--out"];
        let o = edgekf(&[&args[..], &[out.to_str().unwrap()]].concat());
        (out, String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (c, _) = run(&clean, "c.csv");
    let (a, notices) = run(&deleted, "a.csv");
    let (b, _) = run(&emptied, "b.csv");
    assert!(notices.contains("gap(s) bridged"), "{notices}");
    same_estimates(&a, &b);
    let ((j_clean, c_clean), (j_bridged, c_bridged)) = (crank_estimate(&c), crank_estimate(&a));
    eprintln!(
        "crank, joint A 0.25 mm, 3 s: clean names {} {:.4} mm, bridged names {} {:.4} mm ({:+.2} %)",
        ["A", "B", "C"][j_clean],
        c_clean * 1e3,
        ["A", "B", "C"][j_bridged],
        c_bridged * 1e3,
        (c_bridged / c_clean - 1.0) * 100.0
    );
    assert_eq!((j_clean, j_bridged), (0, 0));
    assert!((c_bridged / c_clean - 1.0).abs() < 0.03, "{c_bridged} vs {c_clean}");
    assert!((c_clean / 0.25e-3 - 1.0).abs() < 0.03, "{c_clean}");

    // A gap longer than `[timeline] max_gap_s` ends the run there, with a notice: the estimate
    // is the one of the recording up to the gap.
    let config = dir.join("short_gaps.toml");
    std::fs::write(&config, "[timeline]\nmax_gap_s = 0.3\n").unwrap();
    let cut = dir.join("cut.csv");
    let args = ["crank", "estimate", "--method", "fast", "--config", config.to_str().unwrap(), "--data"];
    let o = edgekf(&[&args[..], &[deleted.to_str().unwrap(), "--out", cut.to_str().unwrap()]].concat());
    let notices = String::from_utf8_lossy(&o.stderr);
    assert!(notices.contains("longer than timeline.max_gap_s") && notices.contains("not used"), "{notices}");
    // The same rows, up to the last one the deleted file kept before 1.2 s, as empty cells.
    let last = read_all(&deleted).t.into_iter().filter(|&t| t < 1.2).fold(0.0, f64::max);
    let emptied = read_all(&emptied);
    let before = rows_of(&emptied, &(0..emptied.len()).filter(|&k| emptied.t[k] <= last).collect::<Vec<_>>());
    let (up_to_gap, _) = run(&write_all(&before, dir.join("before.csv")), "before_est.csv");
    same_estimates(&cut, &up_to_gap);
    std::fs::remove_dir_all(&dir).ok();
}

/// The crank's UKF, its legacy impact-rate map and `crank feature` take spectra and statistics
/// of whole windows: a deleted row and an emptied cell are refused alike, with the file and the
/// first missing sample's time, before any simulation.
#[test]
fn the_crank_spectra_refuse_missing_samples_however_they_are_lost() {
    let dir = scratch("crank-spectra");
    let clean = dir.join("clean.csv");
    edgekf(&["crank", "simulate", "--clearance", "A=0.25e-3", "--duration", "1", "--out", clean.to_str().unwrap()]);
    let (deleted, emptied) = damaged(&clean, &dir);
    let legacy = dir.join("legacy.toml");
    std::fs::write(&legacy, "impact_rate = [701.1, 296.3]\nclearance = [0.05e-3, 0.5e-3]\n").unwrap();
    let out = dir.join("est.csv");
    let first_missing = {
        let (d, _) = data::read(&deleted, &["crank_alpha"]).unwrap();
        let k = d.t.windows(2).position(|w| w[1] - w[0] > 1.5e-4).unwrap();
        format!("t = {:.6} s", d.t[k] + 1e-4)
    };
    for method in [&["--method", "ukf"][..], &["--method", "fast", "--model", legacy.to_str().unwrap()]] {
        let mut lines = Vec::new();
        for data in [&deleted, &emptied] {
            let args = [
                &["crank", "estimate", "--data", data.to_str().unwrap(), "--out"][..],
                &[out.to_str().unwrap()],
                method,
            ];
            let line = refused(&args.concat(), &out);
            assert!(line.contains(data.to_str().unwrap()) && line.contains(&first_missing), "{line}");
            assert!(line.contains("--method fast"), "{line}");
            lines.push(line.replace(data.to_str().unwrap(), "DATA"));
        }
        assert_eq!(lines[0], lines[1], "deleted rows and empty cells refused alike");
    }
    for data in [&deleted, &emptied] {
        let line = refused(&["crank", "feature", "--data", data.to_str().unwrap()], &out);
        assert!(line.contains(&first_missing) && line.contains("needs every sample"), "{line}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
