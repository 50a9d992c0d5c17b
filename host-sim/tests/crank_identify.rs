//! The multi-feature fast estimator (`FastModel`): which joint has the clearance and how
//! large it is, on simulated runs whose seeds and draws (release angle, journal radius) the
//! built-in model was not trained on.
//!
//! Run with `--nocapture` for the figures; `EDGEKF_LONG=1` runs the full test grid (A, B, C ×
//! 0.1–0.5 mm × 4 draws; run it in release).

use edgekf_sim::systems::crank::estimate::model::{FastModel, FEATURES};
use edgekf_sim::systems::crank::estimate::runs::{self, Run};
use edgekf_sim::systems::crank::estimate::train;
use edgekf_sim::systems::crank::{CrankConfig, Joint};

fn long() -> bool {
    std::env::var_os("EDGEKF_LONG").is_some()
}

/// Identification rate, worst and RMS relative clearance error of the built-in model on `runs`,
/// and the number of runs with the right joint within ±3 %.
fn evaluate(runs: &[Run]) -> (f64, f64, f64, usize) {
    evaluate_with(&FastModel::builtin(), runs)
}

fn evaluate_with(model: &FastModel, runs: &[Run]) -> (f64, f64, f64, usize) {
    let mut within = 0;
    let cfg = CrankConfig::default();
    let feats = train::features_of(&cfg, runs, model.window, 2, &|_, _| {}).unwrap();
    for (r, f) in runs.iter().zip(&feats) {
        let e = model.estimate_features(*f);
        let c = e.clearance[e.joint.index()];
        within += usize::from(e.joint == r.joint && (c / r.clearance - 1.0).abs() <= 0.03);
        eprintln!(
            "{r}: named {} {:.4} mm ({:+.1} %; window features {:+.1} %, release law {:?}), scores {:.1}/{:.1}/{:.1}, {} operations",
            e.joint,
            c * 1e3,
            (c / r.clearance - 1.0) * 100.0,
            (e.per_joint[r.joint.index()] / r.clearance - 1.0) * 100.0,
            e.release,
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
    let (rate, worst, rms) = train::score(model, runs, &feats);
    eprintln!(
        "{} runs: joint right in {:.1} %, clearance error RMS {:.1} %, worst {:.1} %, within ±3 % in {within}",
        runs.len(),
        rate * 100.0,
        rms * 100.0,
        worst * 100.0
    );
    (rate, worst, rms, within)
}

/// CI subset: one unseen 10 s run per joint at 0.1, 0.2, 0.3, 0.4 and 0.5 mm (release angle
/// and journal radius drawn from 20–40° and × 0.8–1.2): every joint named right and every
/// clearance within ±3 % (the target).
#[test]
fn fast_model_names_the_joint_and_meets_3_percent() {
    let runs = runs::grid(&[0.1e-3, 0.2e-3, 0.3e-3, 0.4e-3, 0.5e-3], 1, 700_000, 10.0);
    let (rate, worst, _, within) = evaluate(&runs);
    assert_eq!((rate, within), (1.0, runs.len()));
    assert!(worst <= 0.03, "{worst}");
}

/// Without its release stage the same model is the window features' regression alone, which
/// chaos limits to about 8 % RMS: the release stage is what meets ±3 %.
#[test]
fn without_the_release_stage_the_error_is_several_times_larger() {
    let runs = runs::grid(&[0.1e-3, 0.3e-3, 0.5e-3], 1, 710_000, 10.0);
    let mut model = FastModel::builtin();
    model.release = None;
    let (_, worst_off, rms_off, _) = evaluate_with(&model, &runs);
    let (_, worst_on, rms_on, _) = evaluate(&runs);
    assert!(
        worst_on <= 0.03 && rms_off > 2.0 * rms_on && worst_off > 0.03,
        "{rms_off} {worst_off} {rms_on} {worst_on}"
    );
}

/// Full test grid, EDGEKF_LONG=1: A, B, C × 0.1–0.5 mm in 0.05 mm steps × 4 unseen draws. At
/// least 95 % within ±3 % and none beyond ±5 %: at 0.1 mm the first contact comes after about 45
/// samples, and placing it to one sample alone is ±2.2 % of the clearance.
#[test]
fn fast_model_long_grid() {
    if !long() {
        eprintln!("skipped: set EDGEKF_LONG=1");
        return;
    }
    let cs: Vec<f64> = (0..9).map(|k| (0.1 + 0.05 * k as f64) * 1e-3).collect();
    let runs = runs::grid(&cs, 4, 800_000, 10.0);
    let (rate, worst, _, within) = evaluate(&runs);
    assert!(rate >= 0.95, "{rate}");
    assert!(within as f64 >= 0.95 * runs.len() as f64 && worst <= 0.05, "{within} {worst}");
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
    let runs = runs::grid(&[0.2e-3, 0.4e-3], 2, 5, 1.0);
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

/// Recordings from another simulator than the one the model was trained on: the paper's
/// symplectic Euler at 1e-5 s (default configuration) where the training used the adaptive
/// Dormand–Prince integrator. Its impact sequences differ from the first impact on; the first
/// contact's time does not. A, B, C × 0.1, 0.3, 0.5 mm, released at 26° and 34° alternately,
/// journal radius × 0.9 or × 1.1: every joint named right and every clearance within ±3 %.
#[test]
fn fast_model_on_the_papers_integrator() {
    use edgekf_sim::systems::crank::estimate::Recording;
    use edgekf_sim::systems::crank::{Mechanism, SimOptions};
    let model = FastModel::builtin();
    let mut worst = 0.0_f64;
    for (i, (joint, c)) in Joint::ALL.iter().flat_map(|&j| [0.1e-3, 0.3e-3, 0.5e-3].map(|c| (j, c))).enumerate() {
        let mut cfg = CrankConfig::default();
        cfg.release.crank_angle_deg = if i % 2 == 0 { 26.0 } else { 34.0 };
        cfg.contact.journal_radius *= if i % 3 == 0 { 0.9 } else { 1.1 };
        let mut clearances = [None; 3];
        clearances[joint.index()] = Some(c);
        let sim = Mechanism::new(&cfg, clearances).unwrap();
        let rec = sim.simulate(&SimOptions { seed: 600 + i as u64, ..SimOptions::from_config(&cfg, 10.0) }).unwrap();
        let e = model.estimate(&Recording::from_simulation(&rec, cfg.sensor.sample_rate)).unwrap();
        let err = e.clearance[joint.index()] / c - 1.0;
        eprintln!(
            "symplectic Euler: {joint} {:.1} mm released at {}°: named {} {:.4} mm ({:+.2} %, release law {:?})",
            c * 1e3,
            cfg.release.crank_angle_deg,
            e.joint,
            e.clearance[e.joint.index()] * 1e3,
            err * 100.0,
            e.release
        );
        assert_eq!(e.joint, joint);
        worst = worst.max(err.abs());
    }
    assert!(worst <= 0.03, "{worst}");
}

/// A release the laws do not describe: the journal at A already rests at the bottom of its
/// bearing, so the crank swings as the ideal mechanism's from the first sample (about
/// −160 rad/s² at 30° instead of the free flight's −28). The release stage stays out and the
/// window features give the clearance.
#[test]
fn a_journal_resting_at_release_is_left_to_the_window_features() {
    use edgekf_sim::systems::crank::estimate::Recording;
    use edgekf_sim::systems::crank::state::eccentricity_index;
    use edgekf_sim::systems::crank::{Mechanism, SimOptions};
    let cfg = CrankConfig::default();
    let c = 0.25e-3;
    let m = Mechanism::new(&cfg, [Some(c), None, None]).unwrap();
    let mut start = m.release_state();
    start.z[eccentricity_index(Joint::A) + 1] = -0.9999 * c;
    let opts = SimOptions { seed: 5, initial: Some(start), ..SimOptions::from_config(&cfg, 10.0) };
    let rec = Recording::from_simulation(&m.simulate(&opts).unwrap(), cfg.sensor.sample_rate);
    let model = FastModel::builtin();
    let e = model.estimate(&rec).unwrap();
    let level = e.features.release.map(|r| r.release_alpha);
    eprintln!(
        "resting journal: pre-contact level {level:?} rad/s², release law {:?}, named {} {:.4} mm ({:+.1} %)",
        e.release,
        e.joint,
        e.clearance[e.joint.index()] * 1e3,
        (e.clearance[e.joint.index()] / c - 1.0) * 100.0
    );
    let [lo, hi] = model.release.as_ref().unwrap().level[0];
    assert!(level.is_none_or(|l| l < lo || l > hi), "{level:?}");
    assert_eq!(e.release, None);
    assert_eq!(e.clearance[e.joint.index()], e.per_joint[e.joint.index()]);
}
