//! The rotor's bearings in the loop: which fault family the housings' vibration carries
//! ([`family`]: the whole family of lines, prewhitened, as the field diagnoses), that family's
//! lines then fitted in the envelope of the base model's innovations before the search
//! ([`impacts`]), and the impacts' vibration taken out of the data once a defect is named.
//! Two families that explain the lines equally are reported as such, not guessed between.

use super::effects::Effect;
use super::RotorSystem;
use crate::diagnostics::bearings::family::{self, BearingSpec, Diagnosis, Family, FamilyFit, Kinematics, Verdict};
use crate::diagnostics::bearings::impacts::{self, ImpactLine};
use crate::residual_loop::filter::Run;
use crate::residual_loop::{
    search_staged, AddedEffect, EffectKind, LoopOptions, LoopReport, LoopSystem, NotIdentifiable, PreStage,
};
use crate::systems::rotor::bearing_geometry::BearingLine;
use anyhow::{anyhow, Result};
use std::f64::consts::TAU;

impl RotorSystem<'_> {
    /// The loop on the rotor: the bearings' stage ([`Self::first_stage`]) on the base model's
    /// run, then the engine's search.
    pub(super) fn search(&mut self, options: &LoopOptions) -> Result<LoopReport> {
        search_staged(self, options, |sys, run| sys.first_stage(run, options))
    }

    /// The bearings' defects named by their envelope lines ([`impacts`]) and their vibration
    /// taken out of the data; after a defect is named, a broadband stand-in (a mode the model
    /// lacks, a catch-all input) is not fitted: the impacts ring every lightly damped mode.
    pub(super) fn first_stage(&mut self, run: &Run, options: &LoopOptions) -> Result<PreStage<Effect>> {
        self.families = self.diagnose_families();
        let (lines, not_identifiable) = match self.families.as_ref().map(|d| &d.verdict) {
            Some(Verdict::Named(fit)) => (self.family_lines(fit), Vec::new()),
            Some(Verdict::CannotTell(a, b)) => (Vec::new(), self.tie(a, b)),
            Some(Verdict::Nothing) => (Vec::new(), Vec::new()),
            // No running speed in the raw spectrum: every line, each refused on a shaft order.
            None => (self.impact_lines(), Vec::new()),
        };
        if options.progress {
            if let Some(d) = &self.families {
                eprintln!("loop: bearing families: {}", describe(d));
            }
        }
        let traces = self.traces();
        let mut found =
            impacts::stage(&lines, |e| self.label(e), run, &traces, &self.rotor.envelope, options.half_gain);
        let data_changed = self.take_out(&mut found, run.log_likelihood())?;
        if options.progress {
            for (_, a) in &found.added {
                eprintln!(
                    "loop: impacts {} at {}: Δ log-likelihood {:.1}, BIC cost {:.1}",
                    a.kind, a.location, a.delta_log_likelihood, a.bic_penalty
                );
            }
        }
        if let Some(Verdict::Named(fit)) = self.families.as_ref().map(|d| &d.verdict) {
            if let Some(named) = self.named_by_family(fit, &found.added) {
                found.added.push(named);
            }
        }
        let excludes = match found.added.first() {
            Some((_, defect)) => [EffectKind::ExtraMode, EffectKind::UnknownInput]
                .map(|kind| {
                    let why = format!(
                        "not fitted: the impacts of the {} at {} ring every lightly damped mode, and a broadband \
                         stand-in fitted after them is their ringing",
                        defect.kind, defect.location
                    );
                    (kind, why)
                })
                .to_vec(),
            None => Vec::new(),
        };
        Ok(PreStage {
            data_changed,
            added: found.added,
            trials: found.trials,
            refused: found.refused,
            excludes,
            not_identifiable,
        })
    }

    /// Takes the impacts' vibration `found` predicts out of the data, if the base model then
    /// explains the data better than its log-likelihood `before`; otherwise puts it back and
    /// says so on each defect (`not_modelled`), so that the report's "after" is never made
    /// worse by the stage. Whether the data changed.
    fn take_out(&mut self, found: &mut impacts::Outcome<Effect>, before: f64) -> Result<bool> {
        if found.signals.is_empty() {
            return Ok(false);
        }
        for (channel, signal) in &found.signals {
            self.subtract(*channel, signal)?;
        }
        let after = self.run(&[])?.1.log_likelihood();
        if after > before {
            return Ok(true);
        }
        for (channel, signal) in &found.signals {
            let back: Vec<f64> = signal.iter().map(|v| -v).collect();
            self.subtract(*channel, &back)?;
        }
        let why = format!(
            "its vibration is left in the data: taking the impacts' predicted vibration out made the base model's \
             log-likelihood worse ({before:.1} → {after:.1}); the filter does not model impacts"
        );
        for (_, a) in &mut found.added {
            a.detail.not_modelled = Some(why.clone());
        }
        Ok(false)
    }

    /// Every bearing with a geometry, as the family detector reads it (`bearing N`, its lines
    /// as orders), with its index in the configuration.
    fn bearing_specs(&self) -> Vec<(usize, BearingSpec)> {
        let with_geometry = self.cfg.bearings.iter().enumerate().filter_map(|(i, b)| Some((i, b.node, b.geometry?)));
        with_geometry
            .map(|(i, node, g)| (i, BearingSpec { name: format!("bearing {node}"), orders: g.kinematics() }))
            .collect()
    }

    /// The channels the family detector reads, raw (before the first stage takes the impacts
    /// out): the housings' accelerometers, every channel if none is one; and their sample rate
    /// (the filter's).
    pub(super) fn family_channels(&self) -> (Vec<(&str, &[f64])>, f64) {
        let fs = self.sample_rate();
        let raw = |only_accelerometers: bool| -> Vec<(&str, &[f64])> {
            let chosen = self.channel_info.iter().filter(|c| !only_accelerometers || c.unit == "m/s^2");
            chosen.filter_map(|c| Some((c.name.as_str(), self.data.column(&c.name)?))).collect()
        };
        let accelerometers = raw(true);
        (if accelerometers.is_empty() { raw(false) } else { accelerometers }, fs)
    }

    /// The fault family the raw housings' vibration carries, or `None` without bearing
    /// geometry or a readable speed.
    fn diagnose_families(&self) -> Option<Diagnosis> {
        let specs: Vec<BearingSpec> = self.bearing_specs().into_iter().map(|(_, s)| s).collect();
        let (named, fs) = self.family_channels();
        let channels: Vec<&[f64]> = named.iter().map(|c| c.1).collect();
        if specs.is_empty() || fs <= 0.0 {
            return None;
        }
        family::diagnose(&channels, fs, self.speed.hz, &specs)
    }

    /// The named family's lines at its bearing, at the speed and kinematic factor the
    /// detector found; a ball's impacts are looked for at twice its spin (both races, carried
    /// round at the cage's rate) and at the cage's rate (what ball faults mostly show), both
    /// reported as the ball's defect. No line is refused for its distance to a shaft order:
    /// the family was told from the shaft's harmonics by all its members.
    fn family_lines(&self, fit: &FamilyFit) -> Vec<ImpactLine<Effect>> {
        let Some((bearing, spec)) = self.bearing_specs().into_iter().find(|(_, s)| s.name == fit.bearing) else {
            return Vec::new();
        };
        let shaft_hz = self.families.as_ref().map_or(self.red.speed / TAU, |d| d.shaft.hz);
        let k = spec.orders;
        let scale = 1.0 + fit.slip;
        let line = |line: BearingLine, order: f64, hz_order: f64, modulation_hz: Option<f64>| ImpactLine {
            effect: Effect::BearingDefect { bearing, line, order_milli: (order * scale * 1e3).round() as u32 },
            hz: hz_order * scale * shaft_hz,
            modulation_hz,
            synchronous_hz: None,
        };
        match fit.family {
            Family::OuterRace => vec![line(BearingLine::Bpfo, k.bpfo, k.bpfo, None)],
            Family::InnerRace => vec![line(BearingLine::Bpfi, k.bpfi, k.bpfi, Some(shaft_hz))],
            Family::Ball => vec![
                line(BearingLine::Bsf, k.bsf, 2.0 * k.bsf, Some(k.ftf * scale * shaft_hz)),
                line(BearingLine::Bsf, k.bsf, k.ftf, None),
            ],
        }
    }

    /// The named family's defect as the detector found it, when the impacts' fit in the
    /// innovations did not pay its cost (their model has two parameters per envelope bin; the
    /// family's lines are a test of their own, [`family::CARRY`]): named, its vibration not
    /// modelled. `None` when the fit named it already.
    fn named_by_family(&self, fit: &FamilyFit, added: &[(Effect, AddedEffect)]) -> Option<(Effect, AddedEffect)> {
        let (bearing, spec) = self.bearing_specs().into_iter().find(|(_, s)| s.name == fit.bearing)?;
        if added.iter().any(|(e, _)| matches!(e, Effect::BearingDefect { bearing: b, .. } if *b == bearing)) {
            return None;
        }
        let (line, order) = family_line(fit.family, &spec.orders);
        let effect =
            Effect::BearingDefect { bearing, line, order_milli: (order * (1.0 + fit.slip) * 1e3).round() as u32 };
        let mut label = self.label(&effect);
        let strong: Vec<&family::Member> =
            fit.members.iter().filter(|m| !m.on_order && m.strength_db >= family::CARRY.min_db).collect();
        label.detail.band_hz = Some([fit.band.low_hz, fit.band.high_hz]);
        label.detail.not_modelled =
            Some("impacts fitted to the innovations did not pay their cost: its vibration is left in the data".into());
        label.detail.named_by = Some(format!(
            "its family of envelope lines ({}; chance 10^-{:.1} < {:.0e})",
            strong.iter().map(|m| format!("{} {:.1} dB", m.label, m.strength_db)).collect::<Vec<_>>().join(", "),
            fit.score,
            family::CARRY.false_alarm
        ));
        let added = AddedEffect {
            kind: label.kind,
            location: label.location,
            value: strong.iter().map(|m| m.strength_db).fold(f64::NEG_INFINITY, f64::max),
            unit: "dB".into(),
            detail: label.detail,
            explains: strong.iter().map(|m| (m.hz * 100.0).round() / 100.0).collect(),
            delta_log_likelihood: 0.0,
            bic_penalty: 0.0,
            interval: None,
        };
        Some((effect, added))
    }

    /// Two families whose lines the data carry equally: the best is not identifiable, the
    /// other its rival.
    fn tie(&self, a: &FamilyFit, b: &FamilyFit) -> Vec<NotIdentifiable> {
        let label = |f: &FamilyFit| {
            let (bearing, spec) = self.bearing_specs().into_iter().find(|(_, s)| s.name == f.bearing)?;
            let (line, order) = family_line(f.family, &spec.orders);
            Some(self.label(&Effect::BearingDefect { bearing, line, order_milli: (order * 1e3).round() as u32 }))
        };
        let Some(best) = label(a) else { return Vec::new() };
        let reason = format!(
            "the envelope carries the {} family at {} (score {:.1}) and the {} family at {} (score {:.1}) about \
             equally (within a factor 10^{:.0}): these sensors cannot tell which",
            a.family.name(),
            a.bearing,
            a.score,
            b.family.name(),
            b.bearing,
            b.score,
            family::TIE_MARGIN
        );
        let mut n = NotIdentifiable::of(&best, "family_score_gap", a.score - b.score, reason);
        n.rivals =
            label(b).map(|l| format!("{} at {} ({})", l.kind, l.location, b.family.name())).into_iter().collect();
        vec![n]
    }

    /// Every defect line of every bearing with a geometry, at the running speed: an inner-race
    /// defect turns with the shaft through the load zone (modulated at the shaft's rate), a
    /// rolling element with the cage (at the cage's, FTF). A line found on an integer order of
    /// the shaft speed is refused by the stage (a synchronous modulation looks the same).
    fn impact_lines(&self) -> Vec<ImpactLine<Effect>> {
        let shaft_hz = self.red.speed / TAU;
        self.lines
            .iter()
            .map(|&(bearing, line, order)| {
                let cage = self.lines.iter().find(|(b, l, _)| *b == bearing && *l == BearingLine::Ftf).map(|x| x.2);
                let modulation_hz = match line {
                    BearingLine::Bpfi => Some(shaft_hz),
                    BearingLine::Bsf => cage.map(|c| c * shaft_hz),
                    BearingLine::Bpfo | BearingLine::Ftf => None,
                };
                let order_milli = (order * 1e3).round() as u32;
                ImpactLine {
                    effect: Effect::BearingDefect { bearing, line, order_milli },
                    hz: order * shaft_hz,
                    modulation_hz,
                    synchronous_hz: Some(shaft_hz),
                }
            })
            .collect()
    }

    /// Takes `signal` (in the channel's unit) out of channel `channel` of the data: the
    /// vibration of the impacts the first stage found, so that later runs do not see it.
    fn subtract(&mut self, channel: usize, signal: &[f64]) -> Result<()> {
        let col = self.columns.get_mut(channel).ok_or_else(|| anyhow!("no channel #{channel}"))?;
        if col.len() != signal.len() {
            return Err(anyhow!("a signal of {} samples for a channel of {}", signal.len(), col.len()));
        }
        col.iter_mut().zip(signal).for_each(|(v, s)| *v -= s);
        Ok(())
    }
}

/// The line a family is reported by (the ball's by its spin) and its order.
fn family_line(f: Family, k: &Kinematics) -> (BearingLine, f64) {
    match f {
        Family::OuterRace => (BearingLine::Bpfo, k.bpfo),
        Family::InnerRace => (BearingLine::Bpfi, k.bpfi),
        Family::Ball => (BearingLine::Bsf, k.bsf),
    }
}

/// The detector's verdict in a line: the family, its bearing, score and kinematic factor.
pub(super) fn describe(d: &Diagnosis) -> String {
    let fit = |f: &FamilyFit| {
        format!("{} at {} (score {:.1}, lines ×{:.4})", f.family.name(), f.bearing, f.score, 1.0 + f.slip)
    };
    match &d.verdict {
        Verdict::Named(f) => format!("{} at a shaft speed of {:.3} Hz", fit(f), d.shaft.hz),
        Verdict::CannotTell(a, b) => format!("cannot tell {} from {}", fit(a), fit(b)),
        Verdict::Nothing => match d.families.first() {
            Some(best) => format!("no family carried; the strongest, {}, is within chance", fit(best)),
            None => "no family carried".to_string(),
        },
    }
}

/// The detector's verdict for `report.json`'s `bearing_families`: `verdict` (`named`,
/// `cannot_tell`, `nothing`), the shaft speed it read, and every family with its score.
pub(super) fn summary(d: &Diagnosis) -> serde_json::Value {
    let fit = |f: &FamilyFit| {
        serde_json::json!({
            "family": f.family.name(),
            "bearing": f.bearing,
            "score": f.score,
            "carried": f.carried,
            "line_factor": 1.0 + f.slip,
            "channel": f.channel,
            "band_hz": [f.band.low_hz, f.band.high_hz],
            "members": f.members.iter().filter(|m| !m.on_order && m.strength_db >= family::CARRY.min_db)
                .map(|m| serde_json::json!({"label": m.label, "hz": m.hz, "strength_db": m.strength_db}))
                .collect::<Vec<_>>(),
        })
    };
    let (verdict, named, rival) = match &d.verdict {
        Verdict::Named(f) => ("named", Some(fit(f)), None),
        Verdict::CannotTell(a, b) => ("cannot_tell", Some(fit(a)), Some(fit(b))),
        Verdict::Nothing => ("nothing", None, None),
    };
    serde_json::json!({
        "verdict": verdict,
        "named": named,
        "rival": rival,
        "shaft_hz": d.shaft.hz,
        "families": d.families.iter().map(|f| serde_json::json!({
            "family": f.family.name(), "bearing": f.bearing, "score": f.score, "carried": f.carried,
        })).collect::<Vec<_>>(),
    })
}
