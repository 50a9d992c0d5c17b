//! The mode family: a lightly damped mode the model lacks (a housing or foundation resonance),
//! two states per channel oscillating at its frequency, driven by white noise; the same
//! oscillator carries a baseline's resonances ([`healthy`](super::super::healthy)).

use super::EffectTuning;
use super::Parts;
use crate::systems::rotor::estimate::ReducedRotor;
use anyhow::{bail, Result};
use nalgebra::DMatrix;
use std::f64::consts::TAU;

/// An extra mode at `hz` in states from `s` (two per channel), each channel's response at
/// `tuning.mode_std` times its noise.
pub(super) fn extra(p: &mut Parts, red: &ReducedRotor, s: usize, hz: f64, tuning: &EffectTuning) -> Result<()> {
    if !(hz.is_finite() && hz > 0.0) {
        bail!("an extra mode needs a positive frequency, not {hz}");
    }
    for ch in 0..p.c.nrows() {
        let level = tuning.mode_std * red.r[(ch, ch)].sqrt();
        let t = ModeTarget { a: &mut p.a, qc: &mut p.qc, c: &mut p.c, p0: &mut p.p0 };
        oscillator(t, s + 2 * ch, ch, ModeSpec { hz, zeta: tuning.mode_damping, level })?;
    }
    Ok(())
}

/// A mode outside the rotor model as it enters the matrices: frequency, damping and the
/// standard deviation of its response on the channel that reads it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::systems::rotor::loop_system) struct ModeSpec {
    pub hz: f64,
    pub zeta: f64,
    pub level: f64,
}

/// The matrices a mode is written into.
pub(in crate::systems::rotor::loop_system) struct ModeTarget<'a> {
    pub a: &'a mut DMatrix<f64>,
    pub qc: &'a mut DMatrix<f64>,
    pub c: &'a mut DMatrix<f64>,
    pub p0: &'a mut DMatrix<f64>,
}

/// The mode `spec` in states `q, q + 1`, read on channel `ch`, driven by white noise so that
/// its response's standard deviation is `spec.level`.
pub(in crate::systems::rotor::loop_system) fn oscillator(
    t: ModeTarget<'_>,
    q: usize,
    ch: usize,
    spec: ModeSpec,
) -> Result<()> {
    let ModeSpec { hz, zeta, level } = spec;
    if !(hz.is_finite() && hz > 0.0 && zeta.is_finite() && zeta > 0.0 && level.is_finite() && level >= 0.0) {
        bail!("a resonance needs a positive frequency and damping and a level ≥ 0, not {hz} Hz, ζ {zeta}, {level}");
    }
    let (w, v) = (TAU * hz, q + 1);
    t.a[(q, v)] = 1.0;
    t.a[(v, q)] = -w * w;
    t.a[(v, v)] = -2.0 * zeta * w;
    t.c[(ch, q)] = 1.0;
    // White acceleration of density psd gives a stationary displacement variance psd / (4 ζ ω³).
    let var = level * level;
    t.qc[(v, v)] = var * 4.0 * zeta * w.powi(3);
    t.p0[(q, q)] = var;
    t.p0[(v, v)] = var * w * w;
    Ok(())
}
