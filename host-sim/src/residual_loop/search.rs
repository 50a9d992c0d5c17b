//! The search, written against [`LoopSystem`] so every system of edgekf goes through the same
//! engine: candidates from the signatures, each fitted (its states by the filter, its scalar by
//! maximum likelihood) and kept only if it pays for its parameters (BIC) in both halves of the
//! run; then what is left is reported.
//!
//! A system supplies the filter runs, the summaries and the candidates; the engine owns the
//! acceptance rule, the identifiability verdicts and the report, so they read the same for a
//! machine, a mechanism or a vehicle.

use super::filter::Run;
use super::optimize::{maximise, ScalarRange};
use super::signature::{unexplained, Signature, SignatureOptions};
use anyhow::{anyhow, Result};
use serde::Serialize;
use std::fmt::Debug;

pub use super::signature::{Channel, ChannelSignature, PeakSignature, RunSummary};

/// The version of `report.json`'s layout: raised when a field changes meaning or goes away
/// (adding a field does not raise it).
pub const SCHEMA_VERSION: u32 = 2;

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
    /// Two locations of the same kind whose log-likelihoods differ by less than this are
    /// reported as not identifiable from each other.
    pub identifiable_margin: f64,
    /// Check at the end which component parameters the data cannot see (halving or doubling
    /// each changes the log-likelihood by less than its BIC cost).
    pub screen_parameters: bool,
    /// Print progress to standard error.
    pub progress: bool,
}

impl Default for LoopOptions {
    fn default() -> Self {
        Self {
            signatures: SignatureOptions::default(),
            max_effects: 4,
            half_gain: 0.25,
            identifiable_margin: 2.0,
            screen_parameters: true,
            progress: false,
        }
    }
}

/// The kinds of effect, one vocabulary for every system (the README's table gives each kind's
/// `location`, the unit of its `value` and its extra fields).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    /// A constant offset on a channel (channel unit; `drift` in unit/s where it drifts).
    SensorBias,
    /// A factor on a channel's declared scale.
    SensorScale,
    /// A pure delay of a channel, s.
    SensorDelay,
    /// A first-order lag of a channel, s (time constant).
    SensorLag,
    /// A force at an order of the running speed, N (`order`).
    HarmonicForce,
    /// A catch-all input at a node or channel, RMS in N or the channel's unit.
    UnknownInput,
    /// A factor on a component's declared parameter (`parameter`).
    Parameter,
    /// A mass added at a node, kg.
    PointMass,
    /// A mode the model lacks, Hz (`damping`).
    ExtraMode,
    /// A bearing defect: impulse size in the channel's unit (`line`, `harmonics`, `band_hz`).
    BearingDefect,
    /// An actuator's health factor after the onset (1 = healthy; `onset_s`).
    ActuatorHealth,
    /// A joint's radial clearance, m.
    Clearance,
}

impl EffectKind {
    /// The name in reports (`sensor_bias`, …).
    pub fn as_str(self) -> &'static str {
        match self {
            EffectKind::SensorBias => "sensor_bias",
            EffectKind::SensorScale => "sensor_scale",
            EffectKind::SensorDelay => "sensor_delay",
            EffectKind::SensorLag => "sensor_lag",
            EffectKind::HarmonicForce => "harmonic_force",
            EffectKind::UnknownInput => "unknown_input",
            EffectKind::Parameter => "parameter",
            EffectKind::PointMass => "point_mass",
            EffectKind::ExtraMode => "extra_mode",
            EffectKind::BearingDefect => "bearing_defect",
            EffectKind::ActuatorHealth => "actuator_health",
            EffectKind::Clearance => "clearance",
        }
    }
}

impl std::fmt::Display for EffectKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl PartialEq<&str> for EffectKind {
    fn eq(&self, other: &&str) -> bool {
        self.as_str() == *other
    }
}

/// The extra fields of an effect, each used by the kinds the README's table names.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct EffectDetail {
    /// Order of the running speed (harmonic forces, bearing lines).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<f64>,
    /// The parameter (`mass`, `young`, `kxx`, …) of a `parameter` effect.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parameter: Option<String>,
    /// The defect line (`BPFO`, `BPFI`, `BSF`, `FTF`) of a `bearing_defect`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub line: Option<String>,
    /// Harmonics of the defect line modelled.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub harmonics: Option<u32>,
    /// The band the defect's impulses ring in, Hz.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub band_hz: Option<[f64; 2]>,
    /// Drift of a bias, in the channel's unit per second.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drift: Option<f64>,
    /// Damping ratio of an extra mode.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// When the effect began, s from the first sample (change-point effects).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub onset_s: Option<f64>,
}

/// An effect the loop kept.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AddedEffect {
    /// The kind ([`EffectKind`]).
    pub kind: EffectKind,
    /// Channel name, `node N`, or a component (`disk 12`, `shaft`, `bearing 4`).
    pub location: String,
    /// Estimated size in SI units (a force's amplitude averaged over the second half of the
    /// run), or the factor on the declared value for `sensor_scale` and `parameter`.
    pub value: f64,
    /// Unit of `value` (`1` for a factor).
    pub unit: String,
    /// The kind's extra fields.
    #[serde(flatten)]
    pub detail: EffectDetail,
    /// Spectral lines (Hz) of the innovations that were there before this effect and are gone
    /// after it.
    pub explains: Vec<f64>,
    /// Gain in log-likelihood.
    pub delta_log_likelihood: f64,
    /// Its cost: `½ p ln n`.
    pub bic_penalty: f64,
}

/// A candidate the loop fitted and refused.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Refused {
    /// The kind.
    pub kind: EffectKind,
    /// Where.
    pub location: String,
    /// The fitted value, as an added effect would report it, where the fit gave one.
    pub value: Option<f64>,
    /// Why it was refused (at a bound of its range, one half of the run only, no usable model).
    pub reason: String,
}

/// Where a report came from, so that it can be traced and rerun.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Source {
    /// The data file.
    pub data: Option<String>,
    /// SHA-256 of the data file's bytes, hex.
    pub data_sha256: Option<String>,
    /// The configuration file.
    pub config: Option<String>,
    /// The healthy baseline the loop started from, if any.
    pub baseline: Option<String>,
    /// The command line.
    pub command: Option<String>,
    /// edgekf's version.
    pub version: String,
}

/// A system's own part of a report, beside the engine's fields (a running speed, say).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SystemSection {
    /// Fields written at the top level of `report.json`.
    #[serde(flatten)]
    pub fields: serde_json::Map<String, serde_json::Value>,
    /// The same for people: `(label, text)`, printed under the verdict and on the page.
    #[serde(skip)]
    pub lines: Vec<(String, String)>,
}

/// An effect (or location) the data cannot resolve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NotIdentifiable {
    /// Kind.
    pub kind: EffectKind,
    /// Location.
    pub location: String,
    /// The parameter, for `parameter`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parameter: Option<String>,
    /// The statistic behind the verdict (`max_delta_log_likelihood`, `delta_log_likelihood_gap`).
    pub statistic: String,
    /// Its value.
    pub value: f64,
    /// Why, in words.
    pub reason: String,
}

/// One candidate evaluated.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trial {
    /// Iteration.
    pub iteration: usize,
    /// Kind.
    pub kind: EffectKind,
    /// Location.
    pub location: String,
    /// Order (harmonic forces, bearing lines).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<f64>,
    /// Parameter name (parameter effects).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parameter: Option<String>,
    /// Unit of `value`.
    pub unit: String,
    /// Fitted value (scalar effects), as reported.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value: Option<f64>,
    /// Gain in log-likelihood over the current model.
    pub delta_log_likelihood: f64,
    /// The gain in the first and in the second half of the run.
    pub delta_halves: [f64; 2],
    /// `½ p ln n`.
    pub bic_penalty: f64,
    /// Kept.
    pub accepted: bool,
}

/// The series behind the report's plots (not serialised).
#[derive(Debug, Clone, Default)]
pub struct Traces {
    /// Time, s.
    pub t: Vec<f64>,
    /// Sensor channels.
    pub channels: Vec<Channel>,
    /// Virtual-sensing rows (`n12_x`, …).
    pub rows: Vec<Channel>,
    /// `truth_` column of each row, where the file has one.
    pub truth: Vec<Option<Vec<f64>>>,
    /// The base model's run.
    pub before: Run,
    /// The final model's run.
    pub after: Run,
}

/// What the loop found.
#[derive(Debug, Clone, Serialize)]
pub struct LoopReport {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The system (its registry name).
    pub system: String,
    /// Where the report came from.
    pub source: Source,
    /// Effects kept, in order.
    pub effects_added: Vec<AddedEffect>,
    /// The base model.
    pub before: RunSummary,
    /// The final model.
    pub after: RunSummary,
    /// Effects the data cannot resolve.
    pub not_identifiable: Vec<NotIdentifiable>,
    /// Signatures left that no effect of the library explains (empty when the final
    /// innovations are consistent).
    pub unexplained: Vec<Signature>,
    /// Candidates fitted and refused, with the reason.
    pub refused: Vec<Refused>,
    /// Every candidate evaluated.
    pub trials: Vec<Trial>,
    /// Why the loop stopped.
    pub stopped: String,
    /// The system's own fields (a running speed, say), at the top level of the JSON.
    #[serde(flatten)]
    pub section: SystemSection,
    /// The series behind the plots.
    #[serde(skip)]
    pub traces: Traces,
}

/// How an effect is written in the report.
#[derive(Debug, Clone, PartialEq)]
pub struct EffectLabel {
    /// Kind.
    pub kind: EffectKind,
    /// Channel name, `node N`, or a component.
    pub location: String,
    /// The kind's extra fields.
    pub detail: EffectDetail,
    /// Unit of the reported value (`1` for a factor).
    pub unit: String,
}

/// A system the loop can be closed on: a base model with a filter, a library of effects that
/// augment it, and the data. The engine ([`search`]) asks it for filter runs with a list of
/// effects, for summaries of those runs and for candidates; everything else (acceptance,
/// identifiability, the report) is the engine's.
///
/// An effect is `(Self::Effect, θ)`: what and where, plus the scalar the engine fits by
/// maximum likelihood when [`LoopSystem::scalar`] gives it a range (0 otherwise).
pub trait LoopSystem {
    /// One augmentation at one place.
    type Effect: Copy + PartialEq + Debug;
    /// What a run was made with (the system reads effect values from it).
    type Model;
    /// The system's name in the report.
    fn name(&self) -> &str;
    /// Runs the filter with `effects` over the whole recording.
    fn run(&self, effects: &[(Self::Effect, f64)]) -> Result<(Self::Model, Run)>;
    /// The innovations' statistics and the virtual-sensing error of a run.
    fn summarise(&self, run: &Run) -> RunSummary;
    /// Candidates for the next effect, given the current model's `effects` and the summary of
    /// its run, in tiers: a later tier is tried only when no candidate of an earlier one is kept
    /// (the catch-all goes last). The engine drops effects already in the model.
    fn candidates(&self, summary: &RunSummary, effects: &[(Self::Effect, f64)]) -> Vec<Vec<Self::Effect>>;
    /// How `effect` reads in the report.
    fn label(&self, effect: &Self::Effect) -> EffectLabel;
    /// Free parameters `effect` costs in the BIC.
    fn parameters(&self, effect: &Self::Effect) -> usize;
    /// The range of the effect's scalar and the grid points to search it with, if it has one.
    fn scalar(&self, effect: &Self::Effect) -> Option<(ScalarRange, usize)>;
    /// The size the report gives `effect` (in the model of `run`).
    fn value(&self, model: &Self::Model, run: &Run, effect: &Self::Effect, theta: f64) -> f64;
    /// Effects to screen at the end for identifiability, each with the scalars to try (a
    /// component parameter halved and doubled): if none of them changes the log-likelihood by
    /// more than the effect's BIC cost, the data cannot see it. None by default.
    fn screened(&self) -> Vec<(Self::Effect, Vec<f64>)> {
        Vec::new()
    }
    /// Time, channels, virtual rows and truth for the report's plots (the engine fills in
    /// the runs before and after).
    fn traces(&self) -> Traces;
    /// The system's own part of the report (none by default).
    fn section(&self) -> SystemSection {
        SystemSection::default()
    }
}

/// A candidate fitted to the data.
struct Fitted<E, M> {
    effect: E,
    theta: f64,
    model: M,
    run: Run,
    delta: f64,
    halves: [f64; 2],
    penalty: f64,
    label: EffectLabel,
}

/// An effect kept, with the lines it explained.
struct Kept<E> {
    effect: E,
    theta: f64,
    delta: f64,
    penalty: f64,
    label: EffectLabel,
    explains: Vec<f64>,
}

/// The engine's view of a system during one search.
struct Engine<'a, S: LoopSystem> {
    sys: &'a S,
    options: &'a LoopOptions,
    /// Scalar measurements in the run (for the BIC).
    n_meas: f64,
}

impl<S: LoopSystem> Engine<'_, S> {
    fn penalty(&self, e: &S::Effect) -> f64 {
        0.5 * self.sys.parameters(e) as f64 * self.n_meas.ln()
    }

    /// Gain in log-likelihood of `run` over `base`, in the first and the second half.
    fn halves(&self, run: &Run, base: &Run) -> [f64; 2] {
        let n = run.nis.len().min(base.nis.len());
        let mid = n / 2;
        let part = |r: &Run, lo: usize, hi: usize| -> f64 {
            -0.5 * (lo..hi)
                .filter(|&k| r.nis[k].is_finite() && r.log_det_s[k].is_finite())
                .map(|k| r.nis[k] + r.log_det_s[k])
                .sum::<f64>()
        };
        [part(run, 0, mid) - part(base, 0, mid), part(run, mid, n) - part(base, mid, n)]
    }

    /// Fits `cand` on top of `effects`: its scalar by maximum likelihood, its states by the
    /// filter.
    fn fit(&self, effects: &[(S::Effect, f64)], cand: S::Effect, base: &Run) -> Result<Fitted<S::Effect, S::Model>> {
        let with = |theta: f64| {
            let mut e = effects.to_vec();
            e.push((cand, theta));
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
                    return Err(anyhow!(
                        "the likelihood peaks at the edge of the scalar's range ({x:.4}): not an estimate"
                    ));
                }
                x
            }
            None => 0.0,
        };
        let (model, run) = self.sys.run(&with(theta))?;
        let delta = run.log_likelihood() - base.log_likelihood();
        let halves = self.halves(&run, base);
        let label = self.sys.label(&cand);
        Ok(Fitted { effect: cand, theta, model, run, delta, halves, penalty: self.penalty(&cand), label })
    }

    fn trial(&self, iteration: usize, f: &Fitted<S::Effect, S::Model>, accepted: bool) -> Trial {
        Trial {
            iteration,
            kind: f.label.kind,
            location: f.label.location.clone(),
            order: f.label.detail.order,
            parameter: f.label.detail.parameter.clone(),
            unit: f.label.unit.clone(),
            value: self.sys.scalar(&f.effect).map(|_| self.sys.value(&f.model, &f.run, &f.effect, f.theta)),
            delta_log_likelihood: f.delta,
            delta_halves: f.halves,
            bic_penalty: f.penalty,
            accepted,
        }
    }

    /// `kind at location: Δ log-likelihood, BIC cost, halves`.
    fn describe(&self, f: &Fitted<S::Effect, S::Model>) -> String {
        format!(
            "{} at {}: Δ log-likelihood {:.1}, BIC cost {:.1}, halves {:.1} / {:.1}",
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
        effects: &[(S::Effect, f64)],
        cands: Vec<S::Effect>,
        base: &Run,
        refused: &mut Vec<Refused>,
    ) -> Vec<Fitted<S::Effect, S::Model>> {
        let total = cands.len();
        let mut results = Vec::new();
        for (i, cand) in cands.into_iter().enumerate() {
            let label = self.sys.label(&cand);
            self.progress(|| {
                format!("iteration {iteration}: candidate {}/{total}: {} at {}", i + 1, label.kind, label.location)
            });
            match self.fit(effects, cand, base) {
                Ok(f) => results.push(f),
                Err(e) => {
                    self.progress(|| format!("  {} at {}: {e:#}", label.kind, label.location));
                    refused.push(Refused {
                        kind: label.kind,
                        location: label.location.clone(),
                        value: None,
                        reason: format!("{e:#}"),
                    });
                }
            }
        }
        results
    }

    /// Pays for itself: the whole run gains more than the BIC cost, and each half at least
    /// `half_gain` of it.
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

    /// An effect that pays over the whole run but not in both halves: helping only part of the
    /// run, it is not a constant property of the system.
    fn partial(&self, f: &Fitted<S::Effect, S::Model>) -> Signature {
        Signature {
            channel: f.label.location.clone(),
            frequency_hz: None,
            statistic: "delta_log_likelihood_halves".into(),
            value: f.halves[0].min(f.halves[1]),
            description: format!(
                "{}: it helps only part of the run, so it is not a constant property",
                self.describe(f)
            ),
        }
    }

    /// The refusal of an effect that pays over the whole run but not in both halves.
    fn refused_in_halves(&self, f: &Fitted<S::Effect, S::Model>) -> Refused {
        Refused {
            kind: f.label.kind,
            location: f.label.location.clone(),
            value: self.sys.scalar(&f.effect).map(|_| self.sys.value(&f.model, &f.run, &f.effect, f.theta)),
            reason: format!(
                "pays over the whole run (Δ log-likelihood {:.1} against a BIC cost of {:.1}) but not in both halves ({:.1} / {:.1}): it helps only part of the run",
                f.delta, f.penalty, f.halves[0], f.halves[1]
            ),
        }
    }

    /// Effects of [`LoopSystem::screened`] the data cannot see from the final model.
    fn screen(&self, effects: &[(S::Effect, f64)], run: &Run) -> Result<Vec<NotIdentifiable>> {
        let base = run.log_likelihood();
        let mut out = Vec::new();
        for (e, thetas) in self.sys.screened() {
            if effects.iter().any(|(x, _)| *x == e) {
                continue;
            }
            let penalty = self.penalty(&e);
            let label = self.sys.label(&e);
            let mut worst: f64 = 0.0;
            for theta in thetas {
                let mut trial = effects.to_vec();
                trial.push((e, theta));
                let (_, r) = self.sys.run(&trial)?;
                worst = worst.max((r.log_likelihood() - base).abs());
                if worst > penalty {
                    break;
                }
            }
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

/// Closes the loop on `sys`: runs its base model, then adds effects while the innovations are
/// not consistent and an effect pays for its parameters (BIC) in both halves of the run; then
/// screens what the data cannot see and reports what is left.
pub fn search<S: LoopSystem>(sys: &S, options: &LoopOptions) -> Result<LoopReport> {
    let mut engine = Engine { sys, options, n_meas: 2.0 };
    let mut effects: Vec<(S::Effect, f64)> = Vec::new();
    engine.progress(|| "running the base model".into());
    let (mut cur_model, mut cur_run) = sys.run(&effects)?;
    engine.n_meas = cur_run.measurements().max(2) as f64;
    let engine = engine;
    let base_run = cur_run.clone();
    let before = sys.summarise(&cur_run);
    let mut current = before.clone();
    let mut added: Vec<Kept<S::Effect>> = Vec::new();
    let mut trials = Vec::new();
    let mut not_identifiable = Vec::new();
    let mut partial: Vec<Signature> = Vec::new();
    let mut refused: Vec<Refused> = Vec::new();
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
        let mut chosen = None;
        let mut evaluated = Vec::new();
        for tier in sys.candidates(&current, &effects) {
            let mut fresh: Vec<S::Effect> = Vec::new();
            for e in tier {
                if !effects.iter().any(|(x, _)| *x == e) && !fresh.contains(&e) {
                    fresh.push(e);
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
        engine.progress(|| {
            format!(
                "iteration {iteration}: kept {} at {} (Δ log-likelihood {:.1}, BIC cost {:.1})",
                win.label.kind, win.label.location, win.delta, win.penalty
            )
        });
        let next = sys.summarise(&win.run);
        let explains = explained(&current, &next);
        effects.push((win.effect, win.theta));
        added.push(Kept {
            effect: win.effect,
            theta: win.theta,
            delta: win.delta,
            penalty: win.penalty,
            label: win.label,
            explains,
        });
        (cur_model, cur_run) = (win.model, win.run);
        current = next;
    }
    if options.screen_parameters {
        not_identifiable.extend(engine.screen(&effects, &cur_run)?);
    }
    let effects_added = added
        .into_iter()
        .map(|f| AddedEffect {
            kind: f.label.kind,
            location: f.label.location,
            value: sys.value(&cur_model, &cur_run, &f.effect, f.theta),
            unit: f.label.unit,
            detail: f.label.detail,
            explains: f.explains,
            delta_log_likelihood: f.delta,
            bic_penalty: f.penalty,
        })
        .collect();
    let unexplained = if current.consistent {
        Vec::new()
    } else {
        let mut u = unexplained(&current, &options.signatures);
        u.extend(partial);
        u
    };
    let traces = Traces { before: base_run, after: cur_run, ..sys.traces() };
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
        section: sys.section(),
        traces,
    })
}
