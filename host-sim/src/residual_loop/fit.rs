//! Fitting one candidate effect on top of the current model: its scalar by maximum likelihood
//! (and its onset, for an effect that may start mid-run), its states by the filter, and the
//! gains and costs the acceptance rule reads (the whole run, its halves, the BIC cost).

use super::filter::Run;
use super::onset;
use super::optimize::maximise;
use super::options::LoopOptions;
use super::report::{NotIdentifiable, Refused, Trial};
use super::signature::Signature;
use super::system::Described;
use super::system::LoopSystem;
use super::vocabulary::{Applied, EffectLabel};
use anyhow::{anyhow, Result};
use rayon::prelude::*;

/// A half whose data hold at most this share of the information the other half holds about
/// an effect cannot show it: only its consistency with the other half is asked of it (a
/// mode's frequency under a tracked drive shows in the transient, not in the steady state).
const BLIND_HALF: f64 = 0.1;

/// How much a half that cannot see an effect may lose to it by chance: half the 99 % point of
/// χ²(1), the likelihood-ratio allowance for one parameter.
const HALF_SLACK: f64 = 3.32;

/// The reason of every refusal at a bound, as `report.json` writes it.
pub const OUTSIDE: &str = "outside what the model allows";

/// A fit at or beyond what the model allows (the edge of its scalar's range, its
/// [`limit`](super::Fitting::limit)): refused, with the value it reached.
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

/// A fit that ran to the edge of its range while gaining less there than an effect must gain
/// to be added: the likelihood is flat over the whole range, so the edge says nothing about a
/// bound, only that the data cannot see the effect.
#[derive(Debug)]
struct Flat {
    /// The log-likelihood gained at the edge.
    gain: f64,
    /// What an effect must gain to be added.
    penalty: f64,
    /// The range, in words.
    range: String,
}

impl std::fmt::Display for Flat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "its best fit runs to the edge of the range it may take ({}) and gains only {:.2} there, less than the {:.1} an effect must gain to be added: these sensors cannot see it",
            self.range, self.gain, self.penalty
        )
    }
}

impl std::error::Error for Flat {}

/// A candidate fitted to the data.
pub(super) struct Fitted<E, M> {
    pub(super) applied: Applied<E>,
    pub(super) model: M,
    pub(super) run: Run,
    pub(super) delta: f64,
    pub(super) halves: [f64; 2],
    /// What each half would gain from the effect at its fitted value if the effect lasted
    /// through the run (from the curvature of that half's profile likelihood), computed only
    /// for a scalar effect whose halves do not both pay; `None` otherwise.
    pub(super) halves_expected: Option<[f64; 2]>,
    pub(super) penalty: f64,
    pub(super) label: EffectLabel,
}

/// Where in the search a set of candidates is fitted: the iteration, and the tier of the
/// system's candidates (a later tier is tried only when no candidate of an earlier one is
/// kept), so that progress reads "iteration 1, tier 2: candidate 1/2".
#[derive(Debug, Clone, Copy)]
pub(super) struct Round {
    pub(super) iteration: usize,
    pub(super) tier: usize,
}

/// The engine's view of a system during one search.
pub(super) struct Engine<'a, S: LoopSystem> {
    pub(super) sys: &'a S,
    pub(super) options: &'a LoopOptions,
    /// Sample times of the data, s.
    pub(super) t: Vec<f64>,
    /// Scalar measurements in the run (for the BIC).
    pub(super) n_meas: f64,
    /// The current model's NIS per channel, at least 1 (scales the gain floor).
    pub(super) nis_scale: f64,
}

impl<S: LoopSystem> Engine<'_, S> {
    /// What `e` must gain to be added: `½ p ln n` for its parameters (and one more for a
    /// fitted onset), plus the baseline's [`gain_floor`](LoopOptions::gain_floor) over the run.
    pub(super) fn penalty(&self, e: &S::Effect, onset: bool) -> f64 {
        let parameters = self.sys.fitting(e).parameters + usize::from(onset);
        0.5 * parameters as f64 * self.n_meas.ln() + self.options.gain_floor * self.nis_scale * self.n_meas
    }

    /// Fits `cand` on top of `effects`: present from the start and, if it may start mid-run,
    /// with a fitted onset; the better of the two (one that pays for itself first).
    pub(super) fn fit(
        &self,
        effects: &[Applied<S::Effect>],
        cand: S::Effect,
        base: &Run,
    ) -> Result<Fitted<S::Effect, S::Model>> {
        let whole = self.fit_from(effects, cand, None, base);
        if !self.sys.fitting(&cand).may_start_mid_run {
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
        let fitting = self.sys.fitting(&cand);
        let theta = match fitting.scalar {
            Some((range, grid)) => {
                let best = maximise(
                    |th| self.sys.run(&with(th)).ok().map(|(_, r)| r.log_likelihood()),
                    range.low,
                    range.high,
                    grid,
                    range.tolerance,
                )
                .ok_or_else(|| anyhow!("no value of the scalar gives a usable model"))?;
                let x = best.x;
                // A likelihood still rising at the edge of the range has no maximum there: the
                // effect is standing in for something else, and its value would be the range's.
                // Unless it gains too little there to be added: then the likelihood is flat
                // and the data cannot see the effect at all. (An edge where the effect is
                // neutral is a legitimate answer.)
                let edge = (10.0 * range.tolerance).max(0.01 * (range.high - range.low));
                let at = |bound: f64| (x - bound).abs() <= edge && bound != range.neutral;
                if at(range.low) || at(range.high) {
                    let shown = |v: f64| if range.log { v.exp() } else { v };
                    let range_text = format!("{:.4} … {:.4}", shown(range.low), shown(range.high));
                    let (gain, penalty) = (best.value - base.log_likelihood(), self.penalty(&cand, onset_s.is_some()));
                    if gain <= penalty {
                        return Err(Flat { gain, penalty, range: range_text }.into());
                    }
                    return Err(OutOfBounds {
                        value: shown(x),
                        why: format!("the likelihood still rises at the edge of the range it may take ({range_text})"),
                    }
                    .into());
                }
                x
            }
            None => 0.0,
        };
        let applied = Applied { effect: cand, theta, onset_s };
        let (model, run) = self.sys.run(&with(theta))?;
        if let Some(limit) = fitting.limit {
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
        let from = applied.first_sample(&self.t);
        let halves = onset::halves(&run, base, from);
        let mut label = self.sys.label(&cand);
        label.detail.onset_s = onset_s;
        let penalty = self.penalty(&cand, onset_s.is_some());
        let short = halves[0].min(halves[1]) < self.options.half_gain * penalty;
        let halves_expected = match fitting.scalar {
            Some((range, _)) if short && delta > penalty => {
                self.halves_expected(&with, theta - range.neutral, theta, &halves, base, from)
            }
            _ => None,
        };
        Ok(Fitted { applied, model, run, delta, halves, halves_expected, penalty, label })
    }

    /// What each half would gain from a lasting effect at `theta`, `delta` from neutral: the
    /// half's gain in a quadratic model of its profile likelihood, `½ I δ²`, with the curvature
    /// `I` from the gains at `theta ± δ/2` (then `½ I δ²` is twice the drop of the second
    /// difference). A half whose data cannot see the effect expects nothing, and so need not
    /// pay for it: a mode's frequency under a tracked drive shows only in the transient.
    fn halves_expected(
        &self,
        with: &dyn Fn(f64) -> Vec<Applied<S::Effect>>,
        delta: f64,
        theta: f64,
        halves: &[f64; 2],
        base: &Run,
        from: usize,
    ) -> Option<[f64; 2]> {
        let at = |th: f64| self.sys.run(&with(th)).ok().map(|(_, r)| onset::halves(&r, base, from));
        let (lo, hi) = (at(theta - 0.5 * delta)?, at(theta + 0.5 * delta)?);
        let expect = |h: usize| (2.0 * (2.0 * halves[h] - lo[h] - hi[h])).max(0.0);
        Some([expect(0), expect(1)])
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

    pub(super) fn reported_value(&self, f: &Fitted<S::Effect, S::Model>) -> Option<f64> {
        let scalar_or_late = self.sys.fitting(&f.applied.effect).scalar.is_some() || f.applied.onset_s.is_some();
        scalar_or_late.then(|| self.sys.value(&f.model, &f.run, &f.applied))
    }

    pub(super) fn trial(&self, iteration: usize, f: &Fitted<S::Effect, S::Model>, accepted: bool) -> Trial {
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
            delta_halves_expected: f.halves_expected,
            bic_penalty: f.penalty,
            accepted,
        }
    }

    /// `kind at location [from t s]: Δ log-likelihood, BIC cost, halves`.
    pub(super) fn describe(&self, f: &Fitted<S::Effect, S::Model>) -> String {
        let from = f.applied.onset_s.map(|o| format!(" from {o:.3} s")).unwrap_or_default();
        let expected = f.halves_expected.map(|e| format!(" (a lasting effect: {:.1} / {:.1})", e[0], e[1]));
        format!(
            "{} at {}{from}: Δ log-likelihood {:.1}, BIC cost {:.1}, halves {:.1} / {:.1}{}",
            f.label.kind,
            f.label.location,
            f.delta,
            f.penalty,
            f.halves[0],
            f.halves[1],
            expected.unwrap_or_default()
        )
    }

    pub(super) fn progress(&self, msg: impl FnOnce() -> String) {
        if self.options.progress {
            eprintln!("loop: {}", msg());
        }
    }

    /// Fits every candidate of `cands` on top of `effects`; a fit refused goes to `refused`,
    /// one the data cannot see to `hidden`.
    pub(super) fn fit_all(
        &self,
        at: Round,
        effects: &[Applied<S::Effect>],
        cands: Vec<S::Effect>,
        base: &Run,
        (refused, hidden): (&mut Vec<Refused>, &mut Vec<NotIdentifiable>),
    ) -> Vec<Fitted<S::Effect, S::Model>> {
        let total = cands.len();
        let fits: Vec<_> = cands
            .par_iter()
            .enumerate()
            .map(|(i, cand)| {
                let label = self.sys.label(cand);
                self.progress(|| {
                    let Round { iteration, tier } = at;
                    let which = format!("candidate {}/{total}", i + 1);
                    format!("iteration {iteration}, tier {tier}: {which}: {} at {}", label.kind, label.location)
                });
                self.fit(effects, *cand, base)
            })
            .collect();
        let mut results = Vec::new();
        for (cand, fit) in cands.iter().zip(fits) {
            let label = self.sys.label(cand);
            match fit {
                Ok(f) => results.push(f),
                Err(e) => {
                    self.progress(|| format!("  {} at {}: {e:#}", label.kind, label.location));
                    if let Some(flat) = e.downcast_ref::<Flat>() {
                        let statistic = "max_delta_log_likelihood";
                        hidden.push(NotIdentifiable::of(&label, statistic, flat.gain, flat.to_string()));
                        continue;
                    }
                    refused.push(Refused::of(
                        &label,
                        e.downcast_ref::<OutOfBounds>().map(|o| o.value),
                        format!("{e:#}"),
                    ));
                }
            }
        }
        results
    }

    /// Pays for itself: the whole run gains more than the BIC cost, and each half (of the
    /// stretch after the onset, for a change-point effect) at least `half_gain` of it.
    pub(super) fn pays(&self, f: &Fitted<S::Effect, S::Model>) -> bool {
        f.delta > f.penalty && self.pays_in_halves(f)
    }

    /// Each half pays at least `half_gain` of the cost, or its data cannot show the effect: a
    /// lasting effect would gain less than that there and less than [`BLIND_HALF`] of what it
    /// gains in the other half, and the half is not hurt by more than [`HALF_SLACK`].
    pub(super) fn pays_in_halves(&self, f: &Fitted<S::Effect, S::Model>) -> bool {
        let need = self.options.half_gain * f.penalty;
        let blind = |e: [f64; 2], h: usize| e[h] < need && e[h] <= BLIND_HALF * e[1 - h] && f.halves[h] >= -HALF_SLACK;
        (0..2).all(|h| f.halves[h] >= need || f.halves_expected.is_some_and(|e| blind(e, h)))
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
    pub(super) fn partial(&self, f: &Fitted<S::Effect, S::Model>) -> Signature {
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
    pub(super) fn refused_in_halves(&self, f: &Fitted<S::Effect, S::Model>) -> Refused {
        Refused::of(
            &f.label,
            self.reported_value(f),
            format!(
                "pays over the whole run (Δ log-likelihood {:.1} against a BIC cost of {:.1}) but not in {} ({:.1} / {:.1}{}): it helps only part of the run",
                f.delta,
                f.penalty,
                Self::stretch(f),
                f.halves[0],
                f.halves[1],
                f.halves_expected
                    .map(|e| format!(", where a lasting effect would gain {:.1} / {:.1}", e[0], e[1]))
                    .unwrap_or_default()
            ),
        )
    }
}
