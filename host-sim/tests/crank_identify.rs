//! The multi-feature fast estimator (`FastModel`): which joint has the clearance and how
//! large it is, on simulated runs whose seeds and draws (release angle, journal radius) the
//! built-in model was not trained on.
//!
//! Run with `--nocapture` for the figures; `EDGEKF_LONG=1` runs the full test grid (A, B, C ×
//! 0.1–0.5 mm × 4 draws; run it in release).

use edgekf_sim::crank::estimate::model::{FastModel, FEATURES};
use edgekf_sim::crank::estimate::train::{self, Run};
use edgekf_sim::crank::{CrankConfig, Joint};

fn long() -> bool {
    std::env::var_os("EDGEKF_LONG").is_some()
}

/// Identification rate, worst and RMS relative clearance error of the built-in model on `runs`.
fn evaluate(runs: &[Run]) -> (f64, f64, f64) {
    let cfg = CrankConfig::default();
    let model = FastModel::builtin();
    let feats = train::features_of(&cfg, runs, model.window, 2, &|_, _| {}).unwrap();
    for (r, f) in runs.iter().zip(&feats) {
        let e = model.estimate_features(*f);
        eprintln!(
            "{} {:.3} mm (release {:.1}°, radius ×{:.2}, seed {}): named {} {:.4} mm ({:+.1} %), scores {:.1}/{:.1}/{:.1}, {} operations",
            r.joint,
            r.clearance * 1e3,
            r.release_deg,
            r.radius,
            r.seed,
            e.joint,
            e.per_joint[r.joint.index()] * 1e3,
            (e.per_joint[r.joint.index()] / r.clearance - 1.0) * 100.0,
            e.scores[0],
            e.scores[1],
            e.scores[2],
            e.operations
        );
        // The estimate is written in the named joint's column only.
        for j in Joint::ALL {
            assert_eq!(e.clearance[j.index()] > 0.0, j == e.joint);
        }
    }
    let (rate, worst, rms) = train::score(&model, runs, &feats);
    eprintln!(
        "{} runs: joint right in {:.1} %, clearance error RMS {:.1} %, worst {:.1} %",
        runs.len(),
        rate * 100.0,
        rms * 100.0,
        worst * 100.0
    );
    (rate, worst, rms)
}

/// CI subset: one unseen 10 s run per joint at 0.15 and 0.4 mm; every joint named right.
#[test]
fn fast_model_names_the_joint() {
    let runs = train::grid(&[0.15e-3, 0.4e-3], 1, 700_000, 10.0);
    let (rate, worst, _) = evaluate(&runs);
    assert_eq!(rate, 1.0);
    assert!(worst < 0.35, "{worst}");
}

/// Full test grid, EDGEKF_LONG=1: A, B, C × 0.1–0.5 mm in 0.05 mm steps × 4 unseen draws.
#[test]
fn fast_model_long_grid() {
    if !long() {
        eprintln!("skipped: set EDGEKF_LONG=1");
        return;
    }
    let cs: Vec<f64> = (0..9).map(|k| (0.1 + 0.05 * k as f64) * 1e-3).collect();
    let runs = train::grid(&cs, 4, 800_000, 10.0);
    let (rate, _, _) = evaluate(&runs);
    assert!(rate >= 0.95, "{rate}");
}

/// The built-in model round-trips through its TOML, and a broken one is refused.
#[test]
fn model_file_round_trip() {
    let m = FastModel::builtin();
    assert_eq!(m.features.len(), FEATURES);
    let back = FastModel::from_toml_str(&m.to_toml()).unwrap();
    assert_eq!(back, m);
    let broken = m.to_toml().replace("scale = [", "scale = [1.0, ");
    assert!(FastModel::from_toml_str(&broken).is_err());
}

/// Features written and read back are the same; a fit on them reproduces the model's shape.
#[test]
fn features_file_round_trip_and_fit() {
    let runs = train::grid(&[0.2e-3, 0.4e-3], 2, 5, 1.0);
    let feats = train::features_of(&CrankConfig::default(), &runs, 0.25, 2, &|_, _| {}).unwrap();
    let path = std::env::temp_dir().join(format!("edgekf-crank-features-{}.csv", std::process::id()));
    train::write_features(&path, &runs, &feats).unwrap();
    let (r2, f2) = train::read_features(&path).unwrap();
    std::fs::remove_file(&path).ok();
    assert_eq!(r2, runs);
    assert_eq!(f2, feats);
    let m = train::fit(&runs, &feats, 0.25, 1e-2, false, "test".into());
    assert_eq!(m.regression.len(), 3);
    let m2 = FastModel::from_toml_str(&m.to_toml()).unwrap();
    assert_eq!(m2, m);
}
