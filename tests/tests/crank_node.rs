//! Slider-crank joint clearance on the node (`edgekf-crank-qemu`, `edgekf_firmware::systems::crank`):
//! the compiled-in model is the host's built-in one; the streaming features (the shared crate's,
//! which the host uses too) equal the original two-pass host computation; the node's `f32`
//! estimate agrees with the host's `f64` `FastModel`; bad samples are skipped and counted; and,
//! with `--features hil` (run by `cargo xtask test`, which sets `EDGEKF_CRANK_ELF`), the image
//! in QEMU reports bit for bit what the node's code reports on the host.

use edgekf_sim::systems::crank::estimate::model::{feature_vector, FastModel, FEATURES, FEATURE_NAMES};
use edgekf_sim::systems::crank::estimate::runs::Run;
use edgekf_sim::systems::crank::estimate::Recording;
use edgekf_sim::systems::crank::{CrankConfig, Joint};
use edgekf_tests::crank::{check_faulty_run, csv, faulty_csv, reference_features, run_host};

/// Agreement required between the node (`f32`) and the host (`f64`) on the clearance of the
/// whole recording, relative. Measured: below 1e-4 (see the test's output).
const CLEARANCE_TOLERANCE: f64 = 1e-3;

fn recording(joint: Joint, clearance: f64, seed: u64) -> Recording {
    let run = Run { joint, clearance, release_deg: 30.0, radius: 1.0, seed, duration: 2.0 };
    run.simulate(&CrankConfig::default()).unwrap()
}

#[test]
fn compiled_model_is_current() {
    let committed = include_str!("../../firmware/src/systems/crank/generated/clearance.rs");
    assert!(
        FastModel::builtin().to_rust() == committed,
        "firmware/src/systems/crank/generated/clearance.rs is stale: run `cargo run -p edgekf-sim -- crank export --out firmware/src/systems/crank/generated/clearance.rs`"
    );
    // And what the firmware compiles is that model, rounded to f32.
    let m = FastModel::builtin().to_shared();
    assert_eq!(edgekf_firmware::systems::crank::MODEL_F64, m);
    assert_eq!(edgekf_firmware::systems::crank::MODEL.regression[1][7], m.regression[1][7] as f32);
}

/// The streaming features in `f64` against the original two-pass host code, on a clearance run
/// with impacts and on an ideal one.
#[test]
fn streaming_features_equal_the_two_pass_reference() {
    for rec in [recording(Joint::A, 0.25e-3, 3), recording(Joint::C, 0.1e-3, 4)] {
        let f = feature_vector(&rec.crank_alpha, rec.sample_rate, 0.25);
        let (reference, windows) = reference_features(&rec.crank_alpha, rec.sample_rate, 0.25);
        assert_eq!(f.windows, windows);
        assert_eq!(windows, 8);
        for i in 0..FEATURES {
            let d = (f.values[i] - reference[i]).abs();
            eprintln!(
                "{:<16} streaming {:.12} two-pass {:.12} (|Δ| {d:.1e})",
                FEATURE_NAMES[i], f.values[i], reference[i]
            );
            assert!(d <= 1e-10, "{}: {} vs {}", FEATURE_NAMES[i], f.values[i], reference[i]);
        }
    }
}

/// The node's estimator in `f32`, fed the CSV text the QEMU image reads, against the host's
/// `f64` estimator on the same recording: the same joint, the clearance within
/// [`CLEARANCE_TOLERANCE`], every window's running estimate too.
#[test]
fn node_f32_agrees_with_the_host_f64_estimator() {
    let model = FastModel::builtin();
    let shared = model.to_shared();
    for (joint, c, seed) in [(Joint::A, 0.25e-3, 1), (Joint::B, 0.3e-3, 2)] {
        let rec = recording(joint, c, seed);
        let node = run_host(csv(&rec.t, &rec.crank_alpha).as_bytes()).unwrap();
        let host = model.estimate(&rec).unwrap();
        assert_eq!(node.windows.len(), host.features.windows);
        assert_eq!((node.end.samples as usize, node.end.skipped), (rec.t.len(), 0));
        let worst_feature =
            (0..FEATURES).map(|i| (node.features[i] as f64 - host.features.values[i]).abs()).fold(0.0, f64::max);
        let rel = node.estimate.clearance as f64 / host.clearance[host.joint.index()] - 1.0;
        // Every window: the f64 running estimate from the same streaming code.
        let mut worst_window = 0.0f64;
        for w in &node.windows {
            let k = w.samples as usize;
            let f = feature_vector(&rec.crank_alpha[..k], rec.sample_rate, 0.25);
            let e = shared.estimate_with_release(&f.values, f.release.as_ref(), f.windows as u32);
            assert_eq!(w.estimate.joint, e.joint, "window {}", w.window);
            worst_window = worst_window.max((w.estimate.clearance as f64 / e.clearance - 1.0).abs());
        }
        eprintln!(
            "{joint} {:.3} mm (seed {seed}, 2 s): host f64 names {} {:.5} mm, node f32 names {} {:.5} mm ({rel:+.2e}); \
             worst over {} windows {worst_window:.2e}; worst feature |Δ| {worst_feature:.1e}",
            c * 1e3,
            host.joint,
            host.clearance[host.joint.index()] * 1e3,
            Joint::ALL[node.estimate.joint],
            node.estimate.clearance * 1e3,
            node.windows.len()
        );
        assert_eq!(Joint::ALL[node.estimate.joint], host.joint);
        assert_eq!(host.joint, joint, "the host names the simulated joint");
        assert!(rel.abs() <= CLEARANCE_TOLERANCE && worst_window <= CLEARANCE_TOLERANCE, "{rel} {worst_window}");
    }
}

/// Lines with NaN, an empty cell or text are skipped and counted, never a panic; the windows
/// fill with the good samples.
#[test]
fn bad_samples_are_skipped_and_counted() {
    let rec = recording(Joint::A, 0.25e-3, 5);
    let n = 3 * 2500 + 10;
    let mut text = csv(&rec.t[..n], &rec.crank_alpha[..n]);
    text.push_str("0.751,NaN\n0.7511,\n0.7512,oops\n0.7513,inf\n");
    let clean = run_host(csv(&rec.t[..n], &rec.crank_alpha[..n]).as_bytes()).unwrap();
    let run = run_host(text.as_bytes()).unwrap();
    assert_eq!((run.end.samples as usize, run.end.skipped), (n + 4, 4));
    assert_eq!(run.windows.len(), 3);
    assert_eq!(run.estimate, clean.estimate);
    // A NaN inside a window: skipped, the window closes one line later.
    let mut lines: Vec<String> = csv(&rec.t[..n], &rec.crank_alpha[..n]).lines().map(String::from).collect();
    lines.insert(100, "0.00995,nan".into());
    let run = run_host((lines.join("\n") + "\n").as_bytes()).unwrap();
    assert_eq!((run.end.skipped, run.windows[0].samples), (1, 2501));
    assert!(run.estimate.clearance.is_finite());
}

/// Relative clearance change allowed by the faults of `edgekf_tests::crank::faulty_csv` (13
/// samples of 20 000 missing or bad).
const FAULTY_TOLERANCE: f64 = 0.01;

/// Lines missing (10 in a row, and one replaced by garbage), an empty cell, a NaN and a junk
/// line in a 2 s recording: the missing lines are stepped as missing samples by their `t`, the
/// bad cells too, lines without a `t` not at all; every window closes where its 2 500 usable
/// samples end, and the clearance is within [`FAULTY_TOLERANCE`] of the clean run's after as
/// many windows (`edgekf_tests::crank::check_faulty_run`).
#[test]
fn missing_and_garbage_lines_are_bridged_and_counted() {
    let rec = recording(Joint::A, 0.25e-3, 1);
    let text = csv(&rec.t, &rec.crank_alpha);
    let clean = run_host(text.as_bytes()).unwrap();
    let run = run_host(faulty_csv(&text).as_bytes()).unwrap();
    let rel = check_faulty_run(&run, &clean, rec.t.len(), FAULTY_TOLERANCE).unwrap_or_else(|e| panic!("{e:#}"));
    eprintln!(
        "crank node with missing and garbage lines: {} windows, joint {}, clearance {rel:+.2e} off the clean run's after as many",
        run.windows.len(),
        Joint::ALL[run.estimate.joint]
    );
}

#[cfg(feature = "hil")]
mod hil {
    use super::*;
    use edgekf_tests::{crank, qemu};
    use std::time::Duration;

    /// The image in QEMU on a 2 s recording at A and one at B: every window's report and the
    /// final one bit-identical to the node's code on the host, and within
    /// [`CLEARANCE_TOLERANCE`] of the host's `f64` estimator, naming the same (the simulated)
    /// joint.
    #[test]
    fn crank_clearance_in_qemu_matches_the_host() {
        let elf = qemu::image_elf("edgekf-crank-qemu").unwrap_or_else(|e| panic!("{e:#}"));
        let model = FastModel::builtin();
        for (joint, c, seed) in [(Joint::A, 0.25e-3, 1), (Joint::B, 0.3e-3, 2)] {
            let rec = recording(joint, c, seed);
            let text = csv(&rec.t, &rec.crank_alpha);
            let run = qemu::run(&elf, text.as_bytes(), Duration::from_secs(300)).unwrap_or_else(|e| panic!("{e:#}"));
            if let Some(msg) = run.failure() {
                panic!("{msg}");
            }
            let chip = crank::parse(&run.lines).unwrap();
            let host = run_host(text.as_bytes()).unwrap();
            assert_eq!(chip.windows, host.windows, "window reports differ");
            let bits = |f: &[f32]| f.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&chip.features), bits(&host.features), "features differ");
            assert_eq!(chip.estimate, host.estimate, "final estimate differs");
            assert_eq!((chip.end.samples as usize, chip.end.skipped), (rec.t.len(), 0));
            let f64_est = model.estimate(&rec).unwrap();
            let rel = chip.estimate.clearance as f64 / f64_est.clearance[f64_est.joint.index()] - 1.0;
            let stack = edgekf_tests::report::frames::<edgekf_firmware::frame::StackFrame>(&run.lines)
                .unwrap()
                .pop()
                .expect("stack line");
            eprintln!(
                "HIL crank {joint} {:.3} mm: chip names {} {:.5} mm after {} windows, bit-identical to the node's code on the host; \
                 host f64 {} {:.5} mm ({rel:+.2e}); {stack:?}",
                c * 1e3,
                Joint::ALL[chip.estimate.joint],
                chip.estimate.clearance * 1e3,
                chip.windows.len(),
                f64_est.joint,
                f64_est.clearance[f64_est.joint.index()] * 1e3
            );
            assert_eq!(Joint::ALL[chip.estimate.joint], f64_est.joint);
            assert_eq!(f64_est.joint, joint);
            assert!(rel.abs() <= CLEARANCE_TOLERANCE, "{rel}");
        }
    }

    /// Missing lines, garbage lines, an empty cell and a NaN (`edgekf_tests::crank::faulty_csv`)
    /// in QEMU: every window bit-identical to the host run of the same file, and the counts and
    /// bounds of `edgekf_tests::crank::check_faulty_run` (20 000 samples stepped, 13 skipped of
    /// which 11 for missing lines, 4 bad lines of which 2 without a `t`, no time jump; the
    /// windows closing where their usable samples end; the clearance within
    /// [`FAULTY_TOLERANCE`] of the clean run's).
    #[test]
    fn crank_image_bridges_missing_and_garbage_lines() {
        let elf = qemu::image_elf("edgekf-crank-qemu").unwrap_or_else(|e| panic!("{e:#}"));
        let rec = recording(Joint::A, 0.25e-3, 1);
        let text = csv(&rec.t, &rec.crank_alpha);
        let faulty = faulty_csv(&text);
        let run = qemu::run(&elf, faulty.as_bytes(), Duration::from_secs(300)).unwrap_or_else(|e| panic!("{e:#}"));
        if let Some(msg) = run.failure() {
            panic!("{msg}");
        }
        let chip = crank::parse(&run.lines).unwrap();
        assert_eq!(chip, run_host(faulty.as_bytes()).unwrap(), "the chip and the host disagree");
        let clean = run_host(text.as_bytes()).unwrap();
        let rel = check_faulty_run(&chip, &clean, rec.t.len(), FAULTY_TOLERANCE).unwrap_or_else(|e| panic!("{e:#}"));
        eprintln!(
            "HIL crank with missing and garbage lines: {} samples, {} skipped ({} missing lines), {} bad lines ({} \
             without t), {} windows, joint {}, clearance {rel:+.2e} off the clean run's; bit-identical to the host",
            chip.end.samples,
            chip.end.skipped,
            chip.file.missing_lines,
            chip.file.bad_lines,
            chip.file.untimed_lines,
            chip.windows.len(),
            Joint::ALL[chip.estimate.joint]
        );
    }

    /// Bad lines in the input: the image skips and counts them and finishes.
    #[test]
    fn crank_image_skips_bad_samples() {
        let elf = qemu::image_elf("edgekf-crank-qemu").unwrap_or_else(|e| panic!("{e:#}"));
        let rec = recording(Joint::A, 0.25e-3, 5);
        let mut text = csv(&rec.t[..5000], &rec.crank_alpha[..5000]);
        text.insert_str(text.find("\n0.01,").unwrap_or(20) + 1, "0.00999,NaN\n0.009995,\n");
        text.push_str("0.5,inf\n0.5001,x\n");
        let run = qemu::run(&elf, text.as_bytes(), Duration::from_secs(120)).unwrap_or_else(|e| panic!("{e:#}"));
        if let Some(msg) = run.failure() {
            panic!("{msg}");
        }
        let chip = crank::parse(&run.lines).unwrap();
        let host = run_host(text.as_bytes()).unwrap();
        assert_eq!((chip.end.samples, chip.end.skipped), (5004, 4));
        assert_eq!(chip.windows, host.windows);
    }
}
