//! Signatures of the innovations, candidate effects, and the accept-by-BIC loop.

use super::filter::{self, Run};
use super::model::{augment, AugmentedModel, Effect, EffectTuning, Flexibility};
use crate::io::data::DataFile;
use crate::rotor::RotorModel;
use crate::rotor_akf::{reduce, ReducedRotor, Tuning};
use anyhow::{anyhow, Result};
use edgekf::residual::{locate_peak, NisBounds, PeakClass, PeakTolerance, RunningStats, Welch, WhitenessWindow};
use serde::Serialize;
use std::collections::BTreeMap;

/// How the loop runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopOptions {
    /// The base filter's tuning.
    pub tuning: Tuning,
    /// The effects' noise and priors.
    pub effect_tuning: EffectTuning,
    /// Samples before this time (s after the first) are left out of the statistics.
    pub settle: f64,
    /// Virtual-sensing errors are computed from this time on (s after the first sample).
    pub error_after: f64,
    /// At most this many effects are added.
    pub max_effects: usize,
    /// A channel's innovation mean this many standard errors from zero proposes a bias.
    pub bias_z: f64,
    /// False-alarm probability of the whiteness and NIS tests.
    pub alpha: f64,
    /// Spectral peaks of the normalised innovations at least this far above the median, dB.
    pub peak_db: f32,
    /// Two locations whose log-likelihoods differ by less than this are reported as not
    /// identifiable from each other.
    pub identifiable_margin: f64,
}

impl Default for LoopOptions {
    fn default() -> Self {
        Self {
            tuning: Tuning::default(),
            effect_tuning: EffectTuning::default(),
            settle: 0.5,
            error_after: 1.0,
            max_effects: 4,
            bias_z: 5.0,
            alpha: 0.01,
            peak_db: 10.0,
            identifiable_margin: 2.0,
        }
    }
}

/// A spectral peak of one channel's normalised innovation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeakSignature {
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// Above the median level, dB.
    pub prominence_db: f64,
    /// Where it sits (`2x`, `natural 0`, `2x at natural 1`, `unexplained`).
    pub class: String,
    /// The integer order of the running speed it sits at, if any.
    pub order: Option<u32>,
}

/// Innovation statistics of one channel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelSignature {
    /// Channel.
    pub name: String,
    /// Mean innovation.
    pub mean: f64,
    /// Its standard error.
    pub standard_error: f64,
    /// `mean / standard_error`.
    pub z: f64,
    /// RMS innovation.
    pub rms: f64,
    /// Mean of `e² / S_ii` (1 when consistent).
    pub nis: f64,
    /// Ljung–Box p-value (20 lags over the last 2048 samples).
    pub whiteness_p: f64,
    /// Spectral peaks.
    pub peaks: Vec<PeakSignature>,
}

/// A run's summary as reported.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunSummary {
    /// RMS innovation per channel.
    pub innovation_rms: BTreeMap<String, f64>,
    /// Mean NIS divided by the number of channels (1.0 when consistent).
    pub nis_mean: f64,
    /// Whether the mean NIS lies within its χ² bounds at `alpha`.
    pub nis_consistent: bool,
    /// Smallest Ljung–Box p-value over the channels.
    pub whiteness_p: f64,
    /// RMS error of the disk/unbalance-node displacement against `truth_` columns, m.
    pub error_rms: BTreeMap<String, f64>,
    /// `−½ Σ (ln det S + NIS)` over the run.
    pub log_likelihood: f64,
    /// Per-channel signatures.
    pub channels: Vec<ChannelSignature>,
}

/// An effect the loop kept.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AddedEffect {
    /// `sensor_bias`, `harmonic_force`.
    pub kind: String,
    /// Channel name or `node N`.
    pub location: String,
    /// Estimated size (bias; force amplitude), averaged over the second half of the run.
    pub value: f64,
    /// Unit of `value`.
    pub unit: String,
    /// Order of the running speed (harmonic forces).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<u32>,
    /// Gain in log-likelihood.
    pub delta_log_likelihood: f64,
    /// Its cost: `½ p ln n`.
    pub bic_penalty: f64,
    /// The effect.
    #[serde(skip)]
    pub effect: Effect,
}

/// One candidate evaluated.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trial {
    /// Iteration.
    pub iteration: usize,
    /// Kind.
    pub kind: String,
    /// Location.
    pub location: String,
    /// Order (harmonic forces).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<u32>,
    /// Gain in log-likelihood over the current model.
    pub delta_log_likelihood: f64,
    /// `½ p ln n`.
    pub bic_penalty: f64,
    /// Kept.
    pub accepted: bool,
}

/// What the loop found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoopReport {
    /// The system (`rotor`).
    pub system: String,
    /// Effects kept, in order.
    pub effects_added: Vec<AddedEffect>,
    /// The base model.
    pub before: RunSummary,
    /// The final model.
    pub after: RunSummary,
    /// Effects whose location (or kind) the data cannot tell apart.
    pub not_identifiable: Vec<String>,
    /// Signatures left that no kept effect explains.
    pub unexplained: Vec<String>,
    /// Every candidate evaluated.
    pub trials: Vec<Trial>,
    /// Why the loop stopped.
    pub stopped: String,
}

struct Context<'a> {
    red: ReducedRotor,
    model: &'a RotorModel,
    flex: Flexibility,
    columns: Vec<Vec<f64>>,
    t: Vec<f64>,
    /// Displacement rows reported (disk and unbalance nodes, x and y) and their names.
    rows: Vec<usize>,
    row_names: Vec<String>,
    /// Nodes where a harmonic force is tried.
    force_sites: Vec<usize>,
    options: LoopOptions,
    data: &'a DataFile,
}

impl Context<'_> {
    fn run(&self, effects: &[Effect]) -> Result<(AugmentedModel, Run)> {
        let m = augment(&self.red, self.model, &self.flex, effects, &self.options.effect_tuning)?;
        let cols: Vec<&[f64]> = self.columns.iter().map(Vec::as_slice).collect();
        let run = filter::run(&m, 1.0 / self.red.sample_rate, &cols, &self.rows)?;
        Ok((m, run))
    }

    fn summarise(&self, run: &Run) -> RunSummary {
        let t0 = self.t.first().copied().unwrap_or(0.0);
        let keep: Vec<usize> = (0..self.t.len()).filter(|&k| self.t[k] - t0 >= self.options.settle).collect();
        let mut channels = Vec::new();
        let naturals = &self.red.frequencies_hz;
        for (i, name) in self.red.channels.iter().enumerate() {
            let mut stats = RunningStats::<f64>::new();
            let mut nis = RunningStats::<f64>::new();
            let mut white = WhitenessWindow::<f64, 2048>::new();
            let mut welch = Welch::<1024>::new(self.red.sample_rate as f32);
            for &k in &keep {
                let e = run.innovation[i][k];
                let s = run.variance[i][k];
                if !(e.is_finite() && s.is_finite()) {
                    continue;
                }
                stats.push(e);
                nis.push(e * e / s);
                let z = e / s.sqrt();
                white.push(z);
                if let Some(w) = welch.as_mut() {
                    w.push(z);
                }
            }
            let lb = white.ljung_box(20);
            let mut peaks = Vec::new();
            if let Some(w) = welch.as_ref().filter(|w| w.blocks() > 0) {
                let tol = PeakTolerance::new(1.2 * w.bin_width_hz() as f64);
                for p in w.peaks::<8>(self.options.peak_db).iter() {
                    let loc = locate_peak(p.frequency_hz as f64, self.red.speed, naturals, &tol);
                    let (class, order) = match loc.class {
                        PeakClass::Order(o) => {
                            (format!("{}/{}x", o.numerator, o.denominator), o.is_integer().then_some(o.numerator))
                        }
                        PeakClass::OrderAtNatural { order: o, natural } => (
                            format!("{}/{}x at natural {natural}", o.numerator, o.denominator),
                            o.is_integer().then_some(o.numerator),
                        ),
                        PeakClass::Natural(n) => (format!("natural {n}"), None),
                        PeakClass::Unexplained => ("unexplained".to_string(), None),
                    };
                    peaks.push(PeakSignature {
                        frequency_hz: p.frequency_hz as f64,
                        prominence_db: p.prominence_db as f64,
                        class: class.replace("/1x", "x"),
                        order,
                    });
                }
            }
            let se = stats.standard_error();
            channels.push(ChannelSignature {
                name: name.clone(),
                mean: stats.mean(),
                standard_error: se,
                z: stats.mean() / se,
                rms: stats.rms(),
                nis: nis.mean(),
                whiteness_p: lb.p_value,
                peaks,
            });
        }
        let mut nis_total = RunningStats::<f64>::new();
        for &k in &keep {
            nis_total.push(run.nis[k]);
        }
        let m = self.red.channels.len();
        let bounds = NisBounds::new(m, nis_total.count().max(1) as usize, self.options.alpha);
        let mut error_rms = BTreeMap::new();
        for (j, name) in self.row_names.iter().enumerate() {
            if let Some(truth) = self.data.column(&format!("truth_{name}")) {
                let (mut s, mut n) = (0.0, 0usize);
                for ((tk, est), tr) in self.t.iter().zip(&run.outputs[j]).zip(truth) {
                    if tk - t0 >= self.options.error_after && tr.is_finite() {
                        s += (est - tr).powi(2);
                        n += 1;
                    }
                }
                if n > 0 {
                    error_rms.insert(name.clone(), (s / n as f64).sqrt());
                }
            }
        }
        RunSummary {
            innovation_rms: channels.iter().map(|c| (c.name.clone(), c.rms)).collect(),
            nis_mean: nis_total.mean() / m as f64,
            nis_consistent: bounds.contains(nis_total.mean()),
            whiteness_p: channels.iter().map(|c| c.whiteness_p).fold(1.0, f64::min),
            error_rms,
            log_likelihood: run.log_likelihood(),
            channels,
        }
    }

    /// Whether the innovations are white (Bonferroni over the channels), unbiased and NIS
    /// consistent.
    fn consistent(&self, s: &RunSummary) -> bool {
        let m = s.channels.len().max(1) as f64;
        s.nis_consistent
            && s.whiteness_p >= self.options.alpha / m
            && s.channels.iter().all(|c| c.z.abs() < self.options.bias_z)
    }

    /// Candidates from the signatures, strongest first, not already in `effects`.
    fn candidates(&self, s: &RunSummary, effects: &[Effect]) -> Vec<Effect> {
        let mut out = Vec::new();
        let mut biased: Vec<(f64, usize)> = s
            .channels
            .iter()
            .enumerate()
            .filter(|(_, c)| c.z.abs() >= self.options.bias_z)
            .map(|(i, c)| (c.z.abs(), i))
            .collect();
        biased.sort_by(|a, b| b.0.total_cmp(&a.0));
        out.extend(biased.into_iter().map(|(_, channel)| Effect::SensorBias { channel }));
        let mut orders: Vec<(f64, u32)> = Vec::new();
        for c in &s.channels {
            for p in &c.peaks {
                if let Some(k) = p.order {
                    match orders.iter_mut().find(|(_, o)| *o == k) {
                        Some(e) => e.0 = e.0.max(p.prominence_db),
                        None => orders.push((p.prominence_db, k)),
                    }
                }
            }
        }
        orders.sort_by(|a, b| b.0.total_cmp(&a.0));
        for (_, order) in orders {
            for &node in &self.force_sites {
                if order == 1 && self.red.force_nodes.contains(&node) {
                    continue;
                }
                out.push(Effect::HarmonicForce { node, order });
            }
        }
        out.retain(|e| !effects.contains(e));
        out
    }

    fn value(&self, model: &AugmentedModel, run: &Run, effect: Effect) -> f64 {
        let Some(start) = model.effects.iter().position(|(e, _)| *e == effect) else { return f64::NAN };
        let offset: usize = model.effects[..start].iter().map(|(e, _)| e.states()).sum();
        let n = self.t.len();
        let half = n / 2;
        let avg = |f: &dyn Fn(usize) -> f64| (half..n).map(f).sum::<f64>() / (n - half).max(1) as f64;
        match effect {
            Effect::SensorBias { .. } => avg(&|k| run.effect_states[offset][k]),
            Effect::HarmonicForce { .. } => {
                avg(&|k| run.effect_states[offset][k].hypot(run.effect_states[offset + 1][k]))
            }
        }
    }
}

fn order_of(e: &Effect) -> Option<u32> {
    match *e {
        Effect::HarmonicForce { order, .. } => Some(order),
        Effect::SensorBias { .. } => None,
    }
}

/// The family of an effect for identifiability: same kind and order, different location.
fn family(e: &Effect) -> (&'static str, Option<u32>) {
    (e.kind(), order_of(e))
}

/// Closes the loop on `data` with the rotor `model` (its configured sensors, unbalance nodes
/// and operating speed): runs the base filter, then adds effects while the innovations are
/// not consistent and an effect pays for its parameters (BIC).
pub fn close_loop(model: &RotorModel, data: &DataFile, options: &LoopOptions) -> Result<LoopReport> {
    let cfg = model.config();
    let speed = cfg.operation.speed;
    let red = reduce(model, speed, &options.tuning)?;
    let columns: Vec<Vec<f64>> = red
        .channels
        .iter()
        .zip(&red.offsets)
        .map(|(name, off)| {
            data.column(name)
                .map(|c| c.iter().map(|v| v - off).collect())
                .ok_or_else(|| anyhow!("the data file has no channel {name}"))
        })
        .collect::<Result<_>>()?;
    let mut force_sites: Vec<usize> = cfg.disks.iter().map(|d| d.node).chain(red.force_nodes.iter().copied()).collect();
    force_sites.sort_unstable();
    force_sites.dedup();
    let rows: Vec<usize> = force_sites.iter().flat_map(|&n| [2 * n, 2 * n + 1]).collect();
    let row_names: Vec<String> = force_sites.iter().flat_map(|&n| [format!("n{n}_x"), format!("n{n}_y")]).collect();
    let ctx = Context {
        flex: Flexibility::new(model, speed),
        red,
        model,
        columns,
        t: data.t.clone(),
        rows,
        row_names,
        force_sites,
        options: *options,
        data,
    };
    let mut effects: Vec<Effect> = Vec::new();
    let (mut cur_model, mut cur_run) = ctx.run(&effects)?;
    let before = ctx.summarise(&cur_run);
    let mut current = before.clone();
    let mut added = Vec::new();
    let mut trials = Vec::new();
    let mut not_identifiable = Vec::new();
    let n_meas = cur_run.measurements().max(2) as f64;
    let stopped;
    let mut iteration = 0;
    loop {
        if ctx.consistent(&current) {
            stopped = "the innovations are white, unbiased and NIS-consistent".to_string();
            break;
        }
        if effects.len() >= options.max_effects {
            stopped = format!("reached the limit of {} effects", options.max_effects);
            break;
        }
        let cands = ctx.candidates(&current, &effects);
        if cands.is_empty() {
            stopped = "no candidate effect matches the remaining signatures".to_string();
            break;
        }
        iteration += 1;
        let base_ll = cur_run.log_likelihood();
        let mut results = Vec::new();
        for cand in cands {
            let mut trial = effects.clone();
            trial.push(cand);
            match ctx.run(&trial) {
                Ok((m, r)) => {
                    let d = r.log_likelihood() - base_ll;
                    results.push((cand, d, m, r));
                }
                Err(e) => eprintln!("candidate {} at {}: {e:#}", cand.kind(), cand.location(&ctx.red.channels)),
            }
        }
        let Some(best) = results.iter().enumerate().max_by(|a, b| a.1 .1.total_cmp(&b.1 .1)).map(|(i, _)| i) else {
            stopped = "no candidate could be evaluated".to_string();
            break;
        };
        let best_effect = results[best].0;
        let best_d = results[best].1;
        let penalty = 0.5 * best_effect.parameters() as f64 * n_meas.ln();
        let accepted = best_d > penalty;
        for (cand, d, _, _) in &results {
            trials.push(Trial {
                iteration,
                kind: cand.kind().to_string(),
                location: cand.location(&ctx.red.channels),
                order: order_of(cand),
                delta_log_likelihood: *d,
                bic_penalty: 0.5 * cand.parameters() as f64 * n_meas.ln(),
                accepted: accepted && *cand == best_effect,
            });
        }
        if !accepted {
            stopped = format!(
                "the best candidate ({} at {}) gains {best_d:.2} in log-likelihood, less than its BIC cost {penalty:.2}",
                best_effect.kind(),
                best_effect.location(&ctx.red.channels)
            );
            break;
        }
        let rivals: Vec<String> = results
            .iter()
            .filter(|(c, d, _, _)| {
                *c != best_effect && family(c) == family(&best_effect) && best_d - d < options.identifiable_margin
            })
            .map(|(c, d, _, _)| format!("{} (Δ log-likelihood {:.2} lower)", c.location(&ctx.red.channels), best_d - d))
            .collect();
        if !rivals.is_empty() {
            not_identifiable.push(format!(
                "{} at {} is not distinguishable from {}",
                best_effect.kind(),
                best_effect.location(&ctx.red.channels),
                rivals.join(", ")
            ));
        }
        let (_, _, m, r) = results.swap_remove(best);
        cur_model = m;
        cur_run = r;
        effects.push(best_effect);
        added.push((best_effect, best_d, penalty));
        current = ctx.summarise(&cur_run);
    }
    let effects_added = added
        .into_iter()
        .map(|(e, d, penalty)| AddedEffect {
            kind: e.kind().to_string(),
            location: e.location(&ctx.red.channels),
            value: ctx.value(&cur_model, &cur_run, e),
            unit: e.unit().to_string(),
            order: order_of(&e),
            delta_log_likelihood: d,
            bic_penalty: penalty,
            effect: e,
        })
        .collect();
    let unexplained = unexplained(&ctx, &current);
    Ok(LoopReport {
        system: "rotor".to_string(),
        effects_added,
        before,
        after: current,
        not_identifiable,
        unexplained,
        trials,
        stopped,
    })
}

fn unexplained(ctx: &Context<'_>, s: &RunSummary) -> Vec<String> {
    let mut out = Vec::new();
    let m = s.channels.len().max(1) as f64;
    for c in &s.channels {
        if c.z.abs() >= ctx.options.bias_z {
            out.push(format!("{}: innovation mean {:.3e} is {:.1} standard errors from zero", c.name, c.mean, c.z));
        }
        if c.whiteness_p < ctx.options.alpha / m {
            out.push(format!("{}: not white (Ljung–Box p = {:.2e})", c.name, c.whiteness_p));
        }
        for p in &c.peaks {
            out.push(format!(
                "{}: spectral peak at {:.2} Hz ({:.1} dB, {})",
                c.name, p.frequency_hz, p.prominence_db, p.class
            ));
        }
    }
    if !s.nis_consistent {
        out.push(format!("NIS mean {:.3} per channel outside its χ² bounds", s.nis_mean));
    }
    out
}
