//! The firmware's rotor estimator on the host: its compiled-in constants are what the host
//! computes for the paper rotor, and it meets the virtual-sensing target on reference data.

use edgekf_firmware::systems::rotor::{RotorEstimator, RotorImage, SAMPLE_RATE_HZ, STEADY_AFTER};
use edgekf_sim::systems::rotor::{RotorConfig, RotorModel, SimOptions};
use edgekf_tests::rotor::{check_faulty_run, disk_rms_error, faulty_csv, parse_numbered, run_host, run_host_with};
use std::path::Path;

const CONFIG: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../host-sim/configs/rotor_paper.toml");

#[test]
fn compiled_constants_are_current() {
    let text = edgekf_sim::systems::rotor::cli::estimate::export_text(Path::new(CONFIG), 8).unwrap();
    let committed = include_str!("../../firmware/src/generated/rotor.rs");
    assert!(
        text == committed,
        "firmware/src/generated/rotor.rs is stale: run `cargo run -p edgekf-sim -- rotor export --config host-sim/configs/rotor_paper.toml --out firmware/src/generated/rotor.rs`"
    );
}

/// Four seconds of the paper rotor (seed `seed`) and its HIL file.
fn recording(seed: u64) -> (edgekf_sim::systems::rotor::Recording, String) {
    let cfg = RotorConfig::load(Path::new(CONFIG)).unwrap();
    let rec = RotorModel::from_config(&cfg)
        .unwrap()
        .simulate(&SimOptions { duration: 4.0, seed, ..SimOptions::default() })
        .unwrap();
    let csv = rec.to_data_file().to_csv_string().unwrap();
    (rec, csv)
}

#[test]
fn node_estimator_meets_the_disk_target_in_f32() {
    let (rec, csv) = recording(11);
    let reports = run_host(csv.as_bytes()).unwrap();
    let err = disk_rms_error(&reports, &rec, 1.0);
    eprintln!("firmware rotor estimator on the host (f32): disk RMS error {:.3} µm for t ≥ 1 s", err * 1e6);
    assert!(err <= 1e-6, "{err}");
}

/// The node's switch schedule is in samples of the configured rate.
#[test]
fn switch_schedule_uses_the_configured_sample_rate() {
    let cfg = RotorConfig::load(Path::new(CONFIG)).unwrap();
    assert_eq!(cfg.operation.sample_rate, f64::from(SAMPLE_RATE_HZ));
    assert_eq!(f64::from(STEADY_AFTER), 0.5 * cfg.operation.sample_rate);
}

/// On reference data the switch to the steady-state gain at 0.5 s costs no accuracy: the node
/// (switched) and the time-varying filter throughout are identical before sample
/// `STEADY_AFTER`, differ from it on, and reach the same disk error and NIS.
#[test]
fn steady_state_switch_matches_the_time_varying_filter() {
    let (rec, csv) = recording(7);
    let node = run_host(csv.as_bytes()).unwrap();
    let tv = run_host_with(csv.as_bytes(), RotorEstimator::with_switch_at(None)).unwrap();
    let k0 = STEADY_AFTER as usize;
    assert_eq!(node[..k0], tv[..k0]);
    assert_ne!(node[k0].disk, tv[k0].disk, "the gain changes at sample {k0}");
    let (e_node, e_tv) = (disk_rms_error(&node, &rec, 1.0), disk_rms_error(&tv, &rec, 1.0));
    let from_1s = |r: &[edgekf_firmware::systems::rotor::RotorReport]| {
        let v: Vec<f64> = r.iter().zip(&rec.t).filter(|(_, &t)| t >= 1.0).map(|(r, _)| r.nis as f64).collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    let (nis_node, nis_tv) = (from_1s(&node), from_1s(&tv));
    eprintln!(
        "rotor node, t ≥ 1 s: disk RMS error {:.3} µm switched at {:.1} s, {:.3} µm time-varying throughout; \
         NIS mean {nis_node:.3} / {nis_tv:.3}",
        e_node * 1e6,
        STEADY_AFTER as f64 / f64::from(SAMPLE_RATE_HZ),
        e_tv * 1e6
    );
    assert!(e_node <= 1e-6 && e_node <= 1.1 * e_tv, "{e_node} vs {e_tv}");
    assert!((nis_node - nis_tv).abs() <= 0.05 * nis_tv, "{nis_node} vs {nis_tv}");
}

/// A HIL file with lines missing (20 in a row, and one replaced by garbage), an empty cell, a
/// NaN and a junk line: the node bridges the missing lines by their `t`, steps the bad cells as
/// missing, does not step lines without a `t`, counts each, and recovers (the counts and bounds
/// of `edgekf_tests::rotor::check_faulty_run`).
#[test]
fn missing_and_garbage_lines_are_bridged_counted_and_recovered_from() {
    let (rec, csv) = recording(7);
    assert!(csv.starts_with("t,n5_x,"), "the first probe is the second column");
    let clean = parse_numbered(&edgekf_tests::host::lines::<RotorImage>(csv.as_bytes()).unwrap()).unwrap();
    let lines = edgekf_tests::host::lines::<RotorImage>(faulty_csv(&csv).as_bytes()).unwrap();
    let (err, mismatch) = check_faulty_run(&lines, &clean, &rec).unwrap_or_else(|e| panic!("{e:#}"));
    eprintln!(
        "rotor node with missing and garbage lines: disk RMS error {:.3} µm for t ≥ 1 s; from 0.5 s after the \
         faults the estimates are {:.2e} % off the clean run",
        err * 1e6,
        mismatch * 100.0
    );
}
