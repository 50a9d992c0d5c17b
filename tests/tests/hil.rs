//! Hardware-in-the-loop tests: the firmware image runs under QEMU (`-M netduinoplus2`, a
//! Cortex-M4F) with the real ADXL355 driver and main loop talking I²C to a virtual ADXL355 fed
//! from a host CSV file; its defmt output is decoded and compared with the host run of the same
//! code on the same data. Run through `cargo xtask test`, which builds the image and sets
//! `EDGEKF_FW_ELF`.
#![cfg(feature = "hil")]

use edgekf_firmware::frame::StackFrame;
use edgekf_firmware::hil::HilImage;
use edgekf_firmware::systems::oscillator::OscillatorImage;
use edgekf_sim::systems::oscillator::scenario::Scenario;
use edgekf_tests::checks::{
    fault_class, fault_scenario, recovery_mismatch, unaccounted, worst_amplitude_error, DURING_FAULT_BOUND,
    FAULTS_CLEAR_AT,
};
use edgekf_tests::report::RunReport;
use edgekf_tests::{first_difference, host, qemu};
use std::time::Duration;

fn firmware(csv: &[u8]) -> RunReport {
    let elf = qemu::image_elf("edgekf-qemu").unwrap_or_else(|e| panic!("{e:#}"));
    let run = qemu::run(&elf, csv, Duration::from_secs(300)).unwrap_or_else(|e| panic!("{e:#}"));
    if let Some(msg) = run.failure() {
        panic!("{msg}");
    }
    let report = RunReport::parse(run.lines.iter().map(String::as_str)).unwrap_or_else(|e| panic!("{e:#}"));
    assert!(
        report.done,
        "firmware stopped before its end; last lines: {:?}",
        run.lines.iter().rev().take(3).collect::<Vec<_>>()
    );
    report
}

#[test]
fn clean_run_matches_the_host_bit_for_bit() {
    let rec = Scenario::default().simulate();
    let csv = rec.to_csv_string();
    let fw = firmware(csv.as_bytes());
    let host = host::run(csv.as_bytes()).unwrap();
    assert!(fw.health.samples >= 10_000, "only {} samples streamed", fw.health.samples);
    if let Some(diff) = first_difference(&fw, &host) {
        panic!("firmware and host disagree: {diff}");
    }
    let err = worst_amplitude_error(&fw, &rec, 1.0, 6.0).max(worst_amplitude_error(&fw, &rec, 7.0, 12.0));
    let edgekf_firmware::frame::StackFrame { boot, used, total } = fw.stack.expect("stack line");
    eprintln!(
        "HIL clean: {} samples in {} blocks, bit-identical to the host (0 ulp); worst force error {:.3} %; \
         stack high-water {boot} B at start-up, {used} B in the loop, of {total} B; input columns ignored by the device: {}",
        fw.health.samples,
        fw.blocks.len(),
        err * 100.0,
        fw.feed.ignored_columns
    );
    assert!(err < 0.01);
    // The window hand-over's ring (16 KB) is the image's storage, in the entry's frame: it
    // counts in both figures, beside the node's own.
    let ring = std::mem::size_of::<<OscillatorImage as HilImage>::Storage>() as u32;
    assert!(
        boot < 24 * 1024 + ring && used < 8 * 1024 + ring,
        "stack use {boot} B at start-up, {used} B in the loop, the ring's {ring} B included"
    );
}

#[test]
fn the_model_monitor_reports_in_qemu_what_it_reports_on_the_host() {
    // The healthy recording: no `mismatch` frame; a 2.5 mg offset from 6 s on: a bias on the
    // X axis, dated within a window of the offset's start, the same frames as the host's.
    let (healthy, biased, start) = edgekf_tests::monitor::oscillator_recordings(2);
    assert_eq!(firmware(healthy.as_bytes()).mismatches, []);
    let (fw, host) = (firmware(biased.as_bytes()), host::run(biased.as_bytes()).unwrap());
    if let Some(diff) = first_difference(&fw, &host) {
        panic!("firmware and host disagree: {diff}");
    }
    let bias = fw.mismatches.iter().find(|m| m.statistic() == Some(edgekf::residual::Statistic::Bias));
    let bias = bias.unwrap_or_else(|| panic!("no bias mismatch: {:?}", fw.mismatches));
    eprintln!("HIL monitor: offset from sample {start}, frames {:?}", fw.mismatches);
    assert!(bias.channel == 0 && bias.since + 256 > start && bias.since <= start + 256, "{bias:?}");
}

#[test]
fn injected_i2c_faults_are_survived_counted_and_recovered_from() {
    let clean = firmware(Scenario::default().simulate().to_csv_string().as_bytes());
    let csv = fault_scenario().simulate().to_csv_string();
    let fw = firmware(csv.as_bytes());
    let host = host::run(csv.as_bytes()).unwrap();
    if let Some(diff) = first_difference(&fw, &host) {
        panic!("firmware and host disagree on the fault run: {diff}");
    }
    let h = fw.health;
    eprintln!(
        "HIL faults: {h:?}; virtual device: loaded {}, NACKs {}, overwritten entries {}",
        fw.virtual_device.samples_loaded, fw.virtual_device.nacks_sent, fw.virtual_device.overrun_entries
    );
    // The counts of `checks::fault_classes` for its `nack`, `overrun`, `stuck` and
    // `saturation` classes, added up.
    assert_eq!((h.nacks, h.bus_errors, h.recovered, h.failed_polls), (17, 17, 2, 3), "{h:?}");
    assert_eq!((h.fifo_overruns, h.bridged, h.dropped, h.stuck, h.saturated), (1, 32, 0, 200, 50), "{h:?}");
    if let Some(off) = unaccounted(&fw) {
        panic!("{off}");
    }
    let (what, rel) = recovery_mismatch(&clean, &fw, FAULTS_CLEAR_AT + 0.5, 1e-3);
    eprintln!(
        "HIL faults: from 0.5 s after the faults clear, worst mismatch {what} = {:.4} % of the clean RMS",
        rel * 100.0
    );
    assert!(rel < 0.01, "{what}: {rel}");
}

/// One fault class of `checks::fault_classes` alone, in QEMU: the run is bit-identical to the
/// host's, the node's counters are exactly the class's, every fault the virtual device injected
/// is accounted for, the force estimate is accurate before the fault (1 %; before the force
/// step at 6 s for a fault after it), bounded for a second from its start
/// (`DURING_FAULT_BOUND`), and from 0.5 s after it clears within 1 % of the clean run's RMS.
fn fault_class_in_qemu(name: &str) {
    let class = fault_class(name);
    let rec = class.scenario().simulate();
    let csv = rec.to_csv_string();
    let fw = firmware(csv.as_bytes());
    let host = host::run(csv.as_bytes()).unwrap();
    if let Some(diff) = first_difference(&fw, &host) {
        panic!("{name}: firmware and host disagree: {diff}");
    }
    assert_eq!(fw.feed.bad_lines, 0, "{name}: the device's feed refused lines");
    assert_eq!(fw.health, class.health, "{name}: counters (left: firmware, right: expected)");
    if let Some(off) = unaccounted(&fw) {
        panic!("{name}: {off}");
    }
    let clean = host::run(Scenario::default().simulate().to_csv_string().as_bytes()).unwrap();
    let before = worst_amplitude_error(&fw, &rec, 1.0, class.start.min(6.0));
    let during = worst_amplitude_error(&fw, &rec, class.start, class.start + 1.0);
    let (what, rel) = recovery_mismatch(&clean, &fw, class.clear + 0.5, 1e-3);
    let h = fw.health;
    eprintln!(
        "HIL fault {name}: bus errors {} (NACKs {}, timeouts {}, bad IDs {}), recovered {}, failed polls {}, \
         overruns {}, bridged {} (dropped {}), config checks {}, resets {}, stuck {}, saturated {}; \
         force error {:.3} % before, worst {:.3} % in the second from the fault; \
         from 0.5 s after it clears, worst mismatch {what} {:.2e} % of the clean RMS",
        h.bus_errors,
        h.nacks,
        h.timeouts,
        h.bad_id,
        h.recovered,
        h.failed_polls,
        h.fifo_overruns,
        h.bridged,
        h.dropped,
        h.config_checks,
        h.resets,
        h.stuck,
        h.saturated,
        before * 100.0,
        during * 100.0,
        rel * 100.0
    );
    assert!(before < 0.01, "{name}: {before} before the fault");
    assert!(during < DURING_FAULT_BOUND, "{name}: {during} after the fault's start (bound {DURING_FAULT_BOUND})");
    assert!(rel < 0.01, "{name}: {what} {rel} after recovery");
}

#[test]
fn fault_nack_burst_is_retried() {
    fault_class_in_qemu("nack");
}

#[test]
fn fault_fifo_overrun_is_bridged() {
    fault_class_in_qemu("overrun");
}

#[test]
fn fault_bus_timeouts_give_up_the_poll() {
    fault_class_in_qemu("timeout");
}

#[test]
fn fault_garbage_ids_are_not_taken_for_samples() {
    fault_class_in_qemu("garbage");
}

#[test]
fn fault_frozen_output_is_not_used() {
    fault_class_in_qemu("stuck");
}

#[test]
fn fault_saturated_axis_is_not_used() {
    fault_class_in_qemu("saturation");
}

#[test]
fn fault_dropped_samples_are_bridged() {
    fault_class_in_qemu("dropout");
}

#[test]
fn fault_sensor_reset_is_detected_and_reconfigured() {
    fault_class_in_qemu("reset");
}

#[test]
fn a_failing_firmware_run_fails_with_a_readable_message() {
    let elf = qemu::image_elf("edgekf-qemu").unwrap();
    let run = qemu::run(&elf, b"time,accel\n0,1\n", Duration::from_secs(60)).unwrap();
    assert_eq!(run.exit_code, Some(3));
    let msg = run.failure().expect("a failure");
    assert!(msg.contains("exit code Some(3)") && msg.contains("no usable header"), "{msg}");
}

/// Four seconds of the paper rotor (seed 7) and its HIL file.
fn rotor_recording() -> (edgekf_sim::systems::rotor::Recording, String) {
    use edgekf_sim::systems::rotor::{RotorConfig, RotorModel, SimOptions};
    let cfg = RotorConfig::from_toml_str(include_str!("../../host-sim/configs/rotor_paper.toml")).unwrap();
    let rec = RotorModel::from_config(&cfg)
        .unwrap()
        .simulate(&SimOptions { duration: 4.0, seed: 7, ..SimOptions::default() })
        .unwrap();
    let csv = rec.to_data_file().to_csv_string().unwrap();
    (rec, csv)
}

#[test]
fn rotor_virtual_sensing_in_qemu_matches_the_host_bit_for_bit() {
    use edgekf_firmware::systems::rotor::{RotorEnd, RotorImage};
    let (rec, csv) = rotor_recording();
    let elf = qemu::image_elf("edgekf-rotor-qemu").unwrap_or_else(|e| panic!("{e:#}"));
    let lines = edgekf_tests::rotor::qemu_matches_host::<RotorImage, RotorEnd>(&elf, csv.as_bytes())
        .unwrap_or_else(|e| panic!("{e:#}"));
    let fw = edgekf_tests::rotor::parse(&lines).unwrap();
    assert_eq!(fw.len(), rec.t.len(), "firmware reported {} of {} samples", fw.len(), rec.t.len());
    let err = edgekf_tests::rotor::disk_rms_error(&fw, &rec, 1.0);
    let stack = edgekf_tests::report::frames::<StackFrame>(&lines).unwrap().pop().expect("stack line");
    eprintln!(
        "HIL rotor: {} samples bit-identical to the host; disk RMS error {:.3} µm for t ≥ 1 s; {stack:?}",
        fw.len(),
        err * 1e6
    );
    assert!(err <= 1e-6);
}

/// The rotor image on a HIL file with missing lines, garbage lines, an empty cell and a NaN
/// (`edgekf_tests::rotor::faulty_csv`): bit-identical to the host run of the same file, and
/// the counts and bounds of `edgekf_tests::rotor::check_faulty_run` (21 samples bridged for
/// missing lines, 4 bad lines of which 2 without a `t`, no time jump; a report for every other
/// sample; disk error within 1 µm RMS; within 1 % of the clean run from 0.5 s after the faults).
#[test]
fn rotor_image_bridges_missing_and_garbage_lines() {
    use edgekf_firmware::systems::rotor::{RotorEnd, RotorImage};
    use edgekf_tests::rotor::{check_faulty_run, end, faulty_csv, parse_numbered, qemu_matches_host};
    let (rec, csv) = rotor_recording();
    let faulty = faulty_csv(&csv);
    let elf = qemu::image_elf("edgekf-rotor-qemu").unwrap_or_else(|e| panic!("{e:#}"));
    let lines = qemu_matches_host::<RotorImage, RotorEnd>(&elf, faulty.as_bytes()).unwrap_or_else(|e| panic!("{e:#}"));
    let clean = edgekf_tests::host::lines::<RotorImage>(csv.as_bytes()).unwrap();
    let (err, mismatch) =
        check_faulty_run(&lines, &parse_numbered(&clean).unwrap(), &rec).unwrap_or_else(|e| panic!("{e:#}"));
    eprintln!(
        "HIL rotor with missing and garbage lines: {:?}; bit-identical to the host; disk RMS error {:.3} µm for \
         t ≥ 1 s; from 0.5 s after the faults {:.2e} % off the clean run",
        end(&lines).unwrap(),
        err * 1e6,
        mismatch * 100.0
    );
}
