//! The oscillator through the residual loop: the demo's mode and ADXL355 with something the
//! scenario does not declare, and `edgekf loop oscillator` on the declared scenario.

use edgekf_sim::residual_loop::{LoopOptions, LoopReport};
use edgekf_sim::systems::oscillator::loop_system::close_loop;
use edgekf_sim::systems::oscillator::scenario::Scenario;

/// 4 s of the demo scenario (5 N at 87.96 rad/s on a 20 Hz mode, ADXL355 at 1 kHz).
fn declared() -> Scenario {
    Scenario { duration_s: 4.0, ..Scenario::default() }
}

fn close(actual: &Scenario) -> LoopReport {
    let data = actual.simulate().to_data_file();
    let options = LoopOptions { screen_parameters: false, ..LoopOptions::default() };
    let r = close_loop(&declared(), &data, &options).unwrap();
    eprintln!("{}", edgekf_sim::report::text::summary_table(&r));
    r
}

#[test]
fn the_loop_finds_an_undeclared_accelerometer_bias() {
    let mut actual = declared();
    actual.sensor.bias_m_s2[0] = 0.05;
    let r = close(&actual);
    assert_eq!(r.effects_added.len(), 1, "{:?}", r.effects_added);
    let e = &r.effects_added[0];
    assert_eq!((e.kind.as_str(), e.location.as_str(), e.unit.as_str()), ("sensor_bias", "ax", "m/s^2"));
    assert!((e.value / 0.05 - 1.0).abs() < 0.02, "{}", e.value);
    // The bias took the NIS from 3.3 to about its consistent 1 (the ADXL355's low-pass colours
    // its noise, which this white-noise model leaves to `unexplained`).
    assert!(
        r.before.nis_mean > 3.0 && (r.after.nis_mean - 1.0).abs() < 0.2,
        "{} → {}",
        r.before.nis_mean,
        r.after.nis_mean
    );
}

#[test]
fn the_loop_finds_a_wrong_natural_frequency() {
    let mut actual = declared();
    actual.mode.natural_freq_hz = 20.0 / 1.02;
    let r = close(&actual);
    assert_eq!(r.effects_added.len(), 1, "{:?}", r.effects_added);
    let e = &r.effects_added[0];
    assert_eq!(
        (e.kind.as_str(), e.location.as_str(), e.detail.parameter.as_deref()),
        ("parameter", "mode", Some("frequency"))
    );
    assert!((e.value * 1.02 - 1.0).abs() < 0.002, "{}", e.value);
    let (b, a) = (r.before.error_rms["x"], r.after.error_rms["x"]);
    assert!(a < 0.5 * b, "displacement error {b:e} → {a:e}");
}

#[test]
fn the_loop_adds_nothing_to_clean_oscillator_data() {
    for seed in [1, 2, 3] {
        let r = close(&Scenario { seed, ..declared() });
        assert!(r.effects_added.is_empty(), "seed {seed}: {:?}", r.effects_added);
    }
}
