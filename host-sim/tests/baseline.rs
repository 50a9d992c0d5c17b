//! The healthy baseline on the synthetic twin of the CWRU rig (`loop_system::twin`): learned
//! from one healthy recording (its noise levels, the housings' resonances and the motor's
//! tones, which the configuration does not declare), it lets the loop ask what changed on
//! another: a bearing defect is named, a grown unbalance is reported as its ratio to the
//! baseline's, and healthy records get nothing.

use edgekf_sim::residual_loop::baseline::Comparison;
use edgekf_sim::residual_loop::{LoopOptions, LoopReport};
use edgekf_sim::systems::rotor::bearing_geometry::BearingLine;
use edgekf_sim::systems::rotor::loop_system::baseline::{learn, BaselineOptions, RotorBaseline};
use edgekf_sim::systems::rotor::loop_system::twin::{rig, Twin, HEALTHY_UNBALANCE, HOUSINGS};
use edgekf_sim::systems::rotor::loop_system::{close_loop_from, compare_with, RotorLoopOptions};
use edgekf_sim::systems::rotor::RotorModel;
use std::sync::OnceLock;

fn model() -> &'static RotorModel {
    static MODEL: OnceLock<RotorModel> = OnceLock::new();
    MODEL.get_or_init(|| rig().unwrap())
}

/// The baseline every test here starts from: two seconds of the healthy twin, seed 1.
fn baseline() -> &'static RotorBaseline {
    static BASELINE: OnceLock<RotorBaseline> = OnceLock::new();
    BASELINE.get_or_init(|| {
        let healthy = Twin::default().record(model(), 1).unwrap();
        let options = LoopOptions { progress: true, ..LoopOptions::default() };
        learn(model(), &healthy, &options, &RotorLoopOptions::default(), &BaselineOptions::default()).unwrap()
    })
}

fn diagnose(twin: Twin, seed: u64) -> LoopReport {
    let data = twin.record(model(), seed).unwrap();
    let options = LoopOptions { screen_parameters: false, ..LoopOptions::default() };
    close_loop_from(model(), &data, &options, &RotorLoopOptions::default(), baseline()).unwrap()
}

fn comparison(r: &LoopReport, kind: &str, location: &str) -> serde_json::Value {
    let rows = r.section.fields.get("baseline_comparison").and_then(|v| v.as_array()).expect("a comparison");
    rows.iter().find(|c| c["kind"] == kind && c["location"] == location).cloned().unwrap_or_default()
}

#[test]
fn the_baseline_learns_the_housings_and_the_noise() {
    let b = baseline();
    eprintln!("{}", b.to_toml().unwrap());
    // Each housing's resonance (3050 Hz on n1_ay, 3420 Hz on n11_ay, ζ 0.04: 240–270 Hz wide)
    // within a tenth of its width, broad, and driving that housing's channel.
    for (ch, (_, hz, _)) in HOUSINGS.iter().enumerate() {
        let found = b
            .resonances
            .iter()
            .any(|r| (r.frequency_hz - hz).abs() < 0.1 * 2.0 * 0.04 * hz && r.damping > 0.005 && r.drive[ch] > 0.05);
        assert!(found, "{hz} Hz: {:?}", b.resonances);
    }
    // The speed read from the data: 0.4 % below the declared.
    assert!((b.speed_hz / (model().config().operation.speed / std::f64::consts::TAU) - 0.996).abs() < 5e-4);
    // Round trip through the file.
    assert_eq!(&RotorBaseline::from_toml_str(&b.to_toml().unwrap()).unwrap(), b);
    assert!(b.gain_floor >= 0.0 && b.gain_floor.is_finite());
}

#[test]
fn a_defect_is_named_against_the_baseline() {
    for (line, seed) in [(BearingLine::Bpfo, 3), (BearingLine::Bpfi, 4)] {
        let r = diagnose(Twin { defect: Some(line), ..Twin::default() }, seed);
        let named: Vec<_> =
            r.effects_added.iter().map(|e| (e.kind.as_str(), e.detail.line.as_deref(), e.location.as_str())).collect();
        assert_eq!(named, [("bearing_defect", Some(line.name()), "bearing 1")], "{:?}", r.trials);
    }
}

#[test]
fn a_grown_unbalance_is_reported_as_its_ratio_to_the_baseline() {
    let r = diagnose(Twin { unbalance: 5.0 * HEALTHY_UNBALANCE, ..Twin::default() }, 5);
    let c = comparison(&r, "unbalance", "disk 6");
    let ratio = c["ratio_to_baseline"].as_f64().unwrap();
    eprintln!("unbalance ×5: {c}");
    assert!((4.0..=6.0).contains(&ratio), "{c}");
    // The filter's unbalance states take the growth: the loop adds nothing for it.
    assert!(r.effects_added.is_empty(), "{:?}", r.effects_added);
    // The growth is beyond the records' noise, and the page's findings say so in words.
    assert_eq!(c["beyond_noise"], true, "{c}");
    let page = edgekf_sim::report::html::render(&r).unwrap();
    assert!(page.contains("Against the baseline: the unbalance at disk 6 is ×"), "no finding against the baseline");
    // And a record like the baseline's reads about ×1.
    let same = comparison(&diagnose(Twin::default(), 6), "unbalance", "disk 6");
    assert!((0.8..=1.25).contains(&same["ratio_to_baseline"].as_f64().unwrap()), "{same}");
}

/// Healthy records of 1 s get nothing: seeds 30–49 with `EDGEKF_LONG=1` (in two tests that run
/// side by side, about 7 min in release), the first of each ten otherwise (a minute each in
/// the test profile: CI's budget).
fn healthy_records_get_nothing(seeds: std::ops::Range<u64>) {
    let count = if std::env::var_os("EDGEKF_LONG").is_some() { usize::MAX } else { 1 };
    for seed in seeds.take(count) {
        let r = diagnose(Twin { duration: 1.0, ..Twin::default() }, seed);
        assert!(r.effects_added.is_empty(), "seed {seed}: {:?}", r.effects_added);
        eprintln!("healthy seed {seed}: {}", r.stopped);
    }
}

#[test]
fn healthy_records_30_to_39_get_nothing() {
    healthy_records_get_nothing(30..40);
}

#[test]
fn healthy_records_40_to_49_get_nothing() {
    healthy_records_get_nothing(40..50);
}

/// Every `baseline_comparison` row of `seed`'s record of `twin`, from the base model alone.
fn comparisons(twin: Twin, seed: u64) -> Vec<Comparison> {
    let data = twin.record(model(), seed).unwrap();
    compare_with(model(), &data, &LoopOptions::default(), &RotorLoopOptions::default(), baseline()).unwrap()
}

/// The intervals' coverage: on healthy records at 20 seeds the 95 % intervals of the
/// unbalance's and the order levels' ratios hold 1 about 95 % of the time (the records and the
/// baseline's differ only by their noise and the motor's tones' phases), and a five-fold
/// unbalance lies outside its interval.
#[test]
fn the_intervals_hold_one_on_healthy_records_and_leave_out_a_fivefold_unbalance() {
    use rayon::prelude::*;
    let rows: Vec<Comparison> =
        (60..80u64).into_par_iter().flat_map(|seed| comparisons(Twin::default(), seed)).collect();
    let with_interval: Vec<&Comparison> = rows.iter().filter(|c| c.interval.is_some()).collect();
    let holds = with_interval.iter().filter(|c| c.beyond_noise == Some(false)).count();
    let coverage = holds as f64 / with_interval.len() as f64;
    for c in rows.iter().filter(|c| c.beyond_noise != Some(false)) {
        eprintln!("outside: {}", c.describe());
    }
    eprintln!("coverage {holds}/{} = {coverage:.3} ({} rows)", with_interval.len(), rows.len());
    // Every row has an interval, and about 95 % of them hold 1 (a binomial 95 % band for
    // 140 intervals is 91–99 %).
    assert_eq!(with_interval.len(), rows.len());
    assert!((0.90..=0.995).contains(&coverage), "coverage {coverage:.3}");
    let grown = comparisons(Twin { unbalance: 5.0 * HEALTHY_UNBALANCE, ..Twin::default() }, 81);
    let disk = grown.iter().find(|c| c.kind == "unbalance").expect("an unbalance row");
    eprintln!("×5: {}", disk.describe());
    assert_eq!(disk.beyond_noise, Some(true), "{}", disk.describe());
    assert!(disk.interval.unwrap()[0] > 3.0, "{}", disk.describe());
}
