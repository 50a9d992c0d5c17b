//! Host speed of edgekf on the problems `tools/bench/peers.py` times ROSS and filterpy on, for
//! the peers table of `cargo xtask bench` (which runs this in release and writes the JSON it
//! prints on stdout into `target/bench/results.json`).
//!
//! `cargo run --release -p edgekf-sim --example speed -- [PEERS.json]`
//!
//! With the peers' JSON, the paper rotor's 4 s response is also compared with ROSS's, at 1 kHz
//! and at the 10 kHz step it converges to. Times are compute only, best of a few repetitions.

use edgekf::filter::{KalmanFilter, LinearModel, MerweSigmaPoints, UkfModel, UnscentedKalmanFilter};
use edgekf::models::synthetic::{dense_model, Lcg};
use edgekf_sim::residual_loop::LoopOptions;
use edgekf_sim::systems::rotor::bearing_geometry::BearingLine;
use edgekf_sim::systems::rotor::estimate::{reduce, run, FilterPrecision, Tuning};
use edgekf_sim::systems::rotor::loop_system::baseline::{learn, BaselineOptions};
use edgekf_sim::systems::rotor::loop_system::cases::Case;
use edgekf_sim::systems::rotor::loop_system::twin::{self, Twin};
use edgekf_sim::systems::rotor::loop_system::{close_loop, close_loop_from, RotorLoopOptions};
use edgekf_sim::systems::rotor::simulate::Progress;
use edgekf_sim::systems::rotor::{RotorConfig, RotorModel, SimOptions};
use nalgebra::{SMatrix, SVector};
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

const CONFIG: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml");

/// Best time of `repeat` runs of `f`, s, and its last result.
fn best<R>(repeat: usize, mut f: impl FnMut() -> R) -> (f64, R) {
    let mut out = None;
    let mut time = f64::INFINITY;
    for _ in 0..repeat.max(1) {
        let t = Instant::now();
        out = Some(f());
        time = time.min(t.elapsed().as_secs_f64());
    }
    (time, out.expect("at least one run"))
}

/// The UKF problem of `peers.py`: f(x) = A x − 0.01 x³, h(x) = C x + 0.05 (C x)².
struct Cubic {
    a: SMatrix<f64, 14, 14>,
    c: SMatrix<f64, 4, 14>,
}

impl UkfModel<f64, 14, 4> for Cubic {
    fn f(&self, x: &SVector<f64, 14>) -> SVector<f64, 14> {
        self.a * x - x.map(|v| 0.01 * v * v * v)
    }
    fn h(&self, x: &SVector<f64, 14>) -> SVector<f64, 4> {
        let y = self.c * x;
        y + y.map(|v| 0.05 * v * v)
    }
}

/// Relative RMS difference of the disk nodes' x, y (rows of 4) against `reference`.
fn relative_rms(ours: &[[f64; 4]], reference: &[Vec<f64>]) -> f64 {
    let (mut d2, mut r2) = (0.0, 0.0);
    for (a, b) in ours.iter().zip(reference) {
        for (x, y) in a.iter().zip(b) {
            d2 += (x - y) * (x - y);
            r2 += y * y;
        }
    }
    (d2 / r2).sqrt()
}

fn main() -> anyhow::Result<()> {
    let peers: Option<serde_json::Value> = match std::env::args().nth(1) {
        Some(p) => Some(serde_json::from_str(&std::fs::read_to_string(&p)?)?),
        None => None,
    };
    let cfg = RotorConfig::load(Path::new(CONFIG))?;
    let (build_s, model) = best(3, || RotorModel::from_config(&cfg));
    let model = model?;
    let sim = |duration: f64| model.simulate(&SimOptions { duration, noise: false, ..SimOptions::default() });
    eprintln!("time response");
    let (response_4s_s, rec) = best(3, || sim(4.0));
    let rec = rec?;
    let (response_40s_s, _) = best(1, || sim(40.0));
    // Where the 4 s go: the transition matrix (augmented model, matrix exponential), then the steps.
    let (_, discretise_4s_s) = best(3, || {
        let start = Instant::now();
        let mut at = f64::NAN;
        let opts = SimOptions { duration: 4.0, noise: false, ..SimOptions::default() };
        let _ = model.simulate_with_progress(&opts, &mut |p| {
            if let Progress::Discretised { .. } = p {
                at = start.elapsed().as_secs_f64();
            }
        });
        at
    });
    let (csv_4s_s, csv) = best(3, || rec.to_data_file().to_csv_string());
    let csv_bytes = csv?.len();
    let disks: Vec<[f64; 4]> =
        (0..rec.len()).map(|k| [rec.x[12][k], rec.y[12][k], rec.x[23][k], rec.y[23][k]]).collect();
    let agreement = |key: &str| -> Option<f64> {
        let rows: Vec<Vec<f64>> = serde_json::from_value(peers.as_ref()?.get(key)?.clone()).ok()?;
        Some(relative_rms(&disks, &rows))
    };

    eprintln!("modal and Campbell");
    let speed = cfg.operation.speed;
    let (modal_s, _) = best(5, || model.modes(speed));
    let speeds: Vec<f64> = (0..51).map(|i| 1000.0 * f64::from(i) / 50.0).collect();
    let (campbell_s, _) = best(2, || model.campbell(&speeds, 6));

    eprintln!("filter steps");
    let mut rng = Lcg(7);
    let lin: LinearModel<f64, 4, 4> = dense_model::<4, 4>(&mut rng);
    let mut kf = KalmanFilter::new(lin, SVector::zeros(), SMatrix::identity());
    let y = SVector::<f64, 4>::from_fn(|_, _| rng.next());
    let n = 200_000;
    let (kf_s, _) = best(3, || {
        for _ in 0..n {
            kf.predict();
            black_box(kf.update(black_box(&y)).is_ok());
        }
    });
    let lin = dense_model::<14, 4>(&mut rng);
    let cubic = Cubic { a: lin.a, c: lin.c };
    let points = MerweSigmaPoints { alpha: 0.5, beta: 2.0, kappa: 0.0 };
    let mut ukf = UnscentedKalmanFilter::new(points, lin.q, lin.r, SVector::zeros(), SMatrix::identity())
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let n_ukf = 20_000;
    let (ukf_s, _) = best(3, || {
        for _ in 0..n_ukf {
            ukf.predict(&cubic);
            black_box(ukf.update(&cubic, black_box(&y)).is_ok());
        }
    });

    eprintln!("rotor estimate (4 s of probes, 1 kHz)");
    let noisy = model.simulate(&SimOptions { duration: 4.0, seed: 1, ..SimOptions::default() })?.to_data_file();
    let red = reduce(&model, speed, &Tuning::default())?;
    let (estimate_s, _) = best(3, || run(&red, &noisy, FilterPrecision::F64));

    eprintln!("the loop on 4 s at 1 kHz with an undeclared 2× force");
    let declared = Case::declared()?;
    let data = Case::TwoX.data(5)?;
    let (loop_s, report) = best(1, || close_loop(&declared, &data, &LoopOptions::default(), &Default::default()));
    let added: Vec<String> = report?.effects_added.iter().map(|e| format!("{} at {}", e.kind, e.location)).collect();

    eprintln!("the loop on 10 s at 12 kHz from two housings with an outer-race defect, against a healthy baseline");
    let rig = twin::rig()?;
    let healthy = Twin::default().record(&rig, 1)?;
    let (baseline_s, baseline) = best(1, || {
        learn(&rig, &healthy, &LoopOptions::default(), &RotorLoopOptions::default(), &BaselineOptions::default())
    });
    let baseline = baseline?;
    let defect = Twin { duration: 10.0, defect: Some(BearingLine::Bpfo), ..Twin::default() }.record(&rig, 3)?;
    let (housing_s, report) =
        best(1, || close_loop_from(&rig, &defect, &LoopOptions::default(), &RotorLoopOptions::default(), &baseline));
    let housing_added: Vec<String> =
        report?.effects_added.iter().map(|e| format!("{} at {}", e.kind, e.location)).collect();

    let out = serde_json::json!({
        "rotor_build_s": build_s,
        "response_4s_s": response_4s_s,
        "response_40s_s": response_40s_s,
        "discretise_s": discretise_4s_s,
        "csv_4s_s": csv_4s_s,
        "csv_4s_bytes": csv_bytes,
        "response_4s_vs_ross_1khz": agreement("response_4s_disks"),
        "response_4s_vs_ross_10khz": agreement("response_4s_fine_disks"),
        "modal_s": modal_s,
        "campbell_s": campbell_s,
        "kf_step_s": kf_s / f64::from(n),
        "ukf_step_s": ukf_s / f64::from(n_ukf),
        "estimate_samples_per_s": noisy.t.len() as f64 / estimate_s,
        "loop_4s_twox_s": loop_s,
        "loop_4s_twox_added": added,
        "baseline_2s_12khz_s": baseline_s,
        "loop_10s_12khz_s": housing_s,
        "loop_10s_12khz_added": housing_added,
    });
    println!("{out}");
    Ok(())
}
