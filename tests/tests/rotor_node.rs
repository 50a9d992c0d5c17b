//! The firmware's rotor estimator on the host: its compiled-in constants are what the host
//! computes for the paper rotor, and it meets the virtual-sensing target on reference data.

use edgekf_firmware::systems::rotor::{RotorEstimator, RotorImage, RotorReport, SAMPLE_RATE_HZ, STEADY_AFTER};
use edgekf_sim::systems::rotor::{RotorConfig, RotorModel, SimOptions};
use edgekf_tests::rotor::{check_faulty_run, disk_rms_error, faulty_csv, parse_numbered, run_host, run_host_with};
use std::path::Path;

const CONFIG: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../host-sim/configs/rotor_paper.toml");

#[test]
fn compiled_constants_are_current() {
    let text = edgekf_sim::systems::rotor::cli::estimate::export_text(Path::new(CONFIG), 8).unwrap();
    let committed = include_str!("../../firmware/src/systems/rotor/generated/rotor.rs");
    assert!(
        text == committed,
        "firmware/src/systems/rotor/generated/rotor.rs is stale: run `cargo run -p edgekf-sim -- rotor export --config host-sim/configs/rotor_paper.toml --out firmware/src/systems/rotor/generated/rotor.rs`"
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

/// On reference data the node's start-up term (rank 12, real time at 1 kHz) is as good as
/// the dense time-varying filter it replaces, and the switch at 0.5 s costs nothing: the node
/// and its filter with the term throughout are identical before sample `STEADY_AFTER`, differ
/// from it on, and all three reach the same disk error (start-up and t ≥ 1 s) and NIS.
#[test]
fn the_start_up_term_matches_the_dense_time_varying_filter() {
    let (rec, csv) = recording(7);
    let node = run_host(csv.as_bytes()).unwrap();
    let live = run_host_with(csv.as_bytes(), RotorEstimator::with_switch_at(None)).unwrap();
    let dense = edgekf_tests::rotor::dense_start_run(&csv).unwrap();
    let k0 = STEADY_AFTER as usize;
    assert_eq!(node[..k0], live[..k0]);
    assert_ne!(node[k0].disk, live[k0].disk, "the gain changes at sample {k0}");
    let start = |r: &[RotorReport]| worst_rms(r, &rec, 0.1, 0.5);
    let nis_from = |r: &[RotorReport], t0: f64| {
        let v: Vec<f64> = r.iter().zip(&rec.t).filter(|(_, &t)| t >= t0).map(|(r, _)| r.nis as f64).collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    let (e_node, e_live, e_dense) =
        (disk_rms_error(&node, &rec, 1.0), disk_rms_error(&live, &rec, 1.0), disk_rms_error(&dense, &rec, 1.0));
    let (s_node, s_dense) = (start(&node), start(&dense));
    let (nis_node, nis_dense) = (nis_from(&node, 1.0), nis_from(&dense, 1.0));
    let (nis0_node, nis0_dense) = (nis_from(&node[..k0], 0.0), nis_from(&dense[..k0], 0.0));
    eprintln!(
        "rotor node, disk RMS error 0.1–0.5 s: {:.3} µm (dense time-varying {:.3} µm); t ≥ 1 s: {:.3} µm switched at \
         {:.1} s, {:.3} µm with the start-up term throughout, dense {:.3} µm; NIS mean t ≥ 1 s {nis_node:.3} / \
         {nis_dense:.3}, first 0.5 s {nis0_node:.3} / {nis0_dense:.3}",
        s_node * 1e6,
        s_dense * 1e6,
        e_node * 1e6,
        STEADY_AFTER as f64 / f64::from(SAMPLE_RATE_HZ),
        e_live * 1e6,
        e_dense * 1e6
    );
    assert!(e_node <= 1e-6 && e_node <= 1.02 * e_dense && e_live <= 1.02 * e_dense, "{e_node} {e_live} vs {e_dense}");
    assert!(s_node <= 1.02 * s_dense, "start-up {s_node} vs {s_dense}");
    assert!((nis_node - nis_dense).abs() <= 0.02 * nis_dense, "{nis_node} vs {nis_dense}");
    assert!((nis0_node - nis0_dense).abs() <= 0.02 * nis0_dense, "{nis0_node} vs {nis0_dense}");
}

/// Worst RMS error over the disk nodes' x and y for `t0 ≤ t < t1`, m.
fn worst_rms(r: &[RotorReport], rec: &edgekf_sim::systems::rotor::Recording, t0: f64, t1: f64) -> f64 {
    let upto = rec.t.iter().take_while(|t| **t < t1).count();
    disk_rms_error(&r[..upto], rec, t0)
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
