//! The firmware's accelerometer rotor estimator on the host (28 states, robust tuning): its
//! compiled-in constants are what the host computes for `rotor_paper_accel.toml`, and in `f32`
//! it reaches the disk figures of the host's accelerometer tests (`host-sim/tests/rotor_akf_accel.rs`);
//! with `--features hil` (run by `cargo xtask test`, which sets `EDGEKF_ROTOR_ACCEL_ELF`), the
//! image `edgekf-rotor-accel-qemu` in QEMU, bit-identical to its run on the host.

use edgekf_firmware::systems::rotor::accel::{AccelEstimator, RotorAccelEnd, RotorAccelImage, ACCEL_CHANNELS};
use edgekf_firmware::systems::rotor::{RotorReport, STEADY_AFTER};
use edgekf_sim::systems::rotor::estimate::{reduce, run, Estimates, FilterPrecision, Tuning};
use edgekf_sim::systems::rotor::{Recording, RotorConfig, RotorModel, SimOptions};
use edgekf_tests::rotor::disk_rms_error;
use std::path::Path;

const CONFIG: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../host-sim/configs/rotor_paper_accel.toml");

#[test]
fn compiled_constants_are_current() {
    let (text, states) =
        edgekf_sim::systems::rotor::cli::estimate::export_sized_text(Path::new(CONFIG), 8, true).unwrap();
    assert_eq!(states, 28);
    let committed = include_str!("../../firmware/src/systems/rotor/generated/rotor_accel.rs");
    assert!(
        text == committed,
        "firmware/src/systems/rotor/generated/rotor_accel.rs is stale: run `cargo run -p edgekf-sim -- rotor export --config \
         host-sim/configs/rotor_paper_accel.toml --robust --out firmware/src/systems/rotor/generated/rotor_accel.rs`"
    );
}

/// The host filter's disk estimates and NIS as the node's reports (forces left at 0).
fn host_reports(est: &Estimates) -> Vec<RotorReport> {
    (0..est.t.len())
        .map(|k| {
            let d = |node: usize, axis: usize| est.displacement[2 * node + axis][k] as f32;
            RotorReport { disk: [d(12, 0), d(12, 1), d(23, 0), d(23, 1)], force: [0.0; 4], nis: est.nis[k] as f32 }
        })
        .collect()
}

fn nis_mean(nis: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = nis.filter(|n| n.is_finite()).collect();
    v.iter().sum::<f64>() / v.len() as f64
}

/// The accelerometer test's record (4 s, seed 3), its configuration and model.
fn record() -> (RotorConfig, RotorModel, Recording) {
    let cfg = RotorConfig::load(Path::new(CONFIG)).unwrap();
    let truth = RotorModel::from_config(&cfg).unwrap();
    let rec = truth.simulate(&SimOptions { duration: 4.0, seed: 3, ..SimOptions::default() }).unwrap();
    (cfg, truth, rec)
}

/// The node's estimator on `samples`.
fn node_run(samples: impl Iterator<Item = Option<[f32; 4]>>) -> Vec<RotorReport> {
    let mut est = AccelEstimator::accel();
    let reports: Vec<RotorReport> = samples.map(|s| est.step(s)).collect();
    assert_eq!(est.health(), edgekf::filter::FilterHealth::default());
    assert!(est.is_steady() && reports.len() > 2 * STEADY_AFTER as usize);
    reports
}

/// The record's HIL file read as the two-part node reads it: each line's channels split
/// between two virtual ADXL355s (x and y at node 5, x and y at node 32), read back through the
/// driver in 16-sample FIFO blocks and paired in lockstep. The quantisation (3.8e-5 m/s² a code
/// at ±2 g, against 5.5e-3 m/s² of noise) leaves the disk error within 1 % of the direct run.
/// The image `edgekf-rotor-accel-qemu`, run on the host, reports each poll's last sample of
/// that run bit for bit, and clean counts.
#[test]
fn the_two_part_driver_path_reaches_the_same_disk_figures() {
    use edgekf_firmware::line_feed::ChannelReader;
    use edgekf_firmware::node::{Health, Recorded, SampleSource};
    use edgekf_firmware::source::{Adxl355Settings, Axis, AxisPair};
    use edgekf_firmware::virtual_pair::VirtualPairSource;
    let (_, _, rec) = record();
    let data = rec.to_data_file();
    let csv = data.to_csv_string().unwrap();
    let reader = ChannelReader::new(csv.as_bytes(), ACCEL_CHANNELS).unwrap();
    let mut health = Health::default();
    let settings = Adxl355Settings::default().with_axes(AxisPair(Axis::X, Axis::Y));
    let mut source = VirtualPairSource::start(reader, settings, &mut health).unwrap();
    let mut samples = Vec::new();
    while source.advance() {
        source.read(&mut health, |s| samples.push(s));
    }
    assert_eq!(health, Health::default(), "a clean record: no bus or sample events");
    assert_eq!(samples.len(), data.t.len());
    assert!(samples.iter().all(Option::is_some));
    let reports = node_run(samples.into_iter());
    let lines = edgekf_tests::host::lines::<RotorAccelImage>(csv.as_bytes()).unwrap();
    let frames = edgekf_tests::rotor::parse_numbered(&lines).unwrap();
    assert_eq!(frames.len(), data.t.len() / 16);
    for (k, (n, r)) in frames.iter().enumerate() {
        assert_eq!((*n as usize, r), (16 * k + 15, &reports[16 * k + 15]), "poll {k}");
    }
    let end = edgekf_tests::report::frames::<RotorAccelEnd>(&lines).unwrap();
    let (polls, n) = (frames.len() as u32, data.t.len() as u32);
    assert_eq!(end, [RotorAccelEnd { polls, lines: n, ..Default::default() }]);
    let via_parts = disk_rms_error(&reports, &rec, 1.0);
    let columns: Vec<&[f64]> = ACCEL_CHANNELS.iter().map(|c| data.column(c).unwrap()).collect();
    let direct = node_run((0..data.t.len()).map(|k| Some(core::array::from_fn(|i| columns[i][k] as f32))));
    let direct = disk_rms_error(&direct, &rec, 1.0);
    eprintln!(
        "accelerometer rotor node through two virtual ADXL355s: disk RMS error t ≥ 1 s {:.3} µm (channels read \
         directly {:.3} µm)",
        via_parts * 1e6,
        direct * 1e6
    );
    assert!((via_parts - direct).abs() <= 0.01 * direct, "{via_parts} vs {direct}");
}

/// The accelerometer test's record (4 s, seed 3): the node's estimator (`f32`, start-up term
/// then the steady gain at 0.5 s) against the host's time-varying filter of the same robust
/// tuning in `f32`, and the test's bound for the matched model (1.5 µm for t ≥ 1 s).
#[test]
fn node_estimator_reaches_the_accelerometer_tests_disk_figures() {
    let (cfg, truth, rec) = record();
    let data = rec.to_data_file();
    let columns: Vec<&[f64]> = ACCEL_CHANNELS.iter().map(|c| data.column(c).unwrap()).collect();
    let node = node_run((0..data.t.len()).map(|k| Some(core::array::from_fn(|i| columns[i][k] as f32))));
    let host =
        run(&reduce(&truth, cfg.operation.speed, &Tuning::robust()).unwrap(), &data, FilterPrecision::F32).unwrap();
    assert_eq!(host.repairs, (0, 0));
    let host = host_reports(&host);
    let (e_node, e_host) = (disk_rms_error(&node, &rec, 1.0), disk_rms_error(&host, &rec, 1.0));
    let upto = |t1: f64| rec.t.iter().take_while(|t| **t < t1).count();
    let (s_node, s_host) =
        (disk_rms_error(&node[..upto(0.5)], &rec, 0.1), disk_rms_error(&host[..upto(0.5)], &rec, 0.1));
    let nis_node = nis_mean(node[upto(1.0)..].iter().map(|r| r.nis as f64));
    let nis_host = nis_mean(host[upto(1.0)..].iter().map(|r| r.nis as f64));
    eprintln!(
        "accelerometer rotor node (f32, robust tuning): disk RMS error t ≥ 1 s {:.3} µm, host f32 time-varying \
         {:.3} µm; 0.1–0.5 s {:.3} µm / host {:.3} µm; NIS mean t ≥ 1 s {nis_node:.2} / host {nis_host:.2}",
        e_node * 1e6,
        e_host * 1e6,
        s_node * 1e6,
        s_host * 1e6
    );
    assert!(e_node <= 1.5e-6, "{e_node}");
    assert!((e_node - e_host).abs() <= 0.02 * e_host, "node {e_node} vs host {e_host}");
    assert!(s_node <= 1.05 * s_host, "start-up {s_node} vs {s_host}");
    assert!((nis_node - nis_host).abs() <= 0.05 * nis_host, "NIS {nis_node} vs {nis_host}");
}

#[cfg(feature = "hil")]
mod hil {
    use super::*;
    use edgekf_firmware::frame::StackFrame;
    use edgekf_tests::report::frames;
    use edgekf_tests::rotor::{disk_rms_error_numbered, parse_numbered, qemu_matches_host};

    /// The image in QEMU on the accelerometer test's record (4 s, seed 3), through two virtual
    /// ADXL355s: every poll's report (its last sample) and the end frame bit-identical to the
    /// image's code on the host, clean counts, and the disk error of the reported samples for
    /// t ≥ 1 s within 0.8 µm (0.705 µm measured, 0.717 µm over every sample on the host): the
    /// disks move by up to 87 µm RMS, so a filter that lost them fails by far.
    #[test]
    fn rotor_accel_in_qemu_matches_the_host() {
        let (_, _, rec) = record();
        let csv = rec.to_data_file().to_csv_string().unwrap();
        let elf = edgekf_tests::qemu::image_elf("edgekf-rotor-accel-qemu").unwrap_or_else(|e| panic!("{e:#}"));
        let lines = qemu_matches_host::<RotorAccelImage, RotorAccelEnd>(&elf, csv.as_bytes())
            .unwrap_or_else(|e| panic!("{e:#}"));
        let reports = parse_numbered(&lines).unwrap();
        let (polls, n) = (reports.len() as u32, rec.t.len() as u32);
        assert_eq!(polls, n / 16);
        assert_eq!(frames::<RotorAccelEnd>(&lines).unwrap(), [RotorAccelEnd { polls, lines: n, ..Default::default() }]);
        let err = disk_rms_error_numbered(&reports, &rec, 1.0);
        let stack = frames::<StackFrame>(&lines).unwrap().pop().expect("stack line");
        eprintln!(
            "HIL accelerometer rotor: {polls} polls ({n} samples) bit-identical to the host; disk RMS error {:.3} µm \
             for t ≥ 1 s on the reported samples; {stack:?}",
            err * 1e6
        );
        assert!(err <= 0.8e-6, "{err}");
    }
}
