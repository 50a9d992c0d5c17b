//! The vehicle's effect matrix ([`crate::matrix`]): the loop on healthy flights of the
//! reference simulator (its 6-DOF hull, not the node's reduced dynamics), one effect the
//! configuration does not declare per flight. Each declared setting (the mass, the surge
//! drag, each DVL axis's offset) is sized at 3× and 10× its detection limit on a clean flight
//! (seed 1), the limit computed by the engine from the node's model ([`detection_limit`]); a
//! setting the data cannot see at all is expected as "cannot tell". Clean flights at five
//! seeds must get nothing.

use super::config::UuvConfig;
use super::loop_system::effect::{Effect, Parameter};
use super::loop_system::{close_loop, UuvSystem, MODEL_FLOOR};
use super::scenario::Scenario;
use super::simulate::{simulate, SimOptions};
use crate::io::data::DataFile;
use crate::matrix::{clean_cases, outcome, rms_error, setting_cases, without_truth, Outcome};
use crate::residual_loop::tuning::tune;
use crate::residual_loop::{LoopOptions, LoopSystem};
use anyhow::Result;
use std::time::Instant;

/// Length of every flight, s.
const DURATION: f64 = 150.0;
/// Seeds of the clean flights.
const CLEAN_SEEDS: [u64; 5] = [1, 2, 3, 4, 5];
/// Seed of the flights that carry an effect.
const EFFECT_SEED: u64 = 2;
/// Seconds of the filter's start left out of the errors.
const SETTLE_S: f64 = 10.0;
/// Sizes, as multiples of the detection limit.
const MULTIPLES: [f64; 2] = [3.0, 10.0];

/// One case: what the simulated vehicle or its sensors have that the declared ones lack.
pub type Case = crate::matrix::Case<UuvConfig>;

/// The whole matrix for `declared`: clean flights, then each declared setting at 3× and 10×
/// its detection limit (or a fifth of the way to the end of its range, expected as "cannot
/// tell", where the data cannot see it).
pub fn cases(declared: &UuvConfig) -> Result<Vec<Case>> {
    let mut out = clean_cases(declared, &CLEAN_SEEDS);
    let data = flight(declared, 1)?;
    let options = options();
    let mut sys = UuvSystem::new(declared, &data, &options)?;
    // The limits on the model the loop would fit with: its noise set from the clean flight.
    let base = sys.run(&[])?.1;
    tune(&mut sys, &base, &options)?;
    for s in setting_cases(&sys, &options, &MULTIPLES)? {
        let mut truth = declared.clone();
        inject(&mut truth, s.effect, s.theta);
        let shown = if s.factor { format!("×{:.4}", s.value) } else { format!("{:.4} m/s", s.value) };
        let name = format!("{} = {shown} ({})", s.what, s.size);
        out.push(Case { name, truth, seed: EFFECT_SEED, expect: s.expect });
    }
    Ok(out)
}

/// Runs `case` with `declared`: the loop on the flight without its truth columns, scored
/// against them (the thrust gain's RMS error after the loop against the clean flight's).
pub fn run_case(case: &Case, declared: &UuvConfig, clean_error: f64) -> Result<Outcome> {
    let full = flight(&case.truth, case.seed)?;
    let started = Instant::now();
    let report = close_loop(declared, &without_truth(&full), &options())?;
    let seconds = started.elapsed().as_secs_f64();
    let after = rms_error(&full, "truth_k_t", &report.traces.after.outputs[0], SETTLE_S)?;
    Ok(outcome(case, &report, Some((after, clean_error)), seconds))
}

/// The clean flight's thrust-gain RMS error at `seed` with the declared model (before the
/// loop: the model as declared on data that match it).
pub fn clean_error(declared: &UuvConfig, seed: u64) -> Result<f64> {
    let full = flight(declared, seed)?;
    let report = close_loop(declared, &without_truth(&full), &options())?;
    rms_error(&full, "truth_k_t", &report.traces.before.outputs[0], SETTLE_S)
}

/// The loop's options on every flight, as `edgekf loop uuv` has them (the model floor is
/// `close_loop`'s).
fn options() -> LoopOptions {
    LoopOptions { gain_floor: MODEL_FLOOR, ..LoopOptions::default() }
}

/// A healthy flight of `truth` at `seed`.
fn flight(truth: &UuvConfig, seed: u64) -> Result<DataFile> {
    let options = SimOptions { scenario: Scenario::Healthy, duration: DURATION, seed };
    Ok(simulate(truth, &options, &mut |_| {})?.to_data_file())
}

/// Puts `effect` with scalar `theta` into the simulated vehicle, as the loop's model takes it.
fn inject(truth: &mut UuvConfig, effect: Effect, theta: f64) {
    match effect {
        Effect::Parameter(Parameter::Mass) => truth.vehicle.weight *= theta.exp(),
        Effect::Parameter(Parameter::SurgeDrag) => truth.vehicle.hydro.x_uu *= theta.exp(),
        Effect::DvlOffset(axis) => truth.sensors.dvl_offset[axis] = theta,
        Effect::Health(_) | Effect::Bias(_) | Effect::Current => {}
    }
}
