//! The vehicle as a system of the residual loop (`edgekf loop uuv`): the node's joint UKF of
//! state and thruster health, with what the configuration's `[estimator]` declares as the base
//! model, read from every measured channel, and a library of what the model may lack:
//!
//! * `actuator_health` at `thruster main` or `thruster vertical`: the health factor with its
//!   detector, as the node carries it, from an onset the engine fits (1 before it);
//! * `sensor_bias` on an accelerometer, gyro or DVL axis (a slow random walk);
//! * `unknown_input` at `current`: an ocean current nobody declared (two random walks);
//! * `parameter` of the `vehicle`: its mass or surge drag `X_u|u|`, as a factor.
//!
//! * [`effect`]: the effects and the filter states each occupies;
//! * [`filter`](mod@filter): the filter run with a model's effects switched on.

pub mod effect;
pub mod filter;

use super::config::UuvConfig;
use super::estimate::samples;
use crate::io::config_edit::{ConfigEdit, Op};
use crate::io::data::DataFile;
use crate::residual_loop::filter::Run;
use crate::residual_loop::onset::settled_mean;
use crate::residual_loop::optimize::ScalarRange;
use crate::residual_loop::signature::ReferenceLines;
use crate::residual_loop::tuning::TunableNoise;
use crate::residual_loop::{
    search, Applied, Channel, EffectDetail, EffectKind, EffectLabel, Fitting, LoopOptions, LoopReport, LoopSystem,
    RunSummary, SystemSection, Traces,
};
use crate::residual_loop::{Correction, Recording, Rivals};
use anyhow::Result;
use edgekf::systems::uuv::{EstimatorSettings, Sample, Vehicle};
use effect::{Effect, Parameter, Sensor, Thruster, CHANNELS};
use filter::{Plan, Switch};

/// Prior spreads of offsets nobody declared, larger than a data sheet's: an accelerometer's
/// (m/s²), a gyro's (rad/s) and a DVL's (m/s).
const UNDECLARED_BIAS_SD: [f64; 3] = [0.1, 0.01, 0.05];
/// Random-walk density of a DVL offset, m/s per √s.
const DVL_BIAS_PSD: f64 = 1e-4;
/// Samples of the filter's start left out of the statistics, s (the attitude and biases
/// settle in a few seconds).
const SETTLE_S: f64 = 10.0;
/// Log-likelihood per scalar reading an effect must gain beyond its BIC cost: what the reduced
/// vehicle leaves unexplained in healthy flight once its noise is tuned. On seeds 11–18 of
/// 150 s healthy flight the best next effect (a mass or drag factor within 0.1 % of 1) gained
/// at most 4.0 over about 71 000 readings, and 5.6 over 49 500 on seed 11 from 60 s (0.2
/// beyond its cost); a surge drag ×1.3 gains 160.
pub const MODEL_FLOOR: f64 = 1e-4;
/// Channels that see each thruster first: surge (`acc_x`, `gyro_x` for the propeller's torque,
/// `dvl_u`) and heave (`acc_z`, `depth`, `dvl_w`).
const THRUSTER_CHANNELS: [[usize; 3]; 2] = [[0, 3, 8], [2, 6, 10]];

/// The vehicle, its data and the loop's options.
pub struct UuvSystem<'a> {
    vehicle: Vehicle,
    settings: EstimatorSettings,
    data: &'a DataFile,
    samples: Vec<Sample<f64>>,
    declared: Vec<Effect>,
    channels: Vec<Channel>,
    rows: Vec<Channel>,
    options: LoopOptions,
    /// The configuration's velocity and rate process noise, which the engine may scale.
    motion_noise: (f64, f64),
}

impl<'a> UuvSystem<'a> {
    /// The vehicle and estimator of `config` on `data` (one timeline, the measured channels of
    /// `edgekf uuv simulate`).
    pub fn new(config: &UuvConfig, data: &'a DataFile, options: &LoopOptions) -> Result<Self> {
        let units = ["m/s^2", "m/s^2", "m/s^2", "rad/s", "rad/s", "rad/s", "m", "rad", "m/s", "m/s", "m/s"];
        Ok(Self {
            vehicle: config.vehicle,
            settings: config.estimator.settings(config.sensors.rate),
            data,
            samples: declared_offset(samples(data)?, &config.estimator.settings(config.sensors.rate)),
            declared: Effect::declared(&config.estimator.layout()),
            channels: CHANNELS.iter().zip(units).map(|(c, u)| Channel::new(*c, u)).collect(),
            rows: vec![Channel::new("k_t", "1"), Channel::new("k_v", "1"), Channel::new("u", "m/s")],
            options: *options,
            motion_noise: (config.estimator.process.velocity, config.estimator.process.rate),
        })
    }

    /// A slot's prior spread and noise density: the configuration's for what it declares, wider
    /// for what it does not; a health factor opened at an onset starts from the detector's
    /// reopening spread.
    fn switch(&self, e: Effect, from: usize, declared: bool) -> Option<Switch> {
        let (init, p) = (&self.settings.initial, &self.settings.process);
        let (sd, psd) = match e {
            Effect::Health(_) if from > 0 => (self.settings.detector.reopen, p.health),
            Effect::Health(_) => (init.health, p.health),
            Effect::Bias(Sensor::Acc(_)) if declared => (init.acc_bias, p.acc_bias),
            Effect::Bias(Sensor::Gyro(_)) if declared => (init.gyro_bias, p.gyro_bias),
            Effect::Bias(Sensor::Acc(_)) => (UNDECLARED_BIAS_SD[0], p.acc_bias),
            Effect::Bias(Sensor::Gyro(_)) => (UNDECLARED_BIAS_SD[1], p.gyro_bias),
            Effect::Bias(Sensor::Dvl(_)) => (UNDECLARED_BIAS_SD[2], DVL_BIAS_PSD),
            Effect::Current => (init.current, p.current),
            Effect::Parameter(_) | Effect::DvlOffset(_) => return None,
        };
        Some(Switch { states: e.states(), from, sd, psd })
    }

    /// The vehicle with the `parameter` effects applied.
    fn vehicle_with(&self, effects: &[Applied<Effect>]) -> Vehicle {
        let mut v = self.vehicle;
        for e in effects {
            match e.effect {
                Effect::Parameter(Parameter::Mass) => v.weight *= e.theta.exp(),
                Effect::Parameter(Parameter::SurgeDrag) => v.hydro.x_uu *= e.theta.exp(),
                _ => {}
            }
        }
        v
    }

    /// The data as the engine reads them: the health factors' and the surge speed's truth
    /// where simulated.
    fn recording(&self) -> Recording<'_> {
        let truth = ["truth_k_t", "truth_k_v", "truth_u"];
        Recording::of(self.data, &self.channels, &self.rows, &truth, 1.0 / self.settings.dt)
    }

    fn in_model(&self, e: Effect, effects: &[Applied<Effect>]) -> bool {
        self.declared.contains(&e) || effects.iter().any(|a| a.effect == e)
    }
}

/// `samples` with the configuration's DVL offset taken off, as the node's estimator takes it
/// (the loop runs the update directly, not the estimator's `step`).
fn declared_offset(mut samples: Vec<Sample<f64>>, settings: &EstimatorSettings) -> Vec<Sample<f64>> {
    let [ou, ov, ow] = settings.dvl_offset;
    for dvl in samples.iter_mut().filter_map(|s| s.dvl.as_mut()) {
        *dvl = [dvl[0] - ou, dvl[1] - ov, dvl[2] - ow];
    }
    samples
}

impl LoopSystem for UuvSystem<'_> {
    type Effect = Effect;
    /// Each effect with the index of its first state among the run's tracked states.
    type Model = Vec<(Effect, usize)>;

    const NAME: &'static str = "uuv";

    fn run(&self, effects: &[Applied<Effect>]) -> Result<(Self::Model, Run)> {
        let t = &self.data.t;
        let mut switches: Vec<Switch> = self.declared.iter().filter_map(|&e| self.switch(e, 0, true)).collect();
        let mut tracked = Vec::new();
        let mut model = Vec::with_capacity(effects.len());
        for a in effects {
            switches.extend(self.switch(a.effect, a.first_sample(t), false));
            model.push((a.effect, tracked.len()));
            tracked.extend(a.effect.states());
        }
        let plan = Plan { vehicle: self.vehicle_with(effects), settings: &self.settings, switches, tracked };
        let offsets: Vec<(usize, f64)> = effects
            .iter()
            .filter_map(|a| match a.effect {
                Effect::DvlOffset(axis) => Some((axis, a.theta)),
                _ => None,
            })
            .collect();
        if offsets.is_empty() {
            return Ok((model, filter::run(&plan, &self.samples)?));
        }
        let mut samples = self.samples.clone();
        for dvl in samples.iter_mut().filter_map(|s| s.dvl.as_mut()) {
            for &(axis, offset) in &offsets {
                dvl[axis] -= offset;
            }
        }
        Ok((model, filter::run(&plan, &samples)?))
    }

    fn summarise(&self, run: &Run) -> RunSummary {
        let mut o = self.options.signatures;
        o.settle = o.settle.max(SETTLE_S);
        self.recording().summarise(run, &ReferenceLines::default(), &o)
    }

    /// First what the signatures name: an offset on a biased channel (on any IMU axis), the health of a thruster
    /// whose channels are biased or change power mid-run, a current when the DVL's horizontal
    /// channels are biased or coloured; then, as the catch-all, the mass and the surge drag.
    fn candidates(&self, s: &RunSummary, _: &Run, _: &Self::Model, effects: &[Applied<Effect>]) -> Vec<Vec<Effect>> {
        let o = &self.options.signatures;
        let m = s.channels.len().max(1) as f64;
        let biased = |c: usize| s.channels.get(c).is_some_and(|c| c.z.abs() >= o.bias_z);
        let coloured = |c: usize| s.channels.get(c).is_some_and(|c| c.whiteness_p < o.alpha / m);
        let stepped = |c: usize| s.channels.get(c).and_then(|c| c.step).is_some_and(|(_, r)| !(0.5..=2.0).contains(&r));
        let mut named = Vec::new();
        for thruster in [Thruster::Main, Thruster::Vertical] {
            let e = Effect::Health(thruster);
            if THRUSTER_CHANNELS[thruster.index()].iter().any(|&c| biased(c) || stepped(c))
                && !self.in_model(e, effects)
            {
                named.push(e);
            }
        }
        // An IMU offset shows where the attitude and rates it corrupts are measured (an
        // accelerometer's x offset reads as pitch, seen in the depth and the DVL), so every IMU
        // axis is a candidate once any channel is biased; a DVL axis when its own channel is.
        // A horizontal DVL offset is taken up by the current, which the vehicle's roll and pitch
        // project onto the other axes: so every DVL axis is a candidate once one is biased.
        let any_biased = (0..CHANNELS.len()).any(biased);
        let dvl_biased = (8..11).any(biased);
        for c in 0..CHANNELS.len() {
            let also = if c < 6 { any_biased } else { dvl_biased };
            if let Some(sensor) = Sensor::of_channel(c).filter(|_| biased(c) || also) {
                named.push(Effect::Bias(sensor));
            }
        }
        if [8, 9].iter().any(|&c| biased(c) || coloured(c)) {
            named.push(Effect::Current);
        }
        named.retain(|e| !self.in_model(*e, effects));
        let catch_all = if s.consistent {
            Vec::new()
        } else {
            vec![Effect::Parameter(Parameter::Mass), Effect::Parameter(Parameter::SurgeDrag)]
        };
        vec![named, catch_all]
    }

    fn describe(&self, e: &Effect) -> (EffectLabel, Fitting) {
        (self.label(e), self.fitting(e))
    }

    /// The vehicle's mass and surge drag, the configuration's component parameters, and a fixed
    /// offset on each DVL axis (beyond `[estimator.dvl_offset]`, which the samples have taken off).
    fn declared(&self) -> Vec<Effect> {
        let mut out = vec![Effect::Parameter(Parameter::Mass), Effect::Parameter(Parameter::SurgeDrag)];
        out.extend((0..3).map(Effect::DvlOffset));
        out
    }

    /// A DVL's horizontal offset in the body frame is a current that turns with the vehicle:
    /// while the heading holds, the current the model estimates takes it up whole.
    fn rivals(&self, e: &Effect, effects: &[Applied<Effect>]) -> Rivals<Effect> {
        let horizontal = matches!(e, Effect::DvlOffset(0 | 1) | Effect::Bias(Sensor::Dvl(0 | 1)));
        let carried =
            if horizontal && self.in_model(Effect::Current, effects) { vec![Effect::Current] } else { Vec::new() };
        Rivals { carried, ..Rivals::default() }
    }

    /// A health factor or an offset once settled after its onset, a current's speed, or the
    /// fitted factor.
    fn value(&self, model: &Self::Model, run: &Run, effect: &Applied<Effect>) -> f64 {
        let Some(&(_, offset)) = model.iter().find(|(e, _)| *e == effect.effect) else { return f64::NAN };
        let from = effect.first_sample(&self.data.t);
        let s = &run.effect_states;
        match effect.effect {
            Effect::Health(_) | Effect::Bias(_) => settled_mean(&s[offset], from),
            Effect::Current => {
                let speed: Vec<f64> = s[offset].iter().zip(&s[offset + 1]).map(|(n, e)| n.hypot(*e)).collect();
                settled_mean(&speed, from)
            }
            Effect::Parameter(_) => effect.theta.exp(),
            Effect::DvlOffset(_) => effect.theta,
        }
    }

    /// The vehicle's constants are `[vehicle]`'s; the node's estimator carries the IMU's biases
    /// and the current as whole switches of `[estimator]`, and a thruster's health is a fault
    /// its detector tracks.
    fn correction(&self, effect: &Applied<Effect>, value: f64) -> Correction {
        match effect.effect {
            Effect::Parameter(Parameter::Mass) => {
                Correction::model([ConfigEdit::new("vehicle.weight", Op::Scale(value))])
            }
            Effect::Parameter(Parameter::SurgeDrag) => {
                Correction::model([ConfigEdit::new("vehicle.hydro.x_uu", Op::Scale(value))])
            }
            Effect::Bias(Sensor::Acc(_) | Sensor::Gyro(_)) => {
                Correction::model([ConfigEdit::or_absent("estimator.sensor_biases", Op::Switch(true), 0.0)])
            }
            Effect::Current => Correction::model([ConfigEdit::or_absent("estimator.current", Op::Switch(true), 0.0)]),
            Effect::Bias(Sensor::Dvl(axis)) | Effect::DvlOffset(axis) => {
                let key = format!("estimator.dvl_offset.{}", ["u", "v", "w"].get(axis).unwrap_or(&"u"));
                Correction::model([ConfigEdit::or_absent(key, Op::Add(value), 0.0)])
            }
            Effect::Health(_) => Correction::indicator(
                [],
                "a thruster's health is tracked by the node's detector ([estimator] health, [estimator.detector])",
            ),
        }
    }

    fn traces(&self) -> Traces {
        self.recording().traces()
    }

    /// The velocity and rate noise stand for what the reduced dynamics leave out (the hull's
    /// higher-order terms, the current's pull): how much that is depends on the vehicle and
    /// the sea, so the data set it.
    fn scale_noise(&mut self, scale: f64) -> Option<TunableNoise> {
        let (velocity, rate) = self.motion_noise;
        self.settings.process.velocity = velocity * scale;
        self.settings.process.rate = rate * scale;
        let keys = vec![("estimator.process.velocity".into(), velocity), ("estimator.process.rate".into(), rate)];
        Some(TunableNoise { what: "the vehicle's velocity and rate".into(), keys })
    }

    /// What the configuration declared: the base model's states beside the vehicle's.
    fn section(&self, _: &Self::Model, _: &Run) -> SystemSection {
        let declared: Vec<String> = self
            .declared
            .iter()
            .map(|e| {
                let l = self.label(e);
                format!("{} at {}", l.kind, l.location)
            })
            .collect();
        let text =
            if declared.is_empty() { "nothing beyond the vehicle's states".to_string() } else { declared.join(", ") };
        let mut section = SystemSection::default();
        section.fields.insert("declared".into(), serde_json::json!(declared));
        section.lines.push(("declared".into(), text));
        section
    }
}

impl UuvSystem<'_> {
    /// How the report names `e`.
    pub fn label(&self, e: &Effect) -> EffectLabel {
        let (kind, location, unit, detail) = match *e {
            Effect::Health(t) => {
                (EffectKind::ActuatorHealth, format!("thruster {}", t.name()), "1", EffectDetail::default())
            }
            Effect::Bias(s) => {
                (EffectKind::SensorBias, CHANNELS[s.channel()].to_string(), s.unit(), EffectDetail::default())
            }
            Effect::DvlOffset(a) => {
                let s = Sensor::Dvl(a);
                (EffectKind::SensorBias, CHANNELS[s.channel()].to_string(), s.unit(), EffectDetail::default())
            }
            Effect::Current => (EffectKind::UnknownInput, "current".to_string(), "m/s", EffectDetail::default()),
            Effect::Parameter(p) => (
                EffectKind::Parameter,
                "vehicle".to_string(),
                "1",
                EffectDetail { parameter: Some(p.name().into()), ..EffectDetail::default() },
            ),
        };
        EffectLabel { kind, location, detail, unit: unit.into() }
    }

    /// A thruster's health changes mid-run (a fouled propeller, a failing motor); the rest are
    /// properties of the vehicle and its sensors.
    pub fn fitting(&self, e: &Effect) -> Fitting {
        let scalar = match e {
            Effect::Parameter(Parameter::Mass) => Some((ScalarRange::factor(0.8, 1.25, 1e-3), 4)),
            Effect::Parameter(Parameter::SurgeDrag) => Some((ScalarRange::factor(0.7, 1.43, 1e-3), 4)),
            Effect::DvlOffset(_) => {
                let sd = UNDECLARED_BIAS_SD[2];
                Some((ScalarRange { low: -2.0 * sd, high: 2.0 * sd, neutral: 0.0, log: false, tolerance: 1e-4 }, 4))
            }
            _ => None,
        };
        Fitting {
            parameters: e.states().len().max(1),
            scalar,
            limit: None,
            may_start_mid_run: matches!(e, Effect::Health(_)),
        }
    }
}

/// Closes the loop on `data` (one timeline) with the vehicle and estimator of `config`.
/// The gain floor is the larger of [`MODEL_FLOOR`] and the options' (a baseline's).
pub fn close_loop(config: &UuvConfig, data: &DataFile, options: &LoopOptions) -> Result<LoopReport> {
    let options = LoopOptions { gain_floor: options.gain_floor.max(MODEL_FLOOR), ..*options };
    search(&mut UuvSystem::new(config, data, &options)?, &options)
}

/// Learns a [`LevelBaseline`](crate::residual_loop::levels::LevelBaseline) from a healthy
/// recording with the configured vehicle (`edgekf baseline uuv`).
pub fn learn_baseline(
    config: &UuvConfig,
    data: &DataFile,
    condition: Option<String>,
    options: &LoopOptions,
) -> Result<crate::residual_loop::levels::LevelBaseline> {
    crate::residual_loop::levels::LevelBaseline::learn(&mut UuvSystem::new(config, data, options)?, condition, options)
}
