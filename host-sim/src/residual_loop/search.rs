//! The search, written against [`LoopSystem`] so every system of edgekf goes through the same
//! engine: candidates from the signatures, each fitted (its states by the filter, its scalar by
//! maximum likelihood) and kept only if it pays for its parameters (BIC) in both halves of the
//! run; then what is left is reported.
//!
//! A system supplies the filter runs, the summaries and the candidates; the engine owns the
//! acceptance rule, the identifiability verdicts and the report, so they read the same for a
//! machine, a mechanism or a vehicle.

use super::bounds::OUTSIDE;
use super::envelope::LineSearch;
use super::filter::Run;
use super::impacts::{self, ImpactLine};
use super::onset;
use super::optimize::{maximise, ScalarRange};
use super::signature::{unexplained, Signature, SignatureOptions};
use anyhow::{anyhow, Result};
use std::fmt::Debug;

pub use super::report::{
    AddedEffect, LoopReport, NotIdentifiable, Refused, Source, SystemSection, Traces, Trial, SCHEMA_VERSION,
};
pub use super::signature::{Channel, ChannelSignature, PeakSignature, RunSummary};
pub use super::vocabulary::{Applied, EffectDetail, EffectKind, EffectLabel};

/// How the loop runs (the engine's own settings; a system's tuning is its own data).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopOptions {
    /// What counts as a signature.
    pub signatures: SignatureOptions,
    /// At most this many effects are added.
    pub max_effects: usize,
    /// Each half of the run must gain at least this fraction of an effect's BIC cost: an
    /// effect that only helps part of the run is not a constant property of the machine.
    pub half_gain: f64,
    /// Log-likelihood per scalar measurement an effect must gain beyond its BIC cost: what a
    /// healthy baseline's own record would still gain from its best next effect (0 without
    /// a baseline). A change must be larger than what the healthy machine leaves unexplained.
    /// It is scaled by the current model's NIS per channel (at least 1): on a record whose
    /// innovations carry k times the power the model expects, a wrong effect gains about k
    /// times more.
    pub gain_floor: f64,
    /// Two locations of the same kind whose log-likelihoods differ by less than this are
    /// reported as not identifiable from each other.
    pub identifiable_margin: f64,
    /// Check at the end which component parameters the data cannot see (halving or doubling
    /// each changes the log-likelihood by less than its BIC cost).
    pub screen_parameters: bool,
    /// How the lines of periodic impacts are looked for in the innovations' envelope
    /// ([`LoopSystem::impact_lines`]).
    pub envelope: LineSearch,
    /// Print progress to standard error.
    pub progress: bool,
}

impl Default for LoopOptions {
    fn default() -> Self {
        Self {
            signatures: SignatureOptions::default(),
            max_effects: 4,
            half_gain: 0.25,
            gain_floor: 0.0,
            identifiable_margin: 2.0,
            screen_parameters: true,
            envelope: LineSearch::default(),
            progress: false,
        }
    }
}

/// A system the loop can be closed on: a base model with a filter, a library of effects that
/// augment it, and the data. The engine ([`search`]) asks it for filter runs with a list of
/// effects, for summaries of those runs and for candidates; everything else (acceptance,
/// identifiability, the report) is the engine's.
///
/// An effect is an [`Applied`]: what and where (`Self::Effect`), the scalar θ the engine fits
/// by maximum likelihood when [`LoopSystem::scalar`] gives it a range (0 otherwise), and, for
/// effects the system says [may start mid-run](LoopSystem::may_start_mid_run), the onset the
/// engine fits with it.
pub trait LoopSystem: Sync {
    /// One augmentation at one place.
    type Effect: Copy + PartialEq + Debug + Send + Sync;
    /// What a run was made with (the system reads effect values from it).
    type Model: Send;
    /// The system's name in the report.
    fn name(&self) -> &str;
    /// Runs the filter with `effects` over the whole recording; an effect with an
    /// [`onset_s`](Applied::onset_s) acts from that time on and is absent before it.
    fn run(&self, effects: &[Applied<Self::Effect>]) -> Result<(Self::Model, Run)>;
    /// The innovations' statistics and the virtual-sensing error of a run.
    fn summarise(&self, run: &Run) -> RunSummary;
    /// Candidates for the next effect, given the current model's `effects`, its `run` (and
    /// what it was made with, `model`) and the run's summary, in tiers: a later tier is tried
    /// only when no candidate of an earlier one is kept (the catch-all goes last). The engine
    /// drops effects already in the model. A system with many places an effect could act
    /// ranks them from the run's innovations ([`direction`](super::direction)) and proposes
    /// the few they point to.
    fn candidates(
        &self,
        summary: &RunSummary,
        run: &Run,
        model: &Self::Model,
        effects: &[Applied<Self::Effect>],
    ) -> Vec<Vec<Self::Effect>>;
    /// How `effect` reads in the report.
    fn label(&self, effect: &Self::Effect) -> EffectLabel;
    /// Free parameters `effect` costs in the BIC (an onset, when fitted, costs one more).
    fn parameters(&self, effect: &Self::Effect) -> usize;
    /// The range of the effect's scalar and the grid points to search it with, if it has one.
    fn scalar(&self, effect: &Self::Effect) -> Option<(ScalarRange, usize)>;
    /// The largest size the model allows `effect`'s [`value`](LoopSystem::value) to reach
    /// (a force's bound, [`bounds`](super::bounds)), if it has one beside its scalar's range: a
    /// fit beyond it is refused as [`OUTSIDE`] what the model allows. None by default.
    fn limit(&self, _effect: &Self::Effect) -> Option<f64> {
        None
    }
    /// The size the report gives `effect` in the model of `run` (a state's size over the
    /// settled part of the effect's stretch: [`onset::settled_mean`]).
    fn value(&self, model: &Self::Model, run: &Run, effect: &Applied<Self::Effect>) -> f64;
    /// Whether `effect` may begin mid-run (a fault, a knock on the sensor, a part working
    /// loose): the engine then also fits it with an onset, and tests the halves of the stretch
    /// after the onset. Only systems whose [`run`](LoopSystem::run) honours
    /// [`Applied::onset_s`] may say yes; none by default.
    fn may_start_mid_run(&self, _effect: &Self::Effect) -> bool {
        false
    }
    /// Effects to screen at the end for identifiability, each with the scalars to try (a
    /// component parameter halved and doubled): if none of them changes the log-likelihood by
    /// more than the effect's BIC cost, the data cannot see it. None by default.
    fn screened(&self) -> Vec<(Self::Effect, Vec<f64>)> {
        Vec::new()
    }
    /// Periodic impacts the system can name (a bearing's defect lines at the running speed),
    /// looked for in the envelope of the base model's innovations before anything else (see
    /// [`impacts`]); none by default.
    fn impact_lines(&self) -> Vec<ImpactLine<Self::Effect>> {
        Vec::new()
    }
    /// Takes `signal` (in the channel's unit) out of channel `channel` of the data: the
    /// vibration of impacts the first stage found, so that later runs do not see it. Needed
    /// only by systems with [`impact_lines`](LoopSystem::impact_lines).
    fn subtract(&mut self, channel: usize, signal: &[f64]) -> Result<()> {
        let _ = (channel, signal);
        Err(anyhow!("{} cannot take a signal out of its data", self.name()))
    }
    /// Time, channels, virtual rows and truth for the report's plots (the engine fills in
    /// the runs before and after).
    fn traces(&self) -> Traces;
    /// The system's own part of the report, from the model and run the loop ended with (none
    /// by default).
    fn section(&self, _model: &Self::Model, _run: &Run) -> SystemSection {
        SystemSection::default()
    }
}

/// A fit at or beyond what the model allows ([`bounds`](super::bounds)): refused, with the
/// value it reached.
#[derive(Debug)]
struct OutOfBounds {
    value: f64,
    why: String,
}

impl std::fmt::Display for OutOfBounds {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", OUTSIDE, self.why)
    }
}

impl std::error::Error for OutOfBounds {}

/// A candidate fitted to the data.
struct Fitted<E, M> {
    applied: Applied<E>,
    model: M,
    run: Run,
    delta: f64,
    halves: [f64; 2],
    penalty: f64,
    label: EffectLabel,
}

/// An effect kept, with the lines it explained.
struct Kept<E> {
    applied: Applied<E>,
    delta: f64,
    penalty: f64,
    label: EffectLabel,
    explains: Vec<f64>,
}

/// The engine's view of a system during one search.
struct Engine<'a, S: LoopSystem> {
    sys: &'a S,
    options: &'a LoopOptions,
    /// Sample times of the data, s.
    t: Vec<f64>,
    /// Scalar measurements in the run (for the BIC).
    n_meas: f64,
    /// The current model's NIS per channel, at least 1 (scales the gain floor).
    nis_scale: f64,
}

impl<S: LoopSystem> Engine<'_, S> {
    /// `½ p ln n` for the effect's parameters, and one more for a fitted onset, plus the
    /// baseline's [`gain_floor`](LoopOptions::gain_floor) over the run.
    fn penalty(&self, e: &S::Effect, onset: bool) -> f64 {
        self.bic(e, onset) + self.options.gain_floor * self.nis_scale * self.n_meas
    }

    /// `½ p ln n` alone.
    fn bic(&self, e: &S::Effect, onset: bool) -> f64 {
        0.5 * (self.sys.parameters(e) + usize::from(onset)) as f64 * self.n_meas.ln()
    }

    /// Fits `cand` on top of `effects`: present from the start and, if it may start mid-run,
    /// with a fitted onset; the better of the two (one that pays for itself first).
    fn fit(&self, effects: &[Applied<S::Effect>], cand: S::Effect, base: &Run) -> Result<Fitted<S::Effect, S::Model>> {
        let whole = self.fit_from(effects, cand, None, base);
        if !self.sys.may_start_mid_run(&cand) {
            return whole;
        }
        let late = self.fit_onset(effects, cand, base, whole.as_ref().ok());
        let rank = |f: &Fitted<S::Effect, S::Model>| (self.pays(f), f.delta - f.penalty);
        match (whole, late) {
            (Ok(w), Ok(l)) => Ok(if rank(&l) > rank(&w) { l } else { w }),
            (Ok(f), Err(_)) | (Err(_), Ok(f)) => Ok(f),
            (Err(e), Err(_)) => Err(e),
        }
    }

    /// Fits `cand` acting from `onset_s` (from the start if `None`): its scalar by maximum
    /// likelihood, its states by the filter.
    fn fit_from(
        &self,
        effects: &[Applied<S::Effect>],
        cand: S::Effect,
        onset_s: Option<f64>,
        base: &Run,
    ) -> Result<Fitted<S::Effect, S::Model>> {
        let with = |theta: f64| {
            let mut e = effects.to_vec();
            e.push(Applied { effect: cand, theta, onset_s });
            e
        };
        let theta = match self.sys.scalar(&cand) {
            Some((range, grid)) => {
                let x = maximise(
                    |th| self.sys.run(&with(th)).ok().map(|(_, r)| r.log_likelihood()),
                    range.low,
                    range.high,
                    grid,
                    range.tolerance,
                )
                .ok_or_else(|| anyhow!("no value of the scalar gives a usable model"))?
                .x;
                // A likelihood still rising at the edge of the range has no maximum there: the
                // effect is standing in for something else, and its value would be the range's.
                // (An edge where the effect is neutral is a legitimate answer.)
                let edge = (10.0 * range.tolerance).max(0.01 * (range.high - range.low));
                let at = |bound: f64| (x - bound).abs() <= edge && bound != range.neutral;
                if at(range.low) || at(range.high) {
                    let shown = |v: f64| if range.log { v.exp() } else { v };
                    return Err(OutOfBounds {
                        value: shown(x),
                        why: format!(
                            "the likelihood still rises at the edge of the range it may take ({:.4} … {:.4})",
                            shown(range.low),
                            shown(range.high)
                        ),
                    }
                    .into());
                }
                x
            }
            None => 0.0,
        };
        let applied = Applied { effect: cand, theta, onset_s };
        let (model, run) = self.sys.run(&with(theta))?;
        if let Some(limit) = self.sys.limit(&cand) {
            let value = self.sys.value(&model, &run, &applied);
            if value.abs() > limit {
                let unit = self.sys.label(&cand).unit;
                return Err(OutOfBounds {
                    value,
                    why: format!("{value:.4} {unit} beyond the bound of {limit:.4} {unit}"),
                }
                .into());
            }
        }
        let delta = run.log_likelihood() - base.log_likelihood();
        let halves = onset::halves(&run, base, applied.first_sample(&self.t));
        let mut label = self.sys.label(&cand);
        label.detail.onset_s = onset_s;
        let penalty = self.penalty(&cand, onset_s.is_some());
        Ok(Fitted { applied, model, run, delta, halves, penalty, label })
    }

    /// Fits `cand` with an onset: placed where the gain of the whole-run fit `whole` starts to
    /// accumulate (or on a coarse grid when there is none), refined with the scalar held, and
    /// the scalar refitted there.
    fn fit_onset(
        &self,
        effects: &[Applied<S::Effect>],
        cand: S::Effect,
        base: &Run,
        whole: Option<&Fitted<S::Effect, S::Model>>,
    ) -> Result<Fitted<S::Effect, S::Model>> {
        let n = base.nis.len().min(self.t.len());
        let (lo, hi) = onset::window(n).ok_or_else(|| anyhow!("the run is too short to place an onset in"))?;
        let (k0, first) = match whole {
            Some(w) => {
                let k = onset::change_point(&w.run, base, lo, hi);
                (k, self.fit_from(effects, cand, Some(self.t[k]), base)?)
            }
            None => onset::grid(lo, hi)
                .filter_map(|k| self.fit_from(effects, cand, Some(self.t[k]), base).ok().map(|f| (k, f)))
                .max_by(|a, b| a.1.delta.total_cmp(&b.1.delta))
                .ok_or_else(|| anyhow!("no onset gives a usable model"))?,
        };
        let theta = first.applied.theta;
        let sample = |k: f64| (k.round().max(0.0) as usize).clamp(lo, hi);
        let reach = ((hi - lo) / 10).max(2);
        let refined = maximise(
            |k| {
                let mut e = effects.to_vec();
                e.push(Applied { effect: cand, theta, onset_s: Some(self.t[sample(k)]) });
                self.sys.run(&e).ok().map(|(_, r)| r.log_likelihood())
            },
            k0.saturating_sub(reach).max(lo) as f64,
            (k0 + reach).min(hi) as f64,
            6,
            0.5,
        );
        let k1 = refined.map_or(k0, |m| sample(m.x));
        if k1 == k0 {
            return Ok(first);
        }
        let second = self.fit_from(effects, cand, Some(self.t[k1]), base)?;
        Ok(if second.delta >= first.delta { second } else { first })
    }

    fn reported_value(&self, f: &Fitted<S::Effect, S::Model>) -> Option<f64> {
        let scalar_or_late = self.sys.scalar(&f.applied.effect).is_some() || f.applied.onset_s.is_some();
        scalar_or_late.then(|| self.sys.value(&f.model, &f.run, &f.applied))
    }

    fn trial(&self, iteration: usize, f: &Fitted<S::Effect, S::Model>, accepted: bool) -> Trial {
        Trial {
            iteration,
            kind: f.label.kind,
            location: f.label.location.clone(),
            order: f.label.detail.order,
            parameter: f.label.detail.parameter.clone(),
            onset_s: f.applied.onset_s,
            unit: f.label.unit.clone(),
            value: self.reported_value(f),
            delta_log_likelihood: f.delta,
            delta_halves: f.halves,
            bic_penalty: f.penalty,
            accepted,
        }
    }

    /// `kind at location [from t s]: Δ log-likelihood, BIC cost, halves`.
    fn describe(&self, f: &Fitted<S::Effect, S::Model>) -> String {
        let from = f.applied.onset_s.map(|o| format!(" from {o:.3} s")).unwrap_or_default();
        format!(
            "{} at {}{from}: Δ log-likelihood {:.1}, BIC cost {:.1}, halves {:.1} / {:.1}",
            f.label.kind, f.label.location, f.delta, f.penalty, f.halves[0], f.halves[1]
        )
    }

    fn progress(&self, msg: impl FnOnce() -> String) {
        if self.options.progress {
            eprintln!("loop: {}", msg());
        }
    }

    /// Fits every candidate of `cands` on top of `effects`.
    fn fit_all(
        &self,
        iteration: usize,
        effects: &[Applied<S::Effect>],
        cands: Vec<S::Effect>,
        base: &Run,
        refused: &mut Vec<Refused>,
    ) -> Vec<Fitted<S::Effect, S::Model>> {
        let total = cands.len();
        let fits = parallel_map(&cands, |i, cand| {
            let label = self.sys.label(cand);
            self.progress(|| {
                format!("iteration {iteration}: candidate {}/{total}: {} at {}", i + 1, label.kind, label.location)
            });
            self.fit(effects, *cand, base)
        });
        let mut results = Vec::new();
        for (cand, fit) in cands.iter().zip(fits) {
            let label = self.sys.label(cand);
            match fit {
                Ok(f) => results.push(f),
                Err(e) => {
                    self.progress(|| format!("  {} at {}: {e:#}", label.kind, label.location));
                    refused.push(Refused {
                        kind: label.kind,
                        location: label.location.clone(),
                        value: e.downcast_ref::<OutOfBounds>().map(|o| o.value),
                        reason: format!("{e:#}"),
                    });
                }
            }
        }
        results
    }

    /// Pays for itself: the whole run gains more than the BIC cost, and each half (of the
    /// stretch after the onset, for a change-point effect) at least `half_gain` of it.
    fn pays(&self, f: &Fitted<S::Effect, S::Model>) -> bool {
        f.delta > f.penalty && self.pays_in_halves(f)
    }

    fn pays_in_halves(&self, f: &Fitted<S::Effect, S::Model>) -> bool {
        f.halves[0].min(f.halves[1]) >= self.options.half_gain * f.penalty
    }

    /// Rivals of `winner` among `results`: same family, another location, a log-likelihood
    /// within the identifiability margin.
    fn rivals(
        &self,
        winner: &Fitted<S::Effect, S::Model>,
        results: &[Fitted<S::Effect, S::Model>],
    ) -> Vec<NotIdentifiable> {
        results
            .iter()
            .filter(|f| {
                family(&f.label) == family(&winner.label)
                    && f.label.location != winner.label.location
                    && (winner.delta - f.delta).abs() < self.options.identifiable_margin
            })
            .map(|r| NotIdentifiable {
                kind: winner.label.kind,
                location: r.label.location.clone(),
                parameter: r.label.detail.parameter.clone(),
                statistic: "delta_log_likelihood_gap".into(),
                value: winner.delta - r.delta,
                reason: format!(
                    "fits the data as well as {} (log-likelihoods {:.2} apart): the sensors cannot tell the two apart",
                    winner.label.location,
                    winner.delta - r.delta
                ),
            })
            .collect()
    }

    /// What the halves are of, in words.
    fn stretch(f: &Fitted<S::Effect, S::Model>) -> String {
        match f.applied.onset_s {
            Some(o) => format!("both halves of the stretch after its onset at {o:.3} s"),
            None => "both halves of the run".into(),
        }
    }

    /// An effect that pays over the whole run but not in both halves: helping only part of the
    /// run, it is not a constant property of the system.
    fn partial(&self, f: &Fitted<S::Effect, S::Model>) -> Signature {
        Signature {
            channel: f.label.location.clone(),
            frequency_hz: None,
            statistic: "delta_log_likelihood_halves".into(),
            value: f.halves[0].min(f.halves[1]),
            description: format!(
                "{}: it helps only part of the run (not {}), so it is not a lasting property",
                self.describe(f),
                Self::stretch(f)
            ),
        }
    }

    /// The refusal of an effect that pays over the whole run but not in both halves.
    fn refused_in_halves(&self, f: &Fitted<S::Effect, S::Model>) -> Refused {
        Refused {
            kind: f.label.kind,
            location: f.label.location.clone(),
            value: self.reported_value(f),
            reason: format!(
                "pays over the whole run (Δ log-likelihood {:.1} against a BIC cost of {:.1}) but not in {} ({:.1} / {:.1}): it helps only part of the run",
                f.delta,
                f.penalty,
                Self::stretch(f),
                f.halves[0],
                f.halves[1]
            ),
        }
    }

    /// Effects of [`LoopSystem::screened`] the data cannot see from the final model.
    fn screen(&self, effects: &[Applied<S::Effect>], run: &Run) -> Result<Vec<NotIdentifiable>> {
        let base = run.log_likelihood();
        let mut out = Vec::new();
        let screened: Vec<_> =
            self.sys.screened().into_iter().filter(|(e, _)| !effects.iter().any(|x| x.effect == *e)).collect();
        let worsts = parallel_map(&screened, |_, (e, thetas)| -> Result<f64> {
            let penalty = self.bic(e, false);
            let mut worst: f64 = 0.0;
            for &theta in thetas {
                let mut trial = effects.to_vec();
                trial.push(Applied::new(*e, theta));
                let (_, r) = self.sys.run(&trial)?;
                worst = worst.max((r.log_likelihood() - base).abs());
                if worst > penalty {
                    break;
                }
            }
            Ok(worst)
        });
        for ((e, _), worst) in screened.iter().zip(worsts) {
            let worst = worst?;
            let penalty = self.bic(e, false);
            let label = self.sys.label(e);
            let what = label.detail.parameter.clone().unwrap_or_else(|| label.kind.to_string());
            self.progress(|| format!("screen: {what} of {}: |Δ log-likelihood| ≤ {worst:.2}", label.location));
            if worst <= penalty {
                out.push(NotIdentifiable {
                    kind: label.kind,
                    location: label.location,
                    parameter: label.detail.parameter,
                    statistic: "max_delta_log_likelihood".into(),
                    value: worst,
                    reason: format!(
                        "halving or doubling it changes the log-likelihood by at most {worst:.2}, less than its BIC cost {penalty:.1}: these sensors cannot see it"
                    ),
                });
            }
        }
        Ok(out)
    }
}

/// `f` over `items` on every core the machine offers (each worker takes the next item left),
/// the results in the items' order: the candidates' fits are independent runs of the filter,
/// and the result does not depend on the number of cores.
fn parallel_map<T: Sync, R: Send>(items: &[T], f: impl Fn(usize, &T) -> R + Sync) -> Vec<R> {
    let workers = std::thread::available_parallelism().map_or(1, usize::from).min(items.len());
    if workers <= 1 {
        return items.iter().enumerate().map(|(i, item)| f(i, item)).collect();
    }
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut done: Vec<(usize, R)> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                scope.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(item) = items.get(i) else { break mine };
                        mine.push((i, f(i, item)));
                    }
                })
            })
            .collect();
        // A worker that panicked takes the process down as a sequential run would have.
        handles.into_iter().flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))).collect()
    });
    done.sort_by_key(|(i, _)| *i);
    done.into_iter().map(|(_, r)| r).collect()
}

/// The family of an effect for identifiability: same kind and order, different location.
fn family(l: &EffectLabel) -> (EffectKind, Option<u64>, Option<&str>) {
    (l.kind, l.detail.order.map(f64::to_bits), l.detail.parameter.as_deref().map(|_| "parameter"))
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

/// Why `e` is not fitted once the impacts stage has named a defect (`named`): impacts ring
/// every lightly damped mode of the structure, so a broadband stand-in (a mode the model
/// lacks, a catch-all input) fitted after them is their ringing, not a further effect. `None`
/// if `e` is fitted as usual.
fn rung_by_impacts<S: LoopSystem>(sys: &S, e: &S::Effect, named: &[(S::Effect, AddedEffect)]) -> Option<Refused> {
    let label = sys.label(e);
    let (_, defect) = named.first()?;
    matches!(label.kind, EffectKind::ExtraMode | EffectKind::UnknownInput).then(|| Refused {
        kind: label.kind,
        location: label.location,
        value: None,
        reason: format!(
            "not fitted: the impacts of the {} at {} ring every lightly damped mode, and a broadband \
             stand-in fitted after them is their ringing",
            defect.kind, defect.location
        ),
    })
}

/// Closes the loop on `sys`: runs its base model, takes out the periodic impacts its
/// envelope names ([`impacts`]), then adds effects while the innovations are
/// not consistent and an effect pays for its parameters (BIC) in both halves of the run (of
/// the stretch after its onset, for an effect that starts mid-run); then screens what the data
/// cannot see and reports what is left.
pub fn search<S: LoopSystem>(sys: &mut S, options: &LoopOptions) -> Result<LoopReport> {
    let traces = sys.traces();
    let mut effects: Vec<Applied<S::Effect>> = Vec::new();
    if options.progress {
        eprintln!("loop: running the base model");
    }
    let (mut cur_model, mut cur_run) = sys.run(&effects)?;
    let base_run = cur_run.clone();
    let before = sys.summarise(&cur_run);
    let found = impacts::stage(&*sys, &cur_run, &traces, &options.envelope, options.half_gain);
    if !found.signals.is_empty() {
        for (channel, signal) in &found.signals {
            sys.subtract(*channel, signal)?;
        }
        if options.progress {
            for (_, a) in &found.added {
                eprintln!(
                    "loop: impacts {} at {}: Δ log-likelihood {:.1}, BIC cost {:.1}",
                    a.kind, a.location, a.delta_log_likelihood, a.bic_penalty
                );
            }
        }
        (cur_model, cur_run) = sys.run(&effects)?;
    }
    let sys = &*sys;
    let mut engine =
        Engine { sys, options, t: traces.t.clone(), n_meas: cur_run.measurements().max(2) as f64, nis_scale: 1.0 };
    let mut current = sys.summarise(&cur_run);
    let mut added: Vec<Kept<S::Effect>> = Vec::new();
    let mut trials = found.trials;
    let mut not_identifiable = Vec::new();
    let mut partial: Vec<Signature> = Vec::new();
    let mut refused: Vec<Refused> = found.refused;
    let stopped;
    let mut iteration = 0;
    loop {
        if current.consistent {
            stopped = "the innovations are white, unbiased and NIS-consistent".to_string();
            break;
        }
        if effects.len() >= options.max_effects {
            stopped = format!("reached the limit of {} effects", options.max_effects);
            break;
        }
        iteration += 1;
        engine.nis_scale = if current.nis_mean.is_finite() { current.nis_mean.max(1.0) } else { 1.0 };
        let mut chosen = None;
        let mut evaluated = Vec::new();
        for tier in sys.candidates(&current, &cur_run, &cur_model, &effects) {
            let mut fresh: Vec<S::Effect> = Vec::new();
            for e in tier {
                if effects.iter().any(|x| x.effect == e) || fresh.contains(&e) {
                    continue;
                }
                match rung_by_impacts(sys, &e, &found.added) {
                    Some(r) if !refused.contains(&r) => refused.push(r),
                    Some(_) => {}
                    None => fresh.push(e),
                }
            }
            if chosen.is_some() || fresh.is_empty() {
                continue;
            }
            let mut results = engine.fit_all(iteration, &effects, fresh, &cur_run, &mut refused);
            for f in results.iter().filter(|f| f.delta > f.penalty && !engine.pays_in_halves(f)) {
                partial.push(engine.partial(f));
                refused.push(engine.refused_in_halves(f));
            }
            let best = results
                .iter()
                .enumerate()
                .filter(|(_, f)| engine.pays(f))
                .max_by(|a, b| (a.1.delta - a.1.penalty).total_cmp(&(b.1.delta - b.1.penalty)))
                .map(|(i, _)| i);
            if let Some(i) = best {
                let winner = results.swap_remove(i);
                not_identifiable.extend(engine.rivals(&winner, &results));
                chosen = Some(winner);
            }
            evaluated.extend(results);
        }
        for f in &evaluated {
            trials.push(engine.trial(iteration, f, false));
        }
        let Some(win) = chosen else {
            let best = evaluated.iter().max_by(|a, b| (a.delta - a.penalty).total_cmp(&(b.delta - b.penalty)));
            stopped = match best {
                Some(f) => {
                    format!("no candidate pays for itself in both halves of the run (best: {})", engine.describe(f))
                }
                None => "no candidate effect matches the remaining signatures".into(),
            };
            break;
        };
        trials.push(engine.trial(iteration, &win, true));
        engine.progress(|| format!("iteration {iteration}: kept {}", engine.describe(&win)));
        let next = sys.summarise(&win.run);
        let explains = explained(&current, &next);
        effects.push(win.applied);
        added.push(Kept { applied: win.applied, delta: win.delta, penalty: win.penalty, label: win.label, explains });
        (cur_model, cur_run) = (win.model, win.run);
        current = next;
    }
    if options.screen_parameters {
        not_identifiable.extend(engine.screen(&effects, &cur_run)?);
    }
    let effects_added = found
        .added
        .into_iter()
        .map(|(_, a)| a)
        .chain(added.into_iter().map(|f| AddedEffect {
            kind: f.label.kind,
            location: f.label.location,
            value: sys.value(&cur_model, &cur_run, &f.applied),
            unit: f.label.unit,
            detail: f.label.detail,
            explains: f.explains,
            delta_log_likelihood: f.delta,
            bic_penalty: f.penalty,
        }))
        .collect();
    let unexplained = if current.consistent {
        Vec::new()
    } else {
        let mut u = unexplained(&current, &options.signatures);
        u.extend(partial);
        u
    };
    let section = sys.section(&cur_model, &cur_run);
    let traces = Traces { before: base_run, after: cur_run, ..traces };
    Ok(LoopReport {
        schema_version: SCHEMA_VERSION,
        system: sys.name().to_string(),
        source: Source { version: env!("CARGO_PKG_VERSION").into(), ..Source::default() },
        effects_added,
        before,
        after: current,
        not_identifiable,
        unexplained,
        refused,
        trials,
        stopped,
        section,
        traces,
    })
}
