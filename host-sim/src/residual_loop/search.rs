//! The search: candidates from the signatures, each fitted (its states by the filter, its
//! scalar by maximum likelihood) and kept only if it pays for its parameters (BIC) in both
//! halves of the run; then what is left is reported.

use super::filter::{self, Run};
use super::model::{apply_parameters, augment, AugmentedModel, Effect, EffectTuning, Flexibility, Parameter};
use super::optimize::maximise;
use super::signature::{summarise, unexplained, Signature, SignatureOptions};
use crate::io::data::DataFile;
use crate::rotor::bearing_geometry::BearingLine;
use crate::rotor::{RotorConfig, RotorModel};
use crate::rotor_akf::{reduce, ReducedRotor, Tuning};
use anyhow::{anyhow, Result};
use serde::Serialize;

pub use super::signature::{ChannelSignature, PeakSignature, RunSummary};

/// How the loop runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopOptions {
    /// The base filter's tuning.
    pub tuning: Tuning,
    /// The effects' noise and priors.
    pub effect_tuning: EffectTuning,
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
            tuning: Tuning::default(),
            effect_tuning: EffectTuning::default(),
            signatures: SignatureOptions::default(),
            max_effects: 4,
            half_gain: 0.25,
            identifiable_margin: 2.0,
            screen_parameters: true,
            progress: false,
        }
    }
}

/// An effect the loop kept.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AddedEffect {
    /// One of `sensor_bias`, `sensor_scale`, `sensor_delay`, `harmonic_force`,
    /// `unknown_input`, `parameter`, `extra_mode`, `bearing_defect`.
    pub kind: String,
    /// Channel name, `node N`, or a component (`disk 12`, `shaft`, `bearing 4`).
    pub location: String,
    /// Estimated size in SI units (a force's amplitude averaged over the second half of the
    /// run), or the factor on the declared value for `sensor_scale` and `parameter`.
    pub value: f64,
    /// Unit of `value` (`1` for a factor).
    pub unit: String,
    /// Order of the running speed (harmonic forces, bearing lines).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<f64>,
    /// The parameter (`mass`, `young`, `kxx`, …) of a `parameter` effect.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parameter: Option<String>,
    /// The bearing line (`BPFO`, `BPFI`, `BSF`, `FTF`) of a `bearing_defect`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub line: Option<String>,
    /// Spectral lines (Hz) of the innovations that were there before this effect and are gone
    /// after it.
    pub explains: Vec<f64>,
    /// Gain in log-likelihood.
    pub delta_log_likelihood: f64,
    /// Its cost: `½ p ln n`.
    pub bic_penalty: f64,
    /// The effect and its fitted scalar.
    #[serde(skip)]
    pub effect: (Effect, f64),
}

/// An effect (or location) the data cannot resolve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NotIdentifiable {
    /// Kind.
    pub kind: String,
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
    pub kind: String,
    /// Location.
    pub location: String,
    /// Order (harmonic forces, bearing lines).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<f64>,
    /// Parameter name (parameter effects).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parameter: Option<String>,
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
    pub channels: Vec<String>,
    /// Virtual-sensing rows (`n12_x`, …).
    pub rows: Vec<String>,
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
    /// The system (`rotor`).
    pub system: String,
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
    /// Every candidate evaluated.
    pub trials: Vec<Trial>,
    /// Why the loop stopped.
    pub stopped: String,
    /// The series behind the plots.
    #[serde(skip)]
    pub traces: Traces,
}

/// A candidate fitted to the data.
struct Fitted {
    effect: Effect,
    theta: f64,
    model: AugmentedModel,
    run: Run,
    delta: f64,
    halves: [f64; 2],
    penalty: f64,
}

struct Context<'a> {
    cfg: &'a RotorConfig,
    model: &'a RotorModel,
    red: ReducedRotor,
    flex: Flexibility,
    columns: Vec<Vec<f64>>,
    t: Vec<f64>,
    rows: Vec<usize>,
    row_names: Vec<String>,
    /// Nodes where forces are tried (disks and unbalances).
    force_sites: Vec<usize>,
    /// Bearing lines as orders: (bearing index, line, order).
    lines: Vec<(usize, BearingLine, f64)>,
    options: LoopOptions,
    data: &'a DataFile,
    n_meas: f64,
}

impl Context<'_> {
    fn channels(&self) -> usize {
        self.red.channels.len()
    }

    fn run(&self, effects: &[(Effect, f64)]) -> Result<(AugmentedModel, Run)> {
        let cols: Vec<&[f64]> = self.columns.iter().map(Vec::as_slice).collect();
        let dt = 1.0 / self.red.sample_rate;
        let tuning = &self.options.effect_tuning;
        let m = if effects.iter().any(|(e, _)| matches!(e, Effect::Parameter(_))) {
            let cfg = apply_parameters(self.cfg, effects)?;
            let model = RotorModel::from_config(&cfg)?;
            let red = reduce(&model, self.red.speed, &self.options.tuning)?;
            let flex = Flexibility::new(&model, self.red.speed);
            augment(&red, &model, &flex, effects, tuning)?
        } else {
            augment(&self.red, self.model, &self.flex, effects, tuning)?
        };
        let run = filter::run(&m, dt, &cols, &self.rows)?;
        Ok((m, run))
    }

    fn summarise(&self, run: &Run) -> RunSummary {
        let truth: Vec<Option<&[f64]>> =
            self.row_names.iter().map(|n| self.data.column(&format!("truth_{n}"))).collect();
        summarise(
            run,
            &self.t,
            &self.red.channels,
            &self.row_names,
            &truth,
            self.red.speed,
            &self.red.frequencies_hz,
            &self.lines,
            self.red.sample_rate,
            &self.options.signatures,
        )
    }

    fn penalty(&self, e: &Effect) -> f64 {
        0.5 * e.parameters(self.channels()) as f64 * self.n_meas.ln()
    }

    fn location(&self, e: &Effect) -> String {
        e.location(&self.red.channels, self.cfg)
    }

    /// The value the report gives an effect: its fitted scalar, or its states' size over the
    /// second half of the run.
    fn value(&self, model: &AugmentedModel, run: &Run, effect: Effect, theta: f64) -> f64 {
        let Some(pos) = model.effects.iter().position(|(e, _, _)| *e == effect) else { return f64::NAN };
        let m = self.channels();
        let offset: usize = model.effects[..pos].iter().map(|(e, _, _)| e.states(m)).sum();
        let n = self.t.len();
        let half = n / 2;
        let avg = |f: &dyn Fn(usize) -> f64| (half..n).map(f).sum::<f64>() / (n - half).max(1) as f64;
        let s = &run.effect_states;
        match effect {
            Effect::SensorBias { .. } => avg(&|k| s[offset][k]),
            Effect::HarmonicForce { .. } | Effect::BearingDefect { .. } => {
                avg(&|k| s[offset][k].hypot(s[offset + 1][k]))
            }
            Effect::UnknownInput { .. } => avg(&|k| s[offset][k].powi(2) + s[offset + 1][k].powi(2)).sqrt(),
            Effect::SensorScale { .. } | Effect::Parameter(_) => theta.exp(),
            Effect::SensorDelay { .. } | Effect::ExtraMode { .. } => theta,
        }
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
    fn fit(&self, effects: &[(Effect, f64)], cand: Effect, base: &Run) -> Result<Fitted> {
        let with = |theta: f64| {
            let mut e = effects.to_vec();
            e.push((cand, theta));
            e
        };
        let theta = match cand.scalar(self.red.sample_rate) {
            Some(range) => {
                let grid = match cand {
                    Effect::Parameter(_) => 7,
                    _ => 4,
                };
                let best = maximise(
                    |th| self.run(&with(th)).ok().map(|(_, r)| r.log_likelihood()),
                    range.low,
                    range.high,
                    grid,
                    range.tolerance,
                )
                .ok_or_else(|| anyhow!("no value of the scalar gives a usable model"))?;
                best.x
            }
            None => 0.0,
        };
        let (model, run) = self.run(&with(theta))?;
        let delta = run.log_likelihood() - base.log_likelihood();
        let halves = self.halves(&run, base);
        Ok(Fitted { effect: cand, theta, model, run, delta, halves, penalty: self.penalty(&cand) })
    }

    /// Candidates named directly by a signature (a bias, a line at an order, a bearing line or
    /// elsewhere), then the structural ones (scales, delays, parameters, 1× forces off the
    /// unbalance nodes) when the innovations carry lines or colour, then the catch-all.
    fn candidates(&self, s: &RunSummary, effects: &[(Effect, f64)]) -> [Vec<Effect>; 2] {
        let mut named = Vec::new();
        let mut biased: Vec<(f64, usize)> = s
            .channels
            .iter()
            .enumerate()
            .filter(|(_, c)| c.z.abs() >= self.options.signatures.bias_z)
            .map(|(i, c)| (c.z.abs(), i))
            .collect();
        biased.sort_by(|a, b| b.0.total_cmp(&a.0));
        named.extend(biased.into_iter().map(|(_, channel)| Effect::SensorBias { channel }));
        let mut structural = false;
        let mut modes: Vec<u32> = Vec::new();
        let mut orders: Vec<(f64, u32)> = Vec::new();
        for c in &s.channels {
            if c.whiteness_p < self.options.signatures.alpha || !c.peaks.is_empty() {
                structural = true;
            }
            for p in &c.peaks {
                if let Some((bearing, line)) = p.line {
                    if let Some(&(_, _, order)) = self.lines.iter().find(|(b, l, _)| *b == bearing && *l == line) {
                        named.push(Effect::BearingDefect { bearing, line, order_milli: (order * 1e3).round() as u32 });
                    }
                } else if let Some(k) = p.order {
                    match orders.iter_mut().find(|(_, o)| *o == k) {
                        Some(e) => e.0 = e.0.max(p.prominence_db),
                        None => orders.push((p.prominence_db, k)),
                    }
                } else if p.class == "unexplained" {
                    let mhz = (p.frequency_hz * 1e3).round() as u32;
                    let near = |m: &u32| (*m as f64 - mhz as f64).abs() * 1e-3 < 2.0 * s.bin_width_hz;
                    if !modes.iter().any(near) {
                        modes.push(mhz);
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
                named.push(Effect::HarmonicForce { node, order });
            }
        }
        named.extend(modes.into_iter().map(|seed_mhz| Effect::ExtraMode { seed_mhz }));
        if structural || !s.nis_consistent {
            for channel in 0..self.channels() {
                named.push(Effect::SensorScale { channel });
                named.push(Effect::SensorDelay { channel });
            }
            named.extend(Parameter::all(self.cfg).into_iter().map(Effect::Parameter));
        }
        let catch_all: Vec<Effect> = self.force_sites.iter().map(|&node| Effect::UnknownInput { node }).collect();
        let fresh = |v: Vec<Effect>| -> Vec<Effect> {
            let mut out: Vec<Effect> = Vec::new();
            for e in v {
                if !effects.iter().any(|(x, _)| *x == e) && !out.contains(&e) {
                    out.push(e);
                }
            }
            out
        };
        [fresh(named), fresh(catch_all)]
    }

    fn trial(&self, iteration: usize, f: &Fitted, accepted: bool) -> Trial {
        Trial {
            iteration,
            kind: f.effect.kind().to_string(),
            location: self.location(&f.effect),
            order: f.effect.order(),
            parameter: parameter_name(&f.effect),
            value: f.effect.scalar(self.red.sample_rate).map(|_| self.value(&f.model, &f.run, f.effect, f.theta)),
            delta_log_likelihood: f.delta,
            delta_halves: f.halves,
            bic_penalty: f.penalty,
            accepted,
        }
    }

    /// `kind at location (Δ log-likelihood, BIC cost, halves)`.
    fn describe(&self, f: &Fitted) -> String {
        format!(
            "{} at {}: Δ log-likelihood {:.1}, BIC cost {:.1}, halves {:.1} / {:.1}",
            f.effect.kind(),
            self.location(&f.effect),
            f.delta,
            f.penalty,
            f.halves[0],
            f.halves[1]
        )
    }

    fn progress(&self, msg: impl FnOnce() -> String) {
        if self.options.progress {
            eprintln!("loop: {}", msg());
        }
    }
}

fn parameter_name(e: &Effect) -> Option<String> {
    match e {
        Effect::Parameter(p) => Some(p.name().to_string()),
        _ => None,
    }
}

/// The family of an effect for identifiability: same kind and order, different location.
fn family(e: &Effect) -> (&'static str, Option<u64>, Option<&'static str>) {
    (e.kind(), e.order().map(f64::to_bits), parameter_name(e).map(|_| "parameter"))
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

/// Closes the loop on `data` with the rotor `model` (its configured sensors, unbalance nodes,
/// bearings and operating speed): runs the base filter, then adds effects while the
/// innovations are not consistent and an effect pays for its parameters (BIC) in both halves of
/// the run.
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
    let lines = cfg
        .bearings
        .iter()
        .enumerate()
        .filter_map(|(i, b)| b.geometry.map(|g| (i, g)))
        .flat_map(|(i, g)| BearingLine::ALL.map(|l| (i, l, g.order(l))))
        .collect();
    let mut ctx = Context {
        cfg,
        flex: Flexibility::new(model, speed),
        red,
        model,
        columns,
        t: data.t.clone(),
        rows,
        row_names,
        force_sites,
        lines,
        options: *options,
        data,
        n_meas: 2.0,
    };
    let mut effects: Vec<(Effect, f64)> = Vec::new();
    ctx.progress(|| "running the base model".into());
    let (mut cur_model, mut cur_run) = ctx.run(&effects)?;
    ctx.n_meas = cur_run.measurements().max(2) as f64;
    let base_run = cur_run.clone();
    let before = ctx.summarise(&cur_run);
    let mut current = before.clone();
    let mut added: Vec<(Effect, f64, f64, f64, Vec<f64>)> = Vec::new();
    let mut trials = Vec::new();
    let mut not_identifiable = Vec::new();
    let mut partial: Vec<Signature> = Vec::new();
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
        let tiers = ctx.candidates(&current, &effects);
        let mut chosen: Option<Fitted> = None;
        let mut evaluated: Vec<Fitted> = Vec::new();
        for cands in tiers {
            if chosen.is_some() || cands.is_empty() {
                continue;
            }
            let total = cands.len();
            let mut results = Vec::new();
            for (i, cand) in cands.into_iter().enumerate() {
                ctx.progress(|| {
                    format!(
                        "iteration {iteration}: candidate {}/{total}: {} at {}",
                        i + 1,
                        cand.kind(),
                        ctx.location(&cand)
                    )
                });
                match ctx.fit(&effects, cand, &cur_run) {
                    Ok(f) => results.push(f),
                    Err(e) => ctx.progress(|| format!("  {} at {}: {e:#}", cand.kind(), ctx.location(&cand))),
                }
            }
            let min_half = |f: &Fitted| f.halves[0].min(f.halves[1]) >= options.half_gain * f.penalty;
            let best = results
                .iter()
                .enumerate()
                .filter(|(_, f)| f.delta > f.penalty && min_half(f))
                .max_by(|a, b| (a.1.delta - a.1.penalty).total_cmp(&(b.1.delta - b.1.penalty)))
                .map(|(i, _)| i);
            for f in &results {
                if f.delta > f.penalty && !min_half(f) {
                    partial.push(Signature {
                        channel: ctx.location(&f.effect),
                        frequency_hz: None,
                        statistic: "delta_log_likelihood_halves".into(),
                        value: f.halves[0].min(f.halves[1]),
                        description: format!(
                            "{}: it helps only part of the run, so it is not a constant property",
                            ctx.describe(f)
                        ),
                    });
                }
            }
            if let Some(i) = best {
                let winner = results.swap_remove(i);
                let rivals: Vec<&Fitted> = results
                    .iter()
                    .filter(|f| {
                        family(&f.effect) == family(&winner.effect)
                            && ctx.location(&f.effect) != ctx.location(&winner.effect)
                            && (winner.delta - f.delta).abs() < options.identifiable_margin
                    })
                    .collect();
                for r in rivals {
                    not_identifiable.push(NotIdentifiable {
                        kind: winner.effect.kind().into(),
                        location: ctx.location(&r.effect),
                        parameter: parameter_name(&r.effect),
                        statistic: "delta_log_likelihood_gap".into(),
                        value: winner.delta - r.delta,
                        reason: format!(
                            "fits the data as well as {} (log-likelihoods {:.2} apart): the sensors cannot tell the two apart",
                            ctx.location(&winner.effect),
                            winner.delta - r.delta
                        ),
                    });
                }
                chosen = Some(winner);
            }
            evaluated.extend(results);
        }
        for f in &evaluated {
            trials.push(ctx.trial(iteration, f, false));
        }
        let Some(win) = chosen else {
            let best = evaluated.iter().max_by(|a, b| (a.delta - a.penalty).total_cmp(&(b.delta - b.penalty)));
            stopped = match best {
                Some(f) => {
                    format!("no candidate pays for itself in both halves of the run (best: {})", ctx.describe(f))
                }
                None => "no candidate effect matches the remaining signatures".into(),
            };
            break;
        };
        trials.push(ctx.trial(iteration, &win, true));
        ctx.progress(|| {
            format!(
                "iteration {iteration}: kept {} at {} (Δ log-likelihood {:.1}, BIC cost {:.1})",
                win.effect.kind(),
                ctx.location(&win.effect),
                win.delta,
                win.penalty
            )
        });
        let next = ctx.summarise(&win.run);
        added.push((win.effect, win.theta, win.delta, win.penalty, explained(&current, &next)));
        effects.push((win.effect, win.theta));
        cur_model = win.model;
        cur_run = win.run;
        current = next;
    }
    if options.screen_parameters {
        not_identifiable.extend(screen_parameters(&ctx, &effects, &cur_run)?);
    }
    let effects_added = added
        .into_iter()
        .map(|(e, theta, d, penalty, explains)| AddedEffect {
            kind: e.kind().to_string(),
            location: ctx.location(&e),
            value: ctx.value(&cur_model, &cur_run, e, theta),
            unit: e.unit().to_string(),
            order: e.order(),
            parameter: parameter_name(&e),
            line: match e {
                Effect::BearingDefect { line, .. } => Some(line.name().to_string()),
                _ => None,
            },
            explains,
            delta_log_likelihood: d,
            bic_penalty: penalty,
            effect: (e, theta),
        })
        .collect();
    let unexplained = if current.consistent {
        Vec::new()
    } else {
        let mut u = unexplained(&current, &options.signatures);
        u.extend(partial);
        u
    };
    let truth = ctx.row_names.iter().map(|n| data.column(&format!("truth_{n}")).map(<[f64]>::to_vec)).collect();
    let traces = Traces {
        t: ctx.t.clone(),
        channels: ctx.red.channels.clone(),
        rows: ctx.row_names.clone(),
        truth,
        before: base_run,
        after: cur_run,
    };
    Ok(LoopReport {
        system: "rotor".to_string(),
        effects_added,
        before,
        after: current,
        not_identifiable,
        unexplained,
        trials,
        stopped,
        traces,
    })
}

/// Component parameters the data cannot see: neither halving nor doubling one changes the
/// final model's log-likelihood by more than its BIC cost.
fn screen_parameters(ctx: &Context<'_>, effects: &[(Effect, f64)], run: &Run) -> Result<Vec<NotIdentifiable>> {
    let base = run.log_likelihood();
    let mut out = Vec::new();
    for p in Parameter::all(ctx.cfg) {
        let e = Effect::Parameter(p);
        if effects.iter().any(|(x, _)| *x == e) {
            continue;
        }
        let penalty = ctx.penalty(&e);
        let mut worst: f64 = 0.0;
        for factor in [0.5f64, 2.0] {
            let mut trial = effects.to_vec();
            trial.push((e, factor.ln()));
            let (_, r) = ctx.run(&trial)?;
            worst = worst.max((r.log_likelihood() - base).abs());
            if worst > penalty {
                break;
            }
        }
        ctx.progress(|| format!("screen: {} of {}: |Δ log-likelihood| ≤ {worst:.2}", p.name(), p.component(ctx.cfg)));
        if worst <= penalty {
            out.push(NotIdentifiable {
                kind: "parameter".into(),
                location: p.component(ctx.cfg),
                parameter: Some(p.name().into()),
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
