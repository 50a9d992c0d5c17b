//! The loop on the typical measured-data rig (`configs/rotor_rig_bearing.toml`: one disk, two
//! ball-bearing housings, an accelerometer on the housing at node 1): the motor slips 2 % below
//! its nominal 30 Hz, so the running speed is read from the data. Nothing in the configuration
//! declares the slip. (Bearing defects on a 12 kHz rig: `tests/bearing_defects.rs`.)

use edgekf_sim::io::data::DataFile;
use edgekf_sim::residual_loop::{EffectKind, LoopOptions, LoopReport};
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

/// The housing's vibration velocity graded as ISO 20816-3 does, from the accelerometers:
/// checked against the simulator's own displacement of the housing's node, differentiated,
/// on a rig unbalanced enough (×100) that the sensor's noise (about 0.01 mm/s) is negligible.
#[test]
fn the_report_grades_the_housings_vibration_velocity() {
    let mut cfg = RotorConfig::from_toml_str(include_str!("../configs/rotor_rig_bearing.toml")).unwrap();
    cfg.unbalances[0].magnitude *= 100.0;
    let model = RotorModel::from_config(&cfg).unwrap();
    let data = recording(&model, 4);
    let r = close(&model, &data, 0);
    let rows = r.section.fields["severity"].as_array().unwrap();
    assert_eq!(rows.len(), 2, "{rows:?}");
    let dt = data.t[1] - data.t[0];
    for (row, axis) in rows.iter().zip(["x", "y"]) {
        let x = data.column(&format!("truth_n1_{axis}")).unwrap();
        let v: Vec<f64> = x.windows(3).map(|w| (w[2] - w[0]) / (2.0 * dt)).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let truth = (v.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt() * 1e3;
        let got = row["velocity_rms_mm_s"].as_f64().unwrap();
        assert!((got / truth - 1.0).abs() < 0.05, "{row:?}: the housing moves at {truth} mm/s r.m.s.");
        assert_eq!(row["band_hz"][0].as_f64(), Some(10.0));
        assert!(row.get("zone").is_none(), "no class configured, no zone: {row:?}");
    }
}

/// An unbalance the configuration does not declare, at node 3 (between the housing and the
/// disk), on a machine that has run for a while (no start-up transient, as in service), read
/// by the one housing's accelerometer pair: a 1× force at any node gives the same forward
/// orbit at the housing up to its amplitude and phase, so one force is added and every other
/// place it could act is listed as its rival, the true one among them.
#[test]
fn an_undeclared_unbalance_read_at_one_housing_lists_every_place_it_could_act() {
    let model = rig();
    let mut truth_cfg = model.config().clone();
    let mut extra = truth_cfg.unbalances[0];
    (extra.node, extra.magnitude) = (3, 2e-4);
    truth_cfg.unbalances.push(extra);
    let truth = RotorModel::from_config(&truth_cfg).unwrap();
    let speed = true_speed(&truth);
    let opts = SimOptions { duration: 2.0, seed: 5, speed: Some(speed), steady_start: true, ..SimOptions::default() };
    let r = close(&model, &truth.simulate(&opts).unwrap().to_data_file(), 4);
    check_speed(&model, &r);
    assert_eq!(r.effects_added.len(), 1, "{:?}", r.effects_added);
    let force = &r.effects_added[0];
    assert_eq!((force.kind, force.detail.order), (EffectKind::HarmonicForce, Some(1.0)), "{force:?}");
    let ties: Vec<&str> = r
        .not_identifiable
        .iter()
        .filter(|n| n.kind == EffectKind::HarmonicForce && n.reason.contains("cannot tell where it acts"))
        .map(|n| n.location.as_str())
        .collect();
    let places: Vec<&str> = std::iter::once(force.location.as_str()).chain(ties.iter().copied()).collect();
    assert!(places.contains(&"node 3"), "the true place is neither added nor listed: {places:?}");
    // Every node of the shaft but the declared unbalance's (its 1× force is in the model).
    assert!(places.len() >= 7, "{places:?}");
}
