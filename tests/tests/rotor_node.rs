//! The firmware's rotor estimator on the host: its compiled-in constants are what the host
//! computes for the paper rotor, and it meets the virtual-sensing target on reference data.

use edgekf_sim::rotor::{RotorConfig, RotorModel, SimOptions};
use edgekf_tests::rotor::{disk_rms_error, run_host};
use std::path::Path;

const CONFIG: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../host-sim/configs/rotor_paper.toml");

#[test]
fn compiled_constants_are_current() {
    let text = edgekf_sim::rotor_akf::cli::export_text(Path::new(CONFIG), 8).unwrap();
    let committed = include_str!("../../firmware/src/generated/rotor.rs");
    assert!(
        text == committed,
        "firmware/src/generated/rotor.rs is stale: run `cargo run -p edgekf-sim -- rotor export --config host-sim/configs/rotor_paper.toml --out firmware/src/generated/rotor.rs`"
    );
}

#[test]
fn node_estimator_meets_the_disk_target_in_f32() {
    let cfg = RotorConfig::load(Path::new(CONFIG)).unwrap();
    let rec = RotorModel::from_config(&cfg)
        .unwrap()
        .simulate(&SimOptions { duration: 4.0, seed: 11, ..SimOptions::default() })
        .unwrap();
    let csv = rec.to_data_file().to_csv_string().unwrap();
    let reports = run_host(csv.as_bytes()).unwrap();
    let err = disk_rms_error(&reports, &rec, 1.0);
    eprintln!("firmware rotor estimator on the host (f32): disk RMS error {:.3} µm for t ≥ 1 s", err * 1e6);
    assert!(err <= 1e-6, "{err}");
}
