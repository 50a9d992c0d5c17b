//! The rotor's effect matrix ([`crate::matrix`]): the loop on 3 s runs of the paper rotor's
//! reference simulator (the full finite-element rotor, Newmark steps), one effect the
//! configuration does not declare per run. Each declared component parameter (disk masses,
//! the shaft's modulus and density, the bearings' stiffness and damping) is sized at 3× and
//! 10× its detection limit on a clean run (seed 1), the limit computed by the engine from the
//! loop's reduced model ([`crate::residual_loop::limits::detection_limit`]); a parameter the
//! probes cannot see at all is expected as "cannot tell". Sensor offsets, gains and delays,
//! forces at harmonics of the running speed and a point mass stand for the effects the filter
//! carries as states or the configuration lacks a key for, each at two places and sizes
//! stated below. Clean runs at five seeds must get nothing.

use super::loop_system::effects::Effect;
use super::loop_system::inject::{inject_bias, inject_delay, inject_harmonic_force, inject_scale, HarmonicForce};
use super::loop_system::{close_loop, system_for, RotorLoopOptions};
use super::{config::PointMassConfig, RotorConfig, RotorModel, SimOptions};
use crate::io::data::DataFile;
use crate::matrix::{clean_cases, outcome, rms_error, setting_cases, without_truth, Expect, Expected, Outcome};
use crate::residual_loop::{EffectKind, LoopOptions, LoopReport};
use anyhow::Result;
use std::time::Instant;

/// Length of every run, s.
const DURATION: f64 = 3.0;
/// Seeds of the clean runs.
const CLEAN_SEEDS: [u64; 5] = [1, 2, 3, 4, 5];
/// Seed of the runs that carry an effect.
const EFFECT_SEED: u64 = 2;
/// Sizes, as multiples of the detection limit.
const MULTIPLES: [f64; 2] = [3.0, 10.0];
/// Seconds of the filter's start left out of the errors.
const SETTLE_S: f64 = 0.5;

/// What the simulated machine has that the declared one lacks: its configuration (a
/// component parameter changed, a mass added) and what the sensors add to its output.
#[derive(Debug, Clone)]
pub struct Truth {
    /// The simulated rotor.
    pub config: RotorConfig,
    /// Put on its recording after the simulation.
    pub on_data: Vec<OnData>,
}

/// An effect put on a simulated recording.
#[derive(Debug, Clone)]
pub enum OnData {
    /// An offset on a channel, in its unit.
    Bias(&'static str, f64),
    /// A channel's gain.
    Scale(&'static str, f64),
    /// A channel's delay, s.
    Delay(&'static str, f64),
    /// A force at a harmonic of the running speed (its steady response added).
    Force(HarmonicForce),
}

/// One case: the simulated machine and what the loop should say.
pub type Case = crate::matrix::Case<Truth>;

/// The paper rotor as `host-sim/configs/rotor_paper.toml` declares it.
pub fn declared() -> Result<RotorModel> {
    super::loop_system::cases::Case::declared()
}

/// The whole matrix for `declared`: clean runs, each component parameter at 3× and 10× its
/// detection limit (or at a fifth of its range, expected as "cannot tell"), then sensor
/// effects, forces and a point mass at two places each.
pub fn cases(declared: &RotorModel) -> Result<Vec<Case>> {
    let clean = Truth { config: declared.config().clone(), on_data: Vec::new() };
    let mut out = clean_cases(&clean, &CLEAN_SEEDS);
    let data = simulate(&clean, 1)?;
    let sys = system_for(declared, &data, &options(), &RotorLoopOptions::default())?;
    for s in setting_cases(&sys, &options(), &MULTIPLES)? {
        let Effect::Parameter(p) = s.effect else { continue };
        let mut truth = clean.clone();
        p.apply(&mut truth.config, s.value)?;
        let name = format!("{} = ×{:.4} ({})", s.what, s.value, s.size);
        out.push(Case { name, truth, seed: EFFECT_SEED, expect: s.expect });
    }
    out.extend(stated_cases(&clean));
    Ok(out)
}

/// Sensor effects, forces and point masses at stated sizes, two places each.
fn stated_cases(clean: &Truth) -> Vec<Case> {
    let on = |what: OnData| Truth { config: clean.config.clone(), on_data: vec![what] };
    let force = |node, order, amplitude| OnData::Force(HarmonicForce { node, order, amplitude, phase_rad: 0.3 });
    let mut out = vec![
        stated("sensor_bias at n5_x = 20 µm", on(OnData::Bias("n5_x", 20e-6)), EffectKind::SensorBias, "n5_x", 20e-6),
        stated(
            "sensor_bias at n32_y = −5 µm",
            on(OnData::Bias("n32_y", -5e-6)),
            EffectKind::SensorBias,
            "n32_y",
            -5e-6,
        ),
        stated(
            "sensor_scale at n32_y = ×1.05",
            on(OnData::Scale("n32_y", 1.05)),
            EffectKind::SensorScale,
            "n32_y",
            1.05,
        ),
        stated("sensor_scale at n5_x = ×0.97", on(OnData::Scale("n5_x", 0.97)), EffectKind::SensorScale, "n5_x", 0.97),
        stated(
            "sensor_delay at n32_x = 2 ms",
            on(OnData::Delay("n32_x", 2e-3)),
            EffectKind::SensorDelay,
            "n32_x",
            2e-3,
        ),
        stated("sensor_delay at n5_y = 1 ms", on(OnData::Delay("n5_y", 1e-3)), EffectKind::SensorDelay, "n5_y", 1e-3),
        stated(
            "harmonic_force 2× at node 12 = 1.5 N",
            on(force(12, 2.0, 1.5)),
            EffectKind::HarmonicForce,
            "node 12",
            1.5,
        ),
        stated(
            "harmonic_force 3× at node 23 = 0.5 N",
            on(force(23, 3.0, 0.5)),
            EffectKind::HarmonicForce,
            "node 23",
            0.5,
        ),
        stated(
            "harmonic_force 2× at node 17 = 1.5 N",
            on(force(17, 2.0, 1.5)),
            EffectKind::HarmonicForce,
            "node 17",
            1.5,
        ),
    ];
    for (node, mass) in [(18, 0.8), (30, 0.3)] {
        let mut truth = clean.clone();
        truth.config.masses.push(PointMassConfig { node, mass, ip: 0.0, id: 0.0 });
        let name = format!("point_mass at node {node} = {mass} kg");
        out.push(stated(&name, truth, EffectKind::PointMass, &format!("node {node}"), mass));
    }
    out
}

/// A case of stated size (no detection limit: the effect is carried as states or has no
/// declared value).
fn stated(name: &str, truth: Truth, kind: EffectKind, location: &str, value: f64) -> Case {
    let factor = kind == EffectKind::SensorScale;
    let declared = if factor { 1.0 } else { 0.0 };
    let expected = Expected { kind, location: location.into(), parameter: None, value, declared, factor };
    Case { name: name.into(), truth, seed: EFFECT_SEED, expect: Expect::Effect(expected) }
}

/// `truth` simulated at `seed`, with its effects on the data.
pub fn simulate(truth: &Truth, seed: u64) -> Result<DataFile> {
    let model = RotorModel::from_config(&truth.config)?;
    let mut d = model.simulate(&SimOptions { duration: DURATION, seed, ..SimOptions::default() })?.to_data_file();
    for what in &truth.on_data {
        match what {
            OnData::Bias(ch, v) => inject_bias(&mut d, ch, *v)?,
            OnData::Scale(ch, f) => inject_scale(&mut d, ch, *f, None)?,
            OnData::Delay(ch, tau) => inject_delay(&mut d, ch, *tau)?,
            OnData::Force(f) => inject_harmonic_force(&mut d, &model, truth.config.operation.speed, f)?,
        }
    }
    Ok(d)
}

/// Runs `case` with `declared`: the loop on the run without its truth columns, scored against
/// them (the disk nodes' largest RMS error after the loop against the clean run's).
pub fn run_case(case: &Case, declared: &RotorModel, clean_error: f64) -> Result<Outcome> {
    let full = simulate(&case.truth, case.seed)?;
    let started = Instant::now();
    let report = close_loop(declared, &without_truth(&full), &options(), &RotorLoopOptions::default())?;
    let seconds = started.elapsed().as_secs_f64();
    let after = disk_error(&full, &report, true)?;
    Ok(outcome(case, &report, Some((after, clean_error)), seconds))
}

/// The clean run's disk-node error at `seed` with the declared rotor.
pub fn clean_error(declared: &RotorModel, seed: u64) -> Result<f64> {
    let clean = Truth { config: declared.config().clone(), on_data: Vec::new() };
    let full = simulate(&clean, seed)?;
    let report = close_loop(declared, &without_truth(&full), &options(), &RotorLoopOptions::default())?;
    disk_error(&full, &report, false)
}

/// The largest RMS error over the report's virtual rows (the disk nodes), against `full`'s
/// truth, of the final model's run (`after`) or the base model's.
fn disk_error(full: &DataFile, report: &LoopReport, after: bool) -> Result<f64> {
    let run = if after { &report.traces.after } else { &report.traces.before };
    let mut worst: f64 = 0.0;
    for (row, estimate) in report.traces.rows.iter().zip(&run.outputs) {
        worst = worst.max(rms_error(full, &format!("truth_{}", row.name), estimate, SETTLE_S)?);
    }
    Ok(worst)
}

/// The loop's options on every run, as `edgekf loop rotor` has them.
fn options() -> LoopOptions {
    LoopOptions::default()
}
