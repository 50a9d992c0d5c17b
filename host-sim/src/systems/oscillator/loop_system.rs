//! The oscillator as a system of the residual loop: the harmonic-force model of
//! `edgekf::systems::oscillator` (the scaled state `[ωn² x, ωn ẋ, p₁, p₂]`, the force a phasor
//! at the drive frequency) read from the accelerometer channel `ax`, with a small library of
//! what such a mode's model may lack:
//!
//! * `sensor_bias` on `ax` (a random-walk state), `sensor_scale` (a factor on `C`);
//! * `harmonic_force` at 2× or 3× the drive (another phasor): a second harmonic of the force;
//! * `parameter` of the `mode`: its natural frequency or damping ratio, as a factor.
//!
//! The filter is the engine's dense Kalman filter on this continuous model, so the loop and the
//! node's estimator share the model's matrices but not their code path.

use super::scenario::Scenario;
use crate::io::data::DataFile;
use crate::residual_loop::filter::{run_state_space, Run, StateSpace};
use crate::residual_loop::optimize::ScalarRange;
use crate::residual_loop::search::{
    search, Channel, EffectDetail, EffectKind, EffectLabel, LoopOptions, LoopReport, LoopSystem, RunSummary, Traces,
};
use crate::residual_loop::signature::{summarise, ReferenceLines, SummaryContext};
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
}

impl<'a> OscillatorSystem<'a> {
    /// The model of `scenario` (mode, drive, sensor, filter tuning) on `data`'s `ax` channel.
    pub fn new(scenario: &Scenario, data: &'a DataFile, options: &LoopOptions) -> Result<Self> {
        let ax = data.column(CHANNEL).ok_or_else(|| anyhow!("the data file has no channel {CHANNEL}"))?.to_vec();
        Ok(Self {
            params: scenario.estimator_params(),
            data,
            ax,
            channels: [Channel::new(CHANNEL, "m/s^2").shown_in(1e3, "mm/s²")],
            rows: [Channel::new("x", "m").shown_in(1e6, "µm")],
            options: *options,
        })
    }

    /// The declared parameters with the `parameter` effects applied.
    fn params_with(&self, effects: &[(Effect, f64)]) -> HarmonicForceParams {
        let mut p = self.params;
        for &(e, theta) in effects {
            match e {
                Effect::Frequency => p.natural_freq_hz *= theta.exp(),
                Effect::Damping => p.damping_ratio *= theta.exp(),
                _ => {}
            }
        }
        p
    }

    /// Where each effect's states start, and the total state count.
    fn layout(effects: &[(Effect, f64)]) -> (Vec<usize>, usize) {
        let mut n = 4;
        let mut starts = Vec::with_capacity(effects.len());
        for (e, _) in effects {
            starts.push(n);
            n += match e {
                Effect::SensorBias => 1,
                Effect::HarmonicForce { .. } => 2,
                _ => 0,
            };
        }
        (starts, n)
    }
}

impl LoopSystem for OscillatorSystem<'_> {
    type Effect = Effect;
    /// Each effect with the index of its first state among the run's tracked states.
    type Model = Vec<(Effect, usize)>;

    fn name(&self) -> &str {
        "oscillator"
    }

    fn run(&self, effects: &[(Effect, f64)]) -> Result<(Vec<(Effect, usize)>, Run)> {
        let p = self.params_with(effects);
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
        let mut tracked = Vec::new();
        let mut model = Vec::with_capacity(effects.len());
        for (&(e, theta), &s) in effects.iter().zip(&starts) {
            model.push((e, tracked.len()));
            match e {
                Effect::SensorBias => {
                    c[(0, s)] = 1.0;
                    qc[(s, s)] = BIAS_PSD;
                    p0[(s, s)] = BIAS_STD * BIAS_STD;
                    tracked.push(s);
                }
                Effect::HarmonicForce { order } => {
                    let wk = order as f64 * w;
                    (a[(s, s + 1)], a[(s + 1, s)]) = (-wk, wk);
                    // The phasor's real part drives the mode as p₁ does, and is measured with it.
                    a[(1, s)] = wn;
                    c[(0, s)] = 1.0;
                    qc[(s, s)] = p.force_psd;
                    qc[(s + 1, s + 1)] = p.force_psd;
                    p0[(s, s)] = p.initial_force_std.powi(2);
                    p0[(s + 1, s + 1)] = p.initial_force_std.powi(2);
                    tracked.extend([s, s + 1]);
                }
                Effect::SensorScale => scale *= theta.exp(),
                Effect::Frequency | Effect::Damping => {}
            }
        }
        // The bias is added after the scale: it is the sensor's offset, not the motion's.
        for j in 0..n {
            if !effects.iter().zip(&starts).any(|((e, _), &s)| *e == Effect::SensorBias && s == j) {
                c[(0, j)] *= scale;
            }
        }
        let r = DMatrix::from_element(1, 1, p.accel_noise_std * p.accel_noise_std);
        let ss = StateSpace { a: &a, qc: &qc, c: &c, r: &r, p0: &p0 };
        let displacement = DMatrix::from_fn(1, n, |_, j| if j == 0 { 1.0 / (wn * wn) } else { 0.0 });
        let run = run_state_space(&ss, 1.0 / p.sample_rate_hz, &[&self.ax], &displacement, &tracked)?;
        Ok((model, run))
    }

    fn summarise(&self, run: &Run) -> RunSummary {
        let truth = [self.data.column("truth_x")];
        let lines = ReferenceLines {
            speed: self.params.drive_rad_s,
            naturals: vec![self.params.natural_freq_hz],
            named: vec![],
        };
        let ctx = SummaryContext {
            t: &self.data.t,
            channels: &self.channels,
            rows: &self.rows,
            truth: &truth,
            lines: &lines,
            sample_rate: self.params.sample_rate_hz,
        };
        summarise(run, &ctx, &self.options.signatures)
    }

    /// A bias when the innovations' mean is off; lines at 2× or 3× the drive name a force
    /// there; colour or a wrong NIS the scale and the mode's parameters.
    fn candidates(&self, s: &RunSummary, _: &[(Effect, f64)]) -> Vec<Vec<Effect>> {
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

    fn label(&self, e: &Effect) -> EffectLabel {
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

    fn parameters(&self, e: &Effect) -> usize {
        match e {
            Effect::HarmonicForce { .. } => 2,
            _ => 1,
        }
    }

    fn scalar(&self, e: &Effect) -> Option<(ScalarRange, usize)> {
        let factor = |low: f64, high: f64| ScalarRange {
            low: low.ln(),
            high: high.ln(),
            neutral: 0.0,
            log: true,
            tolerance: 1e-5,
        };
        match e {
            Effect::SensorScale => Some((factor(0.5, 2.0), 4)),
            Effect::Frequency => Some((factor(0.8, 1.25), 6)),
            Effect::Damping => Some((factor(0.25, 4.0), 4)),
            Effect::SensorBias | Effect::HarmonicForce { .. } => None,
        }
    }

    /// A bias's mean, a force's amplitude (times the modal mass) over the second half of the
    /// run, or the fitted factor.
    fn value(&self, model: &Vec<(Effect, usize)>, run: &Run, effect: &Effect, theta: f64) -> f64 {
        let n = run.nis.len();
        let half = n / 2;
        let avg = |f: &dyn Fn(usize) -> f64| (half..n).map(f).sum::<f64>() / (n - half).max(1) as f64;
        let Some(&(_, offset)) = model.iter().find(|(e, _)| e == effect) else { return f64::NAN };
        let s = &run.effect_states;
        match effect {
            Effect::SensorBias => avg(&|k| s[offset][k]),
            Effect::HarmonicForce { .. } => self.params.modal_mass_kg * avg(&|k| s[offset][k].hypot(s[offset + 1][k])),
            Effect::SensorScale | Effect::Frequency | Effect::Damping => theta.exp(),
        }
    }

    fn traces(&self) -> Traces {
        Traces {
            t: self.data.t.clone(),
            channels: self.channels.to_vec(),
            rows: self.rows.to_vec(),
            truth: vec![self.data.column("truth_x").map(<[f64]>::to_vec)],
            ..Traces::default()
        }
    }
}

/// Closes the loop on `data` with the model of `scenario`.
pub fn close_loop(scenario: &Scenario, data: &DataFile, options: &LoopOptions) -> Result<LoopReport> {
    search(&OscillatorSystem::new(scenario, data, options)?, options)
}
