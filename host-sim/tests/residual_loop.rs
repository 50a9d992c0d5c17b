//! The residual loop on the paper rotor: injected effects are found, clean data gets nothing.

use edgekf_sim::io::data::DataFile;
use edgekf_sim::residual_loop::cli::summary_table;
use edgekf_sim::residual_loop::inject::{inject_bias, inject_harmonic_force};
use edgekf_sim::residual_loop::{close_loop, LoopOptions, LoopReport};
use edgekf_sim::rotor::{RotorConfig, RotorModel, SimOptions};

const DURATION: f64 = 3.0;

fn paper() -> RotorModel {
    let cfg = RotorConfig::from_toml_str(include_str!("../configs/rotor_paper.toml")).unwrap();
    RotorModel::from_config(&cfg).unwrap()
}

fn data(model: &RotorModel, seed: u64) -> DataFile {
    model.simulate(&SimOptions { duration: DURATION, seed, ..SimOptions::default() }).unwrap().to_data_file()
}

/// Largest disk-node RMS error (x, y of nodes 12 and 23), m.
fn disk_error(r: &LoopReport, after: bool) -> f64 {
    let s = if after { &r.after } else { &r.before };
    s.error_rms.values().copied().fold(0.0, f64::max)
}

fn run(model: &RotorModel, data: &DataFile) -> LoopReport {
    let r = close_loop(model, data, &LoopOptions::default()).unwrap();
    println!("{}", summary_table(&r));
    r
}

#[test]
fn clean_data_gets_nothing() {
    let model = paper();
    for seed in [3, 11, 21] {
        let r = run(&model, &data(&model, seed));
        assert!(r.effects_added.is_empty(), "seed {seed}: {:?}", r.effects_added);
        assert!(disk_error(&r, true) < 1e-6, "seed {seed}");
    }
}

#[test]
fn a_bias_on_n5_x_is_found_and_removed() {
    let model = paper();
    let clean = data(&model, 3);
    let base = run(&model, &clean);
    let mut biased = clean.clone();
    inject_bias(&mut biased, "n5_x", 20e-6).unwrap();
    let r = run(&model, &biased);
    assert_eq!(r.effects_added.len(), 1, "{:?}", r.effects_added);
    let e = &r.effects_added[0];
    assert_eq!((e.kind.as_str(), e.location.as_str(), e.unit.as_str()), ("sensor_bias", "n5_x", "m"));
    assert!((e.value - 20e-6).abs() < 0.2 * 20e-6, "bias {:.3e}", e.value);
    assert!(
        disk_error(&r, true) < 1.5 * disk_error(&base, true),
        "{:.3e} vs clean {:.3e}",
        disk_error(&r, true),
        disk_error(&base, true)
    );
    assert!(disk_error(&r, false) > disk_error(&r, true));
}

#[test]
fn a_2x_force_at_a_disk_is_found() {
    let model = paper();
    let clean = data(&model, 5);
    let base = run(&model, &clean);
    let speed = model.config().operation.speed;
    let mut forced = clean.clone();
    inject_harmonic_force(&mut forced, &model, speed, 12, 2.0, 1.5, 0.3).unwrap();
    let r = run(&model, &forced);
    let e = r.effects_added.first().expect("an effect");
    assert_eq!((e.kind.as_str(), e.location.as_str(), e.order), ("harmonic_force", "node 12", Some(2)));
    assert!((e.value - 1.5).abs() < 0.2 * 1.5, "amplitude {:.3}", e.value);
    assert!(
        disk_error(&r, true) < 1.5 * disk_error(&base, true),
        "{:.3e} vs clean {:.3e}",
        disk_error(&r, true),
        disk_error(&base, true)
    );
}

#[test]
fn a_3x_force_at_the_other_disk_is_found() {
    let model = paper();
    let clean = data(&model, 9);
    let base = run(&model, &clean);
    let speed = model.config().operation.speed;
    let mut forced = clean.clone();
    inject_harmonic_force(&mut forced, &model, speed, 23, 3.0, 1.0, -1.0).unwrap();
    let r = run(&model, &forced);
    let e = r.effects_added.first().expect("an effect");
    assert_eq!((e.kind.as_str(), e.location.as_str(), e.order), ("harmonic_force", "node 23", Some(3)));
    assert!((e.value - 1.0).abs() < 0.2, "amplitude {:.3}", e.value);
    assert!(
        disk_error(&r, true) < 1.5 * disk_error(&base, true),
        "{:.3e} vs clean {:.3e}",
        disk_error(&r, true),
        disk_error(&base, true)
    );
}
