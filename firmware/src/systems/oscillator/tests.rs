//! The oscillator node's tests: the compiled model against the configured one, and the node on
//! a virtual ADXL355 with each of its faults (NACKs, timeouts, garbage, dropped samples, resets).

use super::*;
use crate::virtual_adxl355::{FeedSample, SliceFeed, VirtualCounters};
use edgekf::filter::solve_riccati;
use std::vec::Vec;

/// Gaussian noise of the ADXL355's size (the model's σ) from a fixed-seed xorshift generator.
fn noise(state: &mut u64) -> f64 {
    let mut uniform = || {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        (*state >> 11) as f64 / (1u64 << 53) as f64
    };
    let (u1, u2) = (uniform().max(1e-300), uniform());
    HarmonicForceParams::default().accel_noise_std
        * libm::sqrt(-2.0 * libm::log(u1))
        * libm::cos(2.0 * core::f64::consts::PI * u2)
}

/// Steady forced response of the default mode to a 4 N force at the running speed, with
/// the sensor's noise on every axis.
fn steady_response(n: usize) -> Vec<FeedSample> {
    let p = HarmonicForceParams::default();
    let wn = 2.0 * core::f64::consts::PI * p.natural_freq_hz;
    let w = p.drive_rad_s;
    let (re, im) = (wn * wn - w * w, 2.0 * p.damping_ratio * wn * w);
    let den = re * re + im * im;
    let (xr, xi) = (4.0 * re / den, -4.0 * im / den);
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    (0..n)
        .map(|k| {
            let t = k as f64 * 1e-3;
            let (s, c) = libm::sincos(w * t);
            let a = -w * w * (xr * c - xi * s) + noise(&mut seed);
            FeedSample::new([a as f32, noise(&mut seed) as f32, (9.80665 + noise(&mut seed)) as f32])
        })
        .collect()
}

fn run(samples: &[FeedSample]) -> (Vec<BlockReport>, Health) {
    let (r, h, _) = run_counted(samples);
    (r, h)
}

fn run_counted(samples: &[FeedSample]) -> (Vec<BlockReport>, Health, EstimatorCounters) {
    let r = run_device(samples);
    (r.reports, r.health, r.estimator)
}

/// Everything a run on the virtual device left.
struct Run {
    reports: Vec<BlockReport>,
    health: Health,
    estimator: EstimatorCounters,
    device: VirtualCounters,
}

fn run_device(samples: &[FeedSample]) -> Run {
    let config = NodeConfig::default();
    let sensor = Adxl355::new_i2c(VirtualAdxl355::new(SliceFeed::new(samples)), config.address);
    let mut node = start(sensor, &config).map_err(|(e, _)| e).unwrap();
    let mut reports = Vec::new();
    node.run(|r| reports.push(*r));
    let device = node.source().sensor().interface().bus().counters();
    Run { reports, health: node.health(), estimator: node.estimator().counters(), device }
}

/// Samples of the fault tests: 1.6 s of the steady response, the faults early in it.
const FAULT_RUN: usize = 1600;

/// From block `from` on: the worst over displacement, velocity and the force components of
/// the RMS difference between two runs' block estimates, relative to the reference's RMS.
fn mismatch(reference: &[BlockReport], other: &[BlockReport], from: usize) -> f32 {
    type Pick = fn(&BlockReport) -> f32;
    let picks: [Pick; 4] = [|b| b.displacement, |b| b.velocity, |b| b.force_cos, |b| b.force_sin];
    assert_eq!(reference.len(), other.len());
    let mut worst = 0.0f32;
    for pick in picks {
        let (mut d2, mut r2) = (0.0f32, 0.0f32);
        for (a, b) in reference[from..].iter().zip(&other[from..]) {
            d2 += (pick(a) - pick(b)) * (pick(a) - pick(b));
            r2 += pick(a) * pick(a);
        }
        worst = worst.max(libm::sqrtf(d2 / r2));
    }
    worst
}

/// A fault run against the clean one: the estimator's clock did not slip (one step per
/// sample due), the estimate stayed bounded (the amplitude within 50 % of the true 4 N from
/// block 20 on, once converged), and from block 60 (0.96 s, over 0.5 s after the last
/// fault) it matches the clean run within 1 % of its RMS.
fn assert_recovers(faulty: &Run, clean: &Run) {
    assert_eq!(faulty.estimator.steps, FAULT_RUN as u32, "the estimator's clock slipped");
    assert_eq!(faulty.reports.len(), clean.reports.len());
    for r in &faulty.reports[20..] {
        assert!((r.force_amplitude - 4.0).abs() < 2.0, "unbounded estimate {r:?}");
    }
    let rel = mismatch(&clean.reports, &faulty.reports, 60);
    assert!(rel < 0.01, "after recovery the estimates differ from the clean run by {rel}");
}

/// The committed constants are what the node's configured model computes, bit for bit.
#[test]
fn compiled_constants_match_the_configured_model() {
    let params = NodeConfig::default().estimator;
    let live = params.discrete_model().unwrap();
    let ss = solve_riccati(&live, 1e-12, 100_000).unwrap();
    let compiled =
        model(&constants::HARMONIC_A, &constants::HARMONIC_C, &constants::HARMONIC_Q, &constants::HARMONIC_R);
    assert_eq!(
        compiled, live,
        "regenerate firmware/src/systems/oscillator/generated/harmonic.rs (see module docs)"
    );
    assert_eq!(matrix(&constants::HARMONIC_GAIN), ss.gain);
    assert_eq!(matrix(&constants::HARMONIC_S), ss.innovation);
    // The default node declares no accelerometer offset: its samples reach the filter as read.
    assert_eq!(constants::HARMONIC_ACCEL_OFFSET.to_bits(), 0.0f64.to_bits());
}

#[test]
fn compiled_and_computed_estimators_agree() {
    let params = NodeConfig::default().estimator;
    let mut a = compiled_estimator(&params).unwrap();
    let mut b = HarmonicForceEstimator::<f32>::new(&params).unwrap();
    for k in 0..500 {
        let y = libm::sinf(k as f32 * 0.0879) * 3.0;
        assert_eq!(HarmonicForceEstimator::step(&mut a, Some(y)), HarmonicForceEstimator::step(&mut b, Some(y)));
    }
}

#[test]
fn clean_stream_estimates_the_force() {
    let (reports, health, counters) = run_counted(&steady_response(3200));
    assert_eq!(counters.filter, Default::default(), "{counters:?}");
    let last = reports.last().unwrap();
    assert!((last.force_amplitude - 4.0).abs() < 0.02, "{last:?}");
    assert_eq!(health.samples, 3200, "{health:?}");
    assert_eq!((health.bus_errors, health.stuck, health.saturated, health.bridged), (0, 0, 0, 0));
    // NIS near 1 once converged; a little below, since this force is exactly constant while
    // the model allows it to wander (S = 2.6e-5 includes that, the data's innovations don't).
    let nis: f32 = reports[100..].iter().map(|r| r.nis_mean).sum::<f32>() / (reports.len() - 100) as f32;
    assert!(nis > 0.75 && nis < 1.0, "mean NIS {nis}");
}

#[test]
fn short_nack_burst_is_retried_and_counted() {
    let mut samples = steady_response(320);
    samples[40].nack = 2; // loaded in the 3rd period
    let (reports, health) = run(&samples);
    assert_eq!((health.nacks, health.recovered, health.failed_polls), (2, 1, 0), "{health:?}");
    assert_eq!(health.samples, 320);
    assert!(reports.iter().all(|r| r.read == 16));
}

#[test]
fn long_nack_burst_overruns_and_is_bridged() {
    let mut samples = steady_response(640);
    samples[40].nack = 12; // three whole polls fail (4 attempts each)
    let (reports, health) = run(&samples);
    assert_eq!((health.nacks, health.failed_polls), (12, 3), "{health:?}");
    assert!(health.fifo_overruns >= 1 && health.bridged == 32, "{health:?}");
    assert_eq!(health.samples + health.bridged, 640);
    let last = reports.last().unwrap();
    assert!((last.force_amplitude - 4.0).abs() < 0.05, "{last:?}");
}

#[test]
fn stuck_and_saturated_samples_are_not_used() {
    let mut samples = steady_response(640);
    for s in &mut samples[100..150] {
        s.stuck = true;
    }
    for s in &mut samples[300..310] {
        s.accel[0] = 40.0;
    }
    let (_, health) = run(&samples);
    assert_eq!(health.stuck, 50);
    assert_eq!(health.saturated, 10);
    assert_eq!(health.samples, 640 - 60);
}

/// The invariant every fault run keeps: each sample due is either used, screened out or
/// bridged, and every bridged sample is one the device lost (overwritten, dropped or lost
/// to a reset).
fn assert_accounted(run: &Run, due: usize) {
    let (h, d) = (run.health, run.device);
    assert_eq!((h.samples + h.saturated + h.stuck + h.bridged) as usize, due, "{h:?}");
    assert_eq!(h.bridged, d.overrun_entries / 3 + d.samples_dropped + d.samples_discarded, "{h:?} {d:?}");
    assert_eq!(run.estimator.missing, h.bridged + h.saturated + h.stuck);
    assert_eq!(h.bus_errors, h.nacks + h.timeouts + h.bad_id, "{h:?}");
    assert_eq!((h.nacks, h.timeouts, h.bad_id), (d.nacks_sent, d.timeouts_sent, d.garbage_sent), "{h:?} {d:?}");
}

#[test]
fn timeouts_are_not_retried_and_the_overwritten_samples_are_bridged() {
    let clean = run_device(&steady_response(FAULT_RUN));
    let mut samples = steady_response(FAULT_RUN);
    samples[100].timeout = 3; // due in poll 6: polls 6, 7 and 8 time out at their first transaction
    let run = run_device(&samples);
    let h = run.health;
    assert_eq!((h.timeouts, h.bus_errors, h.nacks, h.recovered, h.failed_polls), (3, 3, 0, 0, 3), "{h:?}");
    // Poll 9 finds 64 samples due and the 32 newest in the FIFO, which overran.
    assert_eq!((h.fifo_overruns, h.bridged, h.dropped), (1, 32, 0), "{h:?}");
    assert_eq!((run.device.timeouts_sent, run.device.overrun_entries), (3, 96));
    assert_eq!(run.reports[9].read, 32);
    assert_eq!(run.reports[9].missing, 32);
    assert_accounted(&run, FAULT_RUN);
    assert_recovers(&run, &clean);
}

#[test]
fn garbage_reads_are_retried_and_never_taken_for_samples() {
    let clean = run_device(&steady_response(FAULT_RUN));
    let mut samples = steady_response(FAULT_RUN);
    samples[100].garbage = 2; // poll 6: two status reads with IDs 0xFF, the third is good
    samples[300].garbage = 6; // poll 18 fails (4 bad reads), poll 19 reads both blocks
    let run = run_device(&samples);
    let h = run.health;
    assert_eq!((h.bad_id, h.bus_errors, h.recovered, h.failed_polls), (8, 8, 2, 1), "{h:?}");
    // Nothing was lost: the FIFO kept the samples of the failed poll (32 fit).
    assert_eq!((h.bridged, h.fifo_overruns, h.skipped_entries, h.samples), (0, 0, 0, FAULT_RUN as u32), "{h:?}");
    assert_eq!(run.device.garbage_sent, 8);
    assert_eq!((run.reports[18].read, run.reports[19].read), (0, 32));
    assert_accounted(&run, FAULT_RUN);
    // Every sample used, in order: after the poll that caught up, bit-identical to the clean
    // run.
    assert_eq!(run.reports[20..], clean.reports[20..]);
}

#[test]
fn dropped_samples_are_bridged_and_counted() {
    let clean = run_device(&steady_response(FAULT_RUN));
    let mut samples = steady_response(FAULT_RUN);
    for s in &mut samples[100..150] {
        s.dropped = true; // 12 of poll 6, all of polls 7 and 8, 6 of poll 9
    }
    let run = run_device(&samples);
    let h = run.health;
    assert_eq!((h.dropped, h.bridged, h.fifo_overruns), (50, 50, 0), "{h:?}");
    // Polls 7 and 8 find the FIFO empty: the configuration is read back, and it is intact.
    assert_eq!((h.config_checks, h.resets, h.failed_polls, h.bus_errors), (2, 0, 0, 0), "{h:?}");
    assert_eq!(run.device.samples_dropped, 50);
    let missing: Vec<u16> = run.reports[5..11].iter().map(|r| r.missing).collect();
    assert_eq!(missing, [0, 12, 16, 16, 6, 0]);
    assert_accounted(&run, FAULT_RUN);
    assert_recovers(&run, &clean);
}

#[test]
fn a_reset_is_detected_the_part_reconfigured_and_the_gap_bridged() {
    let clean = run_device(&steady_response(FAULT_RUN));
    let mut samples = steady_response(FAULT_RUN);
    samples[100].reset = true; // in poll 6's period: 96..99 cleared, 100..111 in standby
    let run = run_device(&samples);
    let h = run.health;
    assert_eq!((h.resets, h.config_checks, h.bridged, h.dropped), (1, 1, 16, 16), "{h:?}");
    assert_eq!((h.failed_polls, h.bus_errors, h.fifo_overruns), (0, 0, 0), "{h:?}");
    assert_eq!((run.device.resets, run.device.samples_discarded), (1, 16));
    assert_eq!((run.reports[6].read, run.reports[6].missing, run.reports[7].read), (0, 16, 16));
    assert_accounted(&run, FAULT_RUN);
    assert_recovers(&run, &clean);
}

#[test]
fn a_reset_behind_a_nack_burst_is_found_once_the_bus_is_back() {
    let clean = run_device(&steady_response(FAULT_RUN));
    let mut samples = steady_response(FAULT_RUN);
    samples[100].reset = true;
    samples[101].nack = 6; // poll 6 fails; poll 7 gets through on its third attempt
    let run = run_device(&samples);
    let h = run.health;
    assert_eq!((h.nacks, h.failed_polls, h.recovered), (6, 1, 1), "{h:?}");
    assert_eq!((h.resets, h.config_checks, h.bridged, h.dropped), (1, 1, 32, 32), "{h:?}");
    assert_eq!(run.device.samples_discarded, 32);
    assert_accounted(&run, FAULT_RUN);
    assert_recovers(&run, &clean);
}

#[test]
fn every_fault_in_one_run() {
    let clean = run_device(&steady_response(FAULT_RUN));
    let mut samples = steady_response(FAULT_RUN);
    samples[40].nack = 3;
    samples[90].timeout = 1;
    samples[130].garbage = 2;
    for s in &mut samples[170..180] {
        s.stuck = true;
    }
    for s in &mut samples[200..205] {
        s.accel[0] = 40.0;
    }
    for s in &mut samples[230..260] {
        s.dropped = true;
    }
    samples[300].reset = true;
    samples[350].nack = 12;
    let run = run_device(&samples);
    let h = run.health;
    assert_eq!((h.nacks, h.timeouts, h.bad_id), (15, 1, 2), "{h:?}");
    assert_eq!((h.stuck, h.saturated, h.resets), (10, 5, 1), "{h:?}");
    assert_accounted(&run, FAULT_RUN);
    assert_recovers(&run, &clean);
}

/// A recording whose length is not a whole number of periods: the samples after its end
/// were never due, so nothing is bridged.
#[test]
fn a_recording_ending_mid_period_bridges_nothing() {
    let run = run_device(&steady_response(650));
    assert_eq!((run.health.samples, run.health.bridged, run.health.dropped), (650, 0, 0), "{:?}", run.health);
    assert_eq!(run.estimator.steps, 650);
}
