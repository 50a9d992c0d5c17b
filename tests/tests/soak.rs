//! Numerical soak: every filter the node runs, in `f32` as on the chip, for many steps on data
//! whose parameters drift slowly (see `edgekf_firmware::soak`, one row per filter in its
//! `SOAKS`, which a test keeps complete). Each must stay finite, keep its covariance positive
//! definite and symmetric (at most one covariance reset per 10⁶ steps), refuse no update, stay
//! consistent (NIS) and keep tracking the truth, block after block
//! (`edgekf_tests::soak::problems`).
//!
//! `cargo test -p edgekf-tests --test soak` is the short soak CI runs (each row's
//! `host_steps`); `EDGEKF_LONG=1 cargo test --release -p edgekf-tests --test soak --
//! --nocapture` runs 10⁷ steps of each and prints the figures the README gives. The same code
//! runs in QEMU (`edgekf-soak`, `tests/tests/soak_qemu.rs`).

use edgekf_firmware::soak::{run, SOAKS};
use edgekf_tests::soak::{line, problems};
use std::time::Instant;

/// Runs soak `name` for its short or (with `EDGEKF_LONG=1`) long step count and checks it.
fn soak(name: &str) {
    let index = SOAKS.iter().position(|r| r.name == name).unwrap_or_else(|| panic!("no soak row {name}"));
    let row = &SOAKS[index];
    let steps = if std::env::var_os("EDGEKF_LONG").is_some() { 10_000_000 } else { row.host_steps };
    let start = Instant::now();
    let frame = run(index, steps).unwrap();
    println!("{} in {:.1} s", line(row, &frame), start.elapsed().as_secs_f64());
    assert_eq!(frame.steps, steps);
    assert!(frame.blocks >= 1, "soak {name}: no block of statistics in {steps} steps");
    if let Some(p) = problems(row, &frame) {
        panic!("{p}");
    }
}

/// One test per row, so that they run in parallel; this test keeps the list complete.
#[test]
fn every_soak_row_has_its_test() {
    let source = include_str!("soak.rs");
    for row in &SOAKS {
        assert!(source.contains(&format!("soak(\"{}\")", row.name)), "soak row {} has no test here", row.name);
    }
}

#[test]
fn the_oscillator_time_varying_filter_stays_sound() {
    soak("oscillator_varying");
}

#[test]
fn the_oscillator_steady_state_filter_stays_sound() {
    soak("oscillator_steady");
}

#[test]
fn the_rotor_filter_with_its_start_up_term_throughout_stays_sound() {
    soak("rotor_start_up");
}

#[test]
fn the_rotor_node_stays_sound() {
    soak("rotor_node");
}

#[test]
fn the_accelerometer_rotor_filter_with_its_start_up_term_throughout_stays_sound() {
    soak("rotor_accel_start_up");
}

#[test]
fn the_accelerometer_rotor_node_stays_sound() {
    soak("rotor_accel_node");
}

#[test]
fn the_joint_ukf_stays_sound() {
    soak("joint_ukf");
}

#[test]
fn the_crank_clearance_estimator_stays_sound() {
    soak("crank");
}

#[test]
fn the_vehicle_joint_ukf_stays_sound() {
    soak("uuv");
}

#[test]
fn the_boom_filter_stays_sound() {
    soak("boom");
}
