//! The oscillator as a system of the residual loop: the harmonic-force model of
//! `edgekf::systems::oscillator` (the scaled state `[ωn² x, ωn ẋ, p₁, p₂]`, the force a phasor
//! at the drive frequency) read from the accelerometer channel `ax`, with a small library of
//! what such a mode's model may lack:
//!
//! * `sensor_bias` on `ax` (a random-walk state), `sensor_scale` (a factor on `C`);
//! * `harmonic_force` at 2× or 3× the drive (another phasor): a second harmonic of the force;
//! * `parameter` of the `mode`: its natural frequency or damping ratio, as a factor.
//!
//! Any of them may begin mid-run (the engine then fits its onset): before it, the effect's
//! states are kept but decoupled, and the mode keeps its declared parameters.
//!
//! The filter is the engine's dense Kalman filter on this continuous model, so the loop and the
//! node's estimator share the model's matrices but not their code path.

use super::scenario::Scenario;
use crate::io::config_edit::{ConfigEdit, Op};
use crate::io::data::DataFile;
use crate::residual_loop::filter::{run_segments, Run, StateSpace};
use crate::residual_loop::onset::settled_mean;
use crate::residual_loop::optimize::ScalarRange;
use crate::residual_loop::signature::ReferenceLines;
use crate::residual_loop::tuning::TunableNoise;
use crate::residual_loop::{
    search, Applied, Channel, EffectDetail, EffectKind, EffectLabel, Fitting, LoopOptions, LoopReport, LoopSystem,
    RunSummary, Traces,
};
use crate::residual_loop::{Correction, Recording};
use anyhow::{anyhow, Result};
use edgekf::systems::oscillator::HarmonicForceParams;
use nalgebra::DMatrix;

/// The channel the model reads.
pub const CHANNEL: &str = "ax";

/// Random-walk density of a bias state, (m/s²)²/s: slow enough to stay a bias.
const BIAS_PSD: f64 = 1e-8;
/// Prior standard deviation of a bias, m/s².
const BIAS_STD: f64 = 1.0;

/// One augmentation of the oscillator's model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Effect {
    /// A constant offset on `ax`.
    SensorBias,
    /// `ax` reads `exp θ` times the acceleration.
    SensorScale,
    /// A force at `order` × the drive frequency.
    HarmonicForce {
        /// 2 or 3.
        order: u32,
    },
    /// The natural frequency is `exp θ` times the declared one.
    Frequency,
    /// The damping ratio is `exp θ` times the declared one.
    Damping,
}

/// The oscillator, its data and the loop's options.
pub struct OscillatorSystem<'a> {
    params: HarmonicForceParams,
    data: &'a DataFile,
    ax: Vec<f64>,
    channels: [Channel; 1],
    rows: [Channel; 1],
    options: LoopOptions,
    /// The declared `[filter] motion_psd`, which the engine may scale
    /// ([`LoopSystem::scale_noise`]).
    motion_psd: f64,
}

impl<'a> OscillatorSystem<'a> {
    /// The data as the engine reads them: the displacement's truth where simulated.
    fn recording(&self) -> Recording<'_> {
        let truth = vec![self.data.column("truth_x")];
        let (t, channels, rows, sample_rate) =
            (&self.data.t, &self.channels[..], &self.rows[..], self.params.sample_rate_hz);
        Recording { t, channels, rows, truth, sample_rate }
    }

    /// The model of `scenario` (mode, drive, sensor, filter tuning) on `data`'s `ax` channel,
    /// less the offset the filter declares (`[filter] accel_offset_m_s2`), as the node's is.
    pub fn new(scenario: &Scenario, data: &'a DataFile, options: &LoopOptions) -> Result<Self> {
        let column = data.column(CHANNEL).ok_or_else(|| anyhow!("the data file has no channel {CHANNEL}"))?;
        let offset = scenario.filter.accel_offset_m_s2;
        let ax = column.iter().map(|a| a - offset).collect();
        let params = scenario.estimator_params();
        Ok(Self {
            motion_psd: params.motion_psd,
            params,
            data,
            ax,
            channels: [Channel::new(CHANNEL, "m/s^2").shown_in(1e3, "mm/s²")],
            rows: [Channel::new("x", "m").shown_in(1e6, "µm")],
            options: *options,
        })
    }

    /// The declared parameters with the `parameter` effects in `active` applied.
    fn params_with(&self, effects: &[Applied<Effect>], active: &[bool]) -> HarmonicForceParams {
        let mut p = self.params;
        for (e, _) in effects.iter().zip(active).filter(|(_, on)| **on) {
            match e.effect {
                Effect::Frequency => p.natural_freq_hz *= e.theta.exp(),
                Effect::Damping => p.damping_ratio *= e.theta.exp(),
                _ => {}
            }
        }
        p
    }

    /// Where each effect's states start, and the total state count.
    fn layout(effects: &[Applied<Effect>]) -> (Vec<usize>, usize) {
        let mut n = 4;
        let mut starts = Vec::with_capacity(effects.len());
        for e in effects {
            starts.push(n);
            n += match e.effect {
                Effect::SensorBias => 1,
                Effect::HarmonicForce { .. } => 2,
                _ => 0,
            };
        }
        (starts, n)
    }

    /// The continuous model with the effects in `active` acting; the states of the others are
    /// kept but decoupled (no dynamics, no noise, not measured), so that they wait at their
    /// prior until their onset.
    fn model(&self, effects: &[Applied<Effect>], active: &[bool]) -> Matrices {
        let p = self.params_with(effects, active);
        let (starts, n) = Self::layout(effects);
        let (wn, w) = (p.omega_n(), p.drive_rad_s);
        let base = p.continuous_a();
        let row = p.measurement_row();
        let mut a = DMatrix::from_fn(n, n, |i, j| if i < 4 && j < 4 { base[(i, j)] } else { 0.0 });
        let mut c = DMatrix::from_fn(1, n, |_, j| if j < 4 { row[j] } else { 0.0 });
        let mut qc = DMatrix::zeros(n, n);
        qc[(1, 1)] = wn * wn * p.motion_psd;
        qc[(2, 2)] = p.force_psd;
        qc[(3, 3)] = p.force_psd;
        let mut p0 = DMatrix::zeros(n, n);
        p0[(0, 0)] = 1.0;
        p0[(1, 1)] = 1.0;
        p0[(2, 2)] = p.initial_force_std.powi(2);
        p0[(3, 3)] = p.initial_force_std.powi(2);
        let mut scale = 1.0;
        let mut bias_states = Vec::new();
        for ((e, &s), &on) in effects.iter().zip(&starts).zip(active) {
            match e.effect {
                Effect::SensorBias => {
                    p0[(s, s)] = BIAS_STD * BIAS_STD;
                    bias_states.push(s);
                    if on {
                        c[(0, s)] = 1.0;
                        qc[(s, s)] = BIAS_PSD;
                    }
                }
                Effect::HarmonicForce { order } => {
                    p0[(s, s)] = p.initial_force_std.powi(2);
                    p0[(s + 1, s + 1)] = p.initial_force_std.powi(2);
                    if on {
                        let wk = order as f64 * w;
                        (a[(s, s + 1)], a[(s + 1, s)]) = (-wk, wk);
                        // The phasor's real part drives the mode as p₁ does, and is measured
                        // with it.
                        a[(1, s)] = wn;
                        c[(0, s)] = 1.0;
                        qc[(s, s)] = p.force_psd;
                        qc[(s + 1, s + 1)] = p.force_psd;
                    }
                }
                Effect::SensorScale if on => scale *= e.theta.exp(),
                Effect::SensorScale | Effect::Frequency | Effect::Damping => {}
            }
        }
        // The bias is added after the scale: it is the sensor's offset, not the motion's.
        for j in (0..n).filter(|j| !bias_states.contains(j)) {
            c[(0, j)] *= scale;
        }
        // The states are scaled by the model's ωn ([ωn² x, ωn ẋ, …]); restate them in the declared
        // ωn's scale, so that every model of a run (before and after a frequency change) shares
        // one state and the displacement row is the same.
        let ratio = self.params.omega_n() / wn;
        let sc = |i: usize| match i {
            0 => ratio * ratio,
            1 => ratio,
            _ => 1.0,
        };
        for i in 0..n {
            for j in 0..n {
                a[(i, j)] *= sc(i) / sc(j);
                qc[(i, j)] *= sc(i) * sc(j);
                p0[(i, j)] *= sc(i) * sc(j);
            }
            c[(0, i)] /= sc(i);
        }
        let r = DMatrix::from_element(1, 1, p.accel_noise_std * p.accel_noise_std);
        Matrices { a, qc, c, r, p0 }
    }
}

/// One model of the oscillator (see [`StateSpace`]).
struct Matrices {
    a: DMatrix<f64>,
    qc: DMatrix<f64>,
    c: DMatrix<f64>,
    r: DMatrix<f64>,
    p0: DMatrix<f64>,
}

impl Matrices {
    fn state_space(&self) -> StateSpace<'_> {
        StateSpace { a: &self.a, qc: &self.qc, c: &self.c, r: &self.r, p0: &self.p0 }
    }
}

impl LoopSystem for OscillatorSystem<'_> {
    type Effect = Effect;
    /// Each effect with the index of its first state among the run's tracked states.
    type Model = Vec<(Effect, usize)>;

    const NAME: &'static str = "oscillator";

    /// One model per stretch between onsets: before an effect's onset it is decoupled.
    fn run(&self, effects: &[Applied<Effect>]) -> Result<(Vec<(Effect, usize)>, Run)> {
        let t = &self.data.t;
        let mut switches: Vec<usize> = effects.iter().map(|e| e.first_sample(t)).collect();
        switches.push(0);
        switches.sort_unstable();
        switches.dedup();
        let models: Vec<(usize, Matrices)> = switches
            .iter()
            .map(|&k| {
                let active: Vec<bool> = effects.iter().map(|e| e.first_sample(t) <= k).collect();
                (k, self.model(effects, &active))
            })
            .collect();
        let segments: Vec<(usize, StateSpace<'_>)> = models.iter().map(|(k, m)| (*k, m.state_space())).collect();
        let (starts, n) = Self::layout(effects);
        let mut tracked = Vec::new();
        let mut model = Vec::with_capacity(effects.len());
        for (e, &s) in effects.iter().zip(&starts) {
            model.push((e.effect, tracked.len()));
            match e.effect {
                Effect::SensorBias => tracked.push(s),
                Effect::HarmonicForce { .. } => tracked.extend([s, s + 1]),
                _ => {}
            }
        }
        let wn = self.params.omega_n();
        let displacement = DMatrix::from_fn(1, n, |_, j| if j == 0 { 1.0 / (wn * wn) } else { 0.0 });
        let dt = 1.0 / self.params.sample_rate_hz;
        let run = run_segments(&segments, dt, &[&self.ax], &displacement, &tracked)?;
        Ok((model, run))
    }

    fn summarise(&self, run: &Run) -> RunSummary {
        let lines = ReferenceLines {
            speed: self.params.drive_rad_s,
            naturals: vec![self.params.natural_freq_hz],
            named: vec![],
        };
        self.recording().summarise(run, &lines, &self.options.signatures)
    }

    /// A bias when the innovations' mean is off; lines at 2× or 3× the drive name a force
    /// there; colour or a wrong NIS the scale and the mode's parameters.
    fn candidates(&self, s: &RunSummary, _: &Run, _: &Self::Model, _: &[Applied<Effect>]) -> Vec<Vec<Effect>> {
        let mut named = Vec::new();
        let c = &s.channels[0];
        if c.z.abs() >= self.options.signatures.bias_z {
            named.push(Effect::SensorBias);
        }
        for order in [2, 3] {
            if c.peaks.iter().any(|p| p.order == Some(order)) {
                named.push(Effect::HarmonicForce { order });
            }
        }
        if c.whiteness_p < self.options.signatures.alpha || !c.peaks.is_empty() || !s.nis_consistent {
            named.extend([Effect::SensorScale, Effect::Frequency, Effect::Damping]);
        }
        vec![named]
    }

    fn describe(&self, e: &Effect) -> (EffectLabel, Fitting) {
        (self.label(e), self.fitting(e))
    }

    /// The mode's frequency and damping (the scenario's component parameters) and the
    /// sensor's scale.
    fn declared(&self) -> Vec<Effect> {
        vec![Effect::Frequency, Effect::Damping, Effect::SensorScale]
    }

    /// A bias's mean, a force's amplitude (times the modal mass) once settled, or the fitted
    /// factor.
    fn value(&self, model: &Vec<(Effect, usize)>, run: &Run, effect: &Applied<Effect>) -> f64 {
        let Some(&(_, offset)) = model.iter().find(|(e, _)| *e == effect.effect) else { return f64::NAN };
        let from = effect.first_sample(&self.data.t);
        let s = &run.effect_states;
        match effect.effect {
            Effect::SensorBias => settled_mean(&s[offset], from),
            Effect::HarmonicForce { .. } => {
                let amplitude: Vec<f64> = s[offset].iter().zip(&s[offset + 1]).map(|(a, b)| a.hypot(*b)).collect();
                self.params.modal_mass_kg * settled_mean(&amplitude, from)
            }
            Effect::SensorScale | Effect::Frequency | Effect::Damping => effect.theta.exp(),
        }
    }

    /// The mode's frequency and damping are the scenario's `[mode]` keys; an offset on `ax` is
    /// the filter's declared one (`[filter] accel_offset_m_s2`, added to: the loop ran with the
    /// declared offset already subtracted). The scenario's `[sensor]` keys are the simulated
    /// sensor's, so a scale has no key; the filter declares no second force.
    fn correction(&self, effect: &Applied<Effect>, value: f64) -> Correction {
        match effect.effect {
            Effect::Frequency => Correction::model([ConfigEdit::new("mode.natural_freq_hz", Op::Scale(value))]),
            Effect::Damping => Correction::model([ConfigEdit::new("mode.damping_ratio", Op::Scale(value))]),
            Effect::SensorBias => {
                Correction::model([ConfigEdit::or_absent("filter.accel_offset_m_s2", Op::Add(value), 0.0)])
            }
            Effect::SensorScale => Correction::not_carried(
                "the scenario's [sensor] keys describe the simulated sensor; the filter has no key for a declared \
                 scale",
            ),
            Effect::HarmonicForce { .. } => {
                Correction::not_carried("the filter carries one force, at the drive frequency; no key declares another")
            }
        }
    }

    fn traces(&self) -> Traces {
        self.recording().traces()
    }

    /// The unmodelled acceleration on the mode stands for what one mode leaves out (its
    /// neighbours, the structure's other paths): how much that is depends on the machine, so
    /// the data set it.
    fn scale_noise(&mut self, scale: f64) -> Option<TunableNoise> {
        self.params.motion_psd = self.motion_psd * scale;
        let keys = vec![("filter.motion_psd".into(), self.motion_psd)];
        Some(TunableNoise { what: "the mode's unmodelled acceleration".into(), keys })
    }
}

impl OscillatorSystem<'_> {
    /// How the report names `e`.
    pub fn label(&self, e: &Effect) -> EffectLabel {
        let (kind, location, unit, detail) = match *e {
            Effect::SensorBias => (EffectKind::SensorBias, CHANNEL, "m/s^2", EffectDetail::default()),
            Effect::SensorScale => (EffectKind::SensorScale, CHANNEL, "1", EffectDetail::default()),
            Effect::HarmonicForce { order } => (
                EffectKind::HarmonicForce,
                "mode",
                "N",
                EffectDetail { order: Some(order as f64), ..EffectDetail::default() },
            ),
            Effect::Frequency => (
                EffectKind::Parameter,
                "mode",
                "1",
                EffectDetail { parameter: Some("frequency".into()), ..EffectDetail::default() },
            ),
            Effect::Damping => (
                EffectKind::Parameter,
                "mode",
                "1",
                EffectDetail { parameter: Some("damping".into()), ..EffectDetail::default() },
            ),
        };
        EffectLabel { kind, location: location.into(), detail, unit: unit.into() }
    }

    /// Every effect may begin mid-run: a knock that shifts the sensor's offset or gain, a rub
    /// that adds a harmonic, a crack or a loosening that changes the mode.
    pub fn fitting(&self, e: &Effect) -> Fitting {
        let parameters = match e {
            Effect::HarmonicForce { .. } => 2,
            _ => 1,
        };
        let scalar = match e {
            Effect::SensorScale => Some((ScalarRange::factor(0.5, 2.0, 1e-5), 4)),
            Effect::Frequency => Some((ScalarRange::factor(0.8, 1.25, 1e-5), 6)),
            Effect::Damping => Some((ScalarRange::factor(0.25, 4.0, 1e-5), 4)),
            Effect::SensorBias | Effect::HarmonicForce { .. } => None,
        };
        Fitting { parameters, scalar, limit: None, may_start_mid_run: true }
    }
}

/// Closes the loop on `data` with the model of `scenario`.
pub fn close_loop(scenario: &Scenario, data: &DataFile, options: &LoopOptions) -> Result<LoopReport> {
    search(&mut OscillatorSystem::new(scenario, data, options)?, options)
}

/// Learns a [`LevelBaseline`](crate::residual_loop::levels::LevelBaseline) from a healthy
/// recording with the scenario's model (`edgekf baseline oscillator`).
pub fn learn_baseline(
    scenario: &Scenario,
    data: &DataFile,
    condition: Option<String>,
    options: &LoopOptions,
) -> Result<crate::residual_loop::levels::LevelBaseline> {
    crate::residual_loop::levels::LevelBaseline::learn(
        &mut OscillatorSystem::new(scenario, data, options)?,
        condition,
        options,
    )
}

#[cfg(test)]
mod tests;
