//! The model monitor: per channel, does the estimator's normalised innovation still look like
//! white standard-normal noise? (The reasoning is on [`ModelMonitor`].)

use super::chi2::normal_quantile;
use super::cusum::{nis_cusum_reference, nis_cusum_threshold, Cusum};
use crate::Real;

/// Lags the whiteness statistic tests. Four cover the slow correlation an unmodelled mode or
/// lag leaves, at four multiply-adds a sample (the oscillator's node spends a tenth of its
/// sample on the whole monitor); with more, the Bonferroni threshold rises and the test loses
/// power on the first lag, where most mismatch shows.
pub const WHITENESS_LAGS: usize = 4;

/// Which statistic raised a mismatch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Statistic {
    /// The CUSUM on the channel's NIS: its variance grew.
    Cusum = 0,
    /// The windowed mean of the normalised innovation: a bias.
    Bias = 1,
    /// The windowed autocorrelation: correlation left in the innovations.
    Whiteness = 2,
}

impl Statistic {
    /// All three, in the order their events are reported.
    pub const ALL: [Statistic; 3] = [Statistic::Cusum, Statistic::Bias, Statistic::Whiteness];

    /// `cusum`, `bias` or `whiteness`.
    pub const fn name(self) -> &'static str {
        match self {
            Statistic::Cusum => "cusum",
            Statistic::Bias => "bias",
            Statistic::Whiteness => "whiteness",
        }
    }

    const fn bit(self) -> u8 {
        1 << self as u8
    }
}

/// A statistic of a channel left its null distribution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Mismatch {
    /// The channel, from 0.
    pub channel: u8,
    /// The statistic.
    pub statistic: Statistic,
    /// The sample (counted from 1 since the monitor started or was reset) where the change is
    /// estimated to begin: where the CUSUM last left zero, or the first sample of the window
    /// that alarmed (counted back over the channel's finite values: a missing one in between
    /// moves the date one sample later).
    pub since_sample: u32,
}

/// What the thresholds are set for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MonitorSettings {
    /// Samples a second per channel.
    pub sample_rate_hz: f64,
    /// False alarms an hour of the whole monitor (all channels, all statistics) on data that
    /// fits the model: the budget is split evenly over them.
    pub false_alarms_per_hour: f64,
    /// Samples per window of the bias and whiteness statistics (windows do not overlap, so a
    /// window's false-alarm probability is exact, not a scan statistic's).
    pub window: u32,
    /// The growth of the innovation variance the CUSUM is tuned for (its reference value).
    pub variance_ratio: f64,
    /// Seconds after start-up (or a reset) before the statistics start: an estimator started
    /// away from the truth has innovations far beyond its covariance until it has converged,
    /// which is not the model failing.
    pub settle_s: f64,
    /// Autocorrelation the whiteness test tolerates before it counts (0: a test of whiteness
    /// itself). A steady-state filter tuned for robustness, with more process noise than the
    /// truth has, leaves its innovations a little anti-correlated on data it explains (the
    /// oscillator's ρ(1) = −0.16): the test then flags correlation beyond that, and its false
    /// alarms on white innovations fall below the stated rate.
    pub whiteness_tolerance: f64,
}

impl MonitorSettings {
    /// One false alarm per 100 hours at `sample_rate_hz`, windows of 256 samples, the CUSUM tuned
    /// for the innovation variance doubling, no settling time, no tolerated correlation.
    pub fn new(sample_rate_hz: f64) -> Self {
        Self {
            sample_rate_hz,
            false_alarms_per_hour: 0.01,
            window: 256,
            variance_ratio: 2.0,
            settle_s: 0.0,
            whiteness_tolerance: 0.0,
        }
    }

    /// The thresholds for a monitor of `channels` channels (in `f64`, once at start-up).
    ///
    /// Each of the `3 × channels` statistics gets an equal share of the false-alarm budget:
    /// an average run length of `L = 3 · channels · 3600 · rate / per_hour` samples. The CUSUM's
    /// threshold comes from [`nis_cusum_threshold`]; a window of `W` samples gets the
    /// probability `W / L`: the bias alarms when the window's mean is beyond the two-sided
    /// normal quantile, the whiteness when one of its [`WHITENESS_LAGS`] standardised
    /// autocorrelations is beyond the Bonferroni share of it.
    pub fn thresholds(&self, channels: usize) -> Thresholds {
        let tests = 3.0 * channels.max(1) as f64;
        let run = tests * 3600.0 * self.sample_rate_hz / self.false_alarms_per_hour;
        let window = self.window.max(2 * WHITENESS_LAGS as u32);
        let p = (f64::from(window) / run).min(1.0);
        Thresholds {
            cusum_reference: nis_cusum_reference(self.variance_ratio),
            cusum_threshold: nis_cusum_threshold(self.variance_ratio, run),
            bias: -normal_quantile(0.5 * p),
            whiteness: -normal_quantile(0.5 * p / WHITENESS_LAGS as f64),
            window,
            settle: (self.settle_s * self.sample_rate_hz).clamp(0.0, u32::MAX as f64) as u32,
            whiteness_tolerance: self.whiteness_tolerance.max(0.0),
        }
    }
}

/// The monitor's thresholds (see [`MonitorSettings::thresholds`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thresholds {
    /// The CUSUM's reference `k` on the NIS.
    pub cusum_reference: f64,
    /// Its threshold `h`.
    pub cusum_threshold: f64,
    /// The bias limit on `|Σz| / √W`, standard deviations of the window's mean.
    pub bias: f64,
    /// The whiteness limit on the largest standardised autocorrelation `(|ρ(k) + 1/W| − tol) ·
    /// √(W(W+2)/(W−k))`.
    pub whiteness: f64,
    /// Samples per window.
    pub window: u32,
    /// Samples after start-up or a reset before the statistics start.
    pub settle: u32,
    /// `|ρ(k)|` tolerated on top of the whiteness limit ([`MonitorSettings::whiteness_tolerance`]).
    pub whiteness_tolerance: f64,
}

/// One channel's statistics: the CUSUM, and the sums of the current window.
#[derive(Debug, Clone, Copy)]
struct Channel<T> {
    cusum: Cusum<T>,
    /// Samples in the current window.
    n: u32,
    /// The window's first value: the sums are of `y = z − shift`, so that a large bias does not
    /// cancel the variance.
    shift: T,
    sum_y: T,
    sum_yy: T,
    /// `Σ yₜ yₜ₋ₖ` within the window, `k = 1..=L`.
    lag: [T; WHITENESS_LAGS],
    /// The window's first values of `y`.
    head: [T; WHITENESS_LAGS],
    /// The latest values of `y`, newest first.
    recent: [T; WHITENESS_LAGS],
}

impl<T: Real> Channel<T> {
    fn new(t: &Thresholds) -> Self {
        let zero = [T::zero(); WHITENESS_LAGS];
        Self {
            cusum: Cusum::new(T::of_f64(t.cusum_reference), T::of_f64(t.cusum_threshold)),
            n: 0,
            shift: T::zero(),
            sum_y: T::zero(),
            sum_yy: T::zero(),
            lag: zero,
            head: zero,
            recent: zero,
        }
    }

    /// Adds one value to the window's sums (inlined: a call would cost the chip a tenth of
    /// this, per sample).
    #[inline(always)]
    fn accumulate(&mut self, z: T) {
        if self.n == 0 {
            self.shift = z;
        }
        let y = z - self.shift;
        // `recent` is zero before the window's first values: their products add nothing.
        // Written out lag by lag (the optimiser kept a loop, twice the instructions).
        let [a, b, c, d] = self.recent;
        let [l1, l2, l3, l4] = &mut self.lag;
        *l1 += y * a;
        *l2 += y * b;
        *l3 += y * c;
        *l4 += y * d;
        if let Some(h) = self.head.get_mut(self.n as usize) {
            *h = y;
        }
        self.recent = [y, a, b, c];
        self.sum_y += y;
        self.sum_yy += y * y;
        self.n += 1;
    }

    /// At the end of a full window: `(bias alarm, whiteness alarm)`; the window is then emptied.
    fn close_window(&mut self, bias_limit: T, white_limit: T, tolerance: T) -> (bool, bool) {
        let n = T::of_f64(f64::from(self.n));
        let sum_z = n * self.shift + self.sum_y;
        let bias = sum_z.abs() > bias_limit * n.sqrt();
        let mean = self.sum_y / n;
        let c0 = self.sum_yy - n * mean * mean;
        let mut white = false;
        if c0 > T::zero() {
            let (mut head, mut tail) = (T::zero(), T::zero());
            for (k, ((&lag, &h), &r)) in self.lag.iter().zip(&self.head).zip(&self.recent).enumerate() {
                let k = k + 1;
                head += h;
                tail += r;
                let kf = T::of_f64(k as f64);
                // Σ (yₜ − ȳ)(yₜ₋ₖ − ȳ) over the window's n − k pairs.
                let ck = lag - mean * (self.sum_y + self.sum_y - head - tail) + (n - kf) * mean * mean;
                let excess = (ck / c0 + T::one() / n).abs() - tolerance;
                let z2 = excess * excess * n * (n + T::of_f64(2.0)) / (n - kf);
                white |= excess > T::zero() && z2 > white_limit * white_limit;
            }
        }
        self.clear_window();
        (bias, white)
    }

    /// Empties the window (the CUSUM runs on).
    fn clear_window(&mut self) {
        let zero = [T::zero(); WHITENESS_LAGS];
        (self.n, self.shift, self.sum_y, self.sum_yy) = (0, T::zero(), T::zero(), T::zero());
        (self.lag, self.head, self.recent) = (zero, zero, zero);
    }
}

/// A model monitor on `C` channels of normalised innovations.
///
/// While the model explains the data, each channel's normalised innovation `z = ν / √S` is
/// white standard-normal noise. A model that stops explaining the data shows as one of three
/// departures, one statistic each: the variance grows (an unmodelled force or mode, a mistuned
/// noise: a CUSUM on the NIS `z²`, the sequential test that detects a small lasting growth
/// soonest for a given false-alarm rate), the mean moves (a sensor offset, a wrong static load:
/// the mean of a window), or correlation appears (a missing lag or mode: the window's
/// autocorrelation at lags 1 to [`WHITENESS_LAGS`]). Thresholds come from the statistics' null
/// distributions for a stated false-alarm rate ([`MonitorSettings::thresholds`]).
///
/// Each (channel, statistic) raises a [`Mismatch`] once, latched until [`reset`](Self::reset);
/// [`take_event`](Self::take_event) hands each one over once. Every alarm is counted
/// ([`alarms`](Self::alarms)); after one the CUSUM restarts, so the count over healthy data is
/// the false-alarm rate. The whiteness statistic is not Ljung–Box ([`super::WhitenessWindow`]):
/// Ljung–Box's far tail is heavier than its χ² approximation (3.4× at 10⁻⁴ for a window of
/// 256, 10 lags, simulated), and that window costs `O(W·L)` at once; the largest standardised
/// autocorrelation with a Bonferroni limit is on the safe side (13 % fewer alarms than stated at
/// 10⁻⁴ for 5 lags, simulated; the long test counts them), and is summed as the samples come.
///
/// Cost per channel and sample: the CUSUM, two sums and [`WHITENESS_LAGS`] products; at the
/// end of a window about 15 operations a lag. `f32` keeps the window's sums exact enough: they
/// are taken about the window's first value, so a bias does not cancel the variance.
///
/// ```
/// use edgekf::residual::{ModelMonitor, MonitorSettings, Statistic};
/// let t = MonitorSettings::new(100.0).thresholds(2);
/// let mut m = ModelMonitor::<f32, 2>::new(&t);
/// // Channel 0 quiet, channel 1 biased by 5σ: its NIS climbs at once, and its window's mean
/// // alarms when the window closes (sample 256), dated from the window's first sample.
/// for _ in 0..256 {
///     m.push(&[0.0, 5.0]);
/// }
/// let e = m.take_event().unwrap();
/// assert_eq!((e.channel, e.statistic), (1, Statistic::Cusum)); // the NIS grew first
/// let e = m.take_event().unwrap();
/// assert_eq!((e.channel, e.statistic, e.since_sample), (1, Statistic::Bias, 1));
/// assert_eq!(m.take_event(), None);
/// assert!(m.latched(1, Statistic::Bias).is_some() && m.latched(0, Statistic::Bias).is_none());
/// m.reset();
/// assert_eq!((m.samples(), m.latched(1, Statistic::Bias)), (0, None));
/// ```
#[derive(Debug, Clone)]
pub struct ModelMonitor<T, const C: usize> {
    channels: [Channel<T>; C],
    window: u32,
    settle: u32,
    bias: T,
    whiteness: T,
    tolerance: T,
    samples: u32,
    alarms: [u32; 3],
    /// Per channel, a bit per [`Statistic`] latched, and one not yet handed over.
    latched: [u8; C],
    unreported: [u8; C],
    since: [[u32; 3]; C],
}

impl<T: Real, const C: usize> ModelMonitor<T, C> {
    /// A monitor with thresholds `t`, nothing seen yet.
    pub fn new(t: &Thresholds) -> Self {
        Self {
            channels: [Channel::new(t); C],
            window: t.window.max(2 * WHITENESS_LAGS as u32),
            settle: t.settle,
            bias: T::of_f64(t.bias),
            whiteness: T::of_f64(t.whiteness),
            tolerance: T::of_f64(t.whiteness_tolerance),
            samples: 0,
            alarms: [0; 3],
            latched: [0; C],
            unreported: [0; C],
            since: [[0; 3]; C],
        }
    }

    /// One sample of every channel's normalised innovation (a non-finite value: no update of
    /// that channel, skipped by all three statistics). `true` when a new mismatch was latched.
    /// The first [`Thresholds::settle`] samples are counted, not tested.
    pub fn push(&mut self, z: &[T; C]) -> bool {
        self.samples = self.samples.saturating_add(1);
        let now = self.samples;
        if now <= self.settle {
            return false;
        }
        // The fields apart, so that the channels are walked while the latches are written.
        let Self { channels, window, bias, whiteness, tolerance, alarms, latched, unreported, since, .. } = self;
        let mut latches = Latches { alarms, latched, unreported, since };
        let mut raised = false;
        for (ch, (&z, c)) in z.iter().zip(channels.iter_mut()).enumerate() {
            if !z.is_finite() {
                continue;
            }
            let cusum = c.cusum.push_finite(z * z);
            let rising = c.cusum.rising();
            c.accumulate(z);
            if !cusum && c.n < *window {
                continue;
            }
            // The rare path: an alarm, or a window to close.
            let mut hits = [None; 3];
            if cusum {
                hits[0] = Some(now.saturating_sub(rising) + 1);
                c.cusum.reset();
            }
            if c.n >= *window {
                let start = now.saturating_sub(c.n) + 1;
                let (b, w) = c.close_window(*bias, *whiteness, *tolerance);
                hits[1] = b.then_some(start);
                hits[2] = w.then_some(start);
            }
            for (s, at) in Statistic::ALL.into_iter().zip(hits) {
                if let Some(at) = at {
                    raised |= latches.alarm(ch, s, at);
                }
            }
        }
        raised
    }

    /// The next latched mismatch not yet handed over (by channel, then statistic), once.
    pub fn take_event(&mut self) -> Option<Mismatch> {
        for (ch, bits) in self.unreported.iter_mut().enumerate() {
            let Some(s) = Statistic::ALL.into_iter().find(|s| *bits & s.bit() != 0) else { continue };
            *bits &= !s.bit();
            let since_sample = self.since.get(ch).and_then(|a| a.get(s as usize)).copied().unwrap_or(0);
            return Some(Mismatch { channel: ch as u8, statistic: s, since_sample });
        }
        None
    }

    /// The sample a latched mismatch of `channel`'s `statistic` is dated from, if latched.
    pub fn latched(&self, channel: usize, statistic: Statistic) -> Option<u32> {
        let bits = self.latched.get(channel)?;
        (bits & statistic.bit() != 0)
            .then(|| self.since.get(channel).and_then(|a| a.get(statistic as usize)).copied())?
    }

    /// Alarms of every channel and statistic since start-up (saturating; not cleared by
    /// [`reset`](Self::reset)).
    pub fn alarms(&self) -> u32 {
        self.alarms.iter().fold(0u32, |a, &n| a.saturating_add(n))
    }

    /// Alarms of `statistic`, every channel (saturating; kept by [`reset`](Self::reset)).
    pub fn alarms_of(&self, statistic: Statistic) -> u32 {
        self.alarms.get(statistic as usize).copied().unwrap_or(0)
    }

    /// Samples pushed since start-up or the last reset.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Clears the latches and the statistics (after the model was corrected, say); the alarm
    /// count is kept.
    pub fn reset(&mut self) {
        for c in self.channels.iter_mut() {
            c.cusum.reset();
            c.clear_window();
        }
        self.samples = 0;
        self.latched = [0; C];
        self.unreported = [0; C];
        self.since = [[0; 3]; C];
    }
}

/// The monitor's alarm counts and latches, borrowed apart from its channels.
struct Latches<'a, const C: usize> {
    alarms: &'a mut [u32; 3],
    latched: &'a mut [u8; C],
    unreported: &'a mut [u8; C],
    since: &'a mut [[u32; 3]; C],
}

impl<const C: usize> Latches<'_, C> {
    /// Counts an alarm of `s` on channel `ch` and latches it, dated `at`, if it is new; `true`
    /// if it was.
    fn alarm(&mut self, ch: usize, s: Statistic, at: u32) -> bool {
        if let Some(n) = self.alarms.get_mut(s as usize) {
            *n = n.saturating_add(1);
        }
        let (Some(latched), Some(unreported), Some(date)) = (
            self.latched.get_mut(ch),
            self.unreported.get_mut(ch),
            self.since.get_mut(ch).and_then(|a| a.get_mut(s as usize)),
        ) else {
            return false;
        };
        if *latched & s.bit() != 0 {
            return false;
        }
        *latched |= s.bit();
        *unreported |= s.bit();
        *date = at;
        true
    }
}

#[cfg(test)]
#[path = "monitor_tests.rs"]
mod tests;
