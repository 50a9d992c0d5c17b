//! What the data cannot tell, decided by the engine for every system: rivals a winner cannot
//! be told from (same family, another place, a log-likelihood within the margin), and the
//! component parameters a system declares that the data cannot see at all.

use super::filter::Run;
use super::fit::{Engine, Fitted};
use super::optimize::ScalarRange;
use super::report::NotIdentifiable;
use super::system::Described;
use super::system::LoopSystem;
use super::vocabulary::{Applied, EffectKind, EffectLabel};
use rayon::prelude::*;

impl<S: LoopSystem> Engine<'_, S> {
    /// How far apart two fits' log-likelihoods must be for the data to prefer one: the
    /// identifiability margin, or the model's floor over the run where that is larger (a
    /// difference the model's own mismatch could make is no evidence, as a gain below it is
    /// none).
    fn tie_margin(&self) -> f64 {
        self.options.identifiable_margin.max(self.options.gain_floor * self.nis_scale * self.n_meas)
    }

    /// Which of `results` (all fitted in one tier) to keep, given the best paying one `best`:
    /// the best, unless a fit of another quantity (a mass against a stiffness) pays within the
    /// [`tie_margin`](Self::tie_margin) of it. Then `None`: the data cannot choose between
    /// two quantities, and a model corrected in the wrong one makes what it estimates worse
    /// than the declared one did (a load read as a stiffness moves every output the
    /// stiffness drives), so neither is added and each is reported with the others
    /// ([`undecided`](Self::undecided)). Ties of one quantity at other places keep the best
    /// and are listed ([`rivals`](Self::rivals)).
    pub(super) fn choose(&self, results: &[Fitted<S::Effect, S::Model>], best: usize) -> Option<usize> {
        let b = &results[best];
        let margin = self.tie_margin();
        let other_quantity = self.tied(results, best, margin).any(|f| quantity(&f.label) != quantity(&b.label));
        (!other_quantity).then_some(best)
    }

    /// The fits of `results` that pay and fit as well as `results[best]` (same family, a
    /// log-likelihood within `margin`), `best` among them.
    fn tied<'r>(
        &'r self,
        results: &'r [Fitted<S::Effect, S::Model>],
        best: usize,
        margin: f64,
    ) -> impl Iterator<Item = &'r Fitted<S::Effect, S::Model>> + 'r {
        let b = &results[best];
        let (family_b, delta_b) = (family(&b.label), b.delta);
        results
            .iter()
            .filter(move |f| self.pays(f) && family(&f.label) == family_b && (delta_b - f.delta).abs() < margin)
    }

    /// When [`choose`](Self::choose) keeps none: every fit tied with `results[best]`, each
    /// reported as what the sensors cannot tell from the others (named as its rivals), with
    /// its own fitted value; and the reason the search stops.
    pub(super) fn undecided(
        &self,
        results: &[Fitted<S::Effect, S::Model>],
        best: usize,
    ) -> (Vec<NotIdentifiable>, String) {
        let margin = self.tie_margin();
        let tied: Vec<_> = self.tied(results, best, margin).collect();
        let b = &results[best];
        let out = tied
            .iter()
            .map(|f| {
                let rivals: Vec<String> =
                    tied.iter().filter(|r| r.label != f.label).map(|r| named(&r.label)).collect();
                let gap = b.delta - f.delta;
                let value = self.reported_value(f).map(|v| format!(" (fitted as {})", shown(v, &f.label.unit)));
                let reason = format!(
                    "fits the data{} as well as {}: log-likelihoods within {margin:.1} of the best, too close to tell the quantities apart, so none of them is added",
                    value.unwrap_or_default(),
                    rivals.join(", ")
                );
                let mut n = NotIdentifiable::of(&f.label, "delta_log_likelihood_gap", gap, reason);
                n.rivals = rivals;
                n
            })
            .collect();
        let names: Vec<String> = tied.iter().map(|f| named(&f.label)).collect();
        let why = format!(
            "the best candidates ({}) change different quantities and fit the data equally well (within {margin:.1} in log-likelihood): these sensors cannot tell which, so none is added",
            names.join(", ")
        );
        (out, why)
    }

    /// Rivals of `winner` among `results`: same family, another location, a log-likelihood
    /// within the [`tie_margin`](Self::tie_margin) or a response the system's signatures
    /// cannot tell from the winner's ([`Rivals::tied`](super::system::Rivals::tied)), each with its own fitted
    /// value.
    pub(super) fn rivals(
        &self,
        effects: &[Applied<S::Effect>],
        winner: &Fitted<S::Effect, S::Model>,
        results: &[Fitted<S::Effect, S::Model>],
    ) -> Vec<NotIdentifiable> {
        let margin = self.tie_margin();
        let ties = self.sys.rivals(&winner.applied.effect, effects).tied;
        let signature_tie = |f: &Fitted<S::Effect, S::Model>| ties.contains(&f.applied.effect);
        results
            .iter()
            .filter(|f| {
                family(&f.label) == family(&winner.label)
                    && f.label.location != winner.label.location
                    && ((winner.delta - f.delta).abs() < margin || signature_tie(f))
            })
            .map(|r| {
                let gap = winner.delta - r.delta;
                let value = match self.reported_value(r) {
                    Some(v) => format!(" (fitted as {}{})", parameter_word(&r.label), shown(v, &r.label.unit)),
                    None => String::new(),
                };
                let w = &winner.label.location;
                let reason = if gap.abs() >= margin {
                    format!(
                        "its response at the sensors is {w}'s up to the effect's own amplitude and phase{value}: the sensors cannot tell where it acts; the fits are {gap:.1} apart in log-likelihood only through what the model assumes of the effect's noise and the run's start, not through the steady response"
                    )
                } else if gap >= 0.0 {
                    format!(
                        "fits the data as well as {w}{value}: log-likelihoods {gap:.2} apart, less than the {margin:.1} that tells two fits apart: the sensors cannot tell the two apart"
                    )
                } else {
                    format!(
                        "fits the data as well as {w}{value}: {:.2} better in log-likelihood, less than the {margin:.1} that tells two fits apart: the sensors cannot tell the two apart, and {w} gains more for what its parameters cost",
                        -gap
                    )
                };
                NotIdentifiable::of(&r.label, "delta_log_likelihood_gap", gap, reason)
            })
            .collect()
    }

    /// The declared effects ([`LoopSystem::declared`]) with a scalar that the data cannot see
    /// from the final model: moving the scalar to its [`probes`] changes the log-likelihood by
    /// less than an effect must gain to be added (its BIC cost and the model's floor, the
    /// acceptance rule's own threshold: an effect below it could never be found). With a probe
    /// on each side, the change is the likelihood's curvature's (the information the data carry
    /// on the scalar), so that an effect already in the data, which tilts the likelihood
    /// towards one side, does not make the data look more informative than they are. A trial
    /// whose filter fails (diverges, cannot be built) counts as seen: the data reject it.
    pub(super) fn screen(&self, effects: &[Applied<S::Effect>], run: &Run) -> Vec<NotIdentifiable> {
        let base = run.log_likelihood();
        let screened: Vec<(S::Effect, Probes)> = self
            .sys
            .declared()
            .into_iter()
            .filter(|e| !effects.iter().any(|x| x.effect == *e))
            .filter_map(|e| Some((e, probes(self.sys.label(&e).kind, &self.sys.fitting(&e).scalar?.0))))
            .collect();
        let worsts: Vec<f64> = screened
            .par_iter()
            .map(|(e, probes)| {
                let mut losses = Vec::new();
                for &theta in &probes.thetas {
                    let mut trial = effects.to_vec();
                    trial.push(Applied::new(*e, theta));
                    let Ok((_, r)) = self.sys.run(&trial) else { return f64::INFINITY };
                    losses.push((theta - probes.neutral, base - r.log_likelihood()));
                }
                probes.change(&losses)
            })
            .collect();
        let mut out = Vec::new();
        for ((e, probes), worst) in screened.iter().zip(worsts) {
            let penalty = self.penalty(e, false);
            let label = self.sys.label(e);
            let what = label.detail.parameter.clone().unwrap_or_else(|| label.kind.to_string());
            self.progress(|| format!("screen: {what} of {}: |Δ log-likelihood| ≤ {worst:.2}", label.location));
            if worst <= penalty {
                let rivals: Vec<String> = self
                    .sys
                    .rivals(e, effects)
                    .carried
                    .iter()
                    .map(|r| {
                        let l = self.sys.label(r);
                        format!("{} at {}", l.kind, l.location)
                    })
                    .collect();
                let taken = if rivals.is_empty() {
                    String::new()
                } else {
                    format!("; {} in the model gives the same innovations", rivals.join(" and "))
                };
                let reason = format!(
                    "{} changes the log-likelihood by about {worst:.2}, less than the {penalty:.1} an effect must gain to be added: these sensors cannot see it{taken}{}",
                    probes.what,
                    probes.limit(worst, penalty, &label.unit)
                );
                let mut verdict = NotIdentifiable::of(&label, "max_delta_log_likelihood", worst, reason);
                verdict.rivals = rivals;
                out.push(verdict);
            }
        }
        out
    }
}

impl<S: LoopSystem> Engine<'_, S> {
    /// The 95 % interval of the value of `effects[i]` in the final `model` and `run`: near the
    /// fit the profile log-likelihood of its scalar is a parabola, whose curvature two runs at
    /// `θ ± h` give; its width is widened by the innovations' NIS (a model that leaves k times
    /// the power it expects unexplained is k times less sure) and mapped through the system's
    /// value. `None` for an effect without a scalar, or where the likelihood does not curve down.
    pub(super) fn interval(
        &self,
        effects: &[Applied<S::Effect>],
        i: usize,
        model: &S::Model,
        run: &Run,
    ) -> Option<[f64; 2]> {
        let e = *effects.get(i)?;
        let (range, _) = self.sys.fitting(&e.effect).scalar?;
        let h = (10.0 * range.tolerance).max(1e-3 * (range.high - range.low));
        let ll = |theta: f64| {
            let mut trial = effects.to_vec();
            trial[i].theta = theta;
            self.sys.run(&trial).ok().map(|(_, r)| r.log_likelihood())
        };
        let (up, down) = (ll(e.theta + h)?, ll(e.theta - h)?);
        let curvature = -(up - 2.0 * run.log_likelihood() + down) / (h * h);
        if !(curvature.is_finite() && curvature > 0.0) {
            return None;
        }
        let half = 1.96 * (self.nis_scale / curvature).sqrt();
        let at = |theta: f64| self.sys.value(model, run, &Applied { theta, ..e });
        let (a, b) = (at(e.theta - half), at(e.theta + half));
        (a.is_finite() && b.is_finite()).then(|| [a.min(b), a.max(b)])
    }
}

/// The scalars an effect is screened at, and how the report says so.
struct Probes {
    thetas: Vec<f64>,
    what: String,
    /// The scalar's neutral value and whether it is a log-factor.
    neutral: f64,
    log: bool,
}

impl Probes {
    /// The log-likelihood's change at the farthest probe, from the `(distance, loss)` of each:
    /// with a probe on each side, that of the parabola through both (the linear part, which an
    /// effect already in the data puts there, taken out); else the largest change.
    fn change(&self, losses: &[(f64, f64)]) -> f64 {
        let largest = losses.iter().map(|(_, l)| l.abs()).fold(0.0, f64::max);
        let &[(d1, l1), (d2, l2)] = losses else { return largest };
        if d1 * d2 >= 0.0 {
            return largest;
        }
        // l = −g d + ½ I d²: two probes give I without g.
        let information = 2.0 * (l1 * d2 - l2 * d1) / (d1 * d2 * (d1 - d2));
        let reach = d1.abs().max(d2.abs());
        if information.is_finite() && information > 0.0 {
            0.5 * information * reach * reach
        } else {
            largest
        }
    }

    /// The smallest change the data could tell, in words, from the log-likelihood's change
    /// `worst` at the farthest probe and the `penalty` an effect must gain: the likelihood is
    /// quadratic near the neutral value, so the change grows with the square of the distance.
    fn limit(&self, worst: f64, penalty: f64, unit: &str) -> String {
        let span = self.thetas.iter().map(|t| (t - self.neutral).abs()).fold(0.0, f64::max);
        if worst <= 0.0 || span <= 0.0 || !worst.is_finite() {
            return String::new();
        }
        let d = span * (penalty / worst).sqrt();
        match self.log {
            true if d > 10f64.ln() => " (not even a factor of ten would show)".into(),
            true => format!(" (the smallest it could tell is a factor of about ×{:.3} or ×{:.3})", d.exp(), (-d).exp()),
            false if d > 10.0 * span => " (not even ten times that range would show)".into(),
            false => format!(" (the smallest it could tell is about ±{d:.3e} {unit})"),
        }
    }
}

/// A component parameter (a factor `θ = ln f`) is screened halved and doubled: a model's
/// declared value may be far off. Any other effect at the two ends of the range its system
/// allows it (a sensor's setting within its tolerance), the neutral end left out.
fn probes(kind: EffectKind, range: &ScalarRange) -> Probes {
    if kind == EffectKind::Parameter {
        let thetas = vec![0.5f64.ln(), 2f64.ln()];
        return Probes { thetas, what: "halving or doubling it".into(), neutral: 0.0, log: true };
    }
    let thetas = [range.low, range.high].into_iter().filter(|t| *t != range.neutral).collect();
    let shown = |v: f64| if range.log { v.exp() } else { v };
    Probes {
        thetas,
        what: format!("moving it over the range it may take ({:.4} … {:.4})", shown(range.low), shown(range.high)),
        neutral: range.neutral,
        log: range.log,
    }
}

/// The family of an effect for identifiability: same kind and order, different location.
fn family(l: &EffectLabel) -> (EffectKind, Option<u64>, Option<&str>) {
    (l.kind, l.detail.order.map(f64::to_bits), l.detail.parameter.as_deref().map(|_| "parameter"))
}

/// The quantity an effect changes: its family, with the parameter's own name (a mass is not a
/// stiffness, though both are parameters).
fn quantity(l: &EffectLabel) -> (EffectKind, Option<u64>, Option<&str>) {
    (l.kind, l.detail.order.map(f64::to_bits), l.detail.parameter.as_deref())
}

/// The parameter an effect changes, with a space after it (`mass `), or nothing: how a fitted
/// value and a tied effect name it.
fn parameter_word(l: &EffectLabel) -> String {
    l.detail.parameter.as_deref().map(|p| format!("{p} ")).unwrap_or_default()
}

/// An effect as a tie names it: `kind parameter at location` (`parameter_tweak mass at tip`).
fn named(l: &EffectLabel) -> String {
    format!("{} {}at {}", l.kind, parameter_word(l), l.location)
}

/// `value unit`, or `×value` for a factor (unit `1`).
fn shown(value: f64, unit: &str) -> String {
    if unit == "1" {
        format!("×{value:.4}")
    } else {
        format!("{value:.4e} {unit}")
    }
}
