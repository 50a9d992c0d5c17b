use super::*;

const OMEGA: f64 = 87.96;

fn demo_mode() -> ModeConfig {
    ModeConfig::default()
}

/// Closed-form free decay from `(x0, 0)`.
fn free_decay(m: &ModeConfig, x0: f64, t: f64) -> (f64, f64) {
    let wn = m.omega_n();
    let z = m.damping_ratio;
    let wd = wn * (1.0 - z * z).sqrt();
    let e = (-z * wn * t).exp();
    let (s, c) = (wd * t).sin_cos();
    let x = e * x0 * (c + z * wn / wd * s);
    let v = -e * x0 * wn * wn / wd * s;
    (x, v)
}

#[test]
fn steady_state_matches_closed_form_amplitude_and_phase() {
    let m = demo_mode();
    let osc = Oscillator::new(m, ForceConfig::constant(OMEGA, 5.0, 30.0));
    let run = osc.simulate(0.0, 0.0, 1000.0, 12_000, DEFAULT_SUBSTEPS);
    let amp = m.steady_state_amplitude(5.0, OMEGA);
    let lag = m.steady_state_lag(OMEGA);
    // The transient decays as e^{−ζωn t} = e^{−2.51 t}: negligible (< 1e-9) after 9 s.
    for s in &run[9_000..] {
        let want_x = amp * (OMEGA * s.t + 30f64.to_radians() - lag).cos();
        let want_v = -amp * OMEGA * (OMEGA * s.t + 30f64.to_radians() - lag).sin();
        assert!((s.x - want_x).abs() < 1e-8 * amp, "t {} x {} want {}", s.t, s.x, want_x);
        assert!((s.v - want_v).abs() < 1e-8 * amp * OMEGA);
        assert!((s.a + OMEGA * OMEGA * want_x).abs() < 1e-7 * amp * OMEGA * OMEGA);
    }
    // The number the project cares about: 5 N at 14 Hz on this mode moves it 0.62 mm.
    assert!((amp - 6.1985e-4).abs() < 1e-8);
}

#[test]
fn resonance_amplification_is_one_over_two_zeta() {
    let m = demo_mode();
    let wn = m.omega_n();
    let osc = Oscillator::new(m, ForceConfig::constant(wn, 1.0, 0.0));
    // At resonance the transient decays equally slowly, so run long: 25 s.
    let run = osc.simulate(0.0, 0.0, 1000.0, 25_000, DEFAULT_SUBSTEPS);
    let s = run.last().unwrap();
    let amp = (s.x.powi(2) + (s.v / wn).powi(2)).sqrt();
    let static_defl = 1.0 / m.stiffness();
    assert!((amp / static_defl - 1.0 / (2.0 * m.damping_ratio)).abs() < 1e-6 * 25.0, "{}", amp / static_defl);
}

#[test]
fn free_decay_matches_closed_form() {
    let m = demo_mode();
    let osc = Oscillator::new(m, ForceConfig::constant(OMEGA, 0.0, 0.0));
    let run = osc.simulate(1e-3, 0.0, 1000.0, 3000, DEFAULT_SUBSTEPS);
    let mut worst: f64 = 0.0;
    for s in &run {
        let (x, v) = free_decay(&m, 1e-3, s.t);
        worst = worst.max((s.x - x).abs());
        assert!((s.v - v).abs() < 1e-9 * m.omega_n() * 1e-3);
    }
    assert!(worst < 1e-12, "worst displacement error {worst:e} m");
    // Sanity of the closed form itself: after 1 s the envelope is e^{−2.51} = 8.1 %.
    let env = (run[1000].x.powi(2) + (run[1000].v / m.omega_n()).powi(2)).sqrt();
    assert!((env / 1e-3 - (-m.damping_ratio * m.omega_n()).exp()).abs() < 2e-3, "{env}");
}

#[test]
fn rk4_converges_at_fourth_order_in_substeps() {
    let m = demo_mode();
    let osc = Oscillator::new(m, ForceConfig::constant(OMEGA, 0.0, 0.0));
    let err = |substeps: u32| {
        let run = osc.simulate(1e-3, 0.0, 1000.0, 1000, substeps);
        run.iter().map(|s| (s.x - free_decay(&m, 1e-3, s.t).0).abs()).fold(0.0, f64::max)
    };
    let (e1, e2, e4) = (err(1), err(2), err(4));
    // Halving h divides the error by 2⁴ = 16.
    for (coarse, fine) in [(e1, e2), (e2, e4)] {
        let ratio = coarse / fine;
        assert!((13.0..19.0).contains(&ratio), "error ratio {ratio} ({coarse:e} → {fine:e})");
    }
    assert!(err(DEFAULT_SUBSTEPS) < 1e-12);
}

#[test]
fn samples_lie_on_the_exact_time_grid() {
    let osc = Oscillator::new(demo_mode(), ForceConfig::default());
    let run = osc.simulate(0.0, 0.0, 1000.0, 12_000, 2);
    assert_eq!(run.len(), 12_000);
    assert_eq!(run[11_999].t, 11_999.0 / 1000.0);
    assert_eq!(run[0].force, 5.0 * 30f64.to_radians().cos());
}

#[test]
fn response_follows_the_force_step() {
    // After the 5 N → 3 N step at 6 s the steady amplitude follows by the ratio 3/5.
    let m = demo_mode();
    let osc = Oscillator::new(m, ForceConfig::default());
    let run = osc.simulate(0.0, 0.0, 1000.0, 14_000, DEFAULT_SUBSTEPS);
    let amp_at = |k: usize| (run[k].x.powi(2) + (run[k].v / OMEGA).powi(2)).sqrt();
    let full = m.steady_state_amplitude(5.0, OMEGA);
    assert!((amp_at(5_999) / full - 1.0).abs() < 1e-6);
    assert!((amp_at(13_999) / full - 0.6).abs() < 1e-6);
}
