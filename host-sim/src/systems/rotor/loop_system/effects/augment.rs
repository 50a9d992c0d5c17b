//! The augmented continuous model: the reduced rotor with the effects' states and rows
//! composed onto its public matrices, one family at a time ([`sensor`](super::sensor),
//! [`force`](super::force), [`mode`](super::mode); a parameter or a point mass changes the
//! configuration the rotor is reduced from, [`parameter`](super::parameter)).

use super::force::{self, Flexibility, Force};
use super::{mode, sensor, Effect, EffectTuning, Parts};
use crate::systems::rotor::estimate::ReducedRotor;
use crate::systems::rotor::RotorModel;
use anyhow::{bail, Result};
use nalgebra::DMatrix;

/// The base model plus effects: `ẋ = A x + w`, `y = C x + v`, and the virtual outputs.
#[derive(Debug, Clone)]
pub struct AugmentedModel {
    /// Continuous system matrix.
    pub a: DMatrix<f64>,
    /// Continuous process-noise density.
    pub qc: DMatrix<f64>,
    /// Sensor rows.
    pub c: DMatrix<f64>,
    /// Measurement-noise covariance per sample.
    pub r: DMatrix<f64>,
    /// Initial covariance.
    pub p0: DMatrix<f64>,
    /// Displacement rows of every node (node-major `n0_x, n0_y, …`), effects included.
    pub displacement: DMatrix<f64>,
    /// The effects with their scalar, and the index of their first state.
    pub effects: Vec<(Effect, f64, usize)>,
    /// The unbalance forces' states (`F_x`, `F_y` per unbalance node, N).
    pub unbalance: std::ops::Range<usize>,
}

/// Builds `red` plus `effects`, each with its scalar (ignored by effects without one; a
/// `Parameter` effect must already be applied to the configuration `red` was reduced from).
///
/// `red`, `model` and `flex` describe the same configuration. A new force reaches a probe through
/// the displacement rows and an accelerometer through its low-pass input (the acceleration of
/// the measured DOF, modal part and static correction alike).
pub fn augment(
    red: &ReducedRotor,
    model: &RotorModel,
    flex: &Flexibility,
    effects: &[(Effect, f64)],
    tuning: &EffectTuning,
) -> Result<AugmentedModel> {
    let n0 = red.states();
    let m = red.c.nrows();
    let extra: usize = effects.iter().map(|(e, _)| e.states(m)).sum();
    let ns = n0 + extra;
    let mut p = Parts::grown(red, ns);
    let mut next = n0;
    let mut placed = Vec::new();
    for &(e, theta) in effects {
        let s = next;
        match e {
            Effect::SensorBias { channel } => sensor::bias(&mut p, s, channel, tuning)?,
            Effect::SensorScale { channel } | Effect::SensorDelay { channel } | Effect::SensorLag { channel } => {
                sensor::channel_ok(&p, channel)?
            }
            Effect::HarmonicForce { node, order } => {
                let turning = Some(order as f64 * red.speed);
                let f = Force { node, first: s, turning, psd: tuning.force_psd, std: tuning.force_std };
                force::place(&mut p, red, model, flex, f)?
            }
            Effect::UnknownInput { node } => {
                let f = Force { node, first: s, turning: None, psd: tuning.unknown_psd, std: tuning.force_std };
                force::place(&mut p, red, model, flex, f)?
            }
            Effect::BearingDefect { .. } => {
                bail!("a bearing defect is fitted on the innovations' envelope, not in the rotor's filter")
            }
            Effect::ExtraMode { .. } => mode::extra(&mut p, red, s, theta, tuning)?,
            Effect::Parameter(_) | Effect::PointMass { .. } => {}
        }
        placed.push((e, theta, s));
        next += e.states(m);
    }
    accelerometers(&mut p, red, n0..ns);
    // Output-side effects last, over the complete dynamics.
    sensor::outputs(&mut p, effects)?;
    sensor::lags(&mut p, &placed)?;
    let u0 = 2 * red.frequencies_hz.len();
    let unbalance = u0..u0 + 2 * red.force_nodes.len();
    let Parts { a, qc, p0, c, displacement } = p;
    Ok(AugmentedModel { a, qc, c, r: red.r.clone(), p0, displacement, effects: placed, unbalance })
}

/// Accelerometers: the new states' share of each measured DOF's acceleration (the
/// displacement row twice through the dynamics) enters the low-pass input (or the output).
fn accelerometers(p: &mut Parts, red: &ReducedRotor, new: std::ops::Range<usize>) {
    let accel: Vec<(usize, Option<usize>, f64, DMatrix<f64>)> = red
        .accel_inputs
        .iter()
        .map(|i| (i.channel, i.state, i.gain, p.displacement.rows(i.row, 1) * &p.a * &p.a))
        .collect();
    for (channel, state, gain, row) in accel {
        for j in new.clone() {
            match state {
                Some(y) => p.a[(y, j)] += gain * row[(0, j)],
                None => p.c[(channel, j)] += gain * row[(0, j)],
            }
        }
    }
}

/// How a force at `node` at `order ×` the running speed enters `red` (augmented as
/// [`augment`] would): its columns in the base model's dynamics (`B`, `red.states() × 2`,
/// for `F_x`, `F_y`) and in the sensor rows (`D`, channels × 2). What
/// [`locate`](crate::diagnostics::locate) ranks a force's or a mass's places with.
pub fn force_columns(
    red: &ReducedRotor,
    model: &RotorModel,
    flex: &Flexibility,
    node: usize,
    order: u32,
) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
    let m = augment(red, model, flex, &[(Effect::HarmonicForce { node, order }, 0.0)], &EffectTuning::default())?;
    let n0 = red.states();
    Ok((m.a.view((0, n0), (n0, 2)).clone_owned(), m.c.view((0, n0), (m.c.nrows(), 2)).clone_owned()))
}
