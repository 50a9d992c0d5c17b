//! Signatures of a run's innovations: bias (mean against its standard error), NIS against its
//! χ² bounds, whiteness (Ljung–Box), spectral lines placed at the system's reference lines
//! (orders of the running speed, natural frequencies, named lines such as a bearing's defect
//! frequencies), and a step in a channel's innovation power (a change during the run). The
//! statistics come from `edgekf::residual`, the same code the node runs.

use super::filter::Run;
use super::order_lines::{order_lines, threshold, OrderLine};
use edgekf::residual::{locate_peak, NisBounds, PeakClass, PeakTolerance, RunningStats, Welch, WhitenessWindow};
use serde::Serialize;
use std::collections::BTreeMap;

/// Welch segment length of the innovation spectra up to [`FINE_ABOVE_HZ`].
pub const SEGMENT: usize = 1024;
/// The segment length above it: at 12 kHz, 1024 samples would make 11.7 Hz bins, too coarse
/// to tell a shaft order or a defect line from its neighbours.
pub const FINE_SEGMENT: usize = 4096;
/// Sample rate above which the spectra use [`FINE_SEGMENT`], Hz.
pub const FINE_ABOVE_HZ: f64 = 4096.0;

/// A channel's Welch spectrum: bin width (Hz), PSD and its strongest peaks (Hz, dB).
type Spectrum = (f64, Vec<f32>, Vec<(f64, f64)>);

/// The Welch spectrum of `z` in segments of `N` at `rate` Hz, peaks above `peak_db`.
fn welch_spectrum<const N: usize>(z: &[f64], rate: f64, peak_db: f32) -> Option<Spectrum>
where
    edgekf::residual::FftLen<N>: edgekf::residual::FftSize,
{
    let mut w = Welch::<N>::new(rate as f32)?;
    for &v in z {
        w.push(v);
    }
    (w.blocks() > 0).then(|| {
        let peaks = w.peaks::<8>(peak_db).iter().map(|p| (p.frequency_hz as f64, p.prominence_db as f64)).collect();
        (w.bin_width_hz() as f64, w.psd().to_vec(), peaks)
    })
}

/// What counts as a signature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SignatureOptions {
    /// Samples before this time (s after the first) are left out of the statistics.
    pub settle: f64,
    /// Virtual-sensing errors are computed from this time on (s after the first sample; 0: the
    /// whole run).
    pub error_after: f64,
    /// A channel's innovation mean this many standard errors from zero is a bias.
    pub bias_z: f64,
    /// False-alarm probability of the whiteness and NIS tests.
    pub alpha: f64,
    /// Spectral lines of the normalised innovations at least this far above the median, dB.
    pub peak_db: f32,
}

impl Default for SignatureOptions {
    fn default() -> Self {
        Self { settle: 0.5, error_after: 0.0, bias_z: 5.0, alpha: 0.01, peak_db: 10.0 }
    }
}

/// A channel as reports show it: its name and SI unit, and the scale and unit people read it in.
///
/// ```
/// use edgekf_sim::residual_loop::Channel;
/// let probe = Channel::new("n5_x", "m").shown_in(1e6, "µm");
/// assert_eq!(probe.display(2.5e-6), 2.5);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Channel {
    /// Name, as in the data file (`n5_x`, `acc_x`).
    pub name: String,
    /// SI unit of its values (`m`, `m/s^2`, `V`).
    pub unit: String,
    /// Factor from SI to the unit people read (1e6 for metres shown in µm).
    #[serde(skip)]
    pub display_scale: f64,
    /// The unit people read (`µm`).
    #[serde(skip)]
    pub display_unit: String,
}

impl Channel {
    /// `name` in `unit`, shown as it is.
    pub fn new(name: impl Into<String>, unit: impl Into<String>) -> Self {
        let unit = unit.into();
        Self { name: name.into(), display_unit: unit.clone(), unit, display_scale: 1.0 }
    }

    /// The same channel shown as `scale ×` its SI value in `unit`.
    pub fn shown_in(self, scale: f64, unit: impl Into<String>) -> Self {
        Self { display_scale: scale, display_unit: unit.into(), ..self }
    }

    /// `v` (SI) in the displayed unit.
    pub fn display(&self, v: f64) -> f64 {
        v * self.display_scale
    }
}

/// A named spectral line a system expects (a bearing's defect frequency, a blade pass).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NamedLine {
    /// Name (`BPFO`).
    pub name: String,
    /// Where it comes from (`bearing #0`).
    pub location: String,
    /// Frequency, Hz.
    pub hz: f64,
}

/// The spectral lines a system supplies to place the innovations' lines at.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReferenceLines {
    /// Running speed, rad/s: lines at its orders are named `2x`, `3/2x`. Zero: nothing rotates.
    pub speed: f64,
    /// Natural frequencies of the model, Hz.
    pub naturals: Vec<f64>,
    /// Named lines; their harmonics (up to [`LINE_HARMONICS`]) name a line too.
    pub named: Vec<NamedLine>,
}

/// What a run is summarised against: the time base, the channels, the virtual-sensing rows
/// with their truth (where the file has it), the reference lines and the sample rate.
#[derive(Debug, Clone, Copy)]
pub struct SummaryContext<'a> {
    /// Time of each sample, s.
    pub t: &'a [f64],
    /// Sensor channels, in the filter's order.
    pub channels: &'a [Channel],
    /// Virtual-sensing rows, in [`Run::outputs`]' order.
    pub rows: &'a [Channel],
    /// Truth of each row, where known.
    pub truth: &'a [Option<&'a [f64]>],
    /// Where lines are placed.
    pub lines: &'a ReferenceLines,
    /// Samples per second.
    pub sample_rate: f64,
}

/// A spectral line of one channel's normalised innovation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeakSignature {
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// Above the median level, dB.
    pub prominence_db: f64,
    /// Where it sits (`2x`, `natural 0`, `2x at natural 1`, `BPFO at bearing 4`,
    /// `unexplained`).
    pub class: String,
    /// The integer order of the running speed it sits at, if any.
    pub order: Option<u32>,
    /// The named line it sits at (index into [`ReferenceLines::named`], harmonic: 1 for the
    /// line itself), if any.
    #[serde(skip)]
    pub line: Option<(usize, u8)>,
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
    /// Its standard error, from the mean square's spread over blocks of the analysed samples
    /// ([`batch_std_error`](super::baseline::batch_std_error)); NaN when too short.
    pub rms_standard_error: f64,
    /// Mean of `e² / S_ii` (1 when consistent).
    pub nis: f64,
    /// The same over the first and the second half of the analysed samples.
    pub nis_halves: [f64; 2],
    /// Where a step in `e² / S_ii` is most likely (CUSUM), s from the first sample, and the
    /// ratio of its mean after to before.
    pub step: Option<(f64, f64)>,
    /// Ljung–Box p-value (20 lags over the last 2048 samples).
    pub whiteness_p: f64,
    /// Spectral lines.
    pub peaks: Vec<PeakSignature>,
    /// The statistic at each order of the running speed ([`order_lines`](super::order_lines)).
    pub order_lines: Vec<OrderLine>,
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
    /// Unbiased, white (Bonferroni over the channels) and NIS-consistent.
    pub consistent: bool,
    /// RMS error of the virtual-sensing rows against `truth_` columns, in the rows' SI unit.
    pub error_rms: BTreeMap<String, f64>,
    /// A system's own error figures against truth, beside the RMS (a boom's `peak_error_pct`),
    /// reported as fields of the summary; the engine only carries them.
    #[serde(flatten)]
    pub metrics: BTreeMap<String, f64>,
    /// `−½ Σ (ln det S + NIS)` over the run.
    pub log_likelihood: f64,
    /// Per-channel signatures.
    pub channels: Vec<ChannelSignature>,
    /// Bin width of the spectra, Hz.
    pub bin_width_hz: f64,
    /// Welch PSD of each channel's normalised innovation (1/Hz), for the plots.
    #[serde(skip)]
    pub spectra: Vec<Vec<f32>>,
}

impl RunSummary {
    /// What the run's NIS inflates the fits' costs and intervals by: its mean where the model
    /// under-states its innovations, never below 1 (a model that over-states them is not
    /// flattered), 1 where it could not be computed.
    pub fn nis_scale(&self) -> f64 {
        if self.nis_mean.is_finite() {
            self.nis_mean.max(1.0)
        } else {
            1.0
        }
    }
}

/// A residual signature left over: a channel (or location), the frequency if it is a line,
/// and the statistic that flags it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Signature {
    /// Channel (or the location a rejected effect would act at).
    pub channel: String,
    /// Frequency of a line, Hz.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency_hz: Option<f64>,
    /// `innovation_mean_z`, `ljung_box_p`, `peak_db`, `nis_step`, `nis_mean`, `delta_log_likelihood_halves`.
    pub statistic: String,
    /// Its value.
    pub value: f64,
    /// In words.
    pub description: String,
}

/// Harmonics of a bearing line that name a spectral line.
pub const LINE_HARMONICS: u8 = 8;

/// The named line (index into `lines`, harmonic) a peak at `f` Hz sits at, within `tol_hz`
/// (the closest, if several are). The line itself is matched first and always; its harmonics
/// (up to [`LINE_HARMONICS`]) only when the peak is at no order of the running speed or
/// natural frequency (`located`), because with four lines per bearing some harmonic falls near
/// almost anything.
///
/// ```
/// use edgekf_sim::residual_loop::signature::{named_line, NamedLine};
/// let lines = [NamedLine { name: "BPFO".into(), location: "bearing #0".into(), hz: 107.55 }];
/// assert_eq!(named_line(107.55, &lines, 1.0, false), Some((0, 1)));
/// assert_eq!(named_line(322.6, &lines, 1.0, false), Some((0, 3)));
/// assert_eq!(named_line(322.6, &lines, 1.0, true), None);
/// ```
pub fn named_line(f: f64, lines: &[NamedLine], tol_hz: f64, located: bool) -> Option<(usize, u8)> {
    let closest = |hs: std::ops::RangeInclusive<u8>| {
        hs.flat_map(|h| lines.iter().enumerate().map(move |(i, l)| ((f - h as f64 * l.hz).abs(), (i, h))))
            .filter(|(d, _)| *d <= tol_hz)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, m)| m)
    };
    closest(1..=1).or_else(|| if located { None } else { closest(2..=LINE_HARMONICS) })
}

/// Summarises `run`: per-channel signatures over the samples after `settle`, the NIS, and the
/// virtual-sensing error of the rows against their truth (where given).
pub fn summarise(run: &Run, ctx: &SummaryContext<'_>, o: &SignatureOptions) -> RunSummary {
    let SummaryContext { t, channels, sample_rate, .. } = *ctx;
    let t0 = t.first().copied().unwrap_or(0.0);
    let keep: Vec<usize> = (0..t.len()).filter(|&k| t[k] - t0 >= o.settle).collect();
    let mut out = Vec::new();
    let mut spectra = Vec::new();
    let fine = sample_rate > FINE_ABOVE_HZ;
    let mut bin_width_hz = sample_rate / if fine { FINE_SEGMENT } else { SEGMENT } as f64;
    for (i, channel) in channels.iter().enumerate() {
        let (signature, spectrum) = channel_signature(run, i, &channel.name, &keep, ctx, o);
        match spectrum {
            // The plots share one frequency axis: a slow channel's spectrum is not drawn.
            Some((width, psd)) => {
                bin_width_hz = width;
                spectra.push(psd);
            }
            None => spectra.push(Vec::new()),
        }
        out.push(signature);
    }
    let m = channels.len().max(1);
    let (nis_mean, nis_consistent) = nis_consistency(run, &keep, channels.len(), o);
    let error_rms = error_rms(run, ctx, t0, o);
    let whiteness_p = out.iter().map(|c| c.whiteness_p).fold(1.0, f64::min);
    let no_order_line = add_order_lines(&mut out, ctx.lines, bin_width_hz, o.alpha);
    let consistent = nis_consistent
        && no_order_line
        && whiteness_p >= o.alpha / m as f64
        && out.iter().all(|c| c.z.abs() < o.bias_z);
    RunSummary {
        innovation_rms: out.iter().map(|c| (c.name.clone(), c.rms)).collect(),
        nis_mean,
        nis_consistent,
        whiteness_p,
        consistent,
        error_rms,
        metrics: BTreeMap::new(),
        log_likelihood: run.log_likelihood(),
        channels: out,
        bin_width_hz,
        spectra,
    }
}

/// Marks each order line over the level for all the channels' tests at once (`alpha`) as a
/// spectral line of its channel, where the Welch spectrum had none at that order, so that the
/// candidates at that order are asked for. `true` when there is none.
fn add_order_lines(channels: &mut [ChannelSignature], lines: &ReferenceLines, bin_width_hz: f64, alpha: f64) -> bool {
    let tests = channels.iter().map(|c| c.order_lines.len()).sum();
    let level = threshold(alpha, tests);
    let tol = PeakTolerance::new(1.2 * bin_width_hz);
    let mut none = true;
    for c in channels.iter_mut() {
        for l in c.order_lines.iter().filter(|l| l.statistic > level) {
            none = false;
            if !c.peaks.iter().any(|p| p.order == Some(l.order)) {
                // Its level above what white innovations give there, in dB.
                let prominence_db = 10.0 * (l.statistic / 2.0).log10();
                c.peaks.push(peak(l.frequency_hz, prominence_db, lines, &tol));
            }
        }
    }
    none
}

/// Channel `i`'s signature over the samples `keep`, and its spectrum (bin width, PSD) where it
/// is sampled at the run's rate.
fn channel_signature(
    run: &Run,
    i: usize,
    name: &str,
    keep: &[usize],
    ctx: &SummaryContext<'_>,
    o: &SignatureOptions,
) -> (ChannelSignature, Option<(f64, Vec<f32>)>) {
    let (t, sample_rate) = (ctx.t, ctx.sample_rate);
    let t0 = t.first().copied().unwrap_or(0.0);
    let mut stats = RunningStats::<f64>::new();
    let mut nis = RunningStats::<f64>::new();
    let mut white = WhitenessWindow::<f64, 2048>::new();
    let mut zs = Vec::with_capacity(keep.len());
    let mut tz = Vec::with_capacity(keep.len());
    let mut z2 = Vec::with_capacity(keep.len());
    let mut squares = Vec::with_capacity(keep.len());
    for &k in keep {
        let e = run.innovation[i][k];
        let s = run.variance[i][k];
        if !(e.is_finite() && s.is_finite()) {
            continue;
        }
        stats.push(e);
        squares.push(e * e);
        nis.push(e * e / s);
        z2.push((t[k] - t0, e * e / s));
        let z = e / s.sqrt();
        white.push(z);
        zs.push(z);
        tz.push(t[k] - t0);
    }
    let lb = white.ljung_box(20);
    let mut peaks = Vec::new();
    // A slow channel (a 5 Hz log in 50 Hz rows) is its own sequence at its own rate.
    let rate = if 2 * zs.len() < keep.len() { sample_rate * zs.len() as f64 / keep.len() as f64 } else { sample_rate };
    let spectrum = if sample_rate > FINE_ABOVE_HZ {
        welch_spectrum::<FINE_SEGMENT>(&zs, rate, o.peak_db)
    } else {
        welch_spectrum::<SEGMENT>(&zs, rate, o.peak_db)
    };
    let mut drawn = None;
    if let Some((width, psd, found)) = spectrum {
        drawn = (rate == sample_rate).then_some((width, psd));
        let tol = PeakTolerance::new(1.2 * width);
        peaks.extend(found.into_iter().map(|(f, prominence_db)| peak(f, prominence_db, ctx.lines, &tol)));
    }
    let se = stats.standard_error();
    let half = z2.len() / 2;
    let mean = |s: &[(f64, f64)]| s.iter().map(|v| v.1).sum::<f64>() / s.len().max(1) as f64;
    let signature = ChannelSignature {
        name: name.to_string(),
        mean: stats.mean(),
        standard_error: se,
        z: stats.mean() / se,
        rms: stats.rms(),
        rms_standard_error: rms_standard_error(&squares, stats.rms()),
        nis: nis.mean(),
        nis_halves: [mean(&z2[..half]), mean(&z2[half..])],
        step: step(&z2),
        whiteness_p: lb.p_value,
        peaks,
        order_lines: order_lines(&zs, &tz, ctx.lines.speed, rate),
    };
    (signature, drawn)
}

/// A spectral line at `f` Hz placed among the reference `lines`: a named line (or its
/// harmonic), an order of the running speed, a natural frequency, or unexplained.
fn peak(f: f64, prominence_db: f64, lines: &ReferenceLines, tol: &PeakTolerance<f64>) -> PeakSignature {
    let located = locate_peak(f, lines.speed, &lines.naturals, tol).class;
    let line = named_line(f, &lines.named, tol.abs_hz, !matches!(located, PeakClass::Unexplained));
    let (class, order) = if let Some((i, h)) = line {
        let times = if h == 1 { String::new() } else { format!("{h}×") };
        let l = &lines.named[i];
        (format!("{times}{} at {}", l.name, l.location), None)
    } else {
        match located {
            PeakClass::Order(o) => {
                (format!("{}/{}x", o.numerator, o.denominator), o.is_integer().then_some(o.numerator))
            }
            PeakClass::OrderAtNatural { order: o, natural } => (
                format!("{}/{}x at natural {natural}", o.numerator, o.denominator),
                o.is_integer().then_some(o.numerator),
            ),
            PeakClass::Natural(n) => (format!("natural {n}"), None),
            PeakClass::Unexplained => ("unexplained".to_string(), None),
        }
    };
    PeakSignature { frequency_hz: f, prominence_db, class: class.replace("/1x", "x"), order, line }
}

/// The NIS per channel over the samples `keep` of a run with `channels` channels, and whether
/// it lies within the χ² bounds.
fn nis_consistency(run: &Run, keep: &[usize], channels: usize, o: &SignatureOptions) -> (f64, bool) {
    let mut nis_total = RunningStats::<f64>::new();
    // Degrees of freedom of the samples' NIS: the channels each had (a slow sensor's channels
    // are in one sample of ten).
    let (mut dof, mut nis_sum) = (0usize, 0.0);
    for &k in keep {
        nis_total.push(run.nis[k]);
        if run.nis[k].is_finite() {
            dof += (0..channels).filter(|&i| run.innovation[i][k].is_finite()).count();
            nis_sum += run.nis[k];
        }
    }
    let m = channels.max(1);
    let samples = nis_total.count().max(1) as usize;
    // Every channel in every sample: `mean(NIS)` against χ²(n m)/n; otherwise NIS per degree of
    // freedom against χ²(dof)/dof (the same test when the channels are all there).
    let uniform = dof == m * samples;
    let (bounds, per_channel) = if uniform || dof == 0 {
        (NisBounds::new(m, samples, o.alpha), nis_total.mean() / m as f64)
    } else {
        (NisBounds::new(1, dof, o.alpha), nis_sum / dof as f64)
    };
    (per_channel, bounds.contains(if uniform || dof == 0 { nis_total.mean() } else { per_channel }))
}

/// The standard error of the RMS of samples whose squares are `squares`: batch means of the
/// squares, carried through the square root (`σ_rms = σ_ms / 2 rms`).
fn rms_standard_error(squares: &[f64], rms: f64) -> f64 {
    let means: Vec<f64> = super::baseline::blocks(squares.len())
        .into_iter()
        .map(|b| squares[b.clone()].iter().sum::<f64>() / b.len() as f64)
        .collect();
    super::baseline::batch_std_error(&means) / (2.0 * rms)
}

/// Each virtual row's RMS error against its truth after `o.error_after`, where it has one.
fn error_rms(run: &Run, ctx: &SummaryContext<'_>, t0: f64, o: &SignatureOptions) -> BTreeMap<String, f64> {
    let mut error_rms = BTreeMap::new();
    for (j, name) in ctx.rows.iter().map(|r| &r.name).enumerate() {
        if let Some(Some(truth)) = ctx.truth.get(j) {
            let (mut s, mut n) = (0.0, 0usize);
            for ((tk, est), tr) in ctx.t.iter().zip(&run.outputs[j]).zip(truth.iter()) {
                if tk - t0 >= o.error_after && tr.is_finite() && est.is_finite() {
                    s += (est - tr).powi(2);
                    n += 1;
                }
            }
            if n > 0 {
                error_rms.insert(name.clone(), (s / n as f64).sqrt());
            }
        }
    }
    error_rms
}

/// The most likely step in the mean of `z²` (CUSUM of `z² − mean`): its time and the ratio of
/// the mean after to the mean before.
fn step(z2: &[(f64, f64)]) -> Option<(f64, f64)> {
    if z2.len() < 20 {
        return None;
    }
    let mean = z2.iter().map(|v| v.1).sum::<f64>() / z2.len() as f64;
    let (mut s, mut best, mut at) = (0.0f64, 0.0f64, 0usize);
    for (k, v) in z2.iter().enumerate() {
        s += v.1 - mean;
        if s.abs() > best.abs() {
            (best, at) = (s, k + 1);
        }
    }
    if at < 5 || at + 5 > z2.len() {
        return None;
    }
    let m = |s: &[(f64, f64)]| s.iter().map(|v| v.1).sum::<f64>() / s.len() as f64;
    Some((z2[at].0, m(&z2[at..]) / m(&z2[..at])))
}

/// The signatures of a summary that are not consistent with a correct model.
pub fn unexplained(s: &RunSummary, o: &SignatureOptions) -> Vec<Signature> {
    let mut out = Vec::new();
    let m = s.channels.len().max(1) as f64;
    for c in &s.channels {
        if c.z.abs() >= o.bias_z {
            out.push(Signature {
                channel: c.name.clone(),
                frequency_hz: None,
                statistic: "innovation_mean_z".into(),
                value: c.z,
                description: format!("innovation mean {:.3e} is {:.1} standard errors from zero", c.mean, c.z),
            });
        }
        if c.whiteness_p < o.alpha / m {
            out.push(Signature {
                channel: c.name.clone(),
                frequency_hz: None,
                statistic: "ljung_box_p".into(),
                value: c.whiteness_p,
                description: format!("not white (Ljung–Box p = {:.2e})", c.whiteness_p),
            });
        }
        if let Some((at, ratio)) = c.step.filter(|(_, r)| !(0.5..=2.0).contains(r)) {
            out.push(Signature {
                channel: c.name.clone(),
                frequency_hz: None,
                statistic: "nis_step".into(),
                value: ratio,
                description: format!(
                    "the normalised innovation power steps by ×{ratio:.2} at t ≈ {at:.2} s: something changed during the run"
                ),
            });
        }
        for p in &c.peaks {
            out.push(Signature {
                channel: c.name.clone(),
                frequency_hz: Some(p.frequency_hz),
                statistic: "peak_db".into(),
                value: p.prominence_db,
                description: format!(
                    "spectral line at {:.2} Hz, {:.1} dB ({})",
                    p.frequency_hz, p.prominence_db, p.class
                ),
            });
        }
    }
    if !s.nis_consistent {
        out.push(Signature {
            channel: "all".into(),
            frequency_hz: None,
            statistic: "nis_mean".into(),
            value: s.nis_mean,
            description: format!("NIS mean {:.3} per channel outside its χ² bounds", s.nis_mean),
        });
    }
    out
}
