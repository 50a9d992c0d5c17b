//! The loop on the typical measured-data rig (`configs/rotor_rig_bearing.toml`: one disk, two
//! ball-bearing housings, an accelerometer on the housing at node 1): the motor slips 2 % below
//! its nominal 30 Hz, so the running speed is read from the data. Nothing in the configuration
//! declares the slip. (Bearing defects on a 12 kHz rig: `tests/bearing_defects.rs`.)

use edgekf_sim::io::data::DataFile;
use edgekf_sim::residual_loop::{LoopOptions, LoopReport};
use edgekf_sim::systems::rotor::loop_system::{close_loop, RotorLoopOptions};
use edgekf_sim::systems::rotor::{RotorConfig, RotorModel, SimOptions};
use std::f64::consts::TAU;

/// The motor's slip below the configured speed.
const SLIP: f64 = 0.02;

fn rig() -> RotorModel {
    let cfg = RotorConfig::from_toml_str(include_str!("../configs/rotor_rig_bearing.toml")).unwrap();
    RotorModel::from_config(&cfg).unwrap()
}

/// The shaft's true speed, rad/s.
fn true_speed(model: &RotorModel) -> f64 {
    model.config().operation.speed * (1.0 - SLIP)
}

/// Two seconds of the rig at the slipping speed.
fn recording(model: &RotorModel, seed: u64) -> DataFile {
    let speed = true_speed(model);
    let opts = SimOptions { duration: 2.0, seed, speed: Some(speed), ..SimOptions::default() };
    model.simulate(&opts).unwrap().to_data_file()
}

fn close(model: &RotorModel, data: &DataFile, max_effects: usize) -> LoopReport {
    let options = LoopOptions { screen_parameters: false, max_effects, ..LoopOptions::default() };
    let rotor = RotorLoopOptions { speed_band: Some(0.1), ..RotorLoopOptions::default() };
    let r = close_loop(model, data, &options, &rotor).unwrap();
    eprintln!("{}", edgekf_sim::report::text::summary_table(&r));
    r
}

/// The running speed is read from the data to well under a spectral bin (0.98 Hz here).
fn check_speed(model: &RotorModel, r: &LoopReport) {
    let s = &r.section.fields["running_speed"];
    let truth = true_speed(model) / TAU;
    let (hz, declared_hz) = (s["hz"].as_f64().unwrap(), s["declared_hz"].as_f64().unwrap());
    assert_eq!(s["source"], "estimated");
    assert!((declared_hz - 30.0).abs() < 1e-3, "{s:?}");
    assert!((hz / truth - 1.0).abs() < 1e-3, "{s:?} against {truth} Hz");
}

#[test]
fn a_healthy_rig_adds_nothing() {
    let model = rig();
    let r = close(&model, &recording(&model, 4), 4);
    check_speed(&model, &r);
    assert!(r.effects_added.is_empty(), "{:?}", r.effects_added);
    assert!(r.after.consistent);
}
