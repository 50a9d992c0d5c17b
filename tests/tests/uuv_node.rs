//! Underwater-vehicle thruster health on the node (`edgekf-uuv-qemu`,
//! `edgekf_firmware::systems::uuv`): the image's code on the host, fed the CSV text the QEMU
//! image reads, declares the paper scenario's fault and recovery as the host's `f64` estimator
//! does; empty DVL cells are missing values, garbage and lost rows are counted and bridged; and,
//! with `--features hil` (run by `cargo xtask test`, which sets `EDGEKF_UUV_ELF`), the image in
//! QEMU reports bit for bit what its code reports on the host.

use edgekf_firmware::frame::Frame;
use edgekf_firmware::hil::FileEnd;
use edgekf_firmware::systems::uuv::{UuvEnd, UuvFrame, UuvImage};
use edgekf_sim::systems::uuv::{simulate, Scenario, SimOptions, UuvConfig, UuvRecording};
use edgekf_tests::host::{file_end, lines};
use edgekf_tests::report::frames;

/// The paper scenario from 200 s to 232 s (the fault at 220 s, the first recovery at 228 s
/// and the relapse at 230 s), as the CSV the image reads.
fn paper_tail(seed: u64) -> (UuvRecording, String) {
    let rec =
        simulate(&UuvConfig::default(), &SimOptions { scenario: Scenario::Paper, duration: 232.0, seed }, &mut |_| {})
            .unwrap();
    let keep: Vec<usize> = (0..rec.t.len()).filter(|&i| rec.t[i] >= 200.0).collect();
    let tail = UuvRecording {
        t: keep.iter().map(|&i| rec.t[i]).collect(),
        columns: rec.columns.iter().map(|c| keep.iter().map(|&i| c[i]).collect()).collect(),
    };
    let text = tail.to_csv(std::path::Path::new("paper_tail.csv")).unwrap();
    (tail, text)
}

/// The host run's per-sample frames, its end frame and its `file` frame.
fn run_host(text: &str) -> (Vec<UuvFrame>, UuvEnd, FileEnd) {
    let out = lines::<UuvImage>(text.as_bytes()).unwrap();
    let per_sample = frames::<UuvFrame>(&out).unwrap();
    let end = frames::<UuvEnd>(&out).unwrap().pop().expect("uuvend frame");
    (per_sample, end, file_end(&out).unwrap())
}

/// The node's vehicle and estimator are the shipped configuration's, as the host's estimator
/// builds them (the committed `generated/uuv.rs`, `edgekf uuv export`'s), and the ones the
/// image ran before they were exported: REMUS 100 and the default settings.
#[test]
fn the_nodes_vehicle_and_estimator_are_the_configurations() {
    use edgekf::systems::uuv::{EstimatorSettings, Vehicle};
    use edgekf_firmware::systems::uuv as node;
    assert_eq!((node::VEHICLE, node::ESTIMATOR), (Vehicle::default(), EstimatorSettings::new(node::LAYOUT, 50.0)));
    let text = include_str!("../../host-sim/configs/uuv_remus100.toml");
    let c = UuvConfig::from_toml_str(text).unwrap();
    assert_eq!(f64::from(node::SAMPLE_RATE_HZ), c.sensors.rate);
    assert_eq!(node::VEHICLE, c.vehicle);
    assert_eq!(node::ESTIMATOR, c.estimator.settings(c.sensors.rate));
}

/// Seconds from `at` to the first frame at or after it whose main-thruster status is
/// `declared` (or healthy when not).
fn latency(rec: &UuvRecording, frames: &[UuvFrame], at: f64, declared: bool) -> f64 {
    let start = rec.t.iter().position(|&t| t >= at - 1e-9).unwrap();
    match (start..frames.len()).find(|&k| (frames[k].status_t != 0) == declared) {
        Some(k) => (k - start) as f64 / 50.0,
        None => f64::INFINITY,
    }
}

#[test]
fn node_declares_the_fault_and_the_recovery_within_a_second() {
    let (rec, text) = paper_tail(3);
    let (frames, end, file) = run_host(&text);
    assert_eq!(frames.len(), rec.t.len());
    assert_eq!((end.samples as usize, file.bad_lines, file.missing_lines), (rec.t.len(), 0, 0));
    assert_eq!((end.covariance_resets, end.refused_updates), (0, 0));
    let [fault, recovery, relapse] =
        [(220.0, true), (228.0, false), (230.0, true)].map(|(t, d)| latency(&rec, &frames, t, d));
    eprintln!("node (host run): fault declared after {fault:.2} s, recovery after {recovery:.2} s, relapse after {relapse:.2} s");
    assert!(fault <= 1.0 && recovery <= 1.0 && relapse <= 1.0, "{fault} {recovery} {relapse}");
    // Before the fault: healthy throughout, and k_t near 1.
    let before = rec.t.iter().position(|&t| t >= 220.0).unwrap();
    assert!(frames[..before].iter().all(|f| f.status_t == 0 && f.status_v == 0));
    assert!((frames[before - 1].k_t - 1.0).abs() < 0.1, "k_t = {}", frames[before - 1].k_t);
    let truth_k = rec.column("truth_k_t").unwrap();
    let late = frames.len() - 1;
    assert!((frames[late].k_t as f64 - truth_k[late]).abs() < 0.1);
}

#[test]
fn garbage_and_lost_rows_are_counted_and_bridged() {
    let (rec, text) = paper_tail(3);
    let mut rows: Vec<String> = text.lines().map(str::to_owned).collect();
    // Row 101 lost, row 201 with garbage for acc_x, row 301 with a NaN depth.
    let set = |row: &str, field: usize, value: &str| {
        let mut cells: Vec<&str> = row.split(',').collect();
        cells[field] = value;
        cells.join(",")
    };
    rows[202] = set(&rows[202], 1, "x");
    rows[302] = set(&rows[302], 7, "NaN");
    rows.remove(102);
    let faulty = rows.join("\n") + "\n";
    let (frames, end, file) = run_host(&faulty);
    assert_eq!(end.samples as usize, rec.t.len(), "every sample stepped, the lost row bridged");
    assert_eq!((file.missing_lines, file.time_jumps), (1, 0));
    assert_eq!(file.bad_lines, 1, "the garbage row; a NaN cell is a missing value");
    let (clean, ..) = run_host(&text);
    let last = frames.len() - 1;
    assert!((frames[last].k_t - clean[last].k_t).abs() < 0.05);
    assert_eq!(frames[last].status_t, clean[last].status_t);
}

#[test]
fn frames_read_back() {
    let f = UuvFrame { sample: 3, k_t: 0.5, status_t: 1, ..UuvFrame::default() };
    let mut line = String::new();
    f.write_line(&mut line).unwrap();
    assert_eq!(UuvFrame::parse(&line).unwrap().unwrap(), f);
}

#[cfg(feature = "hil")]
mod hil {
    use super::*;
    use edgekf_tests::qemu;
    use std::time::Duration;

    /// The image in QEMU on 32 s of the paper scenario: every frame bit-identical to the
    /// image's code on the host.
    #[test]
    fn uuv_in_qemu_matches_the_host() {
        let elf = qemu::image_elf("edgekf-uuv-qemu").unwrap_or_else(|e| panic!("{e:#}"));
        let (_, text) = paper_tail(3);
        let run = qemu::run(&elf, text.as_bytes(), Duration::from_secs(600)).unwrap_or_else(|e| panic!("{e:#}"));
        if let Some(msg) = run.failure() {
            panic!("{msg}");
        }
        let chip = frames::<UuvFrame>(&run.lines).unwrap();
        let (host, end, file) = run_host(&text);
        let bits =
            |f: &UuvFrame| [f.k_t, f.k_t_std, f.k_v, f.k_v_std, f.z, f.psi, f.u, f.phi, f.imu_nis].map(f32::to_bits);
        assert_eq!(chip.len(), host.len());
        for (c, h) in chip.iter().zip(&host) {
            assert_eq!(
                (c.sample, c.status_t, c.status_v, bits(c)),
                (h.sample, h.status_t, h.status_v, bits(h)),
                "sample {}",
                h.sample
            );
        }
        let chip_end = frames::<UuvEnd>(&run.lines).unwrap().pop().expect("uuvend");
        assert_eq!(chip_end, end);
        assert_eq!(file_end(&run.lines).unwrap(), file);
        let stack = frames::<edgekf_firmware::frame::StackFrame>(&run.lines).unwrap().pop().expect("stack line");
        eprintln!("HIL uuv: {} frames bit-identical to the host run; {stack:?}", chip.len());
    }
}

/// Soak: the node's `f32` estimator over a long healthy flight (2 000 s, 10⁵ samples; 10⁶ with
/// `EDGEKF_LONG=1`): no covariance reset, no refused update, never declared, the main
/// thruster's factor within 0.1 of 1 and the IMU update's NIS consistent, block by block.
#[test]
fn node_soak_on_a_long_healthy_flight() {
    let samples: u64 = if std::env::var_os("EDGEKF_LONG").is_some() { 1_000_000 } else { 100_000 };
    let config = UuvConfig::default();
    let opts = SimOptions { scenario: Scenario::Healthy, duration: samples as f64 / 50.0, seed: 77 };
    let rec = simulate(&config, &opts, &mut |_| {}).unwrap();
    let text = rec.to_csv(std::path::Path::new("soak.csv")).unwrap();
    let (frames, end, file) = run_host(&text);
    assert_eq!(file, FileEnd::default(), "a simulated file has no bad, missing or untimed lines");
    assert_eq!(end.samples as u64, samples);
    assert_eq!((end.covariance_resets, end.refused_updates), (0, 0));
    assert!(frames.iter().all(|f| f.status_t == 0 && f.status_v == 0), "declared on healthy data");
    let worst_k = frames.iter().skip(500).map(|f| (f.k_t - 1.0).abs().max((f.k_v - 1.0).abs())).fold(0.0f32, f32::max);
    // NIS per degree of freedom, by blocks of 10⁴ samples (8 with depth and heading).
    let blocks: Vec<f64> = frames[1..]
        .chunks(10_000)
        .map(|b| b.iter().map(|f| f.imu_nis as f64 / 8.0).sum::<f64>() / b.len() as f64)
        .collect();
    let (lo, hi) = blocks.iter().fold((f64::INFINITY, 0.0f64), |(l, h), v| (l.min(*v), h.max(*v)));
    eprintln!(
        "uuv node soak: {samples} samples, worst |k − 1| {worst_k:.4}, NIS per dof by block {lo:.3}–{hi:.3}, {} CUSUM reopenings",
        end.alarms_t + end.alarms_v
    );
    assert!(worst_k < 0.1, "{worst_k}");
    assert!(lo > 0.5 && hi < 2.0, "NIS per dof {lo}–{hi}");
}
