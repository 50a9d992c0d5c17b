//! The clearance estimators' cost on the host (`cargo bench -p edgekf-sim --bench crank_cost`):
//! the fast estimator (window features + release stage) on a whole 10 s recording against one
//! 0.25 s window of the paper's UKF (three sigma points of 8 simulations each, every one a
//! window of the full contact model). A 10 s recording is 40 such windows, plus the release
//! window's iterated update. Both estimators also count their work as they run: the UKF its
//! integration steps (`UkfRun::integration_steps`, about 8 M for 10 s), the fast estimator its
//! arithmetic operations (`ModelEstimate::operations`, about 3.2 M); the chip's instruction
//! counts are `cargo xtask bench`.

use criterion::{criterion_group, criterion_main, Criterion};
use edgekf_sim::systems::crank::estimate::model::FastModel;
use edgekf_sim::systems::crank::estimate::ukf::{self, UkfOptions};
use edgekf_sim::systems::crank::estimate::Recording;
use edgekf_sim::systems::crank::{CrankConfig, Mechanism, SimOptions};
use std::hint::black_box;

/// 0.25 mm at A, released at 30°, `duration` s.
fn recording(duration: f64) -> Recording {
    let cfg = CrankConfig::default();
    let m = Mechanism::new(&cfg, [Some(0.25e-3), None, None]).expect("the paper's mechanism");
    let rec = m.simulate(&SimOptions { seed: 3, ..SimOptions::from_config(&cfg, duration) }).expect("simulates");
    Recording::from_simulation(&rec, cfg.sensor.sample_rate)
}

fn crank_cost(c: &mut Criterion) {
    let model = FastModel::builtin();
    let long = recording(10.0);
    let mut g = c.benchmark_group("crank_cost");
    g.sample_size(10);
    g.bench_function("fast_estimator_10s_recording", |b| {
        b.iter(|| black_box(model.estimate(black_box(&long)).expect("estimates")))
    });
    // The UKF on one window: its cost per window is the same all along the recording.
    let one = recording(0.25);
    let cfg = CrankConfig::default();
    let opts = UkfOptions { initial: 0.1e-3, ..UkfOptions::default() };
    g.bench_function("ukf_one_window", |b| {
        b.iter(|| black_box(ukf::run(&cfg, black_box(&one), &opts, &mut |_, _| {}).expect("runs")))
    });
    g.finish();
}

criterion_group!(benches, crank_cost);
criterion_main!(benches);
