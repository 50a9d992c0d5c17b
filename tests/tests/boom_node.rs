//! Boom tip vibration on the node (`edgekf-boom-qemu`, `edgekf_firmware::systems::boom`): the
//! image's code on the host, fed the CSV text the QEMU image reads, estimates the tip's
//! vibration as the host's `f64` filter does; garbage and lost rows are counted and bridged;
//! its built-in boom and sensors are `boom_ladder30.toml`'s; and, with `--features hil` (run by
//! `cargo xtask test`, which sets `EDGEKF_BOOM_ELF`), the image in QEMU reports bit for bit
//! what its code reports on the host.

use edgekf_firmware::frame::Frame;
use edgekf_firmware::hil::FileEnd;
use edgekf_firmware::systems::boom::{self as node, BoomEnd, BoomFrame, BoomImage};
use edgekf_sim::systems::boom::peaks::peak_errors;
use edgekf_sim::systems::boom::{simulate, BoomConfig, BoomRecording, Scenario, SimOptions};
use edgekf_tests::host::{file_end, lines};
use edgekf_tests::report::frames;

/// `duration` s of `scenario`, seed 2, as the CSV the image reads.
fn recording(scenario: Scenario, duration: f64) -> (BoomRecording, String) {
    let rec = simulate(&BoomConfig::default(), &SimOptions { scenario, duration, seed: 2 }, &mut |_| {}).unwrap();
    let text = rec.to_csv(std::path::Path::new("boom.csv")).unwrap();
    (rec, text)
}

/// The host run's per-sample frames, its end frame and its `file` frame.
fn run_host(text: &str) -> (Vec<BoomFrame>, BoomEnd, FileEnd) {
    let out = lines::<BoomImage>(text.as_bytes()).unwrap();
    let per_sample = frames::<BoomFrame>(&out).unwrap();
    let end = frames::<BoomEnd>(&out).unwrap().pop().expect("boomend frame");
    (per_sample, end, file_end(&out).unwrap())
}

#[test]
fn the_nodes_boom_and_sensors_are_the_configurations() {
    use edgekf_sim::systems::boom::estimate::{model_settings, INCLINOMETER_NOISE};
    let c = BoomConfig::default();
    assert_eq!(node::BOOM, c.constants().unwrap());
    assert_eq!(node::SAMPLE_RATE_HZ as f64, c.gyro.sample_rate);
    assert_eq!(node::model_settings(), model_settings(&c, node::GYRO, INCLINOMETER_NOISE).unwrap());
    let g = edgekf_sim::systems::boom::sensors::GyroModel::of(&c);
    assert_eq!((node::GYRO.a, node::GYRO.sigma, node::GYRO.mean), (g.ar, g.noise, g.bias));
}

#[test]
fn the_node_estimates_the_vibration_on_both_runs() {
    for (scenario, duration) in [(Scenario::Luffing, 60.0), (Scenario::Extension, 140.0)] {
        let (rec, text) = recording(scenario, duration);
        let (frames, end, file) = run_host(&text);
        assert_eq!(frames.len(), rec.t.len());
        assert_eq!((end.samples as usize, file.bad_lines, file.missing_lines), (rec.t.len(), 0, 0));
        assert_eq!((end.covariance_resets, end.refused_updates, end.reduce_failures), (0, 0, 0));
        let col = |n: &str| rec.column(n).unwrap();
        let (truth, rate) = (col("truth_tip_vibration"), col("truth_root_rate"));
        let vib: Vec<f64> = frames.iter().map(|f| f.vibration as f64).collect();
        let paper: Vec<f64> = frames.iter().map(|f| f.paper_vibration as f64).collect();
        let (m, p) = (peak_errors(&rec.t, &vib, truth, rate), peak_errors(&rec.t, &paper, truth, rate));
        eprintln!(
            "node (host run), {}: model {:.2} % over {} peaks, paper {:.1} %; {} fusions",
            scenario.name(),
            m.mean_pct,
            m.peaks,
            p.mean_pct,
            end.fusions
        );
        assert!(m.peaks >= 27 && m.mean_pct <= 2.0, "{m:?}");
        // The paper's method within issue #34's 40 %, the model-based filter well inside it.
        assert!(p.mean_pct <= 40.0 && 10.0 * m.mean_pct < p.mean_pct && end.fusions > 20, "{p:?}");
    }
}

#[test]
fn garbage_and_lost_rows_are_counted_and_bridged() {
    let (rec, text) = recording(Scenario::Luffing, 30.0);
    let mut rows: Vec<String> = text.lines().map(str::to_owned).collect();
    // Row 1001 lost, row 1501 with garbage for the gyro, row 2001 with a NaN inclinometer.
    let set = |row: &str, field: usize, value: &str| {
        let mut cells: Vec<&str> = row.split(',').collect();
        cells[field] = value;
        cells.join(",")
    };
    rows[1502] = set(&rows[1502], 1, "x");
    rows[2002] = set(&rows[2002], 2, "NaN");
    rows.remove(1002);
    let faulty = rows.join("\n") + "\n";
    let (frames, end, file) = run_host(&faulty);
    assert_eq!(end.samples as usize, rec.t.len(), "every sample stepped, the lost row bridged");
    assert_eq!((file.missing_lines, file.time_jumps, file.bad_lines), (1, 0, 1));
    assert_eq!((end.covariance_resets, end.refused_updates), (0, 0));
    // Frames by sample number (a bridged sample and the row after it are reported as one).
    let (clean, ..) = run_host(&text);
    let worst =
        frames.iter().map(|f| (f.vibration - clean[f.sample as usize - 1].vibration).abs()).fold(0.0f32, f32::max);
    eprintln!("a lost row and two bad readings move the vibration by at most {worst:.2e} m");
    assert!(worst < 1e-3, "a lost row and two bad readings move the vibration by {worst} m");
}

#[test]
fn frames_read_back() {
    let f = BoomFrame { sample: 3, vibration: 0.25, nis: 1.5, ..BoomFrame::default() };
    let mut line = String::new();
    f.write_line(&mut line).unwrap();
    assert_eq!(BoomFrame::parse(&line).unwrap().unwrap(), f);
}

#[cfg(feature = "hil")]
mod hil {
    use super::*;
    use edgekf_tests::qemu;
    use std::time::Duration;

    /// The image in QEMU on 40 s of the extension run (it telescopes, so the boom is re-reduced
    /// on the chip): every frame bit-identical to the image's code on the host.
    #[test]
    fn boom_in_qemu_matches_the_host() {
        let elf = qemu::image_elf("edgekf-boom-qemu").unwrap_or_else(|e| panic!("{e:#}"));
        let (_, text) = recording(Scenario::Extension, 40.0);
        let run = qemu::run(&elf, text.as_bytes(), Duration::from_secs(600)).unwrap_or_else(|e| panic!("{e:#}"));
        if let Some(msg) = run.failure() {
            panic!("{msg}");
        }
        let chip = frames::<BoomFrame>(&run.lines).unwrap();
        let (host, end, file) = run_host(&text);
        let bits = |f: &BoomFrame| {
            [f.tip_angle, f.vibration, f.deflection, f.paper_vibration, f.innovation_gyro, f.innovation_incl, f.nis]
                .map(f32::to_bits)
        };
        assert_eq!(chip.len(), host.len());
        for (c, h) in chip.iter().zip(&host) {
            assert_eq!((c.sample, bits(c)), (h.sample, bits(h)), "sample {}", h.sample);
        }
        let chip_end = frames::<BoomEnd>(&run.lines).unwrap().pop().expect("boomend");
        assert_eq!(chip_end, end);
        assert_eq!(file_end(&run.lines).unwrap(), file);
        let stack = frames::<edgekf_firmware::frame::StackFrame>(&run.lines).unwrap().pop().expect("stack line");
        eprintln!("HIL boom: {} frames bit-identical to the host run; {stack:?}", chip.len());
    }
}

/// Soak: the node's `f32` filters over a long run of luffing stops (1 000 s, 10⁵ samples; 10⁶
/// with `EDGEKF_LONG=1`): no covariance reset, refused update or failed reduction, the mean
/// peak error still within 2 % in every block of 10⁴ samples (the paper's method within 40 %),
/// and the NIS steady.
#[test]
fn node_soak_on_a_long_run_of_luffing_stops() {
    let duration = if std::env::var_os("EDGEKF_LONG").is_some() { 10_000.0 } else { 1_000.0 };
    let (rec, text) = recording(Scenario::Luffing, duration);
    let (frames, end, file) = run_host(&text);
    assert_eq!(file, FileEnd::default(), "a simulated file has no bad, missing or untimed lines");
    assert_eq!(end.samples as usize, rec.t.len());
    assert_eq!((end.covariance_resets, end.refused_updates, end.reduce_failures), (0, 0, 0));
    let col = |n: &str| rec.column(n).unwrap();
    let (truth, rate) = (col("truth_tip_vibration"), col("truth_root_rate"));
    let vib: Vec<f64> = frames.iter().map(|f| f.vibration as f64).collect();
    let paper: Vec<f64> = frames.iter().map(|f| f.paper_vibration as f64).collect();
    let nis: Vec<f64> = frames.iter().map(|f| f.nis as f64).collect();
    let block = 10_000;
    let (mut worst, mut worst_paper, mut lo, mut hi) = (0.0f64, 0.0f64, f64::INFINITY, 0.0f64);
    for b in 0..rec.t.len() / block {
        let r = b * block..(b + 1) * block;
        let p = peak_errors(&rec.t[r.clone()], &vib[r.clone()], &truth[r.clone()], &rate[r.clone()]);
        worst = worst.max(p.mean_pct);
        let pp = peak_errors(&rec.t[r.clone()], &paper[r.clone()], &truth[r.clone()], &rate[r.clone()]);
        worst_paper = worst_paper.max(pp.mean_pct);
        let mean_nis = nis[r.clone()].iter().sum::<f64>() / block as f64;
        (lo, hi) = (lo.min(mean_nis), hi.max(mean_nis));
    }
    eprintln!(
        "boom node soak: {} samples, worst block mean peak error {worst:.2} % (the paper's method \
         {worst_paper:.1} %), NIS by block {lo:.3}–{hi:.3}",
        rec.t.len()
    );
    assert!(worst <= 2.0, "{worst} %");
    // The paper's method in `f32` over the whole soak: its filter's covariance stays sound.
    assert!(worst_paper <= 40.0, "the paper's method {worst_paper} %");
    assert!(hi < 1.5 * lo && hi < 4.0, "NIS by block {lo}–{hi}");
}
