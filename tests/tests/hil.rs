//! Hardware-in-the-loop tests: the firmware image runs under QEMU (`-M netduinoplus2`, a
//! Cortex-M4F) with the real ADXL355 driver and main loop talking I²C to a virtual ADXL355 fed
//! from a host CSV file; its defmt output is decoded and compared with the host run of the same
//! code on the same data. Run through `cargo xtask test`, which builds the image and sets
//! `EDGEKF_FW_ELF`.
#![cfg(feature = "hil")]

use edgekf_firmware::frame::StackFrame;
use edgekf_sim::systems::oscillator::scenario::Scenario;
use edgekf_tests::checks::{fault_scenario, recovery_mismatch, worst_amplitude_error, FAULTS_CLEAR_AT};
use edgekf_tests::report::RunReport;
use edgekf_tests::{first_difference, host, qemu};
use std::time::Duration;

fn firmware(csv: &[u8]) -> RunReport {
    let elf = qemu::firmware_elf().unwrap_or_else(|e| panic!("{e:#}"));
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
    assert!(boot < 24 * 1024 && used < 8 * 1024, "stack use {boot} B at start-up, {used} B in the loop");
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
    assert!(h.nacks >= 17 && h.recovered >= 1 && h.failed_polls >= 2, "{h:?}");
    assert!(h.stuck >= 195 && h.saturated == 50 && h.bridged > 0, "{h:?}");
    let (what, rel) = recovery_mismatch(&clean, &fw, FAULTS_CLEAR_AT + 0.5, 1e-3);
    eprintln!(
        "HIL faults: from 0.5 s after the faults clear, worst mismatch {what} = {:.4} % of the clean RMS",
        rel * 100.0
    );
    assert!(rel < 0.01, "{what}: {rel}");
}

#[test]
fn a_failing_firmware_run_fails_with_a_readable_message() {
    let elf = qemu::firmware_elf().unwrap();
    let run = qemu::run(&elf, b"time,accel\n0,1\n", Duration::from_secs(60)).unwrap();
    assert_eq!(run.exit_code, Some(3));
    let msg = run.failure().expect("a failure");
    assert!(msg.contains("exit code Some(3)") && msg.contains("no usable header"), "{msg}");
}

#[test]
fn rotor_virtual_sensing_in_qemu_matches_the_host_bit_for_bit() {
    use edgekf_sim::systems::rotor::{RotorConfig, RotorModel, SimOptions};
    let cfg = RotorConfig::from_toml_str(include_str!("../../host-sim/configs/rotor_paper.toml")).unwrap();
    let rec = RotorModel::from_config(&cfg)
        .unwrap()
        .simulate(&SimOptions { duration: 4.0, seed: 7, ..SimOptions::default() })
        .unwrap();
    let csv = rec.to_data_file().to_csv_string().unwrap();
    let elf = qemu::rotor_elf().unwrap_or_else(|e| panic!("{e:#}"));
    let run = qemu::run(&elf, csv.as_bytes(), Duration::from_secs(600)).unwrap_or_else(|e| panic!("{e:#}"));
    if let Some(msg) = run.failure() {
        panic!("{msg}");
    }
    let fw = edgekf_tests::rotor::parse(&run.lines).unwrap();
    let host = edgekf_tests::rotor::run_host(csv.as_bytes()).unwrap();
    assert_eq!(fw.len(), rec.t.len(), "firmware reported {} of {} samples", fw.len(), rec.t.len());
    for (k, (a, b)) in fw.iter().zip(&host).enumerate() {
        let bits = |r: &edgekf_firmware::systems::rotor::RotorReport| {
            r.disk.iter().chain(&r.force).chain([&r.nis]).map(|v| v.to_bits()).collect::<Vec<_>>()
        };
        assert_eq!(bits(a), bits(b), "sample {k}: firmware {a:?} host {b:?}");
    }
    let err = edgekf_tests::rotor::disk_rms_error(&fw, &rec, 1.0);
    let stack = edgekf_tests::report::frames::<StackFrame>(&run.lines).unwrap().pop().expect("stack line");
    eprintln!(
        "HIL rotor: {} samples bit-identical to the host; disk RMS error {:.3} µm for t ≥ 1 s; {stack:?}",
        fw.len(),
        err * 1e6
    );
    assert!(err <= 1e-6);
}
