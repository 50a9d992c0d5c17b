//! The boom's effect matrix ([`crate::matrix`]): the loop on luffing runs of the reference
//! simulator (its finite elements, not the reduced boom), one effect the configuration does
//! not declare per run. Each declared setting's size is a multiple (3× and 10×) of its
//! detection limit on a clean run (seed 1), the limit computed by the engine from the
//! reduced model ([`detection_limit`]); a setting the data cannot see at all is expected as
//! "cannot tell". A sideways mode seen by a leaning gyro stands for the effects the
//! configuration has no key for. Clean runs at five seeds must get nothing.

use super::config::{BoomConfig, SimLateral};
use super::estimate::{gyro_model, INCLINOMETER_NOISE};
use super::loop_system::{BoomSystem, Effect, MODEL_FLOOR};
use super::peaks::peak_errors;
use super::runs::Scenario;
use super::simulate::{simulate, static_record, SimOptions};
use crate::io::data::DataFile;
use crate::matrix::{clean_cases, outcome, setting_cases, without_truth, Expect, Expected, Outcome};
use crate::residual_loop::{EffectKind, LoopOptions, LoopReport};
use anyhow::{anyhow, Result};
use std::time::Instant;

/// Length of every run, s.
const DURATION: f64 = 120.0;
/// Seeds of the clean runs.
const CLEAN_SEEDS: [u64; 5] = [1, 2, 3, 4, 5];
/// Seed of the runs that carry an effect.
const EFFECT_SEED: u64 = 2;
/// Sizes, as multiples of the detection limit.
const MULTIPLES: [f64; 2] = [3.0, 10.0];

/// One case: what the simulator's boom has that the declared one lacks.
pub type Case = crate::matrix::Case<BoomConfig>;

/// The whole matrix for `declared`: clean runs, then each declared setting at 3× and 10× its
/// detection limit (or at the end of its range, expected as "cannot tell"), then the sideways
/// mode.
pub fn cases(declared: &BoomConfig) -> Result<Vec<Case>> {
    let mut out = clean_cases(declared, &CLEAN_SEEDS);
    let data = run(declared, 1)?.to_data_file();
    let sys = system(declared, declared, &data, 1)?;
    for s in setting_cases(&sys, &options(), &MULTIPLES)? {
        let mut truth = declared.clone();
        inject(&mut truth, s.effect, s.theta);
        let name = format!("{} = {} ({})", s.what, shown(s.value, s.factor), s.size);
        out.push(Case { name, truth, seed: EFFECT_SEED, expect: s.expect });
    }
    out.push(sideways(declared)?);
    Ok(out)
}

/// Runs `case` with `declared`: the loop on the run without its truth columns, scored against
/// them (the paper's peak error after the loop against the clean run's at the same seed).
pub fn run_case(case: &Case, declared: &BoomConfig, clean_error: f64) -> Result<Outcome> {
    let rec = run(&case.truth, case.seed)?;
    let full = rec.to_data_file();
    let bare = without_truth(&full);
    let started = Instant::now();
    let report = close(&case.truth, declared, &bare, case.seed)?;
    let seconds = started.elapsed().as_secs_f64();
    let after = peak_error(&full, &report.traces.after.outputs[0])?;
    Ok(outcome(case, &report, Some((after, clean_error)), seconds))
}

/// The clean run's peak error at `seed` with the declared boom (the model as declared on data
/// that matches it), %.
pub fn clean_error(declared: &BoomConfig, seed: u64) -> Result<f64> {
    let full = run(declared, seed)?.to_data_file();
    let report = close(declared, declared, &without_truth(&full), seed)?;
    peak_error(&full, &report.traces.before.outputs[0])
}

/// The loop's options on every run: the boom's model floor, as `edgekf loop boom` has it.
fn options() -> LoopOptions {
    LoopOptions { gain_floor: MODEL_FLOOR, ..LoopOptions::default() }
}

/// A luffing run of `truth` at `seed`.
fn run(truth: &BoomConfig, seed: u64) -> Result<super::simulate::BoomRecording> {
    simulate(truth, &SimOptions { scenario: Scenario::Luffing, duration: DURATION, seed }, &mut |_| {})
}

/// The declared boom's gyro model from `truth`'s 60 s static record at `seed`.
fn gyro(truth: &BoomConfig, declared: &BoomConfig, seed: u64) -> Result<edgekf::systems::boom::Ar2> {
    let (_, statics) = static_record(truth, 60.0, seed)?;
    gyro_model(declared, &statics)
}

/// The declared boom's loop system on `data`.
fn system<'a>(truth: &BoomConfig, declared: &BoomConfig, data: &'a DataFile, seed: u64) -> Result<BoomSystem<'a>> {
    BoomSystem::new(declared, data, gyro(truth, declared, seed)?, INCLINOMETER_NOISE, &options())
}

/// The loop closed on `data` with `declared`.
fn close(truth: &BoomConfig, declared: &BoomConfig, data: &DataFile, seed: u64) -> Result<LoopReport> {
    super::loop_system::close_loop(declared, data, gyro(truth, declared, seed)?, INCLINOMETER_NOISE, &options())
}

/// The paper's mean peak error of `estimate` against `full`'s truth, %.
fn peak_error(full: &DataFile, estimate: &[f64]) -> Result<f64> {
    let column = |n: &str| full.column(n).ok_or_else(|| anyhow!("the run has no `{n}`"));
    let p = peak_errors(&full.t, estimate, column("truth_tip_vibration")?, column("truth_root_rate")?);
    Ok(p.mean_pct)
}

/// Puts `effect` with scalar `theta` into the simulated boom, as the loop's model would take it.
fn inject(truth: &mut BoomConfig, effect: Effect, theta: f64) {
    let f = theta.exp();
    match effect {
        Effect::InclinometerLag => truth.inclinometer.lag = theta,
        Effect::InclinometerOffset => truth.inclinometer.offset += theta,
        Effect::GyroScale => truth.sim.gyro.scale = Some(truth.gyro.scale * f),
        Effect::GyroDrift => truth.sim.gyro.bias_drift = Some(theta),
        Effect::Stiffness => truth.section.iter_mut().for_each(|s| s.ei *= f),
        Effect::SectionStiffness(i) => {
            if let Some(s) = truth.section.get_mut(usize::from(i)) {
                s.ei *= f;
            }
        }
        Effect::PlatformMass => {
            truth.tip.mass *= f;
            truth.tip.rotary_inertia *= f;
        }
        Effect::ExtraMode { .. } => {}
    }
}

/// The boom's sideways bending read by a gyro leaning 0.05 rad toward it: expected as an
/// extra mode at the sideways boom's first frequency (its finite elements, EI ×2.5).
fn sideways(declared: &BoomConfig) -> Result<Case> {
    use super::{beam::assemble, modal::frequencies};
    let mut truth = declared.clone();
    truth.sim.lateral = Some(SimLateral { ei_factor: 2.5, gust: 1.0, misalignment: 0.05 });
    let mut side = declared.clone();
    side.section.iter_mut().for_each(|s| s.ei *= 2.5);
    let w = frequencies(&assemble(&side, 30.0), declared.boom.gravity, declared.runs.start_angle)?;
    let hz = w.first().ok_or_else(|| anyhow!("the sideways boom has no mode"))? / std::f64::consts::TAU;
    let expected = Expected {
        kind: EffectKind::ExtraMode,
        location: "gyro_rate".into(),
        parameter: None,
        value: hz,
        declared: 0.0,
        factor: false,
    };
    let name = format!("sideways mode at {hz:.3} Hz, gyro leaning 0.05 rad");
    Ok(Case { name, truth, seed: EFFECT_SEED, expect: Expect::Effect(expected) })
}

/// `×1.0312` for a factor, else the value to four significant digits.
fn shown(value: f64, factor: bool) -> String {
    if factor {
        format!("×{value:.4}")
    } else {
        format!("{value:.4e}")
    }
}
