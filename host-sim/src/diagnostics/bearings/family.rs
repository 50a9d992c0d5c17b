//! Bearing diagnosis by fault family, as the field does it (Randall & Antoni 2011, "Rolling
//! element bearing diagnostics — a tutorial"; Smith & Randall 2015, the CWRU benchmark):
//!
//! 1. the discrete part of each channel removed by cepstral prewhitening
//!    ([`prewhiten`](super::prewhiten)), Borghesani et al. 2013;
//! 2. the squared envelope spectrum (SES) of the whole prewhitened band and of the band the
//!    kurtogram (Antoni 2006) finds most impulsive in it;
//! 3. the running speed refined from the raw spectrum's shaft harmonics ([`shaft`](super::shaft));
//! 4. each bearing's defect **families** looked for as a whole: outer race = BPFO × 1…4; inner
//!    race = BPFI × 1…3 and their ±shaft sidebands (the defect turns through the load zone);
//!    ball = 2×BSF × 1…3 with ±FTF sidebands, plus FTF and 2×FTF (the cage modulation that ball
//!    faults mostly show). The kinematic lines may all be off by a common factor `1 + s`,
//!    |s| ≤ [`SLIP`] (slip, a contact angle under load); the members then sit at exact
//!    multiples, so a family 0.5 % from a shaft order is told from it by harmonics 2–4 moving
//!    1–2 % of an order away, not by the fundamental.
//!
//! The statistics ([`CarryRule`]): in the SES of noise each bin's power is about exponential,
//! so a peak `r` times the local median (`10 log₁₀ r` dB) is exceeded by chance with
//! probability `2^(−r)` per bin, and `1 − (1 − 2^(−r))^W` somewhere in a member's window of
//! `W` bins. The members' p-values are combined by the binomial tail of their order statistics
//! (`P(at least j of m below p_(j))`), which charges a family for its number of members, and the
//! search over `s`, bands and channels is paid for by Bonferroni. A member within reach of an
//! integer shaft order is not counted (a synchronous modulation makes the same line): the
//! family's other members decide.

use super::envelope::{kurtogram_bands, spectrum, squared_envelope, Band};
use super::prewhiten::prewhiten;
use super::shaft::{interpolated_peak, shaft_speed, ShaftSpeed};
use serde::Serialize;

/// The kinematic factor of a family's lines is searched within `±SLIP`.
pub const SLIP: f64 = 0.01;

/// A member's window is `±(1 bin + LINE_WIDTH · f)` around its predicted frequency (the
/// speed's drift over the record smears a line by about this much).
pub const LINE_WIDTH: f64 = 0.001;

/// Two families are told apart when their scores (−log₁₀ of the chance probability) differ by
/// at least this: a factor of 100.
pub const TIE_MARGIN: f64 = 2.0;

/// The one rule for "the data carry a family", used by the code and the tests.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CarryRule {
    /// Fewest members that must stand out.
    pub members: usize,
    /// By at least this much over the SES's local median, dB.
    pub min_db: f64,
    /// The chance that noise makes the family look at least as strong (its p-value over the
    /// whole search) must be below this.
    pub false_alarm: f64,
}

/// At least two members ≥ 10 dB above the SES's local median, and a family p-value below 10⁻³.
pub const CARRY: CarryRule = CarryRule { members: 2, min_db: 10.0, false_alarm: 1e-3 };

/// A bearing's defect lines as orders of the shaft speed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Kinematics {
    /// Ball pass frequency, outer race.
    pub bpfo: f64,
    /// Ball pass frequency, inner race.
    pub bpfi: f64,
    /// Ball spin frequency.
    pub bsf: f64,
    /// Cage (fundamental train) frequency.
    pub ftf: f64,
}

/// A bearing the families are looked for at.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BearingSpec {
    /// How reports name it.
    pub name: String,
    /// Its lines.
    pub orders: Kinematics,
}

/// A fault family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub enum Family {
    /// Outer race: BPFO and harmonics.
    OuterRace,
    /// Inner race: BPFI, harmonics, ±shaft sidebands.
    InnerRace,
    /// Rolling element: 2×BSF, harmonics, ±FTF sidebands, FTF and 2×FTF.
    Ball,
}

impl Family {
    /// All three.
    pub const ALL: [Family; 3] = [Family::OuterRace, Family::InnerRace, Family::Ball];

    /// `outer race`, `inner race`, `ball`.
    pub fn name(self) -> &'static str {
        match self {
            Family::OuterRace => "outer race",
            Family::InnerRace => "inner race",
            Family::Ball => "ball",
        }
    }

    /// Its members.
    fn members(self, k: &Kinematics) -> Members {
        let mut m = Vec::new();
        match self {
            Family::OuterRace => (1..=4).for_each(|h| m.push((format!("{h}×BPFO"), h as f64 * k.bpfo, 0.0))),
            Family::InnerRace => {
                for h in 1..=3 {
                    let f = h as f64 * k.bpfi;
                    m.push((format!("{h}×BPFI"), f, 0.0));
                    m.push((format!("{h}×BPFI−1×"), f, -1.0));
                    m.push((format!("{h}×BPFI+1×"), f, 1.0));
                }
            }
            Family::Ball => {
                m.push(("FTF".into(), k.ftf, 0.0));
                m.push(("2×FTF".into(), 2.0 * k.ftf, 0.0));
                for h in 1..=3 {
                    let f = 2.0 * h as f64 * k.bsf;
                    m.push((format!("{}×BSF", 2 * h), f, 0.0));
                    m.push((format!("{}×BSF−FTF", 2 * h), f - k.ftf, 0.0));
                    m.push((format!("{}×BSF+FTF", 2 * h), f + k.ftf, 0.0));
                }
            }
        }
        m
    }
}

/// One member of a family as found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Member {
    /// `2×BPFI+1×`, …
    pub label: String,
    /// Where its peak is, Hz.
    pub hz: f64,
    /// Its peak over the SES's local median, dB.
    pub strength_db: f64,
    /// Within reach of an integer shaft order: not counted.
    pub on_order: bool,
}

/// A family as found on its best channel and band.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FamilyFit {
    /// The family.
    pub family: Family,
    /// The bearing's name.
    pub bearing: String,
    /// The channel (index) and band its SES came from.
    pub channel: usize,
    /// The band.
    pub band: Band,
    /// The kinematic factor found, `s` (the lines are at `(1 + s)` times their nominal orders).
    pub slip: f64,
    /// Its members.
    pub members: Vec<Member>,
    /// Whether the data carry it ([`CARRY`]).
    pub carried: bool,
    /// −log₁₀ of its p-value over the whole search.
    pub score: f64,
}

/// What the data show.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum Verdict {
    /// One family explains the lines best by at least [`TIE_MARGIN`].
    Named(FamilyFit),
    /// Two families (or bearings) explain them equally: the best and its rival.
    CannotTell(FamilyFit, FamilyFit),
    /// No bearing defect the data can show.
    Nothing,
}

/// The diagnosis of a recording.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnosis {
    /// The refined speed.
    pub shaft: ShaftSpeed,
    /// Every bearing's every family at its best, highest score first.
    pub families: Vec<FamilyFit>,
    /// The decision.
    pub verdict: Verdict,
}

/// A squared envelope spectrum with its local median.
struct Ses {
    df: f64,
    power: Vec<f64>,
    floor: Vec<f64>,
}

impl Ses {
    /// The SES of `x` in `band` up to `max_hz`, its floor the median over `±reach_hz`.
    fn of(x: &[f64], fs: f64, band: &Band, max_hz: f64, reach_hz: f64) -> Ses {
        // Power up to a constant (the floor is read the same way, so the ratios are exact).
        let spec = spectrum(&squared_envelope(x, fs, band), fs);
        let df = spec.df;
        let bins = ((max_hz / df).ceil() as usize + 2).min(spec.amplitude.len().saturating_sub(1));
        let power: Vec<f64> = spec.amplitude[..bins].iter().map(|a| a * a).collect();
        let reach = ((reach_hz / df).round() as usize).max(20);
        let floor = (0..bins)
            .map(|k| {
                let mut v: Vec<f64> = power[k.saturating_sub(reach).max(1)..=(k + reach).min(bins - 1)].to_vec();
                let mid = v.len() / 2;
                *v.select_nth_unstable_by(mid, f64::total_cmp).1
            })
            .collect();
        Ses { df, power, floor }
    }
}

/// The squared envelope spectrum of `x` prewhitened, in `band`, up to `max_hz`: bin spacing,
/// power per bin, and its local median over `±reach_hz` (for plots and for reading the lines).
pub fn envelope_spectrum(x: &[f64], fs: f64, band: &Band, max_hz: f64, reach_hz: f64) -> (f64, Vec<f64>, Vec<f64>) {
    let s = Ses::of(&prewhiten(x), fs, band, max_hz, reach_hz);
    (s.df, s.power, s.floor)
}

/// `ln(1 − (1 − 2^(−r))^w)`: the log-probability that noise reaches `r` times the median in
/// one of `w` exponential bins.
fn ln_window_p(r: f64, w: f64) -> f64 {
    if r <= 0.0 {
        return 0.0;
    }
    let ln_q = -r * std::f64::consts::LN_2;
    if ln_q < -30.0 {
        w.ln() + ln_q
    } else {
        (-(w * (-ln_q.exp()).ln_1p()).exp_m1()).ln().min(0.0)
    }
}

/// `ln C(m, i)`.
fn ln_choose(m: usize, i: usize) -> f64 {
    (1..=i).map(|j| ((m + 1 - j) as f64 / j as f64).ln()).sum()
}

/// `ln P(Binomial(m, p) ≥ j)` from `ln p`.
fn ln_binomial_tail(m: usize, ln_p: f64, j: usize) -> f64 {
    let ln_q = (-ln_p.exp()).ln_1p();
    let terms: Vec<f64> =
        (j..=m).map(|i| ln_choose(m, i) + i as f64 * ln_p + if i < m { (m - i) as f64 * ln_q } else { 0.0 }).collect();
    let top = terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    top + terms.iter().map(|t| (t - top).exp()).sum::<f64>().ln()
}

/// The combined log p-value of members' log p-values: the smallest binomial tail of their
/// order statistics from the `rule.members`-th on, times the number of tails looked at.
fn ln_combined(mut ln_p: Vec<f64>, rule: &CarryRule) -> f64 {
    let m = ln_p.len();
    if m < rule.members {
        return 0.0;
    }
    ln_p.sort_by(f64::total_cmp);
    let best = (rule.members..=m).map(|j| ln_binomial_tail(m, ln_p[j - 1], j)).fold(0.0, f64::min);
    (best + ((m + 1 - rule.members) as f64).ln()).min(0.0)
}

/// A family's members: (label, kinematic order scaled by `1 + s`, shaft order added unscaled).
type Members = Vec<(String, f64, f64)>;

/// A family evaluated on one SES at one kinematic factor.
struct Trial {
    slip: f64,
    members: Vec<Member>,
    ln_p: f64,
}

/// Where the search runs: the SES, the speed, the shaft speed's uncertainty.
struct Search<'a> {
    ses: &'a Ses,
    shaft: &'a ShaftSpeed,
}

impl Search<'_> {
    /// Half the width of a member's window at `f`, Hz.
    fn half_width(&self, f: f64) -> f64 {
        self.ses.df + LINE_WIDTH * f
    }

    /// Whether a member at `f` is within reach of an integer shaft order (its window, the
    /// Hann main lobe of two bins, and the speed's uncertainty at that order).
    fn on_order(&self, f: f64) -> bool {
        let fr = self.shaft.hz;
        let k = (f / fr).round();
        k >= 1.0 && (f - k * fr).abs() <= self.half_width(f) + 2.0 * self.ses.df + 3.0 * k * self.shaft.uncertainty_hz
    }

    /// The member at `f` Hz: its peak, strength, and log p-value (0 if not counted).
    fn member(&self, label: &str, f: f64) -> (Member, f64) {
        let (df, p, floor) = (self.ses.df, &self.ses.power, &self.ses.floor);
        let hw = self.half_width(f);
        let lo = ((f - hw) / df).ceil().max(1.0) as usize;
        let hi = (((f + hw) / df).floor() as usize).max(lo).min(p.len().saturating_sub(2));
        // The highest local maximum in the window: a line outside it reaches in with its
        // skirt (Hann's main lobe is four bins wide), which is not a line here.
        let peak = (lo..=hi).filter(|&j| p[j] >= p[j - 1] && p[j] >= p[j + 1]).max_by(|&a, &b| p[a].total_cmp(&p[b]));
        let k = peak.unwrap_or(((f / df).round() as usize).min(p.len() - 1));
        let r = match peak {
            Some(k) if floor[k] > 0.0 => p[k] / floor[k],
            _ => 0.0,
        };
        let on_order = self.on_order(f);
        let ln_p = if on_order { 0.0 } else { ln_window_p(r, (hi + 1 - lo) as f64) };
        let member = Member {
            label: label.to_string(),
            hz: interpolated_peak(p, k) * df,
            strength_db: if r > 0.0 { 10.0 * r.log10() } else { f64::NEG_INFINITY },
            on_order,
        };
        (member, ln_p)
    }

    /// The family's members at kinematic factor `slip`.
    fn trial(&self, spec: &[(String, f64, f64)], slip: f64) -> Trial {
        let fr = self.shaft.hz;
        let (members, ln_ps): (Vec<Member>, Vec<f64>) =
            spec.iter().map(|(label, kin, sh)| self.member(label, (kin * (1.0 + slip) + sh) * fr)).unzip();
        let counted: Vec<f64> = members.iter().zip(&ln_ps).filter(|(m, _)| !m.on_order).map(|(_, p)| *p).collect();
        Trial { slip, members, ln_p: ln_combined(counted, &CARRY) }
    }

    /// The family at its best kinematic factor within `±SLIP`, its log p-value charged for
    /// the number of independent factors tried.
    fn best(&self, spec: &[(String, f64, f64)]) -> Trial {
        let fr = self.shaft.hz;
        let top = spec.iter().map(|(_, kin, _)| kin * fr).fold(0.0, f64::max);
        let step = 0.25 * self.ses.df / top;
        let steps = (SLIP / step).ceil() as i64;
        let mut best = self.trial(spec, 0.0);
        for i in -steps..=steps {
            let t = self.trial(spec, i as f64 * step);
            if t.ln_p < best.ln_p {
                best = t;
            }
        }
        let independent = (2.0 * SLIP * top / (2.0 * self.half_width(top))).max(1.0);
        best.ln_p = (best.ln_p + independent.ln()).min(0.0);
        best
    }
}

/// The bands each channel's SES is made in: the whole prewhitened band, and the kurtogram's
/// most impulsive band at least `min_width` wide.
fn bands(xw: &[f64], fs: f64, min_width: f64) -> Vec<Band> {
    let mut out = vec![Band { low_hz: 0.0, high_hz: 0.5 * fs, kurtosis: 0.0 }];
    out.extend(kurtogram_bands(xw, fs, min_width, min_width, 1));
    out
}

/// The diagnosis of `channels` (sampled at `fs`, each a housing's vibration) for `bearings`,
/// the running speed searched within ±10 % of `nominal_hz`. `None` if no speed can be read.
pub fn diagnose(channels: &[&[f64]], fs: f64, nominal_hz: f64, bearings: &[BearingSpec]) -> Option<Diagnosis> {
    let shaft = shaft_speed(channels, fs, nominal_hz, 0.1)?;
    let specs: Vec<(usize, Family, Members)> = bearings
        .iter()
        .enumerate()
        .flat_map(|(b, spec)| Family::ALL.map(|f| (b, f, f.members(&spec.orders))))
        .collect();
    let top_order = specs.iter().flat_map(|s| s.2.iter().map(|m| m.1 + m.2)).fold(0.0, f64::max) * (1.0 + SLIP);
    let max_hz = (top_order + 1.0) * shaft.hz;
    let mut best: Vec<Option<FamilyFit>> = vec![None; specs.len()];
    let mut looks = 0usize;
    for (ch, x) in channels.iter().enumerate() {
        let xw = prewhiten(x);
        for band in bands(&xw, fs, 1.2 * max_hz) {
            looks += 1;
            let ses = Ses::of(&xw, fs, &band, max_hz * 1.05, shaft.hz);
            let search = Search { ses: &ses, shaft: &shaft };
            for (i, (b, family, spec)) in specs.iter().enumerate() {
                let t = search.best(spec);
                let score = -t.ln_p / std::f64::consts::LN_10;
                if best[i].as_ref().is_none_or(|f| score > f.score) {
                    best[i] = Some(FamilyFit {
                        family: *family,
                        bearing: bearings[*b].name.clone(),
                        channel: ch,
                        band,
                        slip: t.slip,
                        members: t.members,
                        carried: false,
                        score,
                    });
                }
            }
        }
    }
    let charge = (looks.max(1) as f64).log10();
    let mut families: Vec<FamilyFit> = best.into_iter().flatten().collect();
    for f in &mut families {
        f.score = (f.score - charge).max(0.0);
        f.carried = carried(f);
    }
    families.sort_by(|a, b| b.score.total_cmp(&a.score));
    let verdict = decide(&families);
    Some(Diagnosis { shaft, families, verdict })
}

/// [`CARRY`]: enough members strong enough (not on a shaft order), and a small p-value.
pub fn carried(f: &FamilyFit) -> bool {
    let strong = f.members.iter().filter(|m| !m.on_order && m.strength_db >= CARRY.min_db).count();
    strong >= CARRY.members && f.score >= -CARRY.false_alarm.log10()
}

/// The best carried family, or a tie with the next carried one within [`TIE_MARGIN`].
fn decide(families: &[FamilyFit]) -> Verdict {
    let mut carried = families.iter().filter(|f| f.carried);
    match (carried.next(), carried.next()) {
        (None, _) => Verdict::Nothing,
        (Some(a), Some(b)) if a.score - b.score < TIE_MARGIN => Verdict::CannotTell(a.clone(), b.clone()),
        (Some(a), _) => Verdict::Named(a.clone()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chance_of_a_peak_in_noise_is_exponential() {
        // One bin, 10 times the median: 2^-10.
        assert!((ln_window_p(10.0, 1.0) - (-10.0 * std::f64::consts::LN_2)).abs() < 1e-9);
        // Far out in the tail, W bins multiply it.
        assert!((ln_window_p(200.0, 8.0) - (8f64.ln() - 200.0 * std::f64::consts::LN_2)).abs() < 1e-9);
        // Two of four members at p = 1e-3: about 6e-6, times the three tails looked at.
        let l = ln_combined(vec![1e-3f64.ln(), 1e-3f64.ln(), 0.0, 0.0], &CARRY);
        assert!((l.exp() / (3.0 * 6e-6) - 1.0).abs() < 0.01, "{}", l.exp());
        // More members at the same strengths are charged for.
        let many = ln_combined(vec![1e-3f64.ln(), 1e-3f64.ln(), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], &CARRY);
        assert!(many > l);
    }
}
