//! Bearing defects the way they appear on real machines, on the synthetic twin of the CWRU rig
//! (`loop_system::twin`): each housing rings its own resonance near 3 kHz, the motor adds
//! line-frequency harmonics, and a defect of the drive-end bearing sends impacts at its line's
//! rate, with 1.5 % slip and, for the inner race, the load zone's modulation at the shaft
//! rate, through the drive-end housing's resonance. Nothing in the configuration declares the
//! resonances, the tones or the defect, and the motor runs 0.4 % below its declared speed.
//!
//! The loop's first stage must name the defect from the envelope of the innovations and add
//! nothing on a healthy machine. (`tests/cwru.rs` runs the same on the measured records.)

use edgekf_sim::io::data::DataFile;
use edgekf_sim::residual_loop::{LoopOptions, LoopReport};
use edgekf_sim::systems::rotor::bearing_geometry::BearingLine;
use edgekf_sim::systems::rotor::loop_system::twin::{true_speed, Twin};
use edgekf_sim::systems::rotor::loop_system::{close_loop, RotorLoopOptions};
use edgekf_sim::systems::rotor::RotorModel;
use std::f64::consts::TAU;

fn rig() -> RotorModel {
    edgekf_sim::systems::rotor::loop_system::twin::rig().unwrap()
}

/// Two seconds of the rig, with a drive-end defect on `line` if given.
fn recording(model: &RotorModel, defect: Option<BearingLine>, seed: u64) -> DataFile {
    Twin { defect, ..Twin::default() }.record(model, seed).unwrap()
}

/// The loop's first stage alone (no effect of the model's own is searched for).
fn close(model: &RotorModel, data: &DataFile) -> LoopReport {
    let options = LoopOptions { screen_parameters: false, max_effects: 0, ..LoopOptions::default() };
    let rotor = RotorLoopOptions { speed_band: Some(0.1), ..RotorLoopOptions::default() };
    close_loop(model, data, &options, &rotor).unwrap()
}

fn defects(r: &LoopReport) -> Vec<&edgekf_sim::residual_loop::AddedEffect> {
    r.effects_added.iter().filter(|e| e.kind == "bearing_defect").collect()
}

fn check_named(line: BearingLine, seed: u64) {
    let model = rig();
    let r = close(&model, &recording(&model, Some(line), seed));
    let found = defects(&r);
    assert_eq!(found.len(), 1, "{:?}\n{:?}\n{:?}", r.effects_added, r.trials, r.refused);
    let e = found[0];
    eprintln!("{} seed {seed}: {e:?}", line.name());
    assert_eq!(e.detail.line.as_deref(), Some(line.name()));
    assert_eq!(e.location, "bearing 1");
    // The line as measured sits within the slip tolerance of the true one, with harmonics.
    let truth = model.config().bearings[0].geometry.unwrap().order(line) * true_speed(&model) / TAU;
    let measured = e.explains[0];
    assert!((measured / truth - 1.0).abs() < 0.02, "{measured} Hz against {truth}");
    let harmonics = e.detail.harmonics.as_ref().unwrap();
    assert!(harmonics.len() >= 2, "{harmonics:?}");
    // The band is where the impacts are most impulsive: the housing's resonance, or above it
    // where only their onsets reach; well above the lines either way.
    let [lo, _] = e.detail.band_hz.unwrap();
    assert!(lo > 3.0 * truth, "band from {lo} Hz");
    assert!(e.delta_log_likelihood > 2.0 * e.bic_penalty, "{e:?}");
    // The stage never leaves the model worse: the impacts' vibration is taken out only where
    // the base model then explains the data better, and the defect says so where it is not.
    let (before, after) = (r.before.log_likelihood, r.after.log_likelihood);
    assert!(after >= before, "log-likelihood {before} → {after}");
    assert!(e.detail.not_modelled.is_some() || after > before, "taken out without a gain: {e:?}");
}

#[test]
fn an_outer_race_defect_is_named_bpfo_from_the_envelope() {
    check_named(BearingLine::Bpfo, 3);
}

#[test]
fn an_inner_race_defect_is_named_bpfi_through_the_load_zone() {
    check_named(BearingLine::Bpfi, 4);
}

#[test]
fn a_healthy_rig_has_no_bearing_defect() {
    let model = rig();
    for seed in 20..25 {
        let r = close(&model, &recording(&model, None, seed));
        assert!(defects(&r).is_empty(), "seed {seed}: {:?}", r.effects_added);
        // Lines were looked for and refused, not left unexamined.
        let best = r.trials.iter().map(|t| t.delta_log_likelihood - t.bic_penalty).fold(f64::NEG_INFINITY, f64::max);
        eprintln!("healthy seed {seed}: {} lines fitted, best Δ − BIC {best:.1}", r.trials.len());
    }
}

#[test]
fn a_ball_defect_is_named_bsf_from_its_family() {
    // The ball strikes both races at twice its spin, carried round at the cage's rate: the
    // family (2×BSF, its FTF sidebands, the cage's lines) names it, reported by its spin.
    let model = rig();
    let r = close(&model, &recording(&model, Some(BearingLine::Bsf), 6));
    let found = defects(&r);
    assert_eq!(found.len(), 1, "{:?}\n{:?}", r.effects_added, r.refused);
    assert_eq!((found[0].detail.line.as_deref(), found[0].location.as_str()), (Some("BSF"), "bearing 1"));
    let families = &r.section.fields["bearing_families"];
    assert_eq!(families["verdict"], "named", "{families}");
    assert_eq!(families["named"]["family"], "ball", "{families}");
    // The page shows the evidence: the family's envelope spectrum with its members marked.
    let page = edgekf_sim::report::html::render(&r).unwrap();
    let at = page.find("Squared envelope spectrum of the prewhitened").expect("the family's figure");
    let figure = &page[page[..at].rfind("<figure>").unwrap()..at];
    assert!(figure.contains("<svg") && figure.contains("2×BSF") && figure.contains("ball at bearing 1"));
    // And says it first, in words an engineer acts on.
    let findings = &page[page.find("<h2>Findings</h2>").expect("findings")..page.find("<h2>Effects").unwrap_or(at)];
    assert!(findings.contains("Bearing 1: rolling-element (ball) defect (BSF"), "{findings}");
}

#[test]
fn identical_bearings_are_reported_as_a_tie_not_guessed() {
    // Both bearings of one geometry: an outer-race defect's lines fit either equally, so the
    // report says the sensors cannot tell which bearing, names the rival, and adds neither.
    let healthy = rig();
    let mut cfg = healthy.config().clone();
    cfg.bearings[1].geometry = cfg.bearings[0].geometry;
    let model = RotorModel::from_config(&cfg).unwrap();
    let r = close(&model, &recording(&model, Some(BearingLine::Bpfo), 7));
    assert!(defects(&r).is_empty(), "{:?}", r.effects_added);
    let tie: Vec<_> = r.not_identifiable.iter().filter(|n| n.kind == "bearing_defect").collect();
    assert_eq!(tie.len(), 1, "{:?}", r.not_identifiable);
    assert_eq!(tie[0].statistic, "family_score_gap");
    assert!(tie[0].value.abs() < 2.0, "{:?}", tie[0]);
    let places = [tie[0].location.as_str(), tie[0].rivals[0].as_str()];
    assert!(places[0].starts_with("bearing ") && places[1].contains("bearing "), "{places:?}");
    assert_ne!(places[0], places[1].trim_start_matches("bearing_defect at ").split(" (").next().unwrap());
    assert_eq!(r.section.fields["bearing_families"]["verdict"], "cannot_tell");
    let page = edgekf_sim::report::html::render(&r).unwrap();
    assert!(page.contains("These sensors cannot tell: bearing_defect at bearing"), "no tie in the findings");
}
