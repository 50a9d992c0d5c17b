//! The firmware's driver and main loop, run on the host on reference-simulator data: the same
//! checks the QEMU runs make, without QEMU, in every `cargo test`.

use edgekf_sim::systems::oscillator::scenario::Scenario;
use edgekf_tests::checks::{fault_scenario, recovery_mismatch, worst_amplitude_error, FAULTS_CLEAR_AT};
use edgekf_tests::host;

#[test]
fn clean_run_estimates_the_force_within_one_percent() {
    let rec = Scenario::default().simulate();
    let run = host::run(rec.to_csv_string().as_bytes()).unwrap();
    assert!(run.health.samples >= 10_000, "{:?}", run.health);
    assert_eq!(run.health.bus_errors + run.health.stuck + run.health.saturated + run.health.bridged, 0);
    // Converged before the step (5 N), and again after it (3 N at 6.0–6.2 s).
    let before = worst_amplitude_error(&run, &rec, 1.0, 6.0);
    let after = worst_amplitude_error(&run, &rec, 7.0, 12.0);
    eprintln!("force amplitude error: worst {:.3} % before the step, {:.3} % after", before * 100.0, after * 100.0);
    assert!(before < 0.01 && after < 0.01, "before {before}, after {after}");
}

#[test]
fn faults_are_counted_and_the_estimate_recovers() {
    let clean = host::run(Scenario::default().simulate().to_csv_string().as_bytes()).unwrap();
    let faulty = host::run(fault_scenario().simulate().to_csv_string().as_bytes()).unwrap();
    let h = faulty.health;
    eprintln!("fault run health: {h:?}");
    assert!(h.nacks >= 17 && h.recovered >= 1 && h.failed_polls >= 2, "{h:?}");
    assert!(h.fifo_overruns >= 1 && h.bridged > 0, "{h:?}");
    assert!((195..=200).contains(&h.stuck), "{h:?}");
    assert_eq!(h.saturated, 50, "{h:?}");
    let (what, rel) = recovery_mismatch(&clean, &faulty, FAULTS_CLEAR_AT + 0.5, 1e-3);
    eprintln!("after recovery: worst RMS mismatch {what} {:.2e} % of the clean run's RMS", rel * 100.0);
    assert!(rel < 0.01, "{what}: {rel}");
}
