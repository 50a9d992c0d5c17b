//! One timeline for every path: rows deleted from a recording (a 21 ms gap, a 0.5 s gap and 1 %
//! of the rows at random) give the same estimates as the same recording with those samples
//! left as empty cells, on the rotor and the oscillator; the crank, whose spectra need every
//! sample, refuses both alike. The rotor's loop adds nothing to the damaged clean recording.

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

/// The rows lost: 21 from 0.5 s, 500 from 1.2 s, and 1 % of the others at random.
fn lost_rows(t: &[f64]) -> Vec<bool> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    t.iter()
        .enumerate()
        .map(|(k, &tk)| (0.5..0.521).contains(&tk) || (1.2..1.7).contains(&tk) || (k > 0 && rng.gen_bool(0.01)))
        .collect()
}

/// `path` twice: with the lost rows deleted, and with their channels (not `truth_`) emptied.
fn damaged(path: &Path, dir: &Path) -> (PathBuf, PathBuf) {
    let (file, _) = data::read(path, &header(path).iter().map(String::as_str).collect::<Vec<_>>()).unwrap();
    let lost = lost_rows(&file.t);
    let keep: Vec<usize> = (0..file.len()).filter(|&k| !lost[k]).collect();
    let deleted = DataFile {
        names: file.names.clone(),
        t: keep.iter().map(|&k| file.t[k]).collect(),
        columns: file.columns.iter().map(|c| keep.iter().map(|&k| c[k]).collect()).collect(),
    };
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
    let write = |f: &DataFile, name: &str| {
        let p = dir.join(name);
        let names: Vec<&str> = f.names.iter().map(String::as_str).collect();
        let cols: Vec<&[f64]> = f.columns.iter().map(Vec::as_slice).collect();
        data::write(&p, &names, &f.t, &cols).unwrap();
        p
    };
    (write(&deleted, "deleted.csv"), write(&emptied, "emptied.csv"))
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

#[test]
fn the_crank_refuses_lost_samples_however_they_are_lost() {
    let dir = scratch("crank");
    let clean = dir.join("clean.csv");
    edgekf(&["crank", "simulate", "--duration", "2", "--out", clean.to_str().unwrap()]);
    let (file, _) = data::read(&clean, &["crank_alpha"]).unwrap();
    let mut deleted = file.clone();
    deleted.t.drain(500..521);
    for c in &mut deleted.columns {
        c.drain(500..521);
    }
    let mut emptied = file.clone();
    emptied.columns[0][500..521].fill(f64::NAN);
    for (f, name) in [(&deleted, "d.csv"), (&emptied, "e.csv")] {
        let p = dir.join(name);
        let names: Vec<&str> = f.names.iter().map(String::as_str).collect();
        let cols: Vec<&[f64]> = f.columns.iter().map(Vec::as_slice).collect();
        data::write(&p, &names, &f.t, &cols).unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_edgekf"))
            .args(["crank", "estimate", "--data", p.to_str().unwrap(), "--method", "fast", "--out"])
            .arg(dir.join("est.csv"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains("the spectra need"), "{err}");
        assert!(!dir.join("est.csv").exists());
    }
    std::fs::remove_dir_all(&dir).ok();
}
