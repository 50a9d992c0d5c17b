//! The accelerometer offset, from the loop's finding to the declared key and back: the
//! corrected configuration carries it, and the loop then adds nothing (issue #36's checks).

use super::*;
use crate::residual_loop::correction::corrected_config;

/// The declared model: the demo's oscillator with the force held at 5 N, 4 s.
const DECLARED: &str = "duration_s = 4.0\nseed = 2\n\n[force]\namplitude_n = 5.0\n";

fn quiet() -> LoopOptions {
    LoopOptions { progress: false, ..LoopOptions::default() }
}

/// `declared`'s recording at `seed` with a 0.05 m/s² offset on `ax` from the start.
fn offset_run(declared: &Scenario, seed: u64) -> DataFile {
    let mut truth = Scenario { seed, ..declared.clone() };
    truth.sensor.bias_m_s2[0] = 0.05;
    truth.simulate().to_data_file()
}

#[test]
fn an_offset_found_is_declared_and_then_adds_nothing() {
    let declared = Scenario::from_toml_str(DECLARED).unwrap();
    let data = offset_run(&declared, 2);
    let report = close_loop(&declared, &data, &quiet()).unwrap();
    assert_eq!(report.effects_added.len(), 1, "{:?}", report.effects_added);
    let edits = report.corrections[0].correction.edits();
    assert_eq!(edits.len(), 1);
    assert_eq!((edits[0].path.as_str(), edits[0].absent), ("filter.accel_offset_m_s2", Some(0.0)));
    let text = corrected_config(DECLARED, &report.corrections, "out/report.json").unwrap();
    assert!(text.contains("out/report.json"), "{text}");
    let corrected = Scenario::from_toml_str(&text).unwrap();
    let found = corrected.filter.accel_offset_m_s2;
    assert!((found - 0.05).abs() < 0.01, "declared offset {found}");
    // The same data, and a fresh seed with the offset throughout: nothing left to add.
    for (what, data) in [("same run", data), ("fresh seed", offset_run(&declared, 3))] {
        let again = close_loop(&corrected, &data, &quiet()).unwrap();
        assert!(again.effects_added.is_empty(), "{what}: {:?}", again.effects_added);
    }
}

#[test]
fn the_declared_offset_is_taken_off_the_channel() {
    let declared = Scenario::from_toml_str(DECLARED).unwrap();
    let mut with = declared.clone();
    with.filter.accel_offset_m_s2 = 0.05;
    let data = offset_run(&declared, 2);
    let (a, b) = (
        OscillatorSystem::new(&declared, &data, &quiet()).unwrap(),
        OscillatorSystem::new(&with, &data, &quiet()).unwrap(),
    );
    assert!(a.ax.iter().zip(&b.ax).all(|(x, y)| (x - y - 0.05).abs() < 1e-12));
}
