//! The search, written against [`LoopSystem`] so every system of edgekf goes through the same
//! engine: candidates from the signatures, each fitted (its states by the filter, its scalar by
//! maximum likelihood, [`fit`](super::fit)) and kept only if it pays for its parameters (BIC)
//! in both halves of the run; then what the data cannot tell is screened
//! ([`identifiability`](super::identifiability)) and what is left is reported.
//!
//! A system supplies the filter runs, the summaries and the candidates; the engine owns the
//! acceptance rule, the identifiability verdicts and the report, so they read the same for a
//! machine, a mechanism or a vehicle.

use super::correction::EffectCorrection;
use super::filter::Run;
use super::fit::{Engine, Fitted, Round};
use super::options::LoopOptions;
use super::report::{AddedEffect, LoopReport, NotIdentifiable, Refused, Source, Traces, Trial, SCHEMA_VERSION};
use super::signature::{unexplained, RunSummary, Signature};
use super::system::Described;
use super::system::{LoopSystem, PreStage};
use super::tuning::tune;
use super::vocabulary::{Applied, EffectKind, EffectLabel};
use anyhow::Result;

/// How many places a winner may move along its neighbours ([`Rivals::neighbours`](super::system::Rivals::neighbours)).
const CLIMB_STEPS: usize = 4;

/// An effect kept, with the lines it explained.
struct Kept<E> {
    applied: Applied<E>,
    delta: f64,
    penalty: f64,
    label: EffectLabel,
    explains: Vec<f64>,
}

/// Frequencies (Hz) of the lines in `before` that `after` no longer has (per channel, within
/// two bins).
fn explained(before: &RunSummary, after: &RunSummary) -> Vec<f64> {
    let tol = 2.0 * before.bin_width_hz.max(after.bin_width_hz);
    let mut out: Vec<f64> = Vec::new();
    for (b, a) in before.channels.iter().zip(&after.channels) {
        for p in &b.peaks {
            let gone = !a.peaks.iter().any(|q| (q.frequency_hz - p.frequency_hz).abs() <= tol);
            if gone && !out.iter().any(|f| (f - p.frequency_hz).abs() <= tol) {
                out.push((p.frequency_hz * 100.0).round() / 100.0);
            }
        }
    }
    out.sort_by(f64::total_cmp);
    out
}

/// Why `e` is not fitted after what the system's first stage kept (its
/// [`excludes`](PreStage::excludes)); `None` if it is fitted as usual.
fn excluded<S: LoopSystem>(sys: &S, e: &S::Effect, excludes: &[(EffectKind, String)]) -> Option<Refused> {
    let label = sys.label(e);
    let (_, reason) = excludes.iter().find(|(kind, _)| *kind == label.kind)?;
    Some(Refused::of(&label, None, reason.clone()))
}

/// Of `candidates`, the ones worth fitting, each once: not in the model already, not `seen`
/// (fitted before), and not [`excluded`] (whose refusal is recorded in `refused`, once). The
/// one filter of a tier's candidates and of a winner's neighbours.
fn fresh<S: LoopSystem>(
    sys: &S,
    candidates: impl IntoIterator<Item = S::Effect>,
    seen: impl Fn(&S::Effect) -> bool,
    st: &mut State<S::Effect, S::Model>,
) -> Vec<S::Effect> {
    let mut out: Vec<S::Effect> = Vec::new();
    for e in candidates {
        if st.effects.iter().any(|x| x.effect == e) || out.contains(&e) || seen(&e) {
            continue;
        }
        match excluded(sys, &e, &st.excludes) {
            Some(r) if !st.refused.contains(&r) => st.refused.push(r),
            Some(_) => {}
            None => out.push(e),
        }
    }
    out
}

/// Where the search stands: the current model and what has been decided so far.
struct State<E, M> {
    effects: Vec<Applied<E>>,
    model: M,
    run: Run,
    summary: RunSummary,
    added: Vec<Kept<E>>,
    trials: Vec<Trial>,
    not_identifiable: Vec<NotIdentifiable>,
    partial: Vec<Signature>,
    refused: Vec<Refused>,
    /// Kinds not fitted after the first stage, with the reason.
    excludes: Vec<(EffectKind, String)>,
}

impl<S: LoopSystem> Engine<'_, S> {
    /// One iteration: each tier of candidates fitted until one pays, the best kept. `Err` with
    /// the reason the search stops when none does.
    fn iterate(&mut self, st: &mut State<S::Effect, S::Model>, iteration: usize) -> Result<(), String> {
        let tiers = self.sys.candidates(&st.summary, &st.run, &st.model, &st.effects);
        self.iterate_over(st, iteration, tiers)
    }

    /// Once the innovations look consistent: the declared settings the score test finds worth
    /// fitting ([`score`](super::score)), fitted as one tier. `Err` when none is or none pays.
    fn iterate_declared(&mut self, st: &mut State<S::Effect, S::Model>, iteration: usize) -> Result<(), String> {
        self.nis_scale = st.summary.nis_scale();
        let tier = self.declared_worth_fitting(&st.effects, &st.run);
        if tier.is_empty() {
            return Err(String::new());
        }
        self.progress(|| {
            format!("iteration {iteration}: the innovations pass; {} declared setting(s) worth fitting", tier.len())
        });
        self.iterate_over(st, iteration, vec![tier])
    }

    /// [`Self::iterate`] over the given tiers of candidates.
    fn iterate_over(
        &mut self,
        st: &mut State<S::Effect, S::Model>,
        iteration: usize,
        tiers: Vec<Vec<S::Effect>>,
    ) -> Result<(), String> {
        let sys = self.sys;
        self.nis_scale = st.summary.nis_scale();
        let mut chosen = None;
        let mut undecided = None;
        let mut evaluated = Vec::new();
        for (tier_index, tier) in tiers.into_iter().enumerate() {
            let fresh = fresh(sys, tier, |_| false, st);
            if chosen.is_some() || undecided.is_some() || fresh.is_empty() {
                continue;
            }
            let at = Round { iteration, tier: tier_index + 1 };
            let sinks = (&mut st.refused, &mut st.not_identifiable);
            let mut results = self.fit_all(at, &st.effects, fresh, &st.run, sinks);
            let best = self.best_paying(&results).map(|i| self.climb(at, st, &mut results, i));
            for f in results.iter().filter(|f| f.delta > f.penalty && !self.pays_in_halves(f)) {
                st.partial.push(self.partial(f));
                st.refused.push(self.refused_in_halves(f));
            }
            match best.map(|i| (i, self.choose(&results, i))) {
                Some((_, Some(i))) => {
                    let winner = results.swap_remove(i);
                    st.not_identifiable.extend(self.rivals(&st.effects, &winner, &results));
                    chosen = Some(winner);
                }
                Some((i, None)) => {
                    let (unseen, why) = self.undecided(&results, i);
                    st.not_identifiable.extend(unseen);
                    undecided = Some(why);
                }
                None => {}
            }
            evaluated.extend(results);
        }
        for f in &evaluated {
            st.trials.push(self.trial(iteration, f, false));
        }
        let Some(win) = chosen else {
            if let Some(why) = undecided {
                return Err(why);
            }
            let best = evaluated.iter().max_by(|a, b| (a.delta - a.penalty).total_cmp(&(b.delta - b.penalty)));
            return Err(match best {
                Some(f) => {
                    format!("no candidate pays for itself in both halves of the run (best: {})", self.describe(f))
                }
                None => "no candidate effect matches the remaining signatures".into(),
            });
        };
        self.keep(st, iteration, win);
        Ok(())
    }

    /// The paying fit of `results` that gains most over its cost.
    fn best_paying(&self, results: &[Fitted<S::Effect, S::Model>]) -> Option<usize> {
        results
            .iter()
            .enumerate()
            .filter(|(_, f)| self.pays(f))
            .max_by(|a, b| (a.1.delta - a.1.penalty).total_cmp(&(b.1.delta - b.1.penalty)))
            .map(|(i, _)| i)
    }

    /// From the best fit `i` of `results`, fits its neighbours
    /// ([`Rivals::neighbours`](super::system::Rivals::neighbours)) that are [`fresh`] (the filter
    /// of a tier's candidates) and not fitted yet, and moves to the best while that changes, at
    /// most [`CLIMB_STEPS`] times: the
    /// system's proposal places an effect only roughly, the fits decide. The neighbours' fits
    /// join `results`, so that the ones the data cannot tell from the winner are listed as its
    /// rivals. Returns the best's index in the grown `results`.
    fn climb(
        &self,
        at: Round,
        st: &mut State<S::Effect, S::Model>,
        results: &mut Vec<Fitted<S::Effect, S::Model>>,
        mut i: usize,
    ) -> usize {
        for _ in 0..CLIMB_STEPS {
            let neighbours = self.sys.rivals(&results[i].applied.effect, &st.effects).neighbours;
            let next = fresh(self.sys, neighbours, |e| results.iter().any(|f| f.applied.effect == *e), st);
            if next.is_empty() {
                break;
            }
            let sinks = (&mut st.refused, &mut st.not_identifiable);
            results.extend(self.fit_all(at, &st.effects, next, &st.run, sinks));
            match self.best_paying(results) {
                Some(b) if b != i => i = b,
                _ => break,
            }
        }
        i
    }

    /// Drops an effect that no longer pays for itself once the effects added after it are in
    /// (they explain what it stood in for: an offset taken up first by a channel that a wrong
    /// constant skewed): backward elimination, one effect at a time, each against its own cost.
    /// A dropped effect is refused, with what it would have gained.
    fn prune(&self, st: &mut State<S::Effect, S::Model>) {
        'again: while st.effects.len() >= 2 {
            let full = st.run.log_likelihood();
            // The last one was kept against all the others already.
            for i in 0..st.effects.len() - 1 {
                let mut without = st.effects.clone();
                let gone = without.remove(i);
                let Ok((model, run)) = self.sys.run(&without) else { continue };
                let (loss, penalty) = (full - run.log_likelihood(), self.penalty(&gone.effect, gone.onset_s.is_some()));
                if loss > penalty {
                    continue;
                }
                let value = self.sys.value(&st.model, &st.run, &gone);
                let kept = st.added.remove(i);
                self.progress(|| {
                    format!("dropped {} at {}: the later effects explain it", kept.label.kind, kept.label.location)
                });
                st.refused.push(Refused::of(
                    &kept.label,
                    Some(value),
                    format!(
                        "added first (Δ log-likelihood {:.1}), then explained by the effects added after it: with them in, it gains only {loss:.1}, less than its cost of {penalty:.1}",
                        kept.delta
                    ),
                ));
                st.effects = without;
                (st.model, st.run) = (model, run);
                st.summary = self.sys.summarise(&st.run);
                continue 'again;
            }
            break;
        }
    }

    /// What the report lists as added, in order (the first stage's, then the search's, each
    /// with its interval in the final model at the final model's NIS), and each one's
    /// correction of the configuration.
    fn findings(
        &mut self,
        st: &State<S::Effect, S::Model>,
        first: Vec<(S::Effect, AddedEffect)>,
    ) -> (Vec<AddedEffect>, Vec<EffectCorrection>) {
        let named = |e: &AddedEffect| format!("{} at {}", e.kind.as_str(), e.location);
        let mut corrections: Vec<EffectCorrection> = first
            .iter()
            .map(|(e, a)| EffectCorrection {
                effect: named(a),
                correction: self.sys.correction(&Applied::new(*e, 0.0), a.value),
            })
            .collect();
        let mut effects_added: Vec<AddedEffect> = first
            .into_iter()
            .map(|(_, a)| a)
            .chain(st.added.iter().map(|f| AddedEffect {
                kind: f.label.kind,
                location: f.label.location.clone(),
                value: self.sys.value(&st.model, &st.run, &f.applied),
                unit: f.label.unit.clone(),
                detail: f.label.detail.clone(),
                explains: f.explains.clone(),
                delta_log_likelihood: f.delta,
                bic_penalty: f.penalty,
                interval: None,
            }))
            .collect();
        // Each added effect's interval in the final model, at the final model's NIS.
        self.nis_scale = st.summary.nis_scale();
        let intervals: Vec<Option<[f64; 2]>> =
            (0..st.effects.len()).map(|i| self.interval(&st.effects, i, &st.model, &st.run)).collect();
        for (e, interval) in effects_added[corrections.len()..].iter_mut().zip(intervals) {
            e.interval = interval;
        }
        for (f, e) in st.added.iter().zip(&effects_added[corrections.len()..]) {
            corrections
                .push(EffectCorrection { effect: named(e), correction: self.sys.correction(&f.applied, e.value) });
        }
        (effects_added, corrections)
    }

    /// Puts `win` into the model.
    fn keep(&self, st: &mut State<S::Effect, S::Model>, iteration: usize, win: Fitted<S::Effect, S::Model>) {
        st.trials.push(self.trial(iteration, &win, true));
        self.progress(|| format!("iteration {iteration}: kept {}", self.describe(&win)));
        let next = self.sys.summarise(&win.run);
        let explains = explained(&st.summary, &next);
        st.effects.push(win.applied);
        st.added.push(Kept {
            applied: win.applied,
            delta: win.delta,
            penalty: win.penalty,
            label: win.label,
            explains,
        });
        (st.model, st.run) = (win.model, win.run);
        st.summary = next;
    }
}

/// One verdict per effect: what was added is not also unseen, what the data cannot see is not
/// also refused (a fit that ran to the edge of a flat likelihood says nothing about a bound),
/// and an effect found unseen in several iterations is listed once.
fn one_verdict_each<E, M>(st: &mut State<E, M>) {
    st.not_identifiable.retain(|n| !st.added.iter().any(|f| n.names(&f.label)));
    let mut once: Vec<NotIdentifiable> = Vec::new();
    for n in std::mem::take(&mut st.not_identifiable) {
        if !once.iter().any(|m| m.is_about(&n)) {
            once.push(n);
        }
    }
    st.not_identifiable = once;
    let unseen = &st.not_identifiable;
    st.refused.retain(|r| !unseen.iter().any(|n| r.is_about(n)));
}

/// Closes the loop on `sys`: runs its base model, then adds effects while the innovations are
/// not consistent and an effect pays for its parameters (BIC) in both halves of the run (of
/// the stretch after its onset, for an effect that starts mid-run); then screens what the data
/// cannot see and reports what is left.
pub fn search<S: LoopSystem>(sys: &mut S, options: &LoopOptions) -> Result<LoopReport> {
    search_staged(sys, options, |_, _| Ok(PreStage::default()))
}

/// [`search`] with the system's own first stage run on the base model's run before the
/// search: what it names is reported as added, and what it explains it may take out of the
/// system's data ([`PreStage::data_changed`]), so that the search neither sees it nor stands
/// something else in for it.
pub fn search_staged<S: LoopSystem>(
    sys: &mut S,
    options: &LoopOptions,
    first_stage: impl FnOnce(&mut S, &Run) -> Result<PreStage<S::Effect>>,
) -> Result<LoopReport> {
    let traces = sys.traces();
    if options.progress {
        eprintln!("loop: running the base model");
    }
    let (mut model, mut run) = sys.run(&[])?;
    let base_run = run.clone();
    let before = sys.summarise(&run);
    let tuning = tune(sys, &run, options)?;
    let tuning = tuning.map(|t| {
        (model, run) = (t.model, t.run);
        (t.tuning, t.correction)
    });
    let PreStage { added: first, trials, refused, excludes, data_changed, not_identifiable } = first_stage(sys, &run)?;
    if data_changed {
        (model, run) = sys.run(&[])?;
    }
    let sys = &*sys;
    let mut engine =
        Engine { sys, options, t: traces.t.clone(), n_meas: run.measurements().max(2) as f64, nis_scale: 1.0 };
    let summary = sys.summarise(&run);
    let mut st = State {
        effects: Vec::new(),
        model,
        run,
        summary,
        added: Vec::new(),
        trials,
        not_identifiable,
        partial: Vec::new(),
        refused,
        excludes,
    };
    let mut iteration = 0;
    let mut scored = !options.screen_parameters;
    let stopped = loop {
        if st.summary.consistent {
            let consistent = "the innovations are white, unbiased and NIS-consistent".to_string();
            if scored || st.effects.len() >= options.max_effects {
                break consistent;
            }
            scored = true;
            iteration += 1;
            match engine.iterate_declared(&mut st, iteration) {
                Ok(()) => continue,
                Err(why) if why.is_empty() => break consistent,
                Err(why) => break format!("{consistent}; {why}"),
            }
        }
        if st.effects.len() >= options.max_effects {
            break format!("reached the limit of {} effects", options.max_effects);
        }
        iteration += 1;
        if let Err(why) = engine.iterate(&mut st, iteration) {
            break why;
        }
    };
    engine.prune(&mut st);
    if options.screen_parameters {
        st.not_identifiable.extend(engine.screen(&st.effects, &st.run));
    }
    one_verdict_each(&mut st);
    let (effects_added, mut corrections) = engine.findings(&st, first);
    let unexplained = if st.summary.consistent {
        Vec::new()
    } else {
        let mut u = unexplained(&st.summary, &options.signatures);
        u.extend(st.partial);
        u
    };
    let section = sys.section(&st.model, &st.run);
    let tuning = tuning.map(|(tuning, correction)| {
        corrections.push(correction);
        tuning
    });
    Ok(LoopReport {
        schema_version: SCHEMA_VERSION,
        system: S::NAME.to_string(),
        source: Source { version: env!("CARGO_PKG_VERSION").into(), ..Source::default() },
        effects_added,
        corrections,
        tuning,
        before,
        after: st.summary,
        not_identifiable: st.not_identifiable,
        unexplained,
        refused: st.refused,
        trials: st.trials,
        stopped,
        section,
        traces: Traces { before: base_run, after: st.run, ..traces },
    })
}
