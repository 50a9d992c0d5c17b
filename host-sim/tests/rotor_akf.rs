//! Virtual sensing on the paper rotor: data from the reference FE simulation (never from the
//! reduced model), estimates from the reduced phasor AKF.

use edgekf_sim::systems::rotor::estimate::{reduce, run, Estimates, FilterPrecision, ForceModel, Tuning};
use edgekf_sim::systems::rotor::{Recording, RotorConfig, RotorModel, SimOptions};

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

/// The displacement-probe filter with the filter's model off: Young's modulus ±1 %, bearing
/// stiffness +1 %, speed ±0.05 % (the data always from the nominal rotor).
#[test]
fn displacement_filter_under_model_error() {
    let cfg = RotorConfig::from_toml_str(include_str!("../configs/rotor_paper.toml")).unwrap();
    let truth = RotorModel::from_config(&cfg).unwrap();
    let speed = cfg.operation.speed;
    let rec = truth.simulate(&SimOptions { duration: 4.0, seed: 3, ..SimOptions::default() }).unwrap();
    let data = rec.to_data_file();
    let off = |bearing: f64, young: f64| {
        let mut c = cfg.clone();
        for b in &mut c.bearings {
            b.kxx *= bearing;
            b.kyy *= bearing;
        }
        c.shaft.young *= young;
        RotorModel::from_config(&c).unwrap()
    };
    let cases = [
        ("matched", off(1.0, 1.0), 1.0),
        ("Young's modulus +1 %", off(1.0, 1.01), 1.0),
        ("Young's modulus −1 %", off(1.0, 0.99), 1.0),
        ("bearing stiffness +1 %", off(1.01, 1.0), 1.0),
        ("speed +0.05 %", off(1.0, 1.0), 1.0005),
        ("speed −0.05 %", off(1.0, 1.0), 0.9995),
    ];
    for (tname, tuning) in [("default", Tuning::default()), ("robust", Tuning::robust())] {
        for (name, m, factor) in &cases {
            let est = run(&reduce(m, speed * factor, &tuning).unwrap(), &data, FilterPrecision::F64).unwrap();
            let (rms, _) = disk_errors(&est, &rec, 1.0, 0.2);
            let nis: Vec<f64> = est.nis.iter().copied().skip(1000).filter(|v| v.is_finite()).collect();
            eprintln!(
                "displacement probes, {tname} tuning, {name}: disk RMS {:.3} µm, NIS mean {:.1}",
                rms * 1e6,
                nis.iter().sum::<f64>() / nis.len() as f64
            );
            assert_eq!(est.repairs, (0, 0));
            if tname == "robust" {
                assert!(rms <= 3e-6, "robust tuning, {name}: {rms}");
            }
        }
    }
}

/// Time-varying gain for the first 0.5 s, then the steady-state gain: the chip's cheap filter
/// after the start-up.
#[test]
fn switching_to_the_steady_state_gain_after_start_up() {
    use edgekf_sim::systems::rotor::estimate::{run_with, RunOptions};
    for (name, text) in [
        ("displacement probes", include_str!("../configs/rotor_paper.toml")),
        ("accelerometers", include_str!("../configs/rotor_paper_accel.toml")),
    ] {
        let cfg = RotorConfig::from_toml_str(text).unwrap();
        let model = RotorModel::from_config(&cfg).unwrap();
        let rec = model.simulate(&SimOptions { duration: 4.0, seed: 3, ..SimOptions::default() }).unwrap();
        let data = rec.to_data_file();
        let red = reduce(&model, cfg.operation.speed, &Tuning::default()).unwrap();
        let tv = run(&red, &data, FilterPrecision::F64).unwrap();
        let start = std::time::Instant::now();
        let sw = run_with(&red, &data, FilterPrecision::F64, &RunOptions { steady_after: Some(0.5) }).unwrap();
        let (tv_rms, tv_worst) = disk_errors(&tv, &rec, 1.0, 0.5);
        let (sw_rms, sw_worst) = disk_errors(&sw, &rec, 1.0, 0.5);
        eprintln!(
            "{name}: time-varying disk RMS {:.3} µm (worst {:.3} µm for t ≥ 0.5 s); steady-state gain from 0.5 s: {:.3} µm (worst {:.3} µm), run incl. Riccati {:.2} s",
            tv_rms * 1e6,
            tv_worst * 1e6,
            sw_rms * 1e6,
            sw_worst * 1e6,
            start.elapsed().as_secs_f64()
        );
        assert_eq!(sw.repairs, (0, 0));
        assert!(sw_rms <= 2.0 * tv_rms + 0.1e-6, "{name}: switched {sw_rms} vs time-varying {tv_rms}");
    }
}

/// The oracle that ties the two builds of shared's one Kalman filter: at a chip size (20 states
/// × 4 probes) the dynamic-size filter, which runs every size no build compiles in, gives the
/// fixed-size filter's innovations, through the time-varying phase and the switch to the
/// steady-state gain.
#[test]
fn the_dynamic_size_filter_gives_the_fixed_size_innovations() {
    use edgekf_sim::systems::rotor::estimate::filter::run_dynamic;
    use edgekf_sim::systems::rotor::estimate::{run_with, RunOptions};
    let model = paper();
    let rec = model.simulate(&SimOptions { duration: 1.0, seed: 5, ..SimOptions::default() }).unwrap();
    let mut data = rec.to_data_file();
    // A missing sample in each phase: both filters must bridge it the same way.
    let probe = data.names.iter().position(|n| n == "n5_x").unwrap();
    data.columns[probe][100] = f64::NAN;
    data.columns[probe][700] = f64::NAN;
    let red = reduce(&model, model.config().operation.speed, &Tuning::default()).unwrap();
    assert_eq!((red.states(), red.c.nrows()), (20, 4));
    let options = RunOptions { steady_after: Some(0.5) };
    let fixed = run_with(&red, &data, FilterPrecision::F64, &options).unwrap();
    let dynamic = run_dynamic(&red, &data, options).unwrap();
    assert_eq!((fixed.missing, dynamic.missing), (2, 2));
    let mut worst = 0.0f64;
    for (f, d) in fixed.innovation.iter().zip(&dynamic.innovation) {
        let scale = f.iter().filter(|v| v.is_finite()).fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0);
        for (a, b) in f.iter().zip(d) {
            assert_eq!(a.is_nan(), b.is_nan());
            if a.is_finite() {
                worst = worst.max((a - b).abs() / scale);
            }
        }
    }
    let nis_worst = fixed
        .nis
        .iter()
        .zip(&dynamic.nis)
        .filter(|(a, _)| a.is_finite())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "dynamic vs fixed size: innovations within {worst:.1e} of their largest value, NIS within {nis_worst:.1e}"
    );
    assert!(worst <= 1e-9, "innovations differ by {worst:e} relative");
    assert!(nis_worst <= 1e-6, "NIS differs by {nis_worst:e}");
}
