//! Figures of the clearance estimators' documentation (`host-sim/src/crank/estimate/ukf.rs`,
//! `mod.rs`): `cargo run --release -p edgekf-sim --features studies --example crank_study -- <what>` with
//!
//! * `release-curve`: the feature `a` of the release window (first 0.25 s) against the
//!   clearance at A, mean ± std over 16 releases 30.000°, 30.002° … (and at 29–31°);
//! * `information`: per window, `a` at 0.225, 0.25 and 0.275 mm (24 releases each, symplectic
//!   Euler), its spread, its slope, and the clearance std the windows allow together;
//! * `ukf [DURATION] [RECORDINGS]`: the UKF (default options) from 0.01, 0.1 and 0.2 mm on
//!   recordings of 0.25 mm at A (adaptive integrator at 1e-9, released 30° + 0.0013° · r, seed
//!   7 + r);
//! * `two-clearances [RUNS] [DURATION] [SPREAD] [stencil]`: identifiability of A and B together
//!   ([`edgekf_sim::systems::crank::studies::identify2`]): the likelihood surface over cA 0.15–0.35 ×
//!   cB 0.05–0.25 mm about A 0.25 + B 0.15 mm, the Fisher information there and the
//!   single-clearance bound (default 16 runs of 10 s per point released 30 ± 10°; `stencil`:
//!   only cA 0.20–0.30 × cB 0.10–0.20 mm, enough for the Fisher matrix).
use edgekf_sim::systems::crank::config::Method;
use edgekf_sim::systems::crank::estimate::ukf::{self, UkfOptions};
use edgekf_sim::systems::crank::estimate::Recording;
use edgekf_sim::systems::crank::feature::window_features;
use edgekf_sim::systems::crank::studies::identify2::{Analysis, Design};
use edgekf_sim::systems::crank::{CrankConfig, Mechanism, SimOptions};
use rayon::prelude::*;

fn feats(c: f64, angle: f64, seed: u64, dur: f64) -> Vec<f64> {
    let mut cfg = CrankConfig::default();
    cfg.release.crank_angle_deg = angle;
    let m = Mechanism::new(&cfg, [Some(c), None, None]).unwrap();
    let rec = m.simulate(&SimOptions { seed, ..SimOptions::from_config(&cfg, dur) }).unwrap();
    window_features(&rec.crank_alpha, 1e4, 0.25).into_iter().map(|f| f.map_or(f64::NAN, |f| f.a)).collect()
}

/// `m` runs released at `angle + 0.002° · i`, on two threads, in the order of `i`.
fn ensemble(c: f64, angle: f64, m: usize, dur: f64) -> Vec<Vec<f64>> {
    let run = || (0..m).into_par_iter().map(|i| feats(c, angle + 0.002 * i as f64, 100 + i as u64, dur)).collect();
    rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("two threads").install(run)
}

fn mean_std(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let v: Vec<f64> = v.collect();
    let n = v.len() as f64;
    let mu = v.iter().sum::<f64>() / n;
    (mu, (v.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / (n - 1.0)).sqrt())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("release-curve") => {
            for k in 0..=30 {
                let c = 0.10e-3 + k as f64 * 0.01e-3;
                let r = ensemble(c, 30.0, 16, 0.25);
                let (mu, sd) = mean_std(r.iter().map(|x| x[0]));
                println!("release window, {:.2} mm, 30°: a = {mu:6.1} ± {sd:4.1}", c * 1e3);
            }
            for ang in [29.0, 29.5, 30.5, 31.0] {
                let (mu, sd) = mean_std(ensemble(0.25e-3, ang, 16, 0.25).iter().map(|x| x[0]));
                println!("release window, 0.25 mm, {ang}°: a = {mu:6.1} ± {sd:4.1}");
            }
        }
        Some("information") => {
            let cs = [0.225e-3, 0.25e-3, 0.275e-3];
            let e: Vec<Vec<Vec<f64>>> = cs.iter().map(|&c| ensemble(c, 30.0, 24, 10.0)).collect();
            let nw = e[0][0].len();
            let (mut info, mut later) = (0.0, 0.0);
            for k in 0..nw {
                let s: Vec<(f64, f64)> = e.iter().map(|r| mean_std(r.iter().map(|x| x[k]))).collect();
                let slope = (s[2].0 - s[0].0) / 0.05;
                let i = (slope / s[1].1).powi(2);
                info += i;
                if k > 0 {
                    later += i;
                }
                println!(
                    "window {k:2}: a {:6.1} {:6.1} {:6.1} ± {:4.1}, slope {slope:6.0} per mm",
                    s[0].0, s[1].0, s[2].0, s[1].1
                );
            }
            println!(
                "clearance std from the windows (independent, slopes as measured): all {:.4} mm, without the release window {:.4} mm",
                1.0 / info.sqrt(),
                1.0 / later.sqrt()
            );
            let runs: Vec<(f64, f64)> =
                e.iter().map(|r| mean_std(r.iter().map(|x| x[1..].iter().sum::<f64>() / (nw - 1) as f64))).collect();
            let slope = (runs[2].0 - runs[0].0) / 0.05;
            println!(
                "mean a over windows 1–{}: {:.1} / {:.1} / {:.1} ± {:.1} (0.225 / 0.25 / 0.275 mm): slope {slope:.0} per mm, clearance std {:.4} mm",
                nw - 1,
                runs[0].0,
                runs[1].0,
                runs[2].0,
                runs[1].1,
                runs[1].1 / slope.abs()
            );
        }
        Some("ukf") => {
            let dur: f64 = args.get(1).map_or(10.0, |s| s.parse().expect("duration, s"));
            let nrec: usize = args.get(2).map_or(3, |s| s.parse().expect("recordings"));
            let cfg = CrankConfig::default();
            let mut errs = vec![];
            for r in 0..nrec {
                let mut rc = cfg;
                rc.integrator.method = Method::Adaptive;
                rc.integrator.tolerance = 1e-9;
                rc.release.crank_angle_deg = 30.0 + 0.0013 * r as f64;
                let mech = Mechanism::new(&rc, [Some(0.25e-3), None, None]).unwrap();
                let sim =
                    mech.simulate(&SimOptions { seed: 7 + r as u64, ..SimOptions::from_config(&rc, dur) }).unwrap();
                let rec = Recording::from_simulation(&sim, 1e4);
                for initial in [0.01e-3, 0.1e-3, 0.2e-3] {
                    let run =
                        ukf::run(&cfg, &rec, &UkfOptions { initial, ..UkfOptions::default() }, &mut |_, _| {}).unwrap();
                    let err = run.estimate / 0.25e-3 - 1.0;
                    errs.push(err);
                    println!(
                        "recording {r}, from {:.2} mm: {} ({:+.1} %), {} simulations",
                        initial * 1e3,
                        run.release_effect(),
                        err * 100.0,
                        run.simulations
                    );
                }
            }
            let within = errs.iter().filter(|e| e.abs() <= 0.05).count();
            let worst = errs.iter().fold(0.0_f64, |m, e| m.max(e.abs()));
            println!("{dur} s: {within} of {} runs within ±5 %, worst {:.1} %", errs.len(), worst * 100.0);
        }
        Some("two-clearances") => {
            let runs: usize = args.get(1).map_or(16, |s| s.parse().expect("runs per point"));
            let duration: f64 = args.get(2).map_or(10.0, |s| s.parse().expect("duration, s"));
            let spread: f64 = args.get(3).map_or(10.0, |s| s.parse().expect("release spread, degrees"));
            let design = Design { runs, duration, release_spread_deg: spread, ..Design::default() };
            // `stencil`: only the reference's 3 × 3 neighbourhood (the Fisher matrix; a cheaper run).
            let stencil = args.get(4).is_some_and(|s| s == "stencil");
            let (ca, cb, r) = if stencil {
                (vec![0.20e-3, 0.25e-3, 0.30e-3], vec![0.10e-3, 0.15e-3, 0.20e-3], (1, 1))
            } else {
                (
                    vec![0.15e-3, 0.20e-3, 0.25e-3, 0.30e-3, 0.35e-3],
                    vec![0.05e-3, 0.10e-3, 0.15e-3, 0.20e-3, 0.25e-3],
                    (2, 2),
                )
            };
            let start = std::time::Instant::now();
            let a = Analysis::simulate(&CrankConfig::default(), &ca, &cb, r, true, &design, &|k, n| {
                if k % 20 == 0 || k == n {
                    eprintln!("{k}/{n} runs, {:.0} s", start.elapsed().as_secs_f64());
                }
            })
            .unwrap();
            print!("{}", a.report());
            println!("{:.0} s", start.elapsed().as_secs_f64());
        }
        _ => eprintln!(
            "usage: crank_study release-curve | information | ukf [DURATION] [RECORDINGS] | two-clearances [RUNS] [DURATION] [SPREAD] [stencil]"
        ),
    }
}
