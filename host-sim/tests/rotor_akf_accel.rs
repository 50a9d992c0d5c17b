//! Virtual sensing from accelerometers: the ADXL355-like channels of rotor_paper_accel.toml
//! (2nd-order Butterworth low-pass at 250 Hz, 5.5 mm/s² noise per sample at 1 kHz), data from the
//! reference FE simulation, the low-pass inside the filter's model.

use edgekf_sim::systems::rotor::estimate::{reduce, run, Estimates, FilterPrecision, ForceModel, Tuning};
use edgekf_sim::systems::rotor::{Recording, RotorConfig, RotorModel, SimOptions};

fn config() -> RotorConfig {
    RotorConfig::from_toml_str(include_str!("../configs/rotor_paper_accel.toml")).unwrap()
}

/// Worst (over the disk nodes 12 and 23, x and y) RMS error for t ≥ `t0`, m.
fn disk_rms(est: &Estimates, rec: &Recording, t0: f64) -> f64 {
    let mut rms = 0.0f64;
    for node in [12usize, 23] {
        for (d, truth) in [(0, &rec.x[node]), (1, &rec.y[node])] {
            let e = &est.displacement[2 * node + d];
            let (mut s, mut n) = (0.0, 0);
            for k in 0..e.len() {
                if est.t[k] >= t0 {
                    s += (e[k] - truth[k]).powi(2);
                    n += 1;
                }
            }
            rms = rms.max((s / n as f64).sqrt());
        }
    }
    rms
}

fn nis_mean(est: &Estimates, t0: f64) -> f64 {
    let v: Vec<f64> = est.t.iter().zip(&est.nis).filter(|(t, n)| **t >= t0 && n.is_finite()).map(|(_, n)| *n).collect();
    v.iter().sum::<f64>() / v.len() as f64
}

/// The filter's model with the bearing stiffness and the shaft's Young's modulus scaled.
fn filter_model(bearing: f64, young: f64) -> RotorModel {
    let mut cfg = config();
    for b in &mut cfg.bearings {
        b.kxx *= bearing;
        b.kyy *= bearing;
        b.kxy *= bearing;
        b.kyx *= bearing;
    }
    cfg.shaft.young *= young;
    RotorModel::from_config(&cfg).unwrap()
}

#[test]
fn accelerometers_alone_give_the_disk_motion() {
    let cfg = config();
    let truth = RotorModel::from_config(&cfg).unwrap();
    let speed = cfg.operation.speed;
    let rec = truth.simulate(&SimOptions { duration: 4.0, seed: 3, ..SimOptions::default() }).unwrap();
    let data = rec.to_data_file();
    let red = reduce(&truth, speed, &Tuning::default()).unwrap();
    assert_eq!(red.states(), 28, "8 modes, 2 phasors, 4 two-state low-passes");
    let est = run(&red, &data, FilterPrecision::F64).unwrap();
    assert_eq!(est.repairs, (0, 0));
    let matched = disk_rms(&est, &rec, 1.0);
    eprintln!(
        "accelerometers, matched model, default tuning: disk RMS {:.3} µm, NIS mean {:.1}",
        matched * 1e6,
        nis_mean(&est, 1.0)
    );
    assert!(matched <= 1.5e-6, "matched {matched}");

    // Without the sensor's low-pass in the model, its phase lag at the running speed is
    // attributed to the rotor.
    let no_lp = run(
        &reduce(&truth, speed, &Tuning { sensor_lowpass: false, ..Tuning::default() }).unwrap(),
        &data,
        FilterPrecision::F64,
    )
    .unwrap();
    let no_lp = disk_rms(&no_lp, &rec, 1.0);
    eprintln!("without the low-pass in the model: {:.3} µm", no_lp * 1e6);
    assert!(no_lp > 3.0 * matched);

    // The robust tuning under model error in the filter only.
    let robust = Tuning::robust();
    let est32 = run(&reduce(&truth, speed, &robust).unwrap(), &data, FilterPrecision::F32).unwrap();
    eprintln!("f32, robust tuning: disk RMS {:.3} µm, repairs {:?}", disk_rms(&est32, &rec, 1.0) * 1e6, est32.repairs);
    let cases = [
        ("matched", filter_model(1.0, 1.0), 1.0),
        ("Young's modulus +1 %", filter_model(1.0, 1.01), 1.0),
        ("Young's modulus −1 %", filter_model(1.0, 0.99), 1.0),
        ("bearing stiffness +1 %", filter_model(1.01, 1.0), 1.0),
        ("speed +0.05 %", filter_model(1.0, 1.0), 1.0005),
        ("speed −0.05 %", filter_model(1.0, 1.0), 0.9995),
    ];
    for (name, m, factor) in &cases {
        let est = run(&reduce(m, speed * factor, &robust).unwrap(), &data, FilterPrecision::F64).unwrap();
        let rms = disk_rms(&est, &rec, 1.0);
        eprintln!("robust tuning, {name}: disk RMS {:.3} µm, NIS mean {:.1}", rms * 1e6, nis_mean(&est, 1.0));
        assert_eq!(est.repairs, (0, 0));
        assert!(rms <= 3e-6, "{name}: {rms}");
    }
}

#[test]
fn the_random_walk_force_model_drifts_with_accelerometers() {
    let cfg = config();
    let truth = RotorModel::from_config(&cfg).unwrap();
    let rec = truth.simulate(&SimOptions { duration: 4.0, seed: 4, ..SimOptions::default() }).unwrap();
    let tuning = Tuning { force_model: ForceModel::RandomWalk, force_psd: 1e2, ..Tuning::default() };
    let est =
        run(&reduce(&truth, cfg.operation.speed, &tuning).unwrap(), &rec.to_data_file(), FilterPrecision::F64).unwrap();
    let rms = disk_rms(&est, &rec, 1.0);
    eprintln!("random-walk forces from accelerometers: disk RMS {:.3} µm", rms * 1e6);
    assert!(rms > 5e-6, "{rms}");
}
