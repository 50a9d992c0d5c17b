//! Numerical soak: every filter the node runs, in `f32` as on the chip, for many steps on data
//! whose parameters drift slowly (see `edgekf_firmware::soak`, one row per filter in its
//! `SOAKS`, assembled from the systems' rows). Each must stay finite, keep its covariance positive
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

/// Runs soak `index` for its short or (with `EDGEKF_LONG=1`) long step count; its problems, if
/// any.
fn soak(index: usize) -> Option<String> {
    let row = &SOAKS[index];
    let steps = if std::env::var_os("EDGEKF_LONG").is_some() { 10_000_000 } else { row.host_steps };
    let start = Instant::now();
    let frame = run(index, steps).unwrap();
    println!("{} in {:.1} s", line(row, &frame), start.elapsed().as_secs_f64());
    if frame.steps != steps || frame.blocks < 1 {
        return Some(format!(
            "soak {}: {} steps and {} blocks of statistics in {steps} steps",
            row.name, frame.steps, frame.blocks
        ));
    }
    problems(row, &frame)
}

/// Every row of `SOAKS`, each in its own thread (they share the cores, as separate tests
/// would): the rows come from the systems' folders through the firmware's manifest, so a new
/// system's soak runs here without an edit.
#[test]
fn every_filter_stays_sound() {
    let failures: Vec<String> = std::thread::scope(|scope| {
        let runs: Vec<_> = (0..SOAKS.len()).map(|index| scope.spawn(move || soak(index))).collect();
        runs.into_iter().filter_map(|r| r.join().unwrap()).collect()
    });
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
