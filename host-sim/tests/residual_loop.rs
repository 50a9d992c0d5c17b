//! The residual loop on the paper rotor: each undeclared effect is named, sized and removed;
//! clean data gets nothing; what the sensors cannot see is reported as not identifiable, and
//! what the library cannot represent as unexplained.

use edgekf_sim::io::data::DataFile;
use edgekf_sim::residual_loop::cli::summary_table;
use edgekf_sim::residual_loop::inject::{inject_bias, inject_harmonic_force, inject_scale};
use edgekf_sim::residual_loop::{close_loop, LoopOptions, LoopReport, Parameter};
use edgekf_sim::rotor::{RotorConfig, RotorModel, SimOptions};

const DURATION: f64 = 3.0;

fn paper_config() -> RotorConfig {
    RotorConfig::from_toml_str(include_str!("../configs/rotor_paper.toml")).unwrap()
}

fn paper() -> RotorModel {
    RotorModel::from_config(&paper_config()).unwrap()
}

fn data(model: &RotorModel, seed: u64) -> DataFile {
    model.simulate(&SimOptions { duration: DURATION, seed, ..SimOptions::default() }).unwrap().to_data_file()
}

/// Data from the rotor with `parameter` multiplied by `factor` (the loop is given the
/// declared rotor).
fn data_with(parameter: Parameter, factor: f64, seed: u64) -> DataFile {
    let mut cfg = paper_config();
    parameter.apply(&mut cfg, factor).unwrap();
    data(&RotorModel::from_config(&cfg).unwrap(), seed)
}

/// Largest disk-node RMS error over the whole run (x, y of nodes 12 and 23), m.
fn disk_error(r: &LoopReport, after: bool) -> f64 {
    let s = if after { &r.after } else { &r.before };
    s.error_rms.values().copied().fold(0.0, f64::max)
}

fn run_with(model: &RotorModel, data: &DataFile, options: &LoopOptions) -> LoopReport {
    let r = close_loop(model, data, options).unwrap();
    println!("{}", summary_table(&r));
    r
}

fn run(model: &RotorModel, data: &DataFile) -> LoopReport {
    run_with(model, data, &LoopOptions { screen_parameters: false, ..LoopOptions::default() })
}

/// The effect is gone from the error: within 1.5× of the same filter on the clean data.
fn assert_recovered(r: &LoopReport, clean: &LoopReport) {
    assert!(
        disk_error(r, true) < 1.5 * disk_error(clean, true),
        "error after {:.3e} vs clean {:.3e}",
        disk_error(r, true),
        disk_error(clean, true)
    );
    assert!(disk_error(r, false) > disk_error(r, true), "the loop did not improve the error");
}

#[test]
fn twenty_clean_seeds_add_at_most_one_effect() {
    let model = paper();
    let mut false_additions = 0;
    let mut worst: f64 = 0.0;
    for seed in 100..120 {
        let r = run(&model, &data(&model, seed));
        false_additions += r.effects_added.len();
        worst = worst.max(disk_error(&r, true));
    }
    assert!(false_additions <= 1, "{false_additions} effects added to clean data");
    assert!(worst < 1e-6, "worst clean disk error {worst:.3e}");
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
    assert_recovered(&r, &base);
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
    assert_eq!((e.kind.as_str(), e.location.as_str(), e.order), ("harmonic_force", "node 12", Some(2.0)));
    assert!((e.value - 1.5).abs() < 0.2 * 1.5, "amplitude {:.3}", e.value);
    let two_x = 2.0 * speed / std::f64::consts::TAU;
    assert!(e.explains.iter().any(|f| (f - two_x).abs() < 1.0), "explains {:?}, 2x = {two_x:.2} Hz", e.explains);
    assert_recovered(&r, &base);
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
    assert_eq!((e.kind.as_str(), e.location.as_str(), e.order), ("harmonic_force", "node 23", Some(3.0)));
    assert!((e.value - 1.0).abs() < 0.2, "amplitude {:.3}", e.value);
    assert_recovered(&r, &base);
}

#[test]
fn a_5_percent_scale_error_is_found() {
    let model = paper();
    let clean = data(&model, 13);
    let base = run(&model, &clean);
    let mut scaled = clean.clone();
    inject_scale(&mut scaled, "n32_y", 1.05, None).unwrap();
    let r = run(&model, &scaled);
    assert_eq!(r.effects_added.len(), 1, "{:?}", r.effects_added);
    let e = &r.effects_added[0];
    assert_eq!((e.kind.as_str(), e.location.as_str(), e.unit.as_str()), ("sensor_scale", "n32_y", "1"));
    assert!((e.value - 1.05).abs() < 0.2 * 0.05, "scale {:.4}", e.value);
    assert_recovered(&r, &base);
}

#[test]
fn a_heavier_disk_is_found() {
    let model = paper();
    let base = run(&model, &data(&model, 17));
    let r = run(&model, &data_with(Parameter::DiskMass(0), 1.10, 17));
    let e = r.effects_added.first().expect("an effect");
    assert_eq!(
        (e.kind.as_str(), e.location.as_str(), e.parameter.as_deref()),
        ("parameter", "disk 12", Some("mass")),
        "{:?}",
        r.effects_added
    );
    assert!((e.value - 1.10).abs() < 0.2 * 0.10, "factor {:.4}", e.value);
    assert_recovered(&r, &base);
}

#[test]
fn a_stiffer_shaft_is_found() {
    let model = paper();
    let base = run(&model, &data(&model, 19));
    let r = run(&model, &data_with(Parameter::ShaftYoung, 0.95, 19));
    let e = r.effects_added.first().expect("an effect");
    assert_eq!(
        (e.kind.as_str(), e.location.as_str(), e.parameter.as_deref()),
        ("parameter", "shaft", Some("young")),
        "{:?}",
        r.effects_added
    );
    assert!((e.value - 0.95).abs() < 0.2 * 0.05, "factor {:.4}", e.value);
    assert_recovered(&r, &base);
}

#[test]
fn two_effects_at_once() {
    let model = paper();
    let clean = data(&model, 23);
    let base = run(&model, &clean);
    let speed = model.config().operation.speed;
    let mut both = clean.clone();
    inject_bias(&mut both, "n32_x", -25e-6).unwrap();
    inject_harmonic_force(&mut both, &model, speed, 23, 2.0, 2.0, 1.0).unwrap();
    let r = run(&model, &both);
    let found: Vec<(&str, &str)> = r.effects_added.iter().map(|e| (e.kind.as_str(), e.location.as_str())).collect();
    assert!(found.contains(&("sensor_bias", "n32_x")), "{found:?}");
    assert!(found.contains(&("harmonic_force", "node 23")), "{found:?}");
    assert_eq!(found.len(), 2, "{found:?}");
    let bias = r.effects_added.iter().find(|e| e.kind == "sensor_bias").unwrap();
    assert!((bias.value + 25e-6).abs() < 0.2 * 25e-6, "bias {:.3e}", bias.value);
    let force = r.effects_added.iter().find(|e| e.kind == "harmonic_force").unwrap();
    assert!((force.value - 2.0).abs() < 0.2 * 2.0, "force {:.3}", force.value);
    assert_recovered(&r, &base);
}

#[test]
fn a_softer_bearing_is_not_identifiable() {
    let model = paper();
    let r = run_with(&model, &data_with(Parameter::BearingKxx(0), 0.5, 29), &LoopOptions::default());
    assert!(r.effects_added.is_empty(), "{:?}", r.effects_added);
    let listed =
        r.not_identifiable.iter().any(|n| n.location == "bearing 4" && n.parameter.as_deref() == Some("kxx"));
    assert!(listed, "{:?}", r.not_identifiable);
    // The disk masses are visible, so they are not listed.
    assert!(!r.not_identifiable.iter().any(|n| n.parameter.as_deref() == Some("mass")), "{:?}", r.not_identifiable);
}

#[test]
fn a_gain_that_switches_during_the_run_is_unexplained() {
    let model = paper();
    let mut switched = data(&model, 31);
    inject_scale(&mut switched, "n5_x", 1.15, Some(1.5)).unwrap();
    let r = run(&model, &switched);
    assert!(r.effects_added.is_empty(), "forced into {:?}", r.effects_added);
    assert!(!r.after.consistent);
    let names_channel = r.unexplained.iter().any(|s| s.channel == "n5_x");
    assert!(names_channel, "{:#?}", r.unexplained);
    let step = r.unexplained.iter().find(|s| s.statistic == "nis_step" && s.channel == "n5_x");
    assert!(step.is_some(), "{:#?}", r.unexplained);
}
