//! The thruster-health estimator against the reference vehicle: the acceptance
//! figures on 20 seeds of each scenario (current and sensor noise and biases per seed).
//!
//! `cargo test --release -p edgekf-sim --test uuv -- --nocapture` prints the figures.

use edgekf::systems::uuv::{Status, UuvEstimator};
use edgekf_sim::systems::uuv::{estimate, estimate::samples, simulate, EstimateTable, Scenario, SimOptions, UuvConfig};

const SEEDS: u64 = 20;

struct Run {
    t: Vec<f64>,
    truth: [Vec<f64>; 2],
    table: EstimateTable,
}

fn run(scenario: Scenario, seed: u64) -> Run {
    let config = UuvConfig::default();
    let rec = simulate(&config, &SimOptions { scenario, duration: 300.0, seed }, &mut |_| {}).unwrap();
    let data = rec.to_data_file();
    let table = estimate(&config, &data, &[]).unwrap();
    let truth = [rec.column("truth_k_t").unwrap().to_vec(), rec.column("truth_k_v").unwrap().to_vec()];
    Run { t: rec.t, truth, table }
}

/// Seconds from each change of thruster `j`'s truth to the status that matches it (declared
/// below 0.7, healthy above).
fn latencies(r: &Run, j: usize) -> Vec<f64> {
    let truth = &r.truth[j];
    let status = &r.table.status[j];
    (1..r.t.len())
        .filter(|&i| truth[i] != truth[i - 1])
        .map(|i| {
            let declare = truth[i] < 0.7;
            let hit = (i..r.t.len()).find(|&k| status[k].is_some_and(|s| s.declared() == declare));
            hit.map_or(f64::INFINITY, |k| r.t[k] - r.t[i])
        })
        .collect()
}

/// Rows declared before `until` seconds.
fn false_alarms(r: &Run, j: usize, until: f64) -> usize {
    r.t.iter().zip(&r.table.status[j]).filter(|(t, s)| **t < until && s.is_some_and(Status::declared)).count()
}

/// RMS error of factor `j` outside 1 s around each change.
fn rms_outside_changes(r: &Run, j: usize) -> f64 {
    let truth = &r.truth[j];
    let changes: Vec<f64> = (1..r.t.len()).filter(|&i| truth[i] != truth[i - 1]).map(|i| r.t[i]).collect();
    let est = r.table.column(["k_t", "k_v"][j]).unwrap();
    let sq: Vec<f64> = (0..r.t.len())
        .filter(|&i| changes.iter().all(|c| (r.t[i] - c).abs() > 1.0))
        .map(|i| (est[i] - truth[i]).powi(2))
        .collect();
    (sq.iter().sum::<f64>() / sq.len() as f64).sqrt()
}

#[test]
fn paper_scenario_every_fault_and_recovery_within_a_second_no_false_alarm() {
    let mut worst = (0.0f64, 0.0f64);
    for seed in 1..=SEEDS {
        let r = run(Scenario::Paper, seed);
        let lat = latencies(&r, 0);
        assert_eq!(lat.len(), 9, "seed {seed}: the fault, four recoveries and four relapses");
        let slowest = lat.iter().cloned().fold(0.0, f64::max);
        assert!(slowest <= 1.0, "seed {seed}: latencies {lat:?}");
        assert_eq!(false_alarms(&r, 0, 220.0), 0, "seed {seed}: main thruster declared before the fault");
        assert_eq!(false_alarms(&r, 1, 300.0), 0, "seed {seed}: vertical thruster declared");
        let rms = rms_outside_changes(&r, 0);
        assert!(rms <= 0.1, "seed {seed}: k_t RMS error {rms}");
        worst = (worst.0.max(slowest), worst.1.max(rms));
    }
    println!("paper, {SEEDS} seeds: slowest declaration or recovery {:.2} s, worst k_t RMS {:.4}", worst.0, worst.1);
}

#[test]
fn vertical_scenario_k_v_within_a_tenth_of_0_4_by_20_s() {
    let mut worst = (0.0f64, 0.0f64);
    for seed in 1..=SEEDS {
        let r = run(Scenario::Vertical, seed);
        let k_v = r.table.column("k_v").unwrap();
        let off = (0..r.t.len()).filter(|&i| r.t[i] >= 170.0).map(|i| (k_v[i] - 0.4).abs()).fold(0.0, f64::max);
        assert!(off <= 0.1, "seed {seed}: |k_v − 0.4| up to {off} after 170 s");
        let lat = latencies(&r, 1);
        assert!(lat.len() == 1 && lat[0] <= 1.0, "seed {seed}: {lat:?}");
        assert_eq!(false_alarms(&r, 0, 300.0), 0, "seed {seed}: main thruster declared");
        worst = (worst.0.max(off), worst.1.max(lat[0]));
    }
    println!(
        "vertical, {SEEDS} seeds: worst |k_v − 0.4| after 170 s {:.4}, slowest declaration {:.2} s",
        worst.0, worst.1
    );
}

#[test]
fn healthy_vehicle_no_alarm_over_300_s() {
    let mut worst = [0.0f64; 2];
    for seed in 1..=SEEDS {
        let r = run(Scenario::Healthy, seed);
        for (j, w) in worst.iter_mut().enumerate() {
            assert_eq!(false_alarms(&r, j, 300.0), 0, "seed {seed}: thruster {j} declared on healthy data");
            *w = w.max(rms_outside_changes(&r, j));
        }
        assert_eq!(r.table.repairs, (0, 0), "seed {seed}: the filter needed repairs");
    }
    println!("healthy, {SEEDS} seeds: worst RMS error k_t {:.4}, k_v {:.4}", worst[0], worst[1]);
}

/// The node's precision: the same estimator in `f32` declares the same faults as the host's
/// `f64` run, and its factor stays within 0.02 of it.
#[test]
fn f32_estimator_follows_the_f64_one() {
    let config = UuvConfig::default();
    let rec =
        simulate(&config, &SimOptions { scenario: Scenario::Paper, duration: 300.0, seed: 7 }, &mut |_| {}).unwrap();
    let data = rec.to_data_file();
    let host = estimate(&config, &data, &[]).unwrap();
    let settings = config.estimator.settings(config.sensors.rate);
    let mut chip = UuvEstimator::<f32, 20>::new(&config.vehicle, &settings).unwrap();
    let k_t = host.column("k_t").unwrap();
    let mut worst = 0.0f64;
    let mut disagree = 0;
    for (i, s) in samples(&data).unwrap().iter().enumerate() {
        let s32 = edgekf::systems::uuv::Sample {
            acc: s.acc.map(|v| v as f32),
            gyro: s.gyro.map(|v| v as f32),
            depth: s.depth as f32,
            heading: s.heading as f32,
            dvl: s.dvl.map(|d| d.map(|v| v as f32)),
            command: edgekf::systems::uuv::Command {
                n_t: s.command.n_t as f32,
                n_v: s.command.n_v as f32,
                rudder: s.command.rudder as f32,
                elevator: s.command.elevator as f32,
            },
        };
        let e = chip.step(&s32);
        let h = e.main.unwrap();
        worst = worst.max((h.k as f64 - k_t[i]).abs());
        disagree += usize::from(Some(h.status) != host.status[0][i]);
    }
    assert_eq!(chip.health().covariance_resets, 0);
    assert!(disagree <= 10, "{disagree} rows where f32 and f64 declare differently");
    assert!(worst < 0.02, "k_t differs by {worst}");
    println!("f32 vs f64: largest k_t difference {worst:.2e}, {disagree} rows of differing status");
}

/// Behind `EDGEKF_LONG=1`: 100 hours of healthy flight (100 seeds of an hour each, two
/// threads) for the mean time between false alarms. A false alarm is a change from healthy to
/// declared on either thruster; at most 4 in 100 h states a mean time between them of at least
/// 25 h (the issue asks for 24 h).
///
/// `EDGEKF_LONG=1 cargo test --release -p edgekf-sim --test uuv -- --nocapture hundred_hours`
#[test]
fn hundred_hours_of_healthy_flight_give_the_stated_false_alarm_rate() {
    if std::env::var_os("EDGEKF_LONG").is_none() {
        eprintln!("skipped: set EDGEKF_LONG=1 for 100 h of healthy flight");
        return;
    }
    const HOURS: u64 = 100;
    let episodes = |seed: u64| -> (usize, u32, f64) {
        let config = UuvConfig::default();
        let opts = SimOptions { scenario: Scenario::Healthy, duration: 3600.0, seed: 10_000 + seed };
        let rec = simulate(&config, &opts, &mut |_| {}).unwrap();
        let table = estimate(&config, &rec.to_data_file(), &[]).unwrap();
        let mut count = 0;
        for s in &table.status {
            count += s
                .windows(2)
                .filter(|w| !w[0].is_some_and(Status::declared) && w[1].is_some_and(Status::declared))
                .count();
        }
        let k_t = table.column("k_t").unwrap();
        let sd = table.column("k_t_std").unwrap();
        let margin = k_t.iter().zip(sd).map(|(k, s)| k - 3.0 * s).fold(f64::INFINITY, f64::min);
        (count, table.alarms[0] + table.alarms[1], margin)
    };
    let results: Vec<(usize, u32, f64)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..2u64)
            .map(|w| scope.spawn(move || (0..HOURS).filter(|s| s % 2 == w).map(episodes).collect::<Vec<_>>()))
            .collect();
        workers.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    let false_alarms: usize = results.iter().map(|r| r.0).sum();
    let cusum: u32 = results.iter().map(|r| r.1).sum();
    let margin = results.iter().map(|r| r.2).fold(f64::INFINITY, f64::min);
    println!(
        "{HOURS} h healthy: {false_alarms} false alarm(s) (mean time between them {}), {cusum} CUSUM reopenings, lowest k_t − 3σ {margin:.3}",
        if false_alarms == 0 { format!("> {HOURS} h") } else { format!("{:.1} h", HOURS as f64 / false_alarms as f64) }
    );
    assert!(false_alarms <= 4, "{false_alarms} false alarms in {HOURS} h");
}
