//! The firmware's driver and main loop, run on the host on reference-simulator data: the same
//! checks the QEMU runs make, without QEMU, in every `cargo test`.

use edgekf_sim::systems::oscillator::scenario::Scenario;
use edgekf_tests::checks::{
    fault_classes, fault_scenario, recovery_mismatch, unaccounted, worst_amplitude_error, DURING_FAULT_BOUND,
    FAULTS_CLEAR_AT,
};
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
    assert_eq!((h.nacks, h.bus_errors, h.recovered, h.failed_polls), (17, 17, 2, 3), "{h:?}");
    assert_eq!((h.fifo_overruns, h.bridged, h.dropped, h.stuck, h.saturated), (1, 32, 0, 200, 50), "{h:?}");
    assert_eq!(unaccounted(&faulty), None);
    let (what, rel) = recovery_mismatch(&clean, &faulty, FAULTS_CLEAR_AT + 0.5, 1e-3);
    eprintln!("after recovery: worst RMS mismatch {what} {:.2e} % of the clean run's RMS", rel * 100.0);
    assert!(rel < 0.01, "{what}: {rel}");
}

/// Every fault class of `checks::fault_classes` on the host, as the HIL tests run them in
/// QEMU: exact counts, every injected fault accounted for, bounded and recovering estimates.
#[test]
fn every_fault_class_is_counted_exactly_and_recovered_from() {
    let clean = host::run(Scenario::default().simulate().to_csv_string().as_bytes()).unwrap();
    for class in fault_classes() {
        let rec = class.scenario().simulate();
        let run = host::run(rec.to_csv_string().as_bytes()).unwrap();
        let name = class.name;
        assert_eq!(run.health, class.health, "{name}: counters (left: run, right: expected)");
        assert_eq!(unaccounted(&run), None, "{name}");
        assert_eq!(run.estimator.steps, 12_000, "{name}: the estimator's clock slipped");
        let before = worst_amplitude_error(&run, &rec, 1.0, class.start.min(6.0));
        let during = worst_amplitude_error(&run, &rec, class.start, class.start + 1.0);
        let (what, rel) = recovery_mismatch(&clean, &run, class.clear + 0.5, 1e-3);
        eprintln!(
            "{name:<10} force error {:.3} % before, worst {:.3} % in the second from the fault (bound {:.0} %); \
             after recovery {what} {:.2e} %",
            before * 100.0,
            during * 100.0,
            DURING_FAULT_BOUND * 100.0,
            rel * 100.0
        );
        assert!(before < 0.01 && during < DURING_FAULT_BOUND && rel < 0.01, "{name}: {before} {during} {what} {rel}");
    }
}

/// The simulator writes exactly the fault columns the virtual device reads, by the same names.
#[test]
fn fault_columns_are_the_virtual_devices() {
    use edgekf_sim::systems::oscillator::scenario::Recording;
    let written: Vec<&str> = Recording::CHANNELS.iter().copied().filter(|c| c.starts_with("fault_")).collect();
    assert_eq!(written, edgekf_firmware::virtual_adxl355::FAULT_COLUMNS);
}
