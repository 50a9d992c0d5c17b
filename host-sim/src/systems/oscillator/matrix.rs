//! The oscillator's effect matrix ([`crate::matrix`]): the loop on 4 s runs of the reference
//! simulator (RK4 sub-steps of the full mode and force, the ADXL355's noise, low-pass and
//! quantisation), one effect the scenario does not declare per run. The mode's frequency and
//! damping are sized at 3× and 10× their detection limits on a clean run (seed 1), computed by
//! the engine from the loop's model; an accelerometer offset and a second harmonic of the force
//! stand for the effects the loop's filter carries as states. Clean runs at five seeds must
//! get nothing. The channel's scale is a candidate of the loop but not a setting of the
//! simulator's accelerometer, so it has no case.

use super::loop_system::{close_loop, Effect, OscillatorSystem};
use super::scenario::Scenario;
use super::sim::ExtraHarmonic;
use crate::matrix::{clean_cases, outcome, rms_error, setting_cases, without_truth, Expect, Expected, Outcome};
use crate::residual_loop::{EffectKind, LoopOptions};
use anyhow::Result;
use std::time::Instant;

/// Seeds of the clean runs.
const CLEAN_SEEDS: [u64; 5] = [1, 2, 3, 4, 5];
/// Seed of the runs that carry an effect.
const EFFECT_SEED: u64 = 2;
/// Seconds of the filter's start left out of the errors.
const SETTLE_S: f64 = 1.0;
/// Sizes, as multiples of the detection limit.
const MULTIPLES: [f64; 2] = [3.0, 10.0];
/// Accelerometer offsets, m/s²: about 25× and 650× the standard error of the mean of the
/// sensor's noise over a run (4.9e-3 m/s² over 4 000 samples).
const BIASES: [f64; 2] = [0.002, 0.05];
/// Extra harmonics of the force: (order, amplitude in N).
const HARMONICS: [(f64, f64); 3] = [(2.0, 0.5), (2.0, 0.1), (3.0, 0.3)];

/// One case: the simulated scenario (run at the case's seed) and what the loop should say.
pub type Case = crate::matrix::Case<Scenario>;

/// The whole matrix for `declared`: clean runs, the mode's settings at 3× and 10× their
/// limits, then accelerometer offsets and extra harmonics of the force, each at two sizes or places.
pub fn cases(declared: &Scenario) -> Result<Vec<Case>> {
    let mut out = clean_cases(declared, &CLEAN_SEEDS);
    let data = Scenario { seed: 1, ..declared.clone() }.simulate().to_data_file();
    let sys = OscillatorSystem::new(declared, &data, &options())?;
    let base = declared.clone();
    for s in setting_cases(&sys, &options(), &MULTIPLES)? {
        let mut truth = base.clone();
        match s.effect {
            Effect::Frequency => truth.mode.natural_freq_hz *= s.value,
            Effect::Damping => truth.mode.damping_ratio *= s.value,
            Effect::SensorScale | Effect::SensorBias | Effect::HarmonicForce { .. } => continue,
        }
        let name = format!("{} = ×{:.4} ({})", s.what, s.value, s.size);
        out.push(Case { name, truth, seed: EFFECT_SEED, expect: s.expect });
    }
    for bias in BIASES {
        let mut biased = base.clone();
        biased.sensor.bias_m_s2[0] = bias;
        let name = format!("sensor_bias at ax = {bias} m/s²");
        out.push(state_case(&name, biased, EffectKind::SensorBias, "ax", bias));
    }
    for (order, amplitude) in HARMONICS {
        let mut forced = base.clone();
        forced.force.extra.push(ExtraHarmonic::new(order, amplitude, 0.0));
        let name = format!("harmonic_force {order}× = {amplitude} N");
        out.push(state_case(&name, forced, EffectKind::HarmonicForce, "mode", amplitude));
    }
    Ok(out)
}

/// A case whose effect the loop's filter carries as states (no detection limit: its size is
/// stated).
fn state_case(name: &str, truth: Scenario, kind: EffectKind, location: &str, value: f64) -> Case {
    let expected = Expected { kind, location: location.into(), parameter: None, value, declared: 0.0, factor: false };
    Case { name: name.into(), truth, seed: EFFECT_SEED, expect: Expect::Effect(expected) }
}

/// Runs `case` with `declared`: the loop on the run without its truth columns, scored against
/// them (the displacement's RMS error after the loop against the clean run's).
pub fn run_case(case: &Case, declared: &Scenario, clean_error: f64) -> Result<Outcome> {
    let full = Scenario { seed: case.seed, ..case.truth.clone() }.simulate().to_data_file();
    let started = Instant::now();
    let report = close_loop(declared, &without_truth(&full), &options())?;
    let seconds = started.elapsed().as_secs_f64();
    let after = rms_error(&full, "truth_x", &report.traces.after.outputs[0], SETTLE_S)?;
    Ok(outcome(case, &report, Some((after, clean_error)), seconds))
}

/// The clean run's displacement RMS error at `seed` with the declared scenario.
pub fn clean_error(declared: &Scenario, seed: u64) -> Result<f64> {
    let full = Scenario { seed, ..declared.clone() }.simulate().to_data_file();
    let report = close_loop(declared, &without_truth(&full), &options())?;
    rms_error(&full, "truth_x", &report.traces.before.outputs[0], SETTLE_S)
}

/// The loop's options on every run, as `edgekf loop oscillator` has them.
fn options() -> LoopOptions {
    LoopOptions::default()
}
