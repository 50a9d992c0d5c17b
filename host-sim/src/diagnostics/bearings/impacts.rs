//! A machine's first stage of the loop ([`search_staged`](crate::residual_loop::search_staged)):
//! periodic impacts it can name (a bearing defect's lines), found by envelope analysis of the
//! base model's innovations and fitted there by likelihood ([`cyclic`](super::cyclic)), before
//! the search for the model's own effects.
//!
//! Per channel: the most impulsive band ([`kurtogram`]) of the normalised innovations, its
//! squared envelope, and each of the system's [`ImpactLine`]s looked for in the envelope's
//! spectrum ([`find_line`]). A line that is there is fitted as impacts ringing a resonance in
//! that band and kept if it beats both the innovations as they are and the same resonance
//! without impacts by its BIC cost, in both halves of the run. The impacts' vibration (the
//! impacts model's one-step predictions) is then taken out of that channel's data, so the
//! search that follows neither sees it nor stands something else in for it.

use super::cyclic::{fit_background, fit_impacts, intensity, predictions, white, Fit};
use super::envelope::{find_line, kurtogram_bands, spectrum, squared_envelope, Band, LineEvidence, LineSearch};
use crate::residual_loop::filter::Run;
use crate::residual_loop::{AddedEffect, EffectLabel, Refused, Traces, Trial};

/// Periodic impacts a system can name when the innovations' envelope shows their line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactLine<E> {
    /// The effect it is reported as.
    pub effect: E,
    /// The impacts' rate, Hz.
    pub hz: f64,
    /// The rate at which the impacts' strength is modulated (a defect carried through a load
    /// zone), Hz.
    pub modulation_hz: Option<f64>,
    /// A rate whose integer multiples the line must not sit on (the running speed): there the
    /// envelope cannot tell impacts from a synchronous modulation.
    pub synchronous_hz: Option<f64>,
}

/// What the stage kept and tried.
#[derive(Debug, Clone)]
pub struct Outcome<E> {
    /// Effects kept, each with the system's effect it stands for.
    pub added: Vec<(E, AddedEffect)>,
    /// The impacts' vibration per channel, in the channel's unit (to take out of the data).
    pub signals: Vec<(usize, Vec<f64>)>,
    /// Every line fitted (iteration 0).
    pub trials: Vec<Trial>,
    /// Lines seen in the envelope whose fit did not pay.
    pub refused: Vec<Refused>,
}

impl<E> Default for Outcome<E> {
    fn default() -> Self {
        Self { added: Vec::new(), signals: Vec::new(), trials: Vec::new(), refused: Vec::new() }
    }
}

/// A line's fit on one channel.
struct Candidate<E> {
    line: ImpactLine<E>,
    evidence: LineEvidence,
    band: Band,
    fit: Fit,
    g: Vec<f64>,
    /// `ln L` gained over the better of the two alternatives (the innovations as they are,
    /// the resonance without impacts), whole run and halves.
    delta: f64,
    halves: [f64; 2],
    /// BIC cost over that alternative.
    penalty: f64,
    /// Whether the alternative was the resonance without impacts.
    over_resonance: bool,
}

/// One channel's normalised innovations and the lines fitted on them.
struct ChannelFits<E> {
    channel: usize,
    u: Vec<f64>,
    cands: Vec<Candidate<E>>,
}

/// The most impulsive bands tried per channel.
const BANDS: usize = 3;

/// Free parameters of the impacts model beyond white innovations: frequency, damping,
/// background and impact levels, and each envelope bin its intensity was rebuilt from (a
/// complex amplitude: two).
fn impact_parameters(bins: usize) -> usize {
    4 + 2 * bins
}

/// Runs the stage for the machine's `lines` (each reported as `label` says) on its base
/// model's `run`, whose data the `traces` describe; a fit must gain `half_gain` of its cost in
/// each half of the run.
pub fn stage<E: Copy + PartialEq>(
    lines: &[ImpactLine<E>],
    label_of: impl Fn(&E) -> EffectLabel,
    run: &Run,
    traces: &Traces,
    search: &LineSearch,
    half_gain: f64,
) -> Outcome<E> {
    let mut out = Outcome::default();
    let Some(highest) = lines.iter().map(|l| l.hz).max_by(f64::total_cmp) else { return out };
    let Some(fs) = sample_rate(&traces.t) else { return out };
    let n_meas = run.measurements().max(2) as f64;
    let st = Stage { lines, label_of: &label_of, run, traces, search, half_gain, fs, highest, n_meas };
    let mut per_channel: Vec<ChannelFits<E>> = Vec::new();
    for (ch, (innovation, variance)) in run.innovation.iter().zip(&run.variance).enumerate() {
        let u: Vec<f64> = innovation.iter().zip(variance).map(|(e, s)| e / s.sqrt()).collect();
        let cands = st.candidates(&u, &mut out.refused);
        per_channel.push(ChannelFits { channel: ch, u, cands });
    }
    // The channel with the strongest evidence decides first; on the others the same defect is
    // preferred, and another is kept only if its line is not one of the first's combination
    // lines (an inner race's BPFI − 3× sits near BSF).
    per_channel.sort_by(|a, b| {
        let best = |cs: &[Candidate<E>]| {
            cs.iter().filter(|c| st.pays(c)).map(Candidate::score).fold(f64::NEG_INFINITY, f64::max)
        };
        best(&b.cands).total_cmp(&best(&a.cands))
    });
    let mut accepted: Vec<(ImpactLine<E>, f64)> = Vec::new();
    for fits in per_channel {
        st.decide(fits, &mut accepted, &mut out);
    }
    out.added = merged(std::mem::take(&mut out.added));
    out
}

/// What one run of the stage works with.
struct Stage<'a, E, L> {
    lines: &'a [ImpactLine<E>],
    label_of: &'a L,
    run: &'a Run,
    traces: &'a Traces,
    search: &'a LineSearch,
    half_gain: f64,
    /// Samples per second.
    fs: f64,
    /// The highest line, Hz.
    highest: f64,
    /// Scalar measurements of the run (for the BIC).
    n_meas: f64,
}

impl<E> Candidate<E> {
    /// The gain beyond the cost.
    fn score(&self) -> f64 {
        self.delta - self.penalty
    }
}

impl<E: Copy + PartialEq, L: Fn(&E) -> EffectLabel> Stage<'_, E, L> {
    /// `½ p ln n`.
    fn cost(&self, p: usize) -> f64 {
        0.5 * p as f64 * self.n_meas.ln()
    }

    /// Pays for itself over the run and in each half.
    fn pays(&self, c: &Candidate<E>) -> bool {
        c.delta > c.penalty && c.halves[0].min(c.halves[1]) >= self.half_gain * c.penalty
    }

    /// Every line found in the envelope of one of the most impulsive bands of the normalised
    /// innovations `u`, fitted as impacts ringing that band; a line on a whole order of the
    /// running speed is refused into `refused`.
    fn candidates(&self, u: &[f64], refused: &mut Vec<Refused>) -> Vec<Candidate<E>> {
        let (fs, search, highest) = (self.fs, self.search, self.highest);
        // The band must lie above the lines and be wide enough to carry their harmonics; the
        // most impulsive bands are each tried (the most impulsive may carry little energy).
        let (min_hz, min_width) = (3.0 * highest, (search.harmonics as f64 + 0.2) * highest);
        let mut cands: Vec<Candidate<E>> = Vec::new();
        let (null, null_halves) = white(u);
        for band in kurtogram_bands(u, fs, min_hz, min_width, BANDS) {
            let env = squared_envelope(u, fs, &band);
            let spec = spectrum(&env, fs);
            let mut seen: Vec<(ImpactLine<E>, LineEvidence)> = Vec::new();
            for line in self.lines {
                let Some(evidence) = find_line(&spec, line.hz, search) else { continue };
                match synchronous(line, &evidence, spec.df) {
                    Some(order) => {
                        let label = (self.label_of)(&line.effect);
                        if !refused
                            .iter()
                            .any(|r| r.location == label.location && r.reason.contains(&format!("on {order}x")))
                        {
                            refused.push(Refused::of(
                                &label,
                                None,
                                format!(
                                    "its line is in the envelope at {:.2} Hz, on {order}x the running speed: impacts cannot be told from a synchronous modulation there",
                                    evidence.hz
                                ),
                            ));
                        }
                    }
                    None => seen.push((*line, evidence)),
                }
            }
            if seen.is_empty() {
                continue;
            }
            let Some(background) = fit_background(u, fs, (band.low_hz, band.high_hz)) else { continue };
            let background_cost = self.cost(3);
            for (line, evidence) in seen {
                let top = evidence.harmonics.iter().copied().max().unwrap_or(1);
                let (g, bins) =
                    intensity(&env, fs, evidence.hz, top, line.modulation_hz, search.tolerance, search.width);
                let Some(fit) = fit_impacts(u, fs, (band.low_hz, band.high_hz), &g, &background) else { continue };
                let penalty = self.cost(impact_parameters(bins));
                // The alternative the impacts must beat: no resonance, or the resonance alone.
                let over_resonance = background.log_likelihood - background_cost > null;
                let (rival, rival_halves, rival_cost) = if over_resonance {
                    (background.log_likelihood, background.halves, background_cost)
                } else {
                    (null, null_halves, 0.0)
                };
                cands.push(Candidate {
                    line,
                    evidence,
                    band,
                    delta: fit.log_likelihood - rival,
                    halves: [fit.halves[0] - rival_halves[0], fit.halves[1] - rival_halves[1]],
                    fit,
                    g,
                    penalty: penalty - rival_cost,
                    over_resonance,
                });
            }
        }
        cands
    }

    /// Keeps the best paying line of one channel's `fits` (the one defect already `accepted`
    /// elsewhere if it is among them), and says why each other line seen is not kept.
    fn decide(&self, fits: ChannelFits<E>, accepted: &mut Vec<(ImpactLine<E>, f64)>, out: &mut Outcome<E>) {
        let ChannelFits { channel: ch, u, cands } = fits;
        let (run, traces, search, fs) = (self.run, self.traces, self.search, self.fs);
        let pays = |c: &Candidate<E>| self.pays(c);
        let score = Candidate::<E>::score;
        let variance = &run.variance[ch];
        // A line is shadowed by a defect kept on another channel whose combination line it is,
        // or by a stronger line on this one whose combination line it is (105's BSF at
        // 71.8 Hz is its BPFI's 161.7 − 3 × 30.0 Hz).
        let shadows: Vec<Option<(ImpactLine<E>, f64)>> = cands
            .iter()
            .map(|c| {
                let stronger = cands
                    .iter()
                    .filter(|o| pays(o) && o.evidence.prominence_db > c.evidence.prominence_db)
                    .map(|o| (o.line, o.evidence.hz));
                accepted
                    .iter()
                    .copied()
                    .chain(stronger)
                    .find(|(a, hz)| a.effect != c.line.effect && combination(a, *hz, c.evidence.hz, search))
            })
            .collect();
        let known: Vec<usize> = (0..cands.len())
            .filter(|&i| pays(&cands[i]) && accepted.iter().any(|(a, _)| a.effect == cands[i].line.effect))
            .collect();
        let pool: Vec<usize> = if known.is_empty() {
            (0..cands.len()).filter(|&i| pays(&cands[i]) && shadows[i].is_none()).collect()
        } else {
            known
        };
        let best = pool.into_iter().max_by(|&a, &b| score(&cands[a]).total_cmp(&score(&cands[b])));
        for (i, c) in cands.iter().enumerate() {
            let label = (self.label_of)(&c.line.effect);
            let unit = traces.channels.get(ch).map_or_else(String::new, |c| c.unit.clone());
            let signal: Vec<f64> =
                predictions(&u, fs, &c.fit, Some(&c.g)).iter().zip(variance).map(|(z, s)| z * s.sqrt()).collect();
            let value = rms(&signal);
            out.trials.push(Trial {
                iteration: 0,
                kind: label.kind,
                location: label.location.clone(),
                order: label.detail.order,
                parameter: None,
                onset_s: None,
                unit: unit.clone(),
                value: Some(value),
                delta_log_likelihood: c.delta,
                delta_halves: c.halves,
                delta_halves_expected: None,
                bic_penalty: c.penalty,
                accepted: Some(i) == best,
            });
            let reason = if Some(i) == best {
                out.signals.push((ch, signal));
                out.added.push((c.line.effect, added(label, unit, value, c, &c.band)));
                if !accepted.iter().any(|(a, _)| a.effect == c.line.effect) {
                    accepted.push((c.line, c.evidence.hz));
                }
                continue;
            } else if !pays(c) {
                format!(
                    "its line is in the envelope at {:.2} Hz ({:.1} dB), but impacts ringing {:.0}–{:.0} Hz gain {:.1} in log-likelihood over {}, against a BIC cost of {:.1}",
                    c.evidence.hz,
                    c.evidence.prominence_db,
                    c.band.low_hz,
                    c.band.high_hz,
                    c.delta,
                    if c.over_resonance { "the resonance without impacts" } else { "the innovations as they are" },
                    c.penalty
                )
            } else if let Some((a, hz)) = shadows[i] {
                let first = (self.label_of)(&a.effect);
                format!(
                    "its line at {:.2} Hz is a combination line of the {} at {} ({hz:.2} Hz), a stronger line",
                    c.evidence.hz,
                    first.detail.line.as_deref().unwrap_or(first.kind.as_str()),
                    first.location
                )
            } else {
                continue;
            };
            if !out.refused.iter().any(|r| r.location == label.location && r.reason == reason) {
                out.refused.push(Refused::of(&label, Some(value), reason));
            }
        }
    }
}

/// One effect per defect: where several channels show it, their gains and costs add up.
fn merged<E: PartialEq>(added: Vec<(E, AddedEffect)>) -> Vec<(E, AddedEffect)> {
    let mut merged: Vec<(E, AddedEffect)> = Vec::new();
    for (e, a) in added {
        match merged.iter_mut().find(|(x, _)| *x == e) {
            Some((_, m)) => {
                m.delta_log_likelihood += a.delta_log_likelihood;
                m.bic_penalty += a.bic_penalty;
                m.value = m.value.max(a.value);
            }
            None => merged.push((e, a)),
        }
    }
    merged
}

/// The integer order of [`ImpactLine::synchronous_hz`] the line found sits on (within 1 %, at
/// least two bins), if any.
fn synchronous<E>(line: &ImpactLine<E>, evidence: &LineEvidence, df: f64) -> Option<u32> {
    let rate = line.synchronous_hz.filter(|r| *r > 0.0)?;
    let order = (evidence.hz / rate).round();
    // The running speed is itself estimated to a fraction of a per cent.
    let reach = (0.01 * evidence.hz).max(2.0 * df);
    (order >= 1.0 && (evidence.hz - order * rate).abs() <= reach).then_some(order as u32)
}

/// Whether `hz` is a combination line of the impacts `first` found at `first_hz`:
/// `h · first_hz + j · f_m` (h ≤ 4, |j| ≤ 3, `f_m` its modulation or synchronous rate) within the
/// search's tolerance.
fn combination<E>(first: &ImpactLine<E>, first_hz: f64, hz: f64, search: &LineSearch) -> bool {
    let Some(fm) = first.modulation_hz.or(first.synchronous_hz) else { return false };
    (0..=4).any(|h| {
        (-3..=3).any(|j| {
            let f = h as f64 * first_hz + j as f64 * fm;
            (h, j) != (0, 0) && f > 0.0 && (f - hz).abs() <= search.tolerance * hz
        })
    })
}

/// Root mean square of the finite values.
fn rms(x: &[f64]) -> f64 {
    let finite: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    (finite.iter().map(|v| v * v).sum::<f64>() / finite.len().max(1) as f64).sqrt()
}

fn added<E>(mut label: EffectLabel, unit: String, value: f64, c: &Candidate<E>, band: &Band) -> AddedEffect {
    label.detail.harmonics = Some(c.evidence.harmonics.clone());
    label.detail.band_hz = Some([band.low_hz, band.high_hz]);
    label.detail.damping = Some(c.fit.model.damping);
    AddedEffect {
        kind: label.kind,
        location: label.location,
        value,
        unit,
        detail: label.detail,
        explains: c.evidence.harmonics.iter().map(|h| (*h as f64 * c.evidence.hz * 100.0).round() / 100.0).collect(),
        delta_log_likelihood: c.delta,
        bic_penalty: c.penalty,
        interval: None,
    }
}

/// Samples per second of `t` (its median step), if it has two samples.
fn sample_rate(t: &[f64]) -> Option<f64> {
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).filter(|d| d.is_finite() && *d > 0.0).collect();
    if steps.is_empty() {
        return None;
    }
    steps.sort_by(f64::total_cmp);
    Some(1.0 / steps[steps.len() / 2])
}
