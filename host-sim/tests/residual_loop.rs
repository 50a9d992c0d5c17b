//! The residual loop on the paper rotor: each undeclared effect is named, sized and removed;
//! clean data gets nothing; what the sensors cannot see is reported as not identifiable, and
//! what the library cannot represent as unexplained. The cases are `residual_loop::cases`,
//! which also make the README's table.

use edgekf_sim::report::text::summary_table;
use edgekf_sim::residual_loop::{AddedEffect, LoopOptions, LoopReport};
use edgekf_sim::systems::rotor::loop_system::cases::Case;
use edgekf_sim::systems::rotor::loop_system::close_loop;

/// Largest disk-node RMS error over the whole run (x, y of nodes 12 and 23), m.
fn disk_error(r: &LoopReport, after: bool) -> f64 {
    let s = if after { &r.after } else { &r.before };
    s.error_rms.values().copied().fold(0.0, f64::max)
}

fn run_with(case: Case, seed: u64, options: &LoopOptions) -> LoopReport {
    let r = close_loop(&Case::declared().unwrap(), &case.data(seed).unwrap(), options, &Default::default()).unwrap();
    println!("{}: {}", case.describe(), summary_table(&r));
    r
}

fn run(case: Case, seed: u64) -> LoopReport {
    run_with(case, seed, &LoopOptions { screen_parameters: false, ..LoopOptions::default() })
}

/// Runs `case` and its clean twin; checks the effect is gone from the error (within 1.5× of the
/// same filter on the clean data, and better than before the loop); returns the report.
fn found(case: Case, seed: u64) -> LoopReport {
    let clean = run(Case::Clean, seed);
    let r = run(case, seed);
    assert!(
        disk_error(&r, true) < 1.5 * disk_error(&clean, true),
        "error after {:.3e} vs clean {:.3e}",
        disk_error(&r, true),
        disk_error(&clean, true)
    );
    assert!(disk_error(&r, false) > disk_error(&r, true), "the loop did not improve the error");
    r
}

fn only(r: &LoopReport) -> &AddedEffect {
    assert_eq!(r.effects_added.len(), 1, "{:?}", r.effects_added);
    &r.effects_added[0]
}

#[test]
fn twenty_clean_seeds_add_at_most_one_effect() {
    let mut false_additions = 0;
    let mut worst: f64 = 0.0;
    for seed in 100..120 {
        let r = run(Case::Clean, seed);
        false_additions += r.effects_added.len();
        worst = worst.max(disk_error(&r, true));
    }
    assert!(false_additions <= 1, "{false_additions} effects added to clean data");
    assert!(worst < 1e-6, "worst clean disk error {worst:.3e}");
}

#[test]
fn a_bias_is_found() {
    let r = found(Case::Bias, 3);
    let e = only(&r);
    assert_eq!((e.kind.as_str(), e.location.as_str(), e.unit.as_str()), ("sensor_bias", "n5_x", "m"));
    assert!((e.value - 20e-6).abs() < 0.2 * 20e-6, "bias {:.3e}", e.value);
}

#[test]
fn a_2x_force_at_a_disk_is_found() {
    let r = found(Case::TwoX, 5);
    let e = only(&r);
    assert_eq!((e.kind.as_str(), e.location.as_str(), e.detail.order), ("harmonic_force", "node 12", Some(2.0)));
    assert!((e.value - 1.5).abs() < 0.2 * 1.5, "amplitude {:.3}", e.value);
    let two_x = 2.0 * 87.96 / std::f64::consts::TAU;
    assert!(e.explains.iter().any(|f| (f - two_x).abs() < 1.0), "explains {:?}, 2x = {two_x:.2} Hz", e.explains);
}

#[test]
fn a_3x_force_at_the_other_disk_is_found() {
    let r = found(Case::ThreeX, 9);
    let e = only(&r);
    assert_eq!((e.kind.as_str(), e.location.as_str(), e.detail.order), ("harmonic_force", "node 23", Some(3.0)));
    assert!((e.value - 1.0).abs() < 0.2, "amplitude {:.3}", e.value);
}

#[test]
fn a_5_percent_scale_error_is_found() {
    let r = found(Case::Scale, 13);
    let e = only(&r);
    assert_eq!((e.kind.as_str(), e.location.as_str(), e.unit.as_str()), ("sensor_scale", "n32_y", "1"));
    assert!((e.value - 1.05).abs() < 0.2 * 0.05, "scale {:.4}", e.value);
}

#[test]
fn a_heavier_disk_is_found() {
    let r = found(Case::DiskMass, 17);
    let e = only(&r);
    assert_eq!(
        (e.kind.as_str(), e.location.as_str(), e.detail.parameter.as_deref()),
        ("parameter", "disk 12", Some("mass"))
    );
    assert!((e.value - 1.10).abs() < 0.2 * 0.10, "factor {:.4}", e.value);
    // It was tripling the error (and far more): the loop cuts it by well over 3×.
    assert!(disk_error(&r, false) > 3.0 * disk_error(&r, true));
}

#[test]
fn a_softer_shaft_is_found() {
    let r = found(Case::ShaftYoung, 19);
    let e = only(&r);
    assert_eq!(
        (e.kind.as_str(), e.location.as_str(), e.detail.parameter.as_deref()),
        ("parameter", "shaft", Some("young"))
    );
    assert!((e.value - 0.95).abs() < 0.2 * 0.05, "factor {:.4}", e.value);
}

#[test]
fn two_effects_at_once() {
    let r = found(Case::Two, 23);
    let found: Vec<(&str, &str)> = r.effects_added.iter().map(|e| (e.kind.as_str(), e.location.as_str())).collect();
    assert!(found.contains(&("sensor_bias", "n32_x")), "{found:?}");
    assert!(found.contains(&("harmonic_force", "node 23")), "{found:?}");
    assert_eq!(found.len(), 2, "{found:?}");
    let bias = r.effects_added.iter().find(|e| e.kind == "sensor_bias").unwrap();
    assert!((bias.value + 25e-6).abs() < 0.2 * 25e-6, "bias {:.3e}", bias.value);
    let force = r.effects_added.iter().find(|e| e.kind == "harmonic_force").unwrap();
    assert!((force.value - 2.0).abs() < 0.2 * 2.0, "force {:.3}", force.value);
}

#[test]
fn a_softer_bearing_is_not_identifiable() {
    let r = run_with(Case::SoftBearing, 29, &LoopOptions::default());
    assert!(r.effects_added.is_empty(), "{:?}", r.effects_added);
    let listed = r.not_identifiable.iter().any(|n| n.location == "bearing 4" && n.parameter.as_deref() == Some("kxx"));
    assert!(listed, "{:?}", r.not_identifiable);
    // The disk masses and the shaft are visible, so they are not listed.
    let visible = ["mass", "young", "density"];
    assert!(
        !r.not_identifiable.iter().any(|n| visible.contains(&n.parameter.as_deref().unwrap_or(""))),
        "{:?}",
        r.not_identifiable
    );
}

#[test]
fn a_gain_that_switches_during_the_run_is_unexplained() {
    let r = run(Case::GainSwitch, 31);
    assert!(r.effects_added.is_empty(), "forced into {:?}", r.effects_added);
    assert!(!r.after.consistent);
    let step = r.unexplained.iter().find(|s| s.statistic == "nis_step" && s.channel == "n5_x");
    let (at, ratio) = r.after.channels.iter().find(|c| c.name == "n5_x").and_then(|c| c.step).unwrap();
    assert!(step.is_some() && (at - 1.5).abs() < 0.1 && ratio > 2.0, "{:#?}", r.unexplained);
    // Even the catch-all unknown input was tried and refused.
    assert!(r.trials.iter().any(|t| t.kind == "unknown_input" && !t.accepted));
}

#[test]
fn a_delayed_probe_is_found() {
    let r = found(Case::Delay, 37);
    let e = only(&r);
    assert_eq!((e.kind.as_str(), e.location.as_str(), e.unit.as_str()), ("sensor_delay", "n32_x", "s"));
    assert!((e.value - 2e-3).abs() < 0.2 * 2e-3, "delay {:.3e}", e.value);
    assert!(r.after.consistent, "{}", r.stopped);
}

/// What the model allows (`[bounds]`): a best fit at or beyond a bound is refused as "outside
/// what the model allows", never kept. Disk 12 is 60 % heavier than declared (beyond the
/// default ±30 % of a parameter); with `[bounds] force = 1.0` a 1.5 N 2× force is beyond its bound.
#[test]
fn fits_beyond_the_bounds_are_refused() {
    use edgekf_sim::residual_loop::OUTSIDE;
    use edgekf_sim::systems::rotor::loop_system::effects::Parameter;
    use edgekf_sim::systems::rotor::{RotorModel, SimOptions};
    let declared = Case::declared().unwrap();
    let mut heavy = declared.config().clone();
    Parameter::DiskMass(0).apply(&mut heavy, 1.6).unwrap();
    let opts = SimOptions { duration: 3.0, seed: 41, ..SimOptions::default() };
    let data = RotorModel::from_config(&heavy).unwrap().simulate(&opts).unwrap().to_data_file();
    let options = LoopOptions { screen_parameters: false, max_effects: 1, ..LoopOptions::default() };
    let r = close_loop(&declared, &data, &options, &Default::default()).unwrap();
    let refusal = r.refused.iter().find(|x| x.kind == "parameter" && x.location == "disk 12").unwrap();
    assert!(refusal.reason.starts_with(OUTSIDE), "{refusal:?}");
    assert!((refusal.value.unwrap() - 1.3).abs() < 0.02, "{refusal:?}");
    for e in &r.effects_added {
        assert!(!(e.kind == "parameter" && (e.value - 1.0).abs() > 0.3), "kept {e:?}");
    }
    // A force beyond `[bounds] force`.
    let mut cfg = declared.config().clone();
    cfg.bounds.force = Some(1.0);
    let strict = RotorModel::from_config(&cfg).unwrap();
    let r = close_loop(&strict, &Case::TwoX.data(5).unwrap(), &options, &Default::default()).unwrap();
    let refusal = r.refused.iter().find(|x| x.kind == "harmonic_force" && x.location == "node 12").unwrap();
    assert!(refusal.reason.starts_with(OUTSIDE) && refusal.reason.contains("beyond the bound"), "{refusal:?}");
    assert!((refusal.value.unwrap() - 1.5).abs() < 0.3, "{refusal:?}");
    assert!(!r.effects_added.iter().any(|e| e.kind == "harmonic_force" && e.value > 1.0), "{:?}", r.effects_added);
}

#[test]
fn a_2x_force_between_the_disks_is_placed_where_it_acts() {
    let r = found(Case::OffDisk, 41);
    let e = only(&r);
    assert_eq!((e.kind.as_str(), e.detail.order), ("harmonic_force", Some(2.0)));
    // Node 17 itself, or a neighbour the probes cannot tell from it (listed as a rival).
    let near = |l: &str| ["node 16", "node 17", "node 18"].contains(&l);
    assert!(near(&e.location), "placed at {}", e.location);
    assert!(
        e.location == "node 17" || r.not_identifiable.iter().any(|n| n.location == "node 17"),
        "node 17 is neither the place nor a rival: {:?}",
        r.not_identifiable
    );
}

#[test]
fn a_mass_between_the_disks_is_a_point_mass_not_a_denser_shaft() {
    let r = found(Case::PointMass, 43);
    let e = only(&r);
    assert_eq!((e.kind.as_str(), e.unit.as_str()), ("point_mass", "kg"));
    assert!(["node 17", "node 18", "node 19"].contains(&e.location.as_str()), "placed at {}", e.location);
    assert!((e.value - 0.8).abs() < 0.25 * 0.8, "mass {:.3} kg", e.value);
}

/// Beyond bearing 33 the probes see a force at node 35 much as one at its neighbours (the
/// overhang is a lever): the loop places it among them and lists the others it cannot tell
/// from it under `not_identifiable`, the true node among the place and its rivals.
#[test]
fn a_force_on_the_overhang_lists_its_location_rivals() {
    use edgekf_sim::systems::rotor::loop_system::inject::{inject_harmonic_force, HarmonicForce};
    let model = Case::declared().unwrap();
    let speed = model.config().operation.speed;
    let mut d = Case::Clean.data(41).unwrap();
    let force = HarmonicForce { node: 35, order: 2.0, amplitude: 1.5, phase_rad: 0.3 };
    inject_harmonic_force(&mut d, &model, speed, &force).unwrap();
    let options = LoopOptions { screen_parameters: false, ..LoopOptions::default() };
    let r = close_loop(&model, &d, &options, &Default::default()).unwrap();
    println!("{}", summary_table(&r));
    let e = only(&r);
    assert_eq!((e.kind.as_str(), e.detail.order), ("harmonic_force", Some(2.0)));
    let overhang = |l: &str| l.strip_prefix("node ").and_then(|n| n.parse::<usize>().ok()).is_some_and(|n| n >= 32);
    assert!(overhang(&e.location), "placed at {}", e.location);
    let rivals: Vec<&str> = r
        .not_identifiable
        .iter()
        .filter(|n| n.kind.as_str() == "harmonic_force")
        .map(|n| n.location.as_str())
        .collect();
    assert!(!rivals.is_empty() && rivals.iter().all(|l| overhang(l)), "rivals {rivals:?}");
    assert!(
        e.location == "node 35" || rivals.contains(&"node 35"),
        "node 35 is neither the place nor a rival: {rivals:?}"
    );
    assert!(disk_error(&r, false) > 5.0 * disk_error(&r, true), "the force was not taken out of the error");
}
