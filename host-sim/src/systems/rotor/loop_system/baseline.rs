//! A rotor's healthy baseline (`edgekf baseline rotor`): learned from a recording of a good
//! machine, it is what that machine shows and the declared model lacks, each part named and
//! fitted by maximum likelihood on the innovations, and kept only when it pays for its
//! parameters (BIC) in both halves of the record:
//!
//! * each channel's offset (its mean) and measurement-noise level;
//! * the housing's or foundation's resonances the sensors see (frequency, damping and the
//!   level on each channel), one at a time at the strongest line no order explains;
//! * synchronous forces beside the unbalance (a line at an order: 2×, or a motor's tone that
//!   sits on one), their states left to the filter;
//! * the running speed, the estimated unbalance per disk and the 1×–3× levels per channel,
//!   which a record under diagnosis is compared with (`baseline_comparison`).
//!
//! `edgekf loop rotor --baseline` puts these parts into the base model and reads only the
//! operating point (the running speed) from the record under diagnosis.

use super::healthy::{Healthy, Resonance};
use super::speed::estimate_speed;
use super::{Effect, RotorLoopOptions, RotorSystem};
use crate::io::data::DataFile;
use crate::residual_loop::baseline::{batch_std_error, blocks, BaselineSource, Comparison};
use crate::residual_loop::filter::Run;
use crate::residual_loop::onset::halves;
use crate::residual_loop::optimize::maximise;
use crate::residual_loop::{Applied, LoopOptions, LoopSystem};
use crate::systems::rotor::RotorModel;
use anyhow::{anyhow, bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;
use std::path::Path;

/// A channel as the baseline found it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelLevel {
    /// Channel name.
    pub channel: String,
    /// Mean, in the channel's unit (taken out of every record before the filter).
    pub offset: f64,
    /// Measurement-noise standard deviation per sample, in the channel's unit.
    pub noise_std: f64,
}

/// A synchronous force a healthy machine has beside its unbalance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SynchronousForce {
    /// Node.
    pub node: usize,
    /// Order of the running speed.
    pub order: u32,
    /// Its amplitude on the baseline's record, N.
    pub value: f64,
}

/// An unbalance as the filter estimated it on the baseline's record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UnbalanceLevel {
    /// Node.
    pub node: usize,
    /// kg·m.
    pub value: f64,
    /// Its standard error on the baseline's record (absent from baselines learned before it
    /// was kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std_error: Option<f64>,
}

/// A synchronous order's amplitude on a channel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrderLevel {
    /// Channel name.
    pub channel: String,
    /// Order of the running speed.
    pub order: u32,
    /// Amplitude, in the channel's unit.
    pub value: f64,
    /// Its standard error on the baseline's record (as [`UnbalanceLevel::std_error`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std_error: Option<f64>,
}

/// A healthy rotor's baseline, as `baseline.toml` holds it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotorBaseline {
    /// `rotor`.
    pub system: String,
    /// The operating condition it belongs to (a load, say), as the user named it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub condition: Option<String>,
    /// The running speed on the baseline's record, Hz.
    pub speed_hz: f64,
    /// Log-likelihood per scalar measurement the best next effect of the loop's library still
    /// gains beyond its BIC cost on the baseline's own record, with the baseline's parts in
    /// place: what a healthy machine leaves unexplained. A change must gain
    /// [`FLOOR_MARGIN`] times more ([`LoopOptions::gain_floor`]).
    pub gain_floor: f64,
    /// Where it was learned.
    pub source: BaselineSource,
    /// Offsets and noise levels.
    #[serde(default, rename = "channel")]
    pub channels: Vec<ChannelLevel>,
    /// Resonances outside the rotor model.
    #[serde(default, rename = "resonance")]
    pub resonances: Vec<Resonance>,
    /// Synchronous forces beside the unbalance.
    #[serde(default, rename = "synchronous_force")]
    pub forces: Vec<SynchronousForce>,
    /// The unbalance per unbalance node.
    #[serde(default, rename = "unbalance")]
    pub unbalances: Vec<UnbalanceLevel>,
    /// 1×–3× amplitudes per channel.
    #[serde(default, rename = "order_level")]
    pub orders: Vec<OrderLevel>,
}

pub use crate::residual_loop::levels::FLOOR_MARGIN;

/// Orders whose levels a baseline records and a record is compared at.
pub const ORDERS: [u32; 3] = [1, 2, 3];

/// How a baseline is learned.
#[derive(Debug, Clone, PartialEq)]
pub struct BaselineOptions {
    /// At most this many resonances and synchronous forces.
    pub max_parts: usize,
    /// The running speed is read from the data within this fraction of the configured one.
    pub speed_band: f64,
    /// The operating condition's name, if given.
    pub condition: Option<String>,
}

impl Default for BaselineOptions {
    fn default() -> Self {
        Self { max_parts: 12, speed_band: 0.1, condition: None }
    }
}

impl RotorBaseline {
    /// Parses `baseline.toml`.
    pub fn from_toml_str(text: &str) -> Result<Self> {
        let b: RotorBaseline = crate::io::config::parse_toml(text).map_err(|e| anyhow!("{e}"))?;
        if b.system != "rotor" {
            bail!("a baseline of the {}, not of a rotor", b.system);
        }
        Ok(b)
    }

    /// Reads `path`; errors name it.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
        Self::from_toml_str(&text).with_context(|| format!("{}: not a rotor baseline", path.display()))
    }

    /// The file's text, with a header that says what it is.
    pub fn to_toml(&self) -> Result<String> {
        let body = toml::to_string(self).context("cannot write the baseline as TOML")?;
        Ok(format!(
            "# edgekf baseline: what a healthy rotor of this configuration shows that its model lacks.\n\
             # Learned by `{}`; used by `edgekf loop rotor --baseline`.\n\n{body}",
            self.source.command
        ))
    }

    /// The baseline's parts for a filter reading `channels` (in its order): every channel
    /// must have been learned.
    pub fn healthy(&self, channels: &[String]) -> Result<Healthy> {
        let level = |name: &String| {
            self.channels.iter().find(|c| &c.channel == name).ok_or_else(|| {
                let learned: Vec<&str> = self.channels.iter().map(|c| c.channel.as_str()).collect();
                anyhow!("the baseline has no channel {name} (it was learned on {})", learned.join(", "))
            })
        };
        let levels: Vec<&ChannelLevel> = channels.iter().map(level).collect::<Result<_>>()?;
        if self.resonances.iter().any(|r| r.drive.len() != channels.len()) {
            bail!("the baseline's resonances are for {} channels, not {}", self.channels.len(), channels.len());
        }
        Ok(Healthy {
            offsets: levels.iter().map(|c| c.offset).collect(),
            noise_std: levels.iter().map(|c| Some(c.noise_std)).collect(),
            resonances: self.resonances.clone(),
            forces: self.forces.iter().map(|f| Effect::HarmonicForce { node: f.node, order: f.order }).collect(),
        })
    }

    /// The record's levels (`unbalance` per disk, `order_level` per channel and order) beside
    /// the baseline's, from the model and run the loop ended with.
    pub fn compare(&self, sys: &RotorSystem<'_>, model: &super::AugmentedModel, run: &Run) -> Vec<Comparison> {
        let mut out = Vec::new();
        let orders = order_levels(sys);
        for u in unbalance_levels(sys, model, run, &orders) {
            if let Some(b) = self.unbalances.iter().find(|b| b.node == u.node) {
                let c = Comparison::new("unbalance", &format!("disk {}", u.node), None, "kg m", u.value, b.value);
                out.push(c.with_errors(u.std_error, b.std_error));
            }
        }
        for level in orders {
            if let Some(b) = self.orders.iter().find(|o| o.channel == level.channel && o.order == level.order) {
                let unit = sys.channel_unit(&level.channel);
                let c = Comparison::new("order_level", &level.channel, Some(level.order), &unit, level.value, b.value);
                out.push(c.with_errors(level.std_error, b.std_error));
            }
        }
        out
    }
}

/// The amplitude of each channel at the orders [`ORDERS`] of the system's running speed (the
/// channel's projection on the order's cosine and sine over the record), with its standard
/// error: the spread over the record's blocks of each block's phasor along the record's.
pub fn order_levels(sys: &RotorSystem<'_>) -> Vec<OrderLevel> {
    let hz = sys.speed().hz;
    let (t, rate) = (sys.times(), sys.sample_rate());
    let mut out = Vec::new();
    for (name, col) in sys.channel_names().iter().zip(sys.columns()) {
        for order in ORDERS {
            let w = TAU * hz * order as f64;
            let phasor = |range: std::ops::Range<usize>| {
                let (mut c, mut s, mut n) = (0.0, 0.0, 0usize);
                for k in range {
                    let v = col[k];
                    if v.is_finite() {
                        let tk = t.get(k).copied().unwrap_or(k as f64 / rate);
                        c += v * (w * tk).cos();
                        s += v * (w * tk).sin();
                        n += 1;
                    }
                }
                let scale = 2.0 / n.max(1) as f64;
                (scale * c, scale * s)
            };
            let (c, s) = phasor(0..col.len());
            let value = c.hypot(s);
            let along: Vec<f64> =
                blocks(col.len()).into_iter().map(phasor).map(|(bc, bs)| (bc * c + bs * s) / value).collect();
            let se = batch_std_error(&along);
            out.push(OrderLevel { channel: name.clone(), order, value, std_error: se.is_finite().then_some(se) });
        }
    }
    out
}

/// The unbalance per disk in the model of `run`, with a standard error from the 1× levels
/// `orders` (of the same record): the filter reads an unbalance from the synchronous response,
/// so it is known relatively no better than the 1× phasors taken together,
/// `σ/u = 1/√Σ (A/σ_A)²` over the channels. The filter's own unbalance states are too smooth
/// for batch means (their blocks agree to 1 % where records of the same machine differ by 5 %).
/// With several disks the 1× information is shared among them, so each disk's interval is then
/// at least this wide.
fn unbalance_levels(
    sys: &RotorSystem<'_>,
    model: &super::AugmentedModel,
    run: &Run,
    orders: &[OrderLevel],
) -> Vec<UnbalanceLevel> {
    let information: f64 = orders
        .iter()
        .filter(|o| o.order == 1)
        .filter_map(|o| o.std_error.filter(|se| *se > 0.0).map(|se| (o.value / se).powi(2)))
        .sum();
    let relative = (information > 0.0).then(|| information.sqrt().recip());
    sys.unbalance(model, run)
        .into_iter()
        .map(|(node, value)| UnbalanceLevel { node, value, std_error: relative.map(|r| r * value) })
        .collect()
}

/// One part the learning tried: the parts with it, their run and the gain.
struct Tried {
    healthy: Healthy,
    run: Run,
    delta: f64,
    penalty: f64,
    halves: [f64; 2],
    what: String,
}

impl Tried {
    /// Runs the filter with the parts `healthy` and measures the gain over `base`.
    fn run(sys: &RotorSystem<'_>, healthy: Healthy, base: &Run, penalty: f64, what: String) -> Result<Self> {
        let run = sys.run_healthy(&healthy, &[])?.1;
        let (delta, halves) = (run.log_likelihood() - base.log_likelihood(), halves(&run, base, 0));
        Ok(Self { healthy, run, delta, penalty, halves, what })
    }
}

/// Learns the baseline of `model` from the healthy recording `data`: the running speed, the
/// channels' offsets, then the noise levels, resonances and synchronous forces by maximum
/// likelihood (each resonance or force kept only if it pays its BIC cost in both halves), the
/// noise levels once more, and the levels a record is compared at.
pub fn learn(
    model: &RotorModel,
    data: &DataFile,
    options: &LoopOptions,
    rotor: &RotorLoopOptions,
    b: &BaselineOptions,
) -> Result<RotorBaseline> {
    let say = |msg: String| {
        if options.progress {
            eprintln!("baseline: {msg}");
        }
    };
    say(format!("estimating the running speed within ±{:.0} %", b.speed_band * 100.0));
    let speed = estimate_speed(model, data, options, rotor, b.speed_band)?;
    say(speed.describe());
    let bare = RotorSystem::at_speed(model, data, options, rotor, speed)?;
    let m = bare.channel_names().len();
    let offsets: Vec<f64> = bare.columns().iter().map(|c| finite_mean(c)).collect();
    let start = Healthy { offsets, noise_std: vec![None; m], ..Healthy::default() };
    let sys = RotorSystem::healthy(model, data, options, rotor, speed, start.clone())?;
    let n_meas = sys.run(&[])?.1.measurements().max(2) as f64;
    let penalty = |p: usize| 0.5 * p as f64 * n_meas.ln();
    let mut h = fit_noise(&sys, start)?;
    let mut run = sys.run_healthy(&h, &[])?.1;
    say(format!("noise levels {:?}: log-likelihood {:.1}", noise(&sys, &h), run.log_likelihood()));
    for part in 0..b.max_parts {
        let best = best_part(&sys, &h, &run, &penalty, options.half_gain, &say);
        let Some(kept) = best else {
            say(format!("no further part pays for itself after {part}"));
            break;
        };
        say(format!("kept {}", kept.what));
        h = kept.healthy;
        run = kept.run;
    }
    h = fit_noise(&sys, h)?;
    let gain_floor =
        leftover_gain(RotorSystem::healthy(model, data, options, rotor, speed, h.clone())?, options, n_meas, &say)?;
    let (fm, fr) = sys.run_healthy(&h, &[])?;
    let names = sys.channel_names().to_vec();
    let noise_std = noise(&sys, &h);
    let forces = h
        .forces
        .iter()
        .map(|e| {
            let value = sys.value(&fm, &fr, &Applied::new(*e, 0.0));
            match *e {
                Effect::HarmonicForce { node, order } => Ok(SynchronousForce { node, order, value }),
                _ => Err(anyhow!("a healthy force that is not a harmonic force: {e:?}")),
            }
        })
        .collect::<Result<_>>()?;
    let orders = order_levels(&sys);
    Ok(RotorBaseline {
        system: "rotor".into(),
        condition: b.condition.clone(),
        speed_hz: speed.hz,
        gain_floor,
        source: BaselineSource { version: env!("CARGO_PKG_VERSION").into(), ..BaselineSource::default() },
        channels: names
            .iter()
            .zip(&h.offsets)
            .zip(&noise_std)
            .map(|((c, &offset), &noise_std)| ChannelLevel { channel: c.clone(), offset, noise_std })
            .collect(),
        resonances: h.resonances,
        forces,
        unbalances: unbalance_levels(&sys, &fm, &fr, &orders),
        orders,
    })
}

/// The part (a resonance, a synchronous force) whose fit pays most on top of `h` (whose run is
/// `run`), among the strongest lines of the run's innovations no part explains yet; `None` if
/// none pays in both halves of the run.
fn best_part(
    sys: &RotorSystem<'_>,
    h: &Healthy,
    run: &Run,
    penalty: &dyn Fn(usize) -> f64,
    half_gain: f64,
    say: &dyn Fn(String),
) -> Option<Tried> {
    let m = sys.channel_names().len();
    let summary = sys.summarise(run);
    let bin = summary.bin_width_hz;
    // The strongest lines no bearing line names and no part already explains.
    let mut all: Vec<(f64, f64, Option<u32>, usize)> = summary
        .channels
        .iter()
        .enumerate()
        .flat_map(|(ch, c)| c.peaks.iter().map(move |p| (ch, p)))
        .filter(|(_, p)| p.line.is_none() && !p.class.starts_with("natural"))
        .map(|(ch, p)| (p.prominence_db, p.frequency_hz, p.order, ch))
        .filter(|&(_, f, _, _)| !h.resonances.iter().any(|r| (r.frequency_hz - f).abs() < 3.0 * bin))
        .collect();
    all.sort_by(|a, b| b.0.total_cmp(&a.0));
    // A line both channels see is one candidate.
    let mut peaks: Vec<(f64, f64, Option<u32>, usize)> = Vec::new();
    for p in all {
        if !peaks.iter().any(|q| (q.1 - p.1).abs() < 2.0 * bin) {
            peaks.push(p);
        }
    }
    let mut best: Option<Tried> = None;
    // A line at an order may be a synchronous force; any line may be a narrow mode (a
    // motor's tone near an order is one).
    let tries = peaks.iter().take(3).flat_map(|&(_, f, order, ch)| {
        let force = order.map(|k| (f, Some(k), ch));
        force.into_iter().chain([(f, None, ch)])
    });
    for (f, order, ch) in tries {
        let tried = match order {
            Some(k) => try_force(sys, h, run, k, penalty(2)),
            None => try_resonance(sys, h, run, (f, ch), bin, penalty(2 + m)),
        };
        match tried {
            Ok(Some(t)) => {
                say(format!(
                    "{}: Δ log-likelihood {:.1}, BIC cost {:.1}, halves {:.1} / {:.1}",
                    t.what, t.delta, t.penalty, t.halves[0], t.halves[1]
                ));
                let pays = t.delta > t.penalty && t.halves[0].min(t.halves[1]) >= half_gain * t.penalty;
                if pays && best.as_ref().is_none_or(|b| t.delta - t.penalty > b.delta - b.penalty) {
                    best = Some(t);
                }
            }
            Ok(None) => {}
            Err(e) => say(format!("a part at {f:.2} Hz: {e:#}")),
        }
    }
    best
}

/// What the healthy record still leaves unexplained, per scalar measurement: the best next
/// effect's gain beyond its BIC cost after one round of the loop on `probe_sys` (a system of
/// its own: the loop may take impacts out of its channels).
fn leftover_gain(
    mut probe_sys: RotorSystem<'_>,
    options: &LoopOptions,
    n_meas: f64,
    say: &dyn Fn(String),
) -> Result<f64> {
    say("measuring what the healthy record leaves unexplained (one round of the loop)".into());
    let probe = LoopOptions { max_effects: 1, screen_parameters: false, progress: false, gain_floor: 0.0, ..*options };
    let leftover = probe_sys.search(&probe)?;
    Ok(crate::residual_loop::levels::leftover_gain(&leftover, n_meas, say))
}

/// The noise standard deviation of each channel in the model with `h`.
fn noise(sys: &RotorSystem<'_>, h: &Healthy) -> Vec<f64> {
    let r = sys.declared_noise();
    (0..r.len()).map(|ch| h.noise_std.get(ch).copied().flatten().unwrap_or(r[ch])).collect()
}

fn finite_mean(c: &[f64]) -> f64 {
    let (s, n) = c.iter().filter(|v| v.is_finite()).fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 {
        0.0
    } else {
        s / n as f64
    }
}

/// Each channel's noise level by maximum likelihood (a factor from 1/20 to 20 on its current
/// level, in turn).
fn fit_noise(sys: &RotorSystem<'_>, mut h: Healthy) -> Result<Healthy> {
    for ch in 0..h.noise_std.len() {
        let now = noise(sys, &h)[ch];
        let with = |lf: f64| {
            let mut t = h.clone();
            t.noise_std[ch] = Some(now * lf.exp());
            t
        };
        let best = maximise(
            |lf| sys.run_healthy(&with(lf), &[]).ok().map(|(_, r)| r.log_likelihood()),
            20f64.recip().ln(),
            20f64.ln(),
            5,
            0.01,
        )
        .ok_or_else(|| anyhow!("no noise level of channel #{ch} gives a usable filter"))?;
        h = with(best.x);
    }
    Ok(h)
}

/// A resonance near `f` Hz, seen on channel `seen`: its frequency, damping and level on each
/// channel, each by maximum likelihood in turn. It starts on `seen` alone, so that a hump on
/// one housing is not pulled towards another housing's.
fn try_resonance(
    sys: &RotorSystem<'_>,
    h: &Healthy,
    base: &Run,
    (f, seen): (f64, usize),
    bin: f64,
    penalty: f64,
) -> Result<Option<Tried>> {
    let levels = noise(sys, h);
    let drive = levels.iter().enumerate().map(|(ch, s)| if ch == seen { 3.0 * s } else { 0.01 * s }).collect();
    let mut res = Resonance { frequency_hz: f, damping: 0.02, drive };
    let ll = |r: &Resonance| {
        let mut t = h.clone();
        t.resonances.push(r.clone());
        sys.run_healthy(&t, &[]).ok().map(|(_, run)| run.log_likelihood())
    };
    let fail = || anyhow!("no resonance near {f:.2} Hz gives a usable filter");
    let nyquist = 0.5 * sys.sample_rate();
    // A broad housing resonance peaks anywhere in its hump of a noisy spectrum: its centre is
    // searched within 3 % first (at a moderate damping), and again within two bins once the
    // damping is known.
    let centre = |res: &Resonance, half: f64, grid: usize| {
        let (low, high) = ((res.frequency_hz - half).max(0.1), (res.frequency_hz + half).min(0.999 * nyquist));
        maximise(|v| ll(&Resonance { frequency_hz: v, ..res.clone() }), low, high, grid, 0.02 * bin)
            .map(|x| x.x)
            .ok_or_else(fail)
    };
    res.frequency_hz = centre(&res, bin.max(0.03 * f), 9)?;
    // The levels and the damping trade against each other (too large a level favours a narrow
    // peak), so they are fitted in turn twice.
    let fit_levels = |mut res: Resonance| -> Result<Resonance> {
        for (ch, &level) in levels.iter().enumerate() {
            let at = |ll_: f64| {
                let mut r = res.clone();
                r.drive[ch] = level * ll_.exp();
                r
            };
            let x = maximise(|v| ll(&at(v)), 0.01f64.ln(), 1000f64.ln(), 4, 0.1).ok_or_else(fail)?;
            res = at(x.x);
        }
        Ok(res)
    };
    for _ in 0..2 {
        res = fit_levels(res)?;
        let x = maximise(|lz| ll(&Resonance { damping: lz.exp(), ..res.clone() }), 2e-4f64.ln(), 0.3f64.ln(), 4, 0.1)
            .ok_or_else(fail)?;
        res.damping = x.x.exp();
    }
    res.frequency_hz = centre(&res, 2.0 * bin, 3)?;
    res = fit_levels(res)?;
    let what = format!(
        "resonance at {:.2} Hz, ζ {:.4}, levels {:?}",
        res.frequency_hz,
        res.damping,
        res.drive.iter().map(|v| format!("{v:.3e}")).collect::<Vec<_>>()
    );
    let mut t = h.clone();
    t.resonances.push(res);
    Tried::run(sys, t, base, penalty, what).map(Some)
}

/// A synchronous force at `order` on the first disk (1× only where no unbalance is
/// estimated).
fn try_force(sys: &RotorSystem<'_>, h: &Healthy, base: &Run, order: u32, penalty: f64) -> Result<Option<Tried>> {
    let Some(node) = sys.disk_nodes().first().copied() else { return Ok(None) };
    let e = Effect::HarmonicForce { node, order };
    if h.forces.contains(&e) || (order == 1 && sys.unbalance_nodes().contains(&node)) {
        return Ok(None);
    }
    let mut t = h.clone();
    t.forces.push(e);
    Tried::run(sys, t, base, penalty, format!("synchronous force {order}x at node {node}")).map(Some)
}
