//! The rotor as a [`LoopSystem`]: its runs, summaries, effects and report section; the
//! candidates are [`candidates`](super::candidates)'s and the first stage
//! [`bearings`](super::bearings)'.

use super::effects::{AugmentedModel, Effect, Parameter};
use super::RotorSystem;
use crate::diagnostics::severity::Severity;
use crate::io::config_edit::{ConfigEdit, Op};
use crate::residual_loop::filter::Run;
use crate::residual_loop::onset::settled_mean;
use crate::residual_loop::{
    Applied, Correction, EffectDetail, EffectLabel, Fitting, LoopSystem, Rivals, RunSummary, SystemSection, Traces,
};
use anyhow::Result;

impl LoopSystem for RotorSystem<'_> {
    type Effect = Effect;
    type Model = AugmentedModel;

    const NAME: &'static str = "rotor";

    /// Composes the augmented model (the healthy parts, then the effects; re-reducing the
    /// rotor when a component parameter is changed) and runs the filter over the data.
    fn run(&self, applied: &[Applied<Effect>]) -> Result<(AugmentedModel, Run)> {
        self.run_on(&self.red, &self.healthy, applied)
    }

    fn summarise(&self, run: &Run) -> RunSummary {
        self.recording().summarise(run, &self.reference, &self.options.signatures)
    }

    /// Candidates named directly by a signature, then the structural ones, then the
    /// catch-all ([`candidates`]).
    fn candidates(
        &self,
        s: &RunSummary,
        run: &Run,
        model: &AugmentedModel,
        _effects: &[Applied<Effect>],
    ) -> Vec<Vec<Effect>> {
        self.propose(s, run, model)
    }

    /// A force at an order ties with the other nodes the last proposal found explaining its
    /// lines as well (see `places`); a force's and a point mass's neighbours are the shaft's
    /// nodes beside theirs (a mass's not at a disk, where it is the disk's mass).
    fn rivals(&self, effect: &Effect, _effects: &[Applied<Effect>]) -> Rivals<Effect> {
        let beside = |node: usize| [node.wrapping_sub(1), node + 1].into_iter().filter(|&n| n < self.nodes());
        let (tied, neighbours) = match *effect {
            Effect::HarmonicForce { node, order } => (
                self.steady_rivals(node, order).into_iter().map(|node| Effect::HarmonicForce { node, order }).collect(),
                beside(node).map(|node| Effect::HarmonicForce { node, order }).collect(),
            ),
            Effect::PointMass { node } => {
                let disks = self.disk_nodes();
                (
                    Vec::new(),
                    beside(node).filter(|n| !disks.contains(n)).map(|node| Effect::PointMass { node }).collect(),
                )
            }
            _ => (Vec::new(), Vec::new()),
        };
        Rivals { carried: Vec::new(), tied, neighbours }
    }

    fn describe(&self, e: &Effect) -> (EffectLabel, Fitting) {
        (self.label(e), self.fitting(e))
    }

    /// The fitted scalar (a factor as `exp θ`), or the effect states' size once settled.
    fn value(&self, model: &AugmentedModel, run: &Run, applied: &Applied<Effect>) -> f64 {
        let effect = &applied.effect;
        let Some(pos) = model.effects.iter().position(|(e, _, _)| e == effect) else { return f64::NAN };
        let m = self.channels();
        let offset: usize = model.effects[..pos].iter().map(|(e, _, _)| e.states(m)).sum();
        let from = applied.first_sample(&self.data.t);
        let s = &run.effect_states;
        let settled = |f: &dyn Fn(usize) -> f64| settled_mean(&(0..s[offset].len()).map(f).collect::<Vec<_>>(), from);
        match effect {
            Effect::SensorBias { .. } => settled(&|k| s[offset][k]),
            Effect::HarmonicForce { .. } => settled(&|k| s[offset][k].hypot(s[offset + 1][k])),
            Effect::UnknownInput { .. } => settled(&|k| s[offset][k].powi(2) + s[offset + 1][k].powi(2)).sqrt(),
            Effect::SensorScale { .. } | Effect::SensorLag { .. } | Effect::Parameter(_) | Effect::PointMass { .. } => {
                applied.theta.exp()
            }
            Effect::SensorDelay { .. } | Effect::ExtraMode { .. } => applied.theta,
            // Valued by the envelope stage, which fits it.
            Effect::BearingDefect { .. } => f64::NAN,
        }
    }

    /// A component parameter is its keys in the configuration, a point mass a new `[[mass]]`;
    /// a bearing's defect is a fault
    /// the node tracks by its envelope; the sensors', forces' and modes' effects have no key
    /// the rotor's model reads yet.
    fn correction(&self, applied: &Applied<Effect>, value: f64) -> Correction {
        match applied.effect {
            Effect::Parameter(p) => {
                Correction::model(p.keys(self.cfg).into_iter().map(|k| ConfigEdit::new(k, Op::Scale(value))))
            }
            Effect::PointMass { node } => {
                Correction::model([ConfigEdit::or_absent(format!("mass[+node={node}].mass"), Op::Set(value), 0.0)])
            }
            Effect::BearingDefect { .. } => {
                Correction::indicator([], "a bearing defect is a fault: its envelope line is tracked, not modelled")
            }
            e => Correction::not_carried(format!(
                "the rotor's configuration has no key its model reads for a {}",
                e.kind().as_str()
            )),
        }
    }

    /// Every component parameter (the engine screens them for what the data cannot see).
    fn declared(&self) -> Vec<Effect> {
        Parameter::all(self.cfg).into_iter().map(Effect::Parameter).collect()
    }

    fn traces(&self) -> Traces {
        self.recording().traces()
    }

    /// `running_speed`: the speed the loop used and where it came from; with a baseline, the
    /// baseline it started from (`baseline`) and the record's levels beside its
    /// (`baseline_comparison`).
    fn section(&self, model: &AugmentedModel, run: &Run) -> SystemSection {
        let mut section = SystemSection::default();
        if let Ok(v) = serde_json::to_value(self.speed) {
            section.fields.insert("running_speed".into(), v);
        }
        section.lines.push(("running speed".into(), self.speed.describe()));
        if let Some(d) = &self.families {
            section.lines.push(("bearing families".into(), super::bearings::describe(d)));
            section.fields.insert("bearing_families".into(), super::bearings::summary(d));
            let (channels, fs) = self.family_channels();
            section.figures.extend(super::family_figure::figure(&d.verdict, &channels, fs, d.shaft.hz));
        }
        let severity = self.severity();
        for v in &severity {
            section.lines.push(("vibration severity".into(), v.describe()));
        }
        if let Ok(v) = serde_json::to_value(&severity) {
            section.fields.insert("severity".into(), v);
        }
        if let Some(b) = &self.baseline {
            let about = serde_json::json!({
                "condition": b.condition,
                "data": b.source.data,
                "data_sha256": b.source.data_sha256,
                "speed_hz": b.speed_hz,
                "resonances": b.resonances.len(),
                "synchronous_forces": b.forces.len(),
            });
            section.fields.insert("baseline".into(), about);
            let what = b.condition.as_deref().map(|c| format!(" ({c})")).unwrap_or_default();
            section.lines.push(("baseline".into(), format!("learned on {}{what}", b.source.data)));
            let rows = b.compare(self, model, run);
            for c in &rows {
                section.lines.push(("compared".into(), c.describe()));
            }
            if let Ok(v) = serde_json::to_value(&rows) {
                section.fields.insert("baseline_comparison".into(), v);
            }
        }
        section
    }
}

impl RotorSystem<'_> {
    /// The housings' vibration velocity and its ISO 20816-3 zone, per accelerometer (the
    /// standard grades housings; shaft displacement probes are left out), from the raw record.
    fn severity(&self) -> Vec<Severity> {
        let fs = self.sample_rate();
        if self.data.t.len() < 2 || !fs.is_finite() || fs <= 0.0 {
            return Vec::new();
        }
        let class = self.cfg.severity.machine_class;
        let accelerometers = self.channel_info.iter().filter(|c| c.unit == "m/s^2");
        accelerometers
            .filter_map(|c| Severity::of(&c.name, self.data.column(&c.name)?, fs, self.speed.hz, class))
            .collect()
    }

    /// How the report names `e`.
    pub fn label(&self, e: &Effect) -> EffectLabel {
        let detail = EffectDetail {
            order: e.order(),
            parameter: match e {
                Effect::Parameter(p) => Some(p.name().to_string()),
                _ => None,
            },
            line: match e {
                Effect::BearingDefect { line, .. } => Some(line.name().to_string()),
                _ => None,
            },
            ..EffectDetail::default()
        };
        EffectLabel {
            kind: e.kind(),
            location: e.location(&self.red.channels, self.cfg),
            detail,
            unit: match e {
                // A bias is in its channel's unit.
                Effect::SensorBias { channel } => {
                    self.channel_info.get(*channel).map_or_else(|| e.unit().to_string(), |c| c.unit.clone())
                }
                _ => e.unit().to_string(),
            },
        }
    }

    /// Parameters and point masses get a finer grid: a stiffness factor's log-likelihood has
    /// side lobes where a natural frequency crosses a line. A force (harmonic or unknown) may
    /// not exceed `[bounds] force`, by default the rotor's weight: a larger one is the force
    /// standing in for something else.
    pub fn fitting(&self, e: &Effect) -> Fitting {
        let grid = if e.changes_structure() { 7 } else { 4 };
        Fitting {
            parameters: e.parameters(self.channels()),
            scalar: e.scalar(self.red.sample_rate, &self.cfg.bounds, self.cfg.mass()).map(|r| (r, grid)),
            limit: matches!(e, Effect::HarmonicForce { .. } | Effect::UnknownInput { .. })
                .then(|| self.cfg.bounds.force_n(self.cfg.weight())),
            may_start_mid_run: false,
        }
    }
}
