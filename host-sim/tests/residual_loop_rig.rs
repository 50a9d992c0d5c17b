//! The loop on the typical measured-data rig (`configs/rotor_rig_bearing.toml`: one disk, two
//! ball-bearing housings, an accelerometer on the housing at node 1): the motor slips 2 % below
//! its nominal 30 Hz, so the running speed is read from the data, and an outer-race defect of
//! bearing 1 rings the housing (periodic impacts through a 320 Hz resonance, the standard
//! synthetic model). Nothing in the configuration declares the defect or the slip.

use edgekf_sim::io::data::DataFile;
use edgekf_sim::residual_loop::{LoopOptions, LoopReport};
use edgekf_sim::systems::rotor::bearing_geometry::BearingLine;
use edgekf_sim::systems::rotor::loop_system::inject::{inject_bearing_defect, DefectSignal};
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

/// Two seconds of the rig at the slipping speed, with an outer-race defect of bearing 1 if
/// `defect`.
fn recording(model: &RotorModel, defect: bool, seed: u64) -> DataFile {
    let speed = true_speed(model);
    let opts = SimOptions { duration: 2.0, seed, speed: Some(speed), ..SimOptions::default() };
    let mut d = model.simulate(&opts).unwrap().to_data_file();
    if defect {
        let order = model.config().bearings[0].geometry.unwrap().order(BearingLine::Bpfo);
        let signal = DefectSignal {
            frequency_hz: order * speed / TAU,
            peak: 0.05,
            resonance_hz: 320.0,
            damping: 0.08,
            slip: 0.003,
            modulation_hz: None,
            load_zone: 0.5,
        };
        inject_bearing_defect(&mut d, "n1_ay", &signal, seed + 100).unwrap();
    }
    d
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

/// The first effect the loop adds. (Allowed to go on, the loop may add stand-ins for what is
/// left near the housing resonance: the impacts' slip smears the upper harmonics into a band
/// that neither the defect's phasors nor an extra mode of fixed damping follow.)
#[test]
fn an_outer_race_defect_is_named_bpfo_at_the_slipping_speed() {
    let model = rig();
    let r = close(&model, &recording(&model, true, 3), 1);
    check_speed(&model, &r);
    assert_eq!(r.effects_added.len(), 1, "{:?}", r.effects_added);
    let e = &r.effects_added[0];
    assert_eq!(e.kind, "bearing_defect");
    assert_eq!(e.detail.line.as_deref(), Some("BPFO"));
    assert_eq!(e.location, "bearing 1");
    assert!((e.detail.order.unwrap() - 3.585).abs() < 1e-3, "{e:?}");
    // It explains the line's harmonics that were in the innovations, at the true speed.
    let bpfo = 3.5848 * true_speed(&model) / TAU;
    for h in [1.0, 2.0, 4.0, 5.0] {
        assert!(
            e.explains.iter().any(|f| (f - h * bpfo).abs() < 1.5),
            "{h}×BPFO {:.2} Hz not in {:?}",
            h * bpfo,
            e.explains
        );
    }
    // The defect rings the housing, not the shaft: the virtual sensing stays as good.
    for (row, before) in &r.before.error_rms {
        assert!(r.after.error_rms[row] < 1.2 * before.max(0.3e-6), "{row}: {before} → {}", r.after.error_rms[row]);
    }
    assert!(r.after.log_likelihood - r.before.log_likelihood > 1e4);
}

#[test]
fn a_healthy_rig_adds_nothing() {
    let model = rig();
    let r = close(&model, &recording(&model, false, 4), 4);
    check_speed(&model, &r);
    assert!(r.effects_added.is_empty(), "{:?}", r.effects_added);
    assert!(r.after.consistent);
}
