//! The rotor's bearings in the loop: their defect lines at the running speed, looked for in the
//! envelope of the base model's innovations before the search ([`impacts`]), and the impacts'
//! vibration taken out of the data once a defect is named.

use super::effects::Effect;
use super::RotorSystem;
use crate::diagnostics::bearings::impacts::{self, ImpactLine};
use crate::residual_loop::filter::Run;
use crate::residual_loop::{search_staged, EffectKind, LoopOptions, LoopReport, LoopSystem, PreStage};
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
        let lines = self.impact_lines();
        let traces = self.traces();
        let found = impacts::stage(&lines, |e| self.label(e), run, &traces, &self.rotor.envelope, options.half_gain);
        for (channel, signal) in &found.signals {
            self.subtract(*channel, signal)?;
        }
        if options.progress {
            for (_, a) in &found.added {
                eprintln!(
                    "loop: impacts {} at {}: Δ log-likelihood {:.1}, BIC cost {:.1}",
                    a.kind, a.location, a.delta_log_likelihood, a.bic_penalty
                );
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
            data_changed: !found.signals.is_empty(),
            added: found.added,
            trials: found.trials,
            refused: found.refused,
            excludes,
        })
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
