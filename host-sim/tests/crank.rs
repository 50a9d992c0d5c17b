//! The slider-crank reference simulator against physics: textbook dynamics of the ideal
//! mechanism, energy and constraints, impacts in a clearance joint, the paper's spectral
//! feature, and the two integrators against a fine reference.
//!
//! Run with `--nocapture` to see the figures. `EDGEKF_LONG=1` adds a 10 s run per integrator.

use edgekf_sim::systems::crank::feature::window_features;
use edgekf_sim::systems::crank::{CrankConfig, CrankRecording, Integrator, Joint, Mechanism, SimOptions};
use std::time::Instant;

const PAPER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/crank_paper.toml");

fn mech(clearances: [Option<f64>; 3]) -> Mechanism {
    Mechanism::new(&CrankConfig::default(), clearances).unwrap()
}

fn run(m: &Mechanism, duration: f64, integrator: Integrator) -> CrankRecording {
    let opts = SimOptions { integrator, noise_std: 0.0, ..SimOptions::from_config(m.config(), duration) };
    m.simulate(&opts).unwrap()
}

const SE: Integrator = Integrator::SymplecticEuler { step: 1e-5 };
const TIGHT: Integrator = Integrator::Adaptive { tolerance: 1e-10, max_step: 1e-3 };

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// The ideal mechanism's acceleration from the textbook one-degree-of-freedom Lagrange
/// equation, `J(θ) θ̈ + ½ J'(θ) θ̇² + V'(θ) = 0`, with `J` built from the closed-form slider-crank
/// kinematics (`sin φ = −L₁ sin θ / L₂`): an independent derivation of what the R-matrix code
/// computes.
#[test]
fn ideal_acceleration_matches_the_textbook_lagrange_equation() {
    let c = CrankConfig::default();
    let (l1, l2, g) = (c.crank.length, c.rod.length, c.world.gravity);
    let (m1, m2, m3) = (c.crank.mass, c.rod.mass, c.slider.mass);
    let geometry = |th: f64| {
        let (s, co) = th.sin_cos();
        let sphi = -l1 * s / l2;
        let cphi = (1.0 - sphi * sphi).sqrt();
        let b = (l1 * co, l1 * s);
        let cx = l1 * co + l2 * cphi;
        ((b.0 + cx) / 2.0, b.1 / 2.0, sphi.asin(), cx)
    };
    let inertia = |th: f64| {
        let h = 1e-6;
        let (p, q) = (geometry(th + h), geometry(th - h));
        let d = |a: f64, b: f64| (a - b) / (2.0 * h);
        c.crank.inertia
            + m1 * (l1 / 2.0).powi(2)
            + m2 * (d(p.0, q.0).powi(2) + d(p.1, q.1).powi(2))
            + c.rod.inertia * d(p.2, q.2).powi(2)
            + m3 * d(p.3, q.3).powi(2)
    };
    let dv = |th: f64| g * th.cos() * l1 * (m1 + m2) / 2.0;
    let m = mech([None; 3]);
    for (th, rate) in [(30f64.to_radians(), 0.0), (-1.0, 12.0), (2.5, -20.0), (-2.0, 5.0)] {
        let j = inertia(th);
        let dj = (inertia(th + 1e-4) - inertia(th - 1e-4)) / 2e-4;
        let expect = -(dv(th) + 0.5 * dj * rate * rate) / j;
        let mut s = m.release_state();
        s.z[0] = th;
        s.zd[0] = rate;
        let got = m.dynamics(&s).crank_alpha();
        eprintln!("θ = {th:+.3} rad, θ̇ = {rate:+5.1}: θ̈ = {got:+.6} rad/s² (Lagrange {expect:+.6})");
        assert!((got - expect).abs() < 1e-5 * expect.abs().max(1.0), "{got} vs {expect}");
    }
}

#[test]
fn ideal_mechanism_conserves_energy_and_constraints() {
    let m = mech([None; 3]);
    let fine = run(&m, 2.0, TIGHT);
    let paper = run(&m, 2.0, SE);
    let e0 = fine.truth_energy[0];
    let drift = |r: &CrankRecording| r.truth_energy.iter().map(|e| (e - e0).abs()).fold(0.0, f64::max);
    eprintln!(
        "ideal, 2 s: E₀ = {e0:.6} J; |E − E₀| max: adaptive(1e-10) {:.2e} J, symplectic Euler(1e-5) {:.2e} J; \
         constraint residual max {:.1e} / {:.1e} m",
        drift(&fine),
        drift(&paper),
        fine.max_constraint_residual,
        paper.max_constraint_residual
    );
    assert!(drift(&fine) < 1e-9 * e0.abs().max(0.01) * 10.0);
    // Symplectic Euler in these (non-canonical) coordinates is first-order in energy: ~2e-3
    // relative over 2 s at 1e-5 s.
    assert!(drift(&paper) < 5e-3 * e0);
    assert!(fine.max_constraint_residual < 1e-15 && paper.max_constraint_residual < 1e-15);
    // Released from rest at 30°, it swings through the bottom to the mirror angle, 150° the
    // other way (the potential depends on sin θ only), and back.
    let low = fine.truth_crank_angle.iter().copied().fold(f64::INFINITY, f64::min).to_degrees();
    let high = fine.truth_crank_angle[1000..].iter().copied().fold(f64::NEG_INFINITY, f64::max).to_degrees();
    eprintln!("ideal: swing {low:.4}° … {high:.4}°");
    assert!((low + 210.0).abs() < 0.01 && (high - 30.0).abs() < 0.01, "{low} {high}");
    // No clearance, no impacts, and the pin at A carries at least the weight it holds up.
    assert_eq!(fine.stats.impacts, [0, 0, 0]);
    assert!(fine.peak_force(Joint::A) > 5.0);
}

/// A clearance of 1 µm behaves like an ideal joint at the level of the motion; 0.25 mm does not.
#[test]
fn tiny_clearance_approaches_the_ideal_mechanism() {
    let duration = 0.5;
    let ideal = run(&mech([None; 3]), duration, TIGHT);
    let adaptive = Integrator::Adaptive { tolerance: 1e-8, max_step: 1e-3 };
    let mut devs = Vec::new();
    for c in [0.25e-3, 10e-6, 1e-6] {
        let r = run(&mech([Some(c), None, None]), duration, adaptive);
        let dth = max_abs_diff(&r.truth_crank_angle, &ideal.truth_crank_angle);
        let dw = max_abs_diff(&r.truth_crank_rate, &ideal.truth_crank_rate);
        eprintln!(
            "clearance {:7.4} mm: max |Δθ| {dth:.2e} rad, max |Δω| {dw:.2e} rad/s vs ideal ({} impacts)",
            c * 1e3,
            r.stats.impacts[0]
        );
        devs.push(dth);
    }
    // The deviation shrinks with the clearance (about linearly) and is 0.03 % of the swing at 1 µm.
    assert!(devs[0] > 1e-2, "{devs:?}");
    assert!(devs[1] < devs[0] / 5.0 && devs[2] < devs[1] / 4.0, "{devs:?}");
    assert!(devs[2] < 5e-4, "{devs:?}");
}

#[test]
fn clearance_at_a_impacts_and_never_gains_energy() {
    let m = mech([Some(0.25e-3), None, None]);
    let c = 0.25e-3;
    let fine = run(&m, 0.5, TIGHT);
    let paper = run(&m, 0.5, SE);
    for (name, r) in [("adaptive(1e-10)", &fine), ("symplectic Euler(1e-5)", &paper)] {
        let ecc = &r.truth_eccentricity[0];
        let in_contact = ecc.iter().filter(|&&e| e > c).count() as f64 / ecc.len() as f64;
        let deepest = ecc.iter().copied().fold(0.0, f64::max) - c;
        eprintln!(
            "0.25 mm at A, 0.5 s, {name}: {} impacts, peak force {:.0} N, in contact {:.0} % of samples, \
             deepest indentation {:.2} µm, dissipated {:.3e} J, balance error {:.2e} J, largest energy climb {:.2e} J",
            r.stats.impacts[0],
            r.peak_force(Joint::A),
            100.0 * in_contact,
            deepest * 1e6,
            r.truth_dissipated.last().unwrap(),
            r.energy_balance_error(),
            r.energy_rise()
        );
        // Impacts: many contacts, forces far above the ~10 N the weight alone would need,
        // separation and contact phases both, micrometre indentations.
        assert!(r.stats.impacts[0] >= 20, "{name}");
        assert!(r.peak_force(Joint::A) > 200.0, "{name}");
        assert!(in_contact > 0.1 && in_contact < 0.9, "{name}: {in_contact}");
        assert!(deepest > 0.5e-6 && deepest < 20e-6, "{name}: {deepest}");
        // Restitution 0.9 dissipates; the amount is a few per cent of the energy per swing.
        assert!(*r.truth_dissipated.last().unwrap() > 1e-3, "{name}");
        assert_eq!(r.stats.impacts[1..], [0, 0]);
    }
    // Exact accounting with the accurate integrator: energy never climbs (beyond 1e-12 J of
    // 0.06 J) and mechanical + dissipated energy is constant to 1e-8 J.
    assert!(fine.energy_rise() < 1e-12, "{}", fine.energy_rise());
    assert!(fine.energy_balance_error() < 1e-8, "{}", fine.energy_balance_error());
    // The paper's integrator accounts for energy to first order only.
    assert!(paper.energy_balance_error() < 1e-3 * 0.0625 * 5.0);
}

#[test]
fn clearances_at_b_and_c_also_collide() {
    let m = mech([None, Some(0.1e-3), Some(0.1e-3)]);
    let r = run(&m, 0.2, Integrator::Adaptive { tolerance: 1e-8, max_step: 1e-3 });
    eprintln!(
        "0.1 mm at B and C, 0.2 s: impacts {:?}, peak forces B {:.0} N, C {:.0} N, balance error {:.1e} J",
        r.stats.impacts,
        r.peak_force(Joint::B),
        r.peak_force(Joint::C),
        r.energy_balance_error()
    );
    assert_eq!(r.stats.impacts[0], 0);
    assert!(r.stats.impacts[1] > 5 && r.stats.impacts[2] > 5);
    assert!(r.energy_balance_error() < 1e-6);
    assert!(r.max_constraint_residual < 1e-15);
}

/// The estimator's use: windows run back to back from each other's final state give the same
/// samples as one long run, and a clearance change keeps the indentation.
#[test]
fn windows_concatenate_into_one_run() {
    let m = mech([Some(0.25e-3), None, None]);
    let cfg = *m.config();
    let whole = m.simulate(&SimOptions::from_config(&cfg, 0.1)).unwrap();
    let first = m.simulate(&SimOptions::from_config(&cfg, 0.05)).unwrap();
    let second_opts = SimOptions { initial: Some(first.final_state), seed: 2, ..SimOptions::from_config(&cfg, 0.05) };
    let second = m.simulate(&second_opts).unwrap();
    assert_eq!(second.t[0], 0.05);
    let joined: Vec<f64> = first.truth_crank_alpha.iter().chain(&second.truth_crank_alpha).copied().collect();
    assert_eq!(joined, whole.truth_crank_alpha, "symplectic Euler windows are bit-identical to one run");

    // A sigma point with a smaller clearance starts from the same instant without a force jump.
    let smaller = mech([Some(0.2e-3), None, None]);
    let mut state = first.final_state;
    let law = m.contact_law(Joint::A).unwrap();
    // Put the journal 2 µm into the bearing, moving outwards, to make the point.
    let [x, y] = state.eccentricity(Joint::A);
    let r = x.hypot(y).max(1e-9);
    let k = (law.clearance + 2e-6) / r;
    state.set_eccentricity(Joint::A, [x * k, y * k], [0.01 * x / r, 0.01 * y / r]);
    state.impact_velocity[0] = Some(0.01);
    let before = m.dynamics(&state).contact[0].total;
    let moved = smaller.transfer_state(&m, &state);
    let after = smaller.contact_law(Joint::A).map(|_| smaller.dynamics(&moved).contact[0].total).unwrap();
    eprintln!("transfer 0.25 → 0.20 mm at 2 µm indentation: contact force {before:.2} N → {after:.2} N");
    // Same indentation; the stiffness grows as √(1/c), so the force by ~12 %, not by the
    // ~700× a 50 µm indentation would give.
    assert!(after / before > 1.0 && after / before < 1.2, "{before} → {after}");
}

/// The paper's feature: `a` of the exponential fit of each 0.25 s window's spectrum grows with
/// the clearance at A (0.05, 0.1, 0.25, 0.5 mm), on average, with the paper's integrator and a
/// 5 rad/s² sensor. The motion is chaotic, so one run's windows are a sample: 10 s from each of
/// four release angles (the paper's 30° among them) give 160 windows per clearance, and each
/// rise must exceed twice its standard error.
#[test]
fn spectral_feature_rises_with_clearance() {
    let mut pooled = Vec::new();
    for c in [0.05e-3, 0.1e-3, 0.25e-3, 0.5e-3] {
        let mut all = Vec::new();
        let mut per_angle = Vec::new();
        for angle in [20.0, 30.0, 40.0, 50.0] {
            let mut cfg = CrankConfig::default();
            cfg.release.crank_angle_deg = angle;
            let m = Mechanism::new(&cfg, [Some(c), None, None]).unwrap();
            let rec = m.simulate(&SimOptions::from_config(&cfg, 10.0)).unwrap();
            let a: Vec<f64> = window_features(&rec.crank_alpha, cfg.sensor.sample_rate, 0.25)
                .into_iter()
                .map(|f| f.expect("every window fits").a)
                .collect();
            assert_eq!(a.len(), 40);
            per_angle.push(format!("{angle}°: {:.1}", a.iter().sum::<f64>() / 40.0));
            all.extend(a);
        }
        let n = all.len() as f64;
        let mean = all.iter().sum::<f64>() / n;
        let std = (all.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let se = std / n.sqrt();
        eprintln!(
            "clearance {:.2} mm: a = {mean:7.2} ± {se:.2} rad/s² (window std {std:.1}, 160 windows; {})",
            c * 1e3,
            per_angle.join(", ")
        );
        pooled.push((mean, se));
    }
    for w in pooled.windows(2) {
        let ((m0, s0), (m1, s1)) = (w[0], w[1]);
        assert!(m1 - m0 > 2.0 * s0.hypot(s1), "{pooled:?}");
    }
}

/// Error in the crank angle against a fine reference (adaptive, tolerance 1e-12), with the work
/// (evaluations of the equations of motion) each integrator spent, over 0.05 s from `start`.
fn compare(m: &Mechanism, start: Option<edgekf_sim::systems::crank::State>, cases: &[Integrator]) -> Vec<(u64, f64)> {
    let duration = 0.05;
    let go = |integrator| {
        let opts =
            SimOptions { integrator, noise_std: 0.0, initial: start, ..SimOptions::from_config(m.config(), duration) };
        let t = Instant::now();
        (m.simulate(&opts).unwrap(), t.elapsed().as_secs_f64() * 1e3)
    };
    let (reference, _) = go(Integrator::Adaptive { tolerance: 1e-12, max_step: 1e-4 });
    eprintln!(
        "  reference: adaptive, tolerance 1e-12: {} evaluations, {:?} impacts",
        reference.stats.evaluations, reference.stats.impacts
    );
    eprintln!(
        "  {:<34} {:>11} {:>9} {:>12} {:>13} {:>10}",
        "integrator", "evaluations", "wall [ms]", "max|Δθ| rad", "max|Δω| rad/s", "balance J"
    );
    let label = |i: &Integrator| match i {
        Integrator::SymplecticEuler { step } => format!("symplectic Euler, h = {step:e} s"),
        Integrator::Adaptive { tolerance, .. } => format!("adaptive DP5(4), tol = {tolerance:e}"),
    };
    cases
        .iter()
        .map(|integ| {
            let (r, wall) = go(*integ);
            let dth = max_abs_diff(&r.truth_crank_angle, &reference.truth_crank_angle);
            let dw = max_abs_diff(&r.truth_crank_rate, &reference.truth_crank_rate);
            eprintln!(
                "  {:<34} {:>11} {:>9.2} {:>12.2e} {:>13.2e} {:>10.2e}",
                label(integ),
                r.stats.evaluations,
                wall,
                dth,
                dw,
                r.energy_balance_error()
            );
            (r.stats.evaluations, dth)
        })
        .collect()
}

/// Error against a fine reference per unit of work, with 0.25 mm at A, over two 0.05 s
/// stretches: from release (free flight and eight impacts) and from t = 0.12 s (the journal
/// rides on the bearing, bouncing without leaving it). Short on purpose: impacts make the motion
/// sensitive to its initial state, so over long runs every integrator's error would be the
/// reference's own divergence.
#[test]
fn integrator_comparison() {
    let m = mech([Some(0.25e-3), None, None]);
    let cases = [
        Integrator::SymplecticEuler { step: 1e-5 },
        Integrator::SymplecticEuler { step: 1e-6 },
        Integrator::SymplecticEuler { step: 1e-7 },
        Integrator::Adaptive { tolerance: 1e-6, max_step: 1e-3 },
        Integrator::Adaptive { tolerance: 1e-8, max_step: 1e-3 },
        Integrator::Adaptive { tolerance: 1e-10, max_step: 1e-3 },
    ];
    eprintln!("from release, 0.05 s:");
    let r = compare(&m, None, &cases);
    // Symplectic Euler converges towards the reference at first order: the reference is right.
    assert!(r[1].1 < r[0].1 / 5.0 && r[2].1 < r[1].1, "{r:?}");
    // Adaptive at 1e-6: under half the paper's work and over 10× more accurate; at 1e-8: still
    // less work and over 100× more accurate. Symplectic Euler needs over 100× the work of
    // adaptive(1e-8) and is still less accurate.
    assert!(r[3].0 * 2 < r[0].0 && r[3].1 < r[0].1 / 10.0, "{r:?}");
    assert!(r[4].0 < r[0].0 && r[4].1 < r[0].1 / 100.0, "{r:?}");
    assert!(r[2].0 > 100 * r[4].0 && r[2].1 > r[4].1, "{r:?}");

    let settle = SimOptions {
        integrator: Integrator::Adaptive { tolerance: 1e-10, max_step: 1e-3 },
        noise_std: 0.0,
        ..SimOptions::from_config(m.config(), 0.12)
    };
    let start = m.simulate(&settle).unwrap().final_state;
    assert!(start.impact_velocity[0].is_some(), "in contact at 0.12 s");
    eprintln!("riding on the bearing from t = 0.12 s, 0.05 s:");
    let r = compare(&m, Some(start), &cases);
    assert!(r[1].1 < r[0].1 / 5.0 && r[2].1 < r[1].1 / 5.0, "{r:?}");
    // The stiff contact keeps the adaptive steps short here: at 1e-6 it spends ~1.4× the
    // paper's work for an error over 100× smaller.
    assert!(r[3].0 < 2 * r[0].0 && r[3].1 < r[0].1 / 100.0, "{r:?}");
    assert!(r[4].0 < 5 * r[0].0 && r[4].1 < r[0].1 / 10_000.0, "{r:?}");
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let cfg = CrankConfig::default();
    for c in [f64::NAN, -1e-3, 0.0, 0.02, f64::INFINITY] {
        assert!(Mechanism::new(&cfg, [Some(c), None, None]).is_err(), "{c}");
    }
    // Clearances that would let the rod stand vertical.
    let mut big_pins = cfg;
    big_pins.contact.journal_radius = 0.05;
    assert!(Mechanism::new(&big_pins, [Some(0.015), Some(0.015), Some(0.015)])
        .unwrap_err()
        .to_string()
        .contains("rod"));
    let m = mech([Some(0.25e-3), None, None]);
    for duration in [0.0, -1.0, f64::NAN, 1e-6] {
        assert!(m.simulate(&SimOptions::from_config(&cfg, duration)).is_err(), "{duration}");
    }
    let bad_step =
        SimOptions { integrator: Integrator::SymplecticEuler { step: 0.0 }, ..SimOptions::from_config(&cfg, 0.01) };
    assert!(m.simulate(&bad_step).is_err());
    let mut s = m.release_state();
    s.set_eccentricity(Joint::B, [1e-4, 0.0], [0.0; 2]);
    let err = m.simulate(&SimOptions { initial: Some(s), ..SimOptions::from_config(&cfg, 0.01) }).unwrap_err();
    assert!(err.to_string().contains("ideal joint B"), "{err}");
    s = m.release_state();
    s.zd[0] = f64::NAN;
    assert!(m.simulate(&SimOptions { initial: Some(s), ..SimOptions::from_config(&cfg, 0.01) }).is_err());
    // A step far too large for the contact stiffness diverges and says so.
    let wild = SimOptions {
        integrator: Integrator::SymplecticEuler { step: 1e-3 },
        sample_rate: 1000.0,
        ..SimOptions::from_config(&cfg, 0.5)
    };
    match m.simulate(&wild) {
        Err(e) => assert!(e.to_string().contains("failed"), "{e}"),
        Ok(r) => assert!(r.truth_crank_alpha.iter().all(|v| v.is_finite())),
    }
    let mut bad = cfg;
    bad.rod.length = 0.04;
    assert!(Mechanism::new(&bad, [None; 3]).unwrap_err().to_string().contains("rod.length"));
}

#[test]
fn paper_config_file_is_the_default() {
    let file = CrankConfig::load(std::path::Path::new(PAPER)).unwrap();
    assert_eq!(file, CrankConfig::default());
    let err = CrankConfig::from_toml_str("[crank]\nmass = 0.3\nlength = 0.05\n").unwrap_err();
    assert!(err.to_string().contains("inertia"), "{err}");
    let err = CrankConfig::from_toml_str("[sensor]\nnoise = 5.0\n").unwrap_err();
    assert!(err.to_string().contains("noise"), "{err}");
    let err = CrankConfig::from_toml_str("[contact]\nrestitution = 1.5\n").unwrap_err();
    assert!(err.to_string().contains("contact.restitution"), "{err}");
}

/// 10 s at the paper's step and adaptively (EDGEKF_LONG=1; time it in release for the figure).
#[test]
fn long_run_figures() {
    if std::env::var_os("EDGEKF_LONG").is_none() {
        eprintln!("skipped: set EDGEKF_LONG=1");
        return;
    }
    for (name, clearances) in [("ideal", [None; 3]), ("0.25 mm at A", [Some(0.25e-3), None, None])] {
        let m = mech(clearances);
        for integ in [SE, Integrator::Adaptive { tolerance: 1e-8, max_step: 1e-3 }] {
            let t = Instant::now();
            let r = run(&m, 10.0, integ);
            let e0 = r.truth_energy[0];
            eprintln!(
                "{name}, 10 s, {integ:?}: wall {:.2} s, {} evaluations, {} impacts, energy end {:.6} J (E₀ {e0:.6}), \
                 balance error {:.2e} J, largest climb {:.2e} J, constraint residual {:.1e} m",
                t.elapsed().as_secs_f64(),
                r.stats.evaluations,
                r.stats.impacts[0],
                r.truth_energy.last().unwrap(),
                r.energy_balance_error(),
                r.energy_rise(),
                r.max_constraint_residual
            );
        }
    }
}
