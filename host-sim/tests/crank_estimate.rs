//! Clearance estimation on simulated recordings: the paper's UKF (sigma points are clearance
//! simulations) and the fast feature map, on runs the estimators did not simulate themselves.
//!
//! Run with `--nocapture` for the figures; `EDGEKF_LONG=1` adds the 10 s UKF reproduction and
//! the fast estimator's full test grid (run those in release).

use edgekf_sim::systems::crank::config::Method;
use edgekf_sim::systems::crank::estimate::fast::FeatureMap;
use edgekf_sim::systems::crank::estimate::ukf::{self, UkfOptions};
use edgekf_sim::systems::crank::estimate::{write_estimates, Recording};
use edgekf_sim::systems::crank::{CrankConfig, Mechanism, SimOptions};
use std::time::Instant;

fn long() -> bool {
    std::env::var_os("EDGEKF_LONG").is_some()
}

/// A recording of `duration` s with clearance `c` at A, released at `angle`°, journal radius
/// scaled by `radius`, noise seed `seed`.
fn recording(c: f64, angle: f64, radius: f64, seed: u64, duration: f64) -> Recording {
    let mut cfg = CrankConfig::default();
    cfg.release.crank_angle_deg = angle;
    cfg.contact.journal_radius *= radius;
    let m = Mechanism::new(&cfg, [Some(c), None, None]).unwrap();
    let rec = m.simulate(&SimOptions { seed, ..SimOptions::from_config(&cfg, duration) }).unwrap();
    Recording::from_simulation(&rec, cfg.sensor.sample_rate)
}

fn ukf_from_three_starts(duration: f64, bound: f64) {
    let cfg = CrankConfig::default();
    // The recording comes from another simulator than the filter's sigma points: the adaptive
    // integrator at a tighter tolerance (1e-9 against 1e-8), so no sigma point can replay its
    // impact sequence.
    let mut rc = cfg;
    rc.integrator.method = Method::Adaptive;
    rc.integrator.tolerance = 1e-9;
    let m = Mechanism::new(&rc, [Some(0.25e-3), None, None]).unwrap();
    let rec = Recording::from_simulation(
        &m.simulate(&SimOptions { seed: 7, ..SimOptions::from_config(&rc, duration) }).unwrap(),
        rc.sensor.sample_rate,
    );
    for initial in [0.01e-3, 0.1e-3, 0.2e-3] {
        let started = Instant::now();
        let opts = UkfOptions { initial, ..UkfOptions::default() };
        let run = ukf::run(&cfg, &rec, &opts, &mut |_, _| {}).unwrap();
        let err = run.estimate / 0.25e-3 - 1.0;
        eprintln!(
            "UKF {duration} s from {:.2} mm: {} ({:+.1} %, {} iterations), R std {:.1}, {} simulations, {} integration steps, {:.2} s",
            initial * 1e3,
            run.release_effect(),
            err * 100.0,
            run.release_iterations,
            run.measurement_std,
            run.simulations,
            run.integration_steps,
            started.elapsed().as_secs_f64()
        );
        let windows = run.steps.len() as u64;
        assert_eq!(run.simulations, (windows + run.release_iterations as u64) * 3 * opts.members as u64);
        assert!(err.abs() < bound, "from {initial}: {:?}", run.estimate);
        assert_eq!(run.rows().len(), run.steps.len() + 1);
        assert_eq!(run.rows().last().unwrap().clearance[0], run.estimate);
    }
}

/// The paper's experiment, shortened to 4 s (16 windows) for CI: from 0.01, 0.1 and 0.2 mm the
/// estimate reaches 0.25 mm within ±5 % (measured: −3.0, +3.1, +1.4 %). The information is
/// in the release window (see `ukf`'s documentation); the later windows only choose its branch.
#[test]
fn ukf_approaches_the_clearance_from_three_starts() {
    ukf_from_three_starts(4.0, 0.05);
}

/// 10 s (40 windows), EDGEKF_LONG=1 (measured: −0.1, +3.5, +5.3 %).
#[test]
fn ukf_long_reproduction() {
    if !long() {
        eprintln!("skipped: set EDGEKF_LONG=1");
        return;
    }
    ukf_from_three_starts(10.0, 0.06);
}

fn fast_grid(clearances: &[f64], variants: &[(f64, f64, u64)], duration: f64) -> f64 {
    let map = FeatureMap::builtin();
    let mut worst: f64 = 0.0;
    for &c in clearances {
        for &(angle, radius, seed) in variants {
            let rec = recording(c, angle, radius, seed, duration);
            let est = map.estimate(&rec).unwrap();
            let err = est.clearance[0] / c - 1.0;
            worst = worst.max(err.abs());
            eprintln!(
                "fast: {:.2} mm, release {angle}°, journal radius ×{radius}, seed {seed}: impact rate {:.1}/s → {:.4} mm ({:+.1} %), {} operations",
                c * 1e3,
                est.features.impact_rate,
                est.clearance[0] * 1e3,
                err * 100.0,
                est.operations
            );
        }
    }
    worst
}

/// Recordings from release angles and journal radii the map was not built from (22°, 30°, 38°
/// and radius × 0.8, × 1.2 were): 0.1 and 0.4 mm.
#[test]
fn fast_estimator_on_unseen_runs() {
    let worst = fast_grid(&[0.1e-3, 0.4e-3], &[(26.0, 1.1, 21), (34.0, 0.9, 22)], 10.0);
    eprintln!("fast: worst error {:.1} %", worst * 100.0);
    assert!(worst < 0.25, "{worst}");
}

/// The full test grid 0.1–0.5 mm, EDGEKF_LONG=1.
#[test]
fn fast_estimator_long_grid() {
    if !long() {
        eprintln!("skipped: set EDGEKF_LONG=1");
        return;
    }
    let variants = [(26.0, 1.1, 31), (34.0, 0.9, 32), (21.0, 1.0, 33), (39.0, 1.15, 34), (30.0, 0.85, 35)];
    let worst = fast_grid(&[0.1e-3, 0.15e-3, 0.2e-3, 0.3e-3, 0.35e-3, 0.45e-3, 0.5e-3], &variants, 10.0);
    eprintln!("fast: worst error over the grid {:.1} %", worst * 100.0);
}

/// `edgekf crank estimate` writes the estimate file for both methods.
#[test]
fn estimate_command_writes_the_estimate_file() {
    let dir = std::env::temp_dir().join(format!("edgekf-crank-estimate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let data = dir.join("data.csv");
    let cfg = CrankConfig::default();
    let m = Mechanism::new(&cfg, [Some(0.25e-3), None, None]).unwrap();
    m.simulate(&SimOptions::from_config(&cfg, 1.0)).unwrap().write_csv(&data).unwrap();
    for method in ["ukf", "fast"] {
        let out = dir.join(format!("est_{method}.csv"));
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_edgekf"))
            .args(["crank", "estimate", "--data", data.to_str().unwrap(), "--method", method])
            .args(["--initial", "0.1e-3", "--out", out.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = std::fs::read_to_string(&out).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("t,clearance_A,clearance_B,clearance_C"));
        // Both: one row per 0.25 s window, then the whole recording's.
        let body: Vec<&str> = lines.collect();
        assert_eq!(body.len(), 5, "{method}: {text}");
        if method == "fast" {
            // The fast estimator names one joint: one non-zero clearance column in every row; the
            // last window (t = 0.9999 s) holds the whole recording's 4 windows, as the last row.
            let cells = |row: &str| -> Vec<f64> { row.split(',').map(|c| c.parse().unwrap()).collect() };
            for row in &body {
                assert_eq!(cells(row)[1..].iter().filter(|c| **c > 0.0).count(), 1, "{text}");
            }
            assert_eq!(cells(body[3])[1..], cells(body[4])[1..], "{text}");
            assert!((cells(body[4])[1] / 0.25e-3 - 1.0).abs() < 0.03, "{text}");
        }
        let (back, _) = Recording::read(&data, &Default::default()).unwrap();
        assert_eq!(back.truth_clearance, Some([0.25e-3, 0.0, 0.0]));
    }
    // A mistake is one line, not a panic.
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_edgekf"))
        .args(["crank", "estimate", "--data", data.to_str().unwrap(), "--method", "ukf", "--initial", "0.25"])
        .args(["--out", dir.join("x.csv").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--initial"));
    write_estimates(&dir.join("empty.csv"), &[]).ok();
    // `crank train` writes a model that `estimate --method fast --model` reads.
    let model = dir.join("model.toml");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_edgekf"))
        .args(["crank", "train", "--out", model.to_str().unwrap(), "--clearances", "0.2e-3,0.4e-3"])
        .args(["--variants", "2", "--duration", "0.5", "--threads", "2", "--release-variants", "10"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("training set: joint right in"));
    let out = dir.join("est_model.csv");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_edgekf"))
        .args(["crank", "estimate", "--data", data.to_str().unwrap(), "--method", "fast"])
        .args(["--model", model.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("estimate: joint "));
    std::fs::remove_dir_all(&dir).ok();
}
