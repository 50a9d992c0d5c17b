//! The reference boom against what it must reproduce: its own modes in free decay (the
//! integrator and the damping fit checked against the eigenvalue solution), the sensors' models
//! (the gyro's AR(2) noise and bias from the static record, its reading of the tip's rate, the
//! inclinometer's lag), and the telescoping run.

use edgekf_sim::systems::boom::beam::assemble;
use edgekf_sim::systems::boom::modal::frequencies;
use edgekf_sim::systems::boom::simulate::static_record;
use edgekf_sim::systems::boom::{simulate, BoomConfig, BoomRecording, Scenario, SimOptions};
use std::f64::consts::PI;

fn run(config: &BoomConfig, scenario: Scenario, duration: f64) -> BoomRecording {
    simulate(config, &SimOptions { scenario, duration, seed: 1 }, &mut |_| {}).unwrap()
}

/// Zero crossings (upward) of `v` between `from` and `to` s, interpolated.
fn up_crossings(t: &[f64], v: &[f64], from: f64, to: f64) -> Vec<f64> {
    (1..t.len())
        .filter(|&i| t[i] > from && t[i] < to && v[i - 1] < 0.0 && v[i] >= 0.0)
        .map(|i| t[i - 1] + (t[i] - t[i - 1]) * -v[i - 1] / (v[i] - v[i - 1]))
        .collect()
}

/// Frequency (Hz) and damping ratio of the free decay of `v` over `[from, to]`: mean period of
/// the upward crossings, and the slope of the log of the positive peaks.
fn decay(t: &[f64], v: &[f64], from: f64, to: f64) -> (f64, f64) {
    let c = up_crossings(t, v, from, to);
    let period = (c[c.len() - 1] - c[0]) / (c.len() - 1) as f64;
    let peaks: Vec<(f64, f64)> = c
        .windows(2)
        .map(|w| {
            let (i0, i1) = (t.partition_point(|&s| s < w[0]), t.partition_point(|&s| s < w[1]));
            let k = (i0..i1).max_by(|&a, &b| v[a].total_cmp(&v[b])).unwrap();
            (t[k], v[k].ln())
        })
        .collect();
    let n = peaks.len() as f64;
    let (mt, ml) = (peaks.iter().map(|p| p.0).sum::<f64>() / n, peaks.iter().map(|p| p.1).sum::<f64>() / n);
    let slope = peaks.iter().map(|p| (p.0 - mt) * (p.1 - ml)).sum::<f64>()
        / peaks.iter().map(|p| (p.0 - mt).powi(2)).sum::<f64>();
    let w = 2.0 * PI / period;
    (1.0 / period, -slope / w)
}

#[test]
fn after_a_stop_the_boom_rings_at_its_first_mode_with_its_damping() {
    let c = BoomConfig::default();
    let rec = run(&c, Scenario::Luffing, 19.0);
    let (t, v) = (&rec.t, rec.column("truth_tip_vibration").unwrap());
    // The first move ends at 6 s; the second starts at 18 s. Mode 2 (3 Hz, ζ 2 %) has died
    // away by 9 s.
    let (f, zeta) = decay(t, v, 9.0, 17.9);
    let angle = rec.column("truth_root_angle").unwrap()[1200];
    let w = frequencies(&assemble(&c, 30.0), c.boom.gravity, angle).unwrap();
    let f1 = w[0] / (2.0 * PI);
    assert!((f / f1 - 1.0).abs() < 0.005, "rings at {f:.4} Hz, mode 1 at {f1:.4} Hz");
    assert!((zeta / c.damping.zeta[0] - 1.0).abs() < 0.1, "ζ {zeta:.4}");
    let amplitude = v[900..1790].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(amplitude > 0.05, "the stop excites the boom: {amplitude} m");
    println!("free decay at 30 m: {f:.4} Hz (mode 1 {f1:.4} Hz), ζ {zeta:.4}, amplitude {amplitude:.3} m");
}

#[test]
fn the_static_record_is_the_gyros_ar2_noise_about_its_bias() {
    let c = BoomConfig::default();
    let (t, g) = static_record(&c, 600.0, 3).unwrap();
    assert_eq!(t.len(), 60_000);
    let mean = g.iter().sum::<f64>() / g.len() as f64;
    // The declared-or-sim bias 2e-3 rad/s plus 1e-6 per s of drift (3e-4 at the middle).
    assert!((mean - 2.3e-3).abs() < 5e-5, "mean {mean}");
    let y: Vec<f64> = g.iter().map(|v| v - mean).collect();
    // Least squares of y_k on (y_{k−1}, y_{k−2}) after the drift is taken out.
    let fit = |y: &[f64]| {
        let (mut s11, mut s12, mut s22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for k in 2..y.len() {
            let (x1, x2) = (y[k - 1], y[k - 2]);
            (s11, s12, s22) = (s11 + x1 * x1, s12 + x1 * x2, s22 + x2 * x2);
            (b1, b2) = (b1 + x1 * y[k], b2 + x2 * y[k]);
        }
        let det = s11 * s22 - s12 * s12;
        [(b1 * s22 - b2 * s12) / det, (s11 * b2 - s12 * b1) / det]
    };
    let slope = {
        let mt = t.iter().sum::<f64>() / t.len() as f64;
        t.iter().zip(&y).map(|(a, b)| (a - mt) * b).sum::<f64>() / t.iter().map(|a| (a - mt).powi(2)).sum::<f64>()
    };
    let detrended: Vec<f64> = t.iter().zip(&y).map(|(a, b)| b - slope * (a - 300.0)).collect();
    let [a1, a2] = fit(&detrended);
    assert!((a1 + 0.6538).abs() < 0.02 && (a2 - 0.06745).abs() < 0.02, "a = [{a1}, {a2}]");
    assert!((slope - 1e-6).abs() < 3e-7, "drift {slope}");
}

#[test]
fn the_gyro_reads_the_tips_rate_and_the_inclinometer_lags_the_root() {
    let c = BoomConfig::default();
    let rec = run(&c, Scenario::Luffing, 30.0);
    let col = |n: &str| rec.column(n).unwrap();
    let (gyro, bias, tip) = (col("gyro_rate"), col("truth_gyro_bias"), col("truth_tip_angle"));
    let dt = 0.01;
    // The tip's rate by central differences of its angle against the gyro without its bias.
    let err: Vec<f64> =
        (1..rec.t.len() - 1).map(|k| gyro[k] - bias[k] - (tip[k + 1] - tip[k - 1]) / (2.0 * dt)).collect();
    let rms = (err.iter().map(|e| e * e).sum::<f64>() / err.len() as f64).sqrt();
    let peak_rate = (1..rec.t.len() - 1).map(|k| ((tip[k + 1] - tip[k - 1]) / (2.0 * dt)).abs()).fold(0.0, f64::max);
    // AR(2) noise of 3e-4 rad/s driving noise has a standard deviation of about 4e-4.
    assert!(rms < 1e-3 && peak_rate > 0.05, "gyro error RMS {rms} against a peak rate {peak_rate}");
    // The inclinometer: the root angle through a 0.3 s first-order lag, plus 5e-4 rad of noise.
    let (root, incl) = (col("truth_root_angle"), col("incl_angle"));
    let k = 1.0 - (-dt / c.inclinometer.lag).exp();
    let mut lagged = root[0];
    let mut sq = 0.0;
    let mut unlagged = 0.0;
    for i in 1..root.len() {
        lagged += k * (root[i] - lagged);
        sq += (incl[i] - lagged).powi(2);
        unlagged += (incl[i] - root[i]).powi(2);
    }
    let n = (root.len() - 1) as f64;
    let (rms, raw) = ((sq / n).sqrt(), (unlagged / n).sqrt());
    assert!(rms < 7e-4 && raw > 3.0 * rms, "inclinometer against the lagged root: {rms}; against the root: {raw}");
}

#[test]
fn the_extension_run_telescopes_from_18_to_30_m_and_stiffens_as_it_shortens() {
    let c = BoomConfig::default();
    let rec = run(&c, Scenario::Extension, 140.0);
    let l = rec.column("boom_length").unwrap();
    assert_eq!(l[0], 18.0);
    assert!((l[l.len() - 1] - 30.0).abs() < 1e-9);
    let v = rec.column("truth_tip_vibration").unwrap();
    // Early rest (18–19 m): far stiffer than the last one (30 m).
    let (f_short, _) = decay(&rec.t, v, 8.0, 17.9);
    let (f_long, _) = decay(&rec.t, v, 136.0, 139.9);
    let peaks = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(f_short > 1.8 * f_long && peaks > 0.1, "{f_short:.3} Hz short, {f_long:.3} Hz long, peak {peaks:.3} m");
    println!("extension: {f_short:.3} Hz near 19 m, {f_long:.3} Hz at 30 m");
}

/// The paper's method on both runs, with the figures printed beside the paper's 1.31 %.
#[test]
fn the_papers_method_on_both_runs() {
    use edgekf_sim::systems::boom::estimate::{estimate, gyro_model, Method};
    use edgekf_sim::systems::boom::peaks::peak_errors;
    let c = BoomConfig::default();
    let (_, statics) = static_record(&c, 60.0, 1).unwrap();
    let ar = gyro_model(&c, &statics).unwrap();
    for (scenario, duration) in [(Scenario::Luffing, 120.0), (Scenario::Extension, 140.0)] {
        let rec = run(&c, scenario, duration);
        let est = estimate(&c, &rec.to_data_file(), ar, Method::Paper).unwrap();
        let (truth, rate) = (rec.column("truth_tip_vibration").unwrap(), rec.column("truth_root_rate").unwrap());
        let p = peak_errors(&rec.t, est.column("tip_vibration").unwrap(), truth, rate);
        assert!(p.peaks >= 27 && p.free_decay_peaks >= 27, "{p:?}");
        // Within issue #34's 40 %, far from the paper's 1.31 %, and worse during the moves than in
        // free decay.
        assert!(p.mean_pct <= 40.0, "{p:?}");
        assert!(p.free_decay_mean_pct > 5.0 && p.mean_pct > p.free_decay_mean_pct, "{p:?}");
        assert!(est.fusions > 50, "{} equilibrium instants fused", est.fusions);
        println!(
            "paper's method, {} run: {} peaks, mean {:.1} %, median {:.1} %; {} free-decay peaks, mean {:.1} % (paper: 1.31 %)",
            scenario.name(),
            p.peaks,
            p.mean_pct,
            p.median_pct,
            p.free_decay_peaks,
            p.free_decay_mean_pct
        );
    }
}

/// Which of the paper's steps costs how much: each replaced by what it stands for.
#[test]
fn the_papers_method_taken_apart() {
    use edgekf_sim::systems::boom::ablation::ablation;
    use edgekf_sim::systems::boom::estimate::gyro_model;
    let c = BoomConfig::default();
    let (_, statics) = static_record(&c, 60.0, 1).unwrap();
    let ar = gyro_model(&c, &statics).unwrap();
    for (scenario, duration) in [(Scenario::Luffing, 120.0), (Scenario::Extension, 140.0)] {
        let rec = run(&c, scenario, duration);
        let rows = ablation(&c, &rec, ar).unwrap();
        for (name, p) in &rows {
            println!(
                "{} run, {name}: mean {:.1} %, median {:.1} %, free decay {:.1} %",
                scenario.name(),
                p.mean_pct,
                p.median_pct,
                p.free_decay_mean_pct
            );
        }
        let mean = |i: usize| rows[i].1.mean_pct;
        // The AR filter takes out the gyro's noise and leaves the motion (issue #34: before, it
        // passed 44 % of the rate and cost 76–100 points); the method within the 40 %;
        // with every step ideal what is left is the equilibrium instants themselves (the second
        // mode moves the peak of the relative rate off the first mode's crossing).
        assert!((mean(1) - mean(0)).abs() < 5.0, "without the AR filter {} against {}", mean(1), mean(0));
        assert!(mean(0) <= 40.0 && mean(5) < 30.0, "the method {}, all four {}", mean(0), mean(5));
    }
}

/// The estimators' reduced boom (Rayleigh–Ritz on polynomials, `edgekf::systems::boom`) against
/// the reference's finite elements: the same boom by another formulation.
#[test]
fn the_reduced_boom_agrees_with_the_finite_elements() {
    use edgekf_sim::systems::boom::modal::first_mode;
    let c = BoomConfig::default();
    let constants = c.constants().unwrap();
    for length in [18.0, 24.0, 30.0] {
        let phi = c.runs.start_angle;
        let reduced = constants.reduce(length, phi).unwrap();
        let beam = assemble(&c, length);
        let w = frequencies(&beam, c.boom.gravity, phi).unwrap();
        let (w1, shape) = first_mode(&beam, c.boom.gravity, phi).unwrap();
        assert!((w1 - w[0]).abs() < 1e-9 * w[0]);
        let m = &reduced.modes;
        let f = |i: usize| (m[i].omega / w[i] - 1.0) * 100.0;
        assert!(
            f(0).abs() < 0.5 && f(1).abs() < 1.0 && f(2).abs() < 3.0,
            "{length} m: modes off by {:.3} %, {:.3} %, {:.3} %",
            f(0),
            f(1),
            f(2)
        );
        // The first mode's ratio of tip deflection to slope (what `α l` stands for).
        let tip = beam.tip();
        let ratio = |d: f64, s: f64| d / (length * s);
        let (fe, rr) = (ratio(shape[tip], shape[tip + 1]), ratio(m[0].tip_deflection, m[0].tip_slope));
        assert!((rr / fe - 1.0).abs() < 0.005, "{length} m: α {rr:.4} against {fe:.4}");
        // The sag at the tip.
        let g = c.boom.gravity;
        let k = edgekf_sim::systems::boom::modal::stiffness(&beam, g, phi);
        let sag = k.cholesky().unwrap().solve(&(&beam.gm * (-g * phi.cos())));
        assert!(
            (reduced.sag.0 / sag[tip] - 1.0).abs() < 0.01,
            "{length} m: sag {} against {}",
            reduced.sag.0,
            sag[tip]
        );
        let hz = |w: f64| w / (2.0 * PI);
        println!(
            "{length} m: modes {:.4} / {:.4} / {:.3} Hz against {:.4} / {:.4} / {:.3} Hz, α {rr:.4} against {fe:.4}, sag {:.4} m",
            hz(m[0].omega),
            hz(m[1].omega),
            hz(m[2].omega),
            hz(w[0]),
            hz(w[1]),
            hz(w[2]),
            reduced.sag.0
        );
    }
}

/// The model-based filter's peak errors on `scenario` simulated with `truth` and estimated with
/// `declared`.
fn model_peak_errors(
    truth: &BoomConfig,
    declared: &BoomConfig,
    scenario: Scenario,
    duration: f64,
) -> edgekf_sim::systems::boom::peaks::PeakErrors {
    use edgekf_sim::systems::boom::estimate::{estimate, gyro_model, Method};
    use edgekf_sim::systems::boom::peaks::peak_errors;
    let (_, statics) = static_record(truth, 60.0, 1).unwrap();
    let ar = gyro_model(declared, &statics).unwrap();
    let rec = run(truth, scenario, duration);
    let est = estimate(declared, &rec.to_data_file(), ar, Method::Model).unwrap();
    let (vib, rate) = (rec.column("truth_tip_vibration").unwrap(), rec.column("truth_root_rate").unwrap());
    peak_errors(&rec.t, est.column("tip_vibration").unwrap(), vib, rate)
}

fn print_errors(what: &str, scenario: Scenario, p: &edgekf_sim::systems::boom::peaks::PeakErrors) {
    println!(
        "model, {what}, {} run: {} peaks, mean {:.2} %, median {:.2} %; {} free-decay peaks, mean {:.2} %",
        scenario.name(),
        p.peaks,
        p.mean_pct,
        p.median_pct,
        p.free_decay_peaks,
        p.free_decay_mean_pct
    );
}

/// The model-based filter on both runs with the boom and sensors as declared: within 2 %.
#[test]
fn the_model_based_filter_on_both_runs() {
    let c = BoomConfig::default();
    for (scenario, duration) in [(Scenario::Luffing, 120.0), (Scenario::Extension, 140.0)] {
        let p = model_peak_errors(&c, &c, scenario, duration);
        print_errors("as declared", scenario, &p);
        assert!(p.peaks >= 27 && p.mean_pct <= 2.0, "{p:?}");
    }
}

/// The sensors not as declared: the gyro's scale 0.3 % off and the inclinometer's lag 50 % off
/// (either way): within 3 %.
#[test]
fn the_model_based_filter_with_the_sensors_off() {
    let declared = BoomConfig::default();
    for lag in [1.5, 0.5] {
        let mut truth = declared.clone();
        truth.sim.gyro.scale = Some(1.003 * declared.gyro.scale);
        truth.sim.inclinometer.lag = Some(lag * declared.inclinometer.lag);
        for (scenario, duration) in [(Scenario::Luffing, 120.0), (Scenario::Extension, 140.0)] {
            let p = model_peak_errors(&truth, &declared, scenario, duration);
            print_errors(&format!("gyro scale +0.3 %, lag ×{lag}"), scenario, &p);
            assert!(p.peaks >= 27 && p.mean_pct <= 3.0, "{p:?}");
        }
    }
}

/// The boom not as declared: every section's EI 5 % lower and the platform 10 % heavier:
/// within 4 %.
#[test]
fn the_model_based_filter_with_the_boom_off() {
    let declared = BoomConfig::default();
    let mut truth = declared.clone();
    for s in &mut truth.section {
        s.ei *= 0.95;
    }
    truth.tip.mass *= 1.1;
    for (scenario, duration) in [(Scenario::Luffing, 120.0), (Scenario::Extension, 140.0)] {
        let p = model_peak_errors(&truth, &declared, scenario, duration);
        print_errors("EI −5 %, platform +10 %", scenario, &p);
        assert!(p.peaks >= 27 && p.mean_pct <= 4.0, "{p:?}");
    }
}

/// The luffing drive not as declared: its lag 50 % longer with its acceleration limit a third
/// lower, or the other way: within 3 % (the drive's model carries the root's rate through the
/// moves, so this is this design's own weak point).
#[test]
fn the_model_based_filter_with_the_drive_off() {
    let declared = BoomConfig::default();
    for factor in [1.5, 1.0 / 1.5] {
        let mut truth = declared.clone();
        truth.drive.lag *= factor;
        truth.drive.max_accel /= factor;
        for (scenario, duration) in [(Scenario::Luffing, 120.0), (Scenario::Extension, 140.0)] {
            let p = model_peak_errors(&truth, &declared, scenario, duration);
            print_errors(&format!("drive lag ×{factor:.2}"), scenario, &p);
            assert!(p.peaks >= 27 && p.mean_pct <= 3.0, "{p:?}");
        }
    }
}

/// The node's precision: the same filter in `f32` within 1 mm of the `f64` run, and no worse.
#[test]
fn the_model_based_filter_in_f32() {
    use edgekf::systems::boom::ModelEstimator;
    use edgekf_sim::systems::boom::estimate::{gyro_model, model_settings, INCLINOMETER_NOISE};
    use edgekf_sim::systems::boom::peaks::peak_errors;
    let c = BoomConfig::default();
    let (_, statics) = static_record(&c, 60.0, 1).unwrap();
    let settings = model_settings(&c, gyro_model(&c, &statics).unwrap(), INCLINOMETER_NOISE).unwrap();
    let rec = run(&c, Scenario::Extension, 140.0);
    let col = |n: &str| rec.column(n).unwrap();
    let (gyro, incl, length, command) = (col("gyro_rate"), col("incl_angle"), col("boom_length"), col("luff_rate_cmd"));
    let mut wide = ModelEstimator::<f64>::new(&settings, length[0]).unwrap();
    let mut narrow = ModelEstimator::<f32>::new(&settings, length[0]).unwrap();
    let (mut v64, mut v32) = (Vec::new(), Vec::new());
    for k in 0..rec.t.len() {
        v64.push(wide.step(gyro[k], incl[k], length[k], command[k]).vibration);
        let e = narrow.step(gyro[k] as f32, incl[k] as f32, length[k] as f32, command[k] as f32);
        v32.push(e.vibration as f64);
    }
    let worst = v64.iter().zip(&v32).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    let truth = col("truth_tip_vibration");
    let p = peak_errors(&rec.t, &v32, truth, col("truth_root_rate"));
    println!("f32 against f64: within {:.2e} m; f32 mean peak error {:.2} %", worst, p.mean_pct);
    assert!(worst < 1e-3 && p.mean_pct <= 2.0, "{worst} m, {p:?}");
}

/// The sideways boom of `[sim.lateral]`: a gyro leaning by δ reads cos δ of the luffing plane's
/// rate (with no wind, exactly), and wind with the gyro upright changes no reading (its own
/// random stream); with both, the gyro reads the sideways bending on top.
#[test]
fn the_sideways_boom_reaches_the_gyro_only_through_its_lean() {
    use edgekf_sim::systems::boom::config::SimLateral;
    let mut c = BoomConfig::default();
    // An ideal gyro: its reading is its rate.
    c.sim.gyro = edgekf_sim::systems::boom::config::SimGyro {
        noise: Some(0.0),
        bias: Some(0.0),
        bias_drift: Some(0.0),
        quantum: Some(0.0),
        ..Default::default()
    };
    let plain = run(&c, Scenario::Luffing, 30.0);
    let with = |gust: f64, lean: f64| {
        let mut l = c.clone();
        l.sim.lateral = Some(SimLateral { ei_factor: 2.5, gust, misalignment: lean });
        run(&l, Scenario::Luffing, 30.0)
    };
    let gyro = |r: &BoomRecording| r.column("gyro_rate").unwrap().to_vec();
    let calm = with(0.0, 0.05);
    let scaled: Vec<f64> = gyro(&plain).iter().map(|v| v * 0.05f64.cos()).collect();
    let worst = scaled.iter().zip(gyro(&calm)).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-12, "calm, leaning: {worst}");
    assert_eq!(gyro(&with(1.0, 0.0)), gyro(&plain), "wind, upright");
    let windy = with(1.0, 0.05);
    let extra = gyro(&windy).iter().zip(&scaled).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / scaled.len() as f64;
    assert!(extra.sqrt() > 1e-4, "the sideways bending reads {:.2e} rad/s RMS", extra.sqrt());
    assert_eq!(windy.column("truth_tip_vibration"), plain.column("truth_tip_vibration"));
}
