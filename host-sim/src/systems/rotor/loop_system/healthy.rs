//! What a healthy machine of this kind shows that its declared model lacks, as parts of the
//! model ([`Healthy`]): the channels' offsets and noise levels, the housing's or foundation's
//! resonances the sensors see, and the synchronous forces a good machine has beside its
//! unbalance. Learned from a healthy recording ([`super::baseline`]), they are put into the base
//! model before the loop asks what changed, so the loop reports a change, not the machine.

use super::effects::mode::{oscillator, ModeSpec, ModeTarget};
use super::effects::Effect;
use crate::systems::rotor::estimate::ReducedRotor;
use anyhow::{bail, Result};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// A lightly damped mode outside the rotor model (a housing or foundation resonance), driven
/// by broadband forces, on every channel with its own level: two states per channel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Resonance {
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping: f64,
    /// Its response's standard deviation on each channel (in the filter's channel order), in
    /// the channel's unit.
    pub drive: Vec<f64>,
}

/// The healthy parts of a rotor's model, per channel in the filter's order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Healthy {
    /// Offset of each channel, taken out of the data before the filter (empty: none).
    pub offsets: Vec<f64>,
    /// Measurement-noise standard deviation per sample of each channel (`None`: the
    /// configuration's).
    pub noise_std: Vec<Option<f64>>,
    /// Resonances outside the rotor model.
    pub resonances: Vec<Resonance>,
    /// Synchronous forces (harmonic forces at orders) every run carries, their states estimated.
    pub forces: Vec<Effect>,
}

impl Healthy {
    /// Offset of channel `ch` (0 when none was learned).
    pub fn offset(&self, ch: usize) -> f64 {
        self.offsets.get(ch).copied().unwrap_or(0.0)
    }

    /// `red` with the noise levels and the resonances in place: each resonance adds
    /// `2 × channels` states after the rotor's, read directly on its channel.
    ///
    /// ```
    /// # use edgekf_sim::systems::rotor::{RotorConfig, RotorModel};
    /// # use edgekf_sim::systems::rotor::estimate::{reduce, Tuning};
    /// use edgekf_sim::systems::rotor::loop_system::healthy::{Healthy, Resonance};
    /// # let cfg = RotorConfig::from_toml_str(include_str!("../../../../configs/rotor_cwru.toml")).unwrap();
    /// # let model = RotorModel::from_config(&cfg).unwrap();
    /// let red = reduce(&model, cfg.operation.speed, &Tuning::default()).unwrap();
    /// let housing = Resonance { frequency_hz: 3000.0, damping: 0.04, drive: vec![0.3, 0.05] };
    /// let h = Healthy { noise_std: vec![Some(0.02), None], resonances: vec![housing], ..Healthy::default() };
    /// let out = h.apply(&red).unwrap();
    /// assert_eq!(out.states(), red.states() + 4);
    /// assert!((out.r[(0, 0)] - 4e-4).abs() < 1e-15 && out.r[(1, 1)] == red.r[(1, 1)]);
    /// assert_eq!(out.c[(1, red.states() + 2)], 1.0);
    /// ```
    pub fn apply(&self, red: &ReducedRotor) -> Result<ReducedRotor> {
        let m = red.c.nrows();
        let mut out = red.clone();
        for (ch, std) in self.noise_std.iter().enumerate() {
            if let Some(s) = *std {
                if ch >= m || !(s.is_finite() && s > 0.0) {
                    bail!("a healthy noise level of {s} for channel #{ch} of {m}");
                }
                out.r[(ch, ch)] = s * s;
            }
        }
        if self.resonances.is_empty() {
            return Ok(out);
        }
        let n0 = red.states();
        let ns = n0 + 2 * m * self.resonances.len();
        let grow = |mat: &DMatrix<f64>, rows: usize| {
            let mut g = DMatrix::<f64>::zeros(rows, ns);
            g.view_mut((0, 0), (mat.nrows(), mat.ncols())).copy_from(mat);
            g
        };
        out.a = grow(&red.a, ns);
        out.qc = grow(&red.qc, ns);
        out.p0 = grow(&red.p0, ns);
        out.c = grow(&red.c, m);
        out.displacement = grow(&red.displacement, red.displacement.nrows());
        out.force = grow(&red.force, red.force.nrows());
        for (i, res) in self.resonances.iter().enumerate() {
            if res.drive.len() != m {
                bail!(
                    "a resonance at {} Hz with drive levels for {} channels, not {m}",
                    res.frequency_hz,
                    res.drive.len()
                );
            }
            let s = n0 + 2 * m * i;
            for (ch, &level) in res.drive.iter().enumerate() {
                let t = ModeTarget { a: &mut out.a, qc: &mut out.qc, c: &mut out.c, p0: &mut out.p0 };
                oscillator(t, s + 2 * ch, ch, ModeSpec { hz: res.frequency_hz, zeta: res.damping, level })?;
            }
        }
        Ok(out)
    }
}
