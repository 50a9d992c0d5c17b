//! Virtual sensing on the paper rotor: data from the reference FE simulation (never from the
//! reduced model), estimates from the reduced phasor AKF.

use edgekf_sim::rotor::{Recording, RotorConfig, RotorModel, SimOptions};
use edgekf_sim::rotor_akf::{reduce, run, Estimates, FilterPrecision, ForceModel, Tuning};

fn paper() -> RotorModel {
    let cfg = RotorConfig::from_toml_str(include_str!("../configs/rotor_paper.toml")).unwrap();
    RotorModel::from_config(&cfg).unwrap()
}

/// Worst (over the disk nodes 12 and 23, x and y) RMS error for t ≥ `t_rms` and absolute error
/// for t ≥ `t_worst`, m.
fn disk_errors(est: &Estimates, rec: &Recording, t_rms: f64, t_worst: f64) -> (f64, f64) {
    let (mut rms, mut worst) = (0.0f64, 0.0f64);
    for node in [12usize, 23] {
        for (d, truth) in [(0, &rec.x[node]), (1, &rec.y[node])] {
            let e = &est.displacement[2 * node + d];
            let (mut s, mut n) = (0.0, 0);
            for k in 0..e.len() {
                let err = e[k] - truth[k];
                if est.t[k] >= t_rms {
                    s += err * err;
                    n += 1;
                }
                if est.t[k] >= t_worst {
                    worst = worst.max(err.abs());
                }
            }
            rms = rms.max((s / n as f64).sqrt());
        }
    }
    (rms, worst)
}

/// Worst relative error of the force amplitude at each unbalance node for t ≥ `t0`.
fn force_error(est: &Estimates, rec: &Recording, t0: f64) -> f64 {
    let mut worst = 0.0f64;
    for (j, f) in rec.forces.iter().enumerate() {
        for k in 0..est.t.len() {
            if est.t[k] >= t0 {
                let amp = est.force[2 * j][k].hypot(est.force[2 * j + 1][k]);
                let truth = f.x[k].hypot(f.y[k]);
                worst = worst.max((amp - truth).abs() / truth);
            }
        }
    }
    worst
}

#[test]
fn phasor_akf_meets_the_virtual_sensing_targets() {
    let model = paper();
    let speed = model.config().operation.speed;
    let rec = model.simulate(&SimOptions { duration: 4.0, seed: 3, ..SimOptions::default() }).unwrap();
    let data = rec.to_data_file();
    let red = reduce(&model, speed, &Tuning::default()).unwrap();
    let est = run(&red, &data, FilterPrecision::F64).unwrap();
    assert_eq!(est.repairs, (0, 0));
    let (rms, worst) = disk_errors(&est, &rec, 1.0, 0.2);
    let (_, startup) = disk_errors(&est, &rec, 1.0, 0.0);
    let force = force_error(&est, &rec, 0.5);
    eprintln!(
        "phasor AKF, 8 modes: disk RMS {:.3} µm (t ≥ 1 s), worst {:.3} µm (t ≥ 0.2 s), start-up worst {:.3} µm; force amplitude within {:.2} % after 0.5 s",
        rms * 1e6,
        worst * 1e6,
        startup * 1e6,
        force * 100.0
    );
    assert!(rms <= 1e-6, "disk RMS {rms}");
    assert!(worst <= 5e-6, "disk worst {worst}");
    assert!(force <= 0.05, "force amplitude error {force}");

    // The chip's arithmetic on the same data.
    let est32 = run(&red, &data, FilterPrecision::F32).unwrap();
    let (rms32, worst32) = disk_errors(&est32, &rec, 1.0, 0.2);
    eprintln!("f32: disk RMS {:.3} µm, worst {:.3} µm, repairs {:?}", rms32 * 1e6, worst32 * 1e6, est32.repairs);
}

#[test]
fn the_papers_random_walk_forces_have_a_higher_floor() {
    let model = paper();
    let speed = model.config().operation.speed;
    let rec = model.simulate(&SimOptions { duration: 4.0, seed: 5, ..SimOptions::default() }).unwrap();
    let data = rec.to_data_file();
    let phasor = run(&reduce(&model, speed, &Tuning::default()).unwrap(), &data, FilterPrecision::F64).unwrap();
    // Best of a small grid for the random-walk model, so the comparison is fair to it.
    let mut best = f64::INFINITY;
    for psd in [1e1, 1e2, 1e3, 1e4] {
        let tuning = Tuning { force_model: ForceModel::RandomWalk, force_psd: psd, ..Tuning::default() };
        let est = run(&reduce(&model, speed, &tuning).unwrap(), &data, FilterPrecision::F64).unwrap();
        let (rms, _) = disk_errors(&est, &rec, 1.0, 0.2);
        eprintln!("random-walk forces, density {psd:e} N²/s: disk RMS {:.3} µm", rms * 1e6);
        best = best.min(rms);
    }
    let (rms, _) = disk_errors(&phasor, &rec, 1.0, 0.2);
    eprintln!("phasor {:.3} µm vs best random walk {:.3} µm", rms * 1e6, best * 1e6);
    assert!(rms * 2.0 < best, "phasor {rms} vs random walk {best}");
}
