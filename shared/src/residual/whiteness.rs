//! Whiteness of a scalar innovation sequence: sample autocorrelation and the Ljung–Box test
//! (the reasoning is on [`WhitenessWindow`]).

use super::chi2::chi2_sf;
use crate::Real;

/// The last `W` finite scalar innovations (a ring buffer) and their whiteness statistics:
/// sample autocorrelation and the Ljung–Box test.
///
/// A consistent Kalman filter's innovations are white: whatever was predictable from the past
/// has been used. Correlation left in them means the model misses dynamics (a mode, a harmonic
/// force, a delay) or the noise covariances are mistuned, even when the mean and the NIS look
/// right. Ljung–Box pools the first `L` autocorrelations into one statistic with a known null
/// distribution (χ²(L)), so a monitor gets one p-value per window.
///
/// Cost: `push` is O(1); [`autocorrelation`](Self::autocorrelation) is O(W) and
/// [`ljung_box`](Self::ljung_box) O(W·L), all in `T` (a window of 512 with 20 lags is about
/// 10⁴ multiply-adds: run it once per window, not per sample). Only the χ² tail is `f64`.
///
/// Numerics: the window is scaled by its largest magnitude and centred with a corrected two-pass
/// mean before the lag products are summed, so a large bias does not cancel the variance and no
/// finite input overflows, even in `f32`. On `f32` data the Ljung–Box statistic agrees with the
/// `f64` computation on the same samples to 3e-6 (relative) and its p-value to 3e-6 (absolute)
/// for W = 512, L = 20, also under a bias of 10⁴ standard deviations (the `f32_matches_f64`
/// test): far below the test's own sampling spread.
///
/// ```
/// use edgekf::residual::WhitenessWindow;
/// let mut w = WhitenessWindow::<f32, 256>::new();
/// // A slowly oscillating "innovation" is anything but white.
/// for k in 0..300 {
///     w.push(libm::sinf(0.3 * k as f32));
/// }
/// assert_eq!(w.len(), 256);
/// assert!(w.autocorrelation(1) > 0.9);
/// let lb = w.ljung_box(10);
/// assert_eq!(lb.lags, 10);
/// assert!(lb.p_value < 1e-9 && !lb.is_white(0.05));
/// ```
#[derive(Debug, Clone)]
pub struct WhitenessWindow<T: Real, const W: usize> {
    buf: [T; W],
    /// Where the next value goes.
    next: usize,
    len: usize,
    non_finite: u32,
}

/// Result of a Ljung–Box test on one window.
///
/// `q = n (n + 2) Σₖ ρ(k)² / (n − k)` for `k = 1..=lags` is χ²(lags) distributed when the
/// innovations are white (for `n` well above `lags`), so `p_value = P(χ²(lags) ≥ q)` is
/// uniformly distributed on (0, 1) for a consistent filter and tiny when correlation is left.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LjungBox {
    /// The statistic `q` (0 when nothing could be tested).
    pub q: f64,
    /// Upper-tail probability of `q` under χ²(`lags`); 1 when nothing could be tested.
    pub p_value: f64,
    /// Number of lags used (the degrees of freedom): the request clamped to `W/4` and to `n/4`.
    pub lags: usize,
    /// Number of samples `n` in the window.
    pub samples: usize,
}

impl LjungBox {
    /// Whether whiteness is accepted at false-alarm probability `alpha` (`p_value ≥ alpha`).
    pub fn is_white(&self, alpha: f64) -> bool {
        self.p_value >= alpha
    }
}

/// A window prepared for lag products: deviations `dₜ = (xₜ/2 − m/2) · (2/max|x|) − c`, where
/// `m` is a first estimate of the mean and `c` the mean of the scaled deviations from it (the
/// corrected two-pass algorithm, with the correction kept apart instead of added into `m`).
///
/// Halving first keeps `xₜ − m` from overflowing near `T::MAX`; subtracting before scaling keeps
/// the deviations exact when a bias is large compared with the spread (`xₜ·s − m·s` would round
/// each product at the bias's precision); keeping `c` apart keeps the centring finer than one
/// unit in the last place of the bias.
struct Centred<T> {
    start: usize,
    n: usize,
    half_first: T,
    scale2: T,
    correction: T,
    /// `Σ dₜ²`.
    c0: T,
}

impl<T: Real, const W: usize> Default for WhitenessWindow<T, W> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real, const W: usize> WhitenessWindow<T, W> {
    /// An empty window.
    pub fn new() -> Self {
        Self { buf: [T::zero(); W], next: 0, len: 0, non_finite: 0 }
    }

    /// Appends one innovation, dropping the oldest once `W` are held.
    ///
    /// NaN and infinity are not stored (one would poison every statistic of the window) but
    /// counted in [`non_finite`](Self::non_finite).
    pub fn push(&mut self, v: T) {
        if !v.is_finite() {
            self.non_finite = self.non_finite.saturating_add(1);
            return;
        }
        if let Some(slot) = self.buf.get_mut(self.next) {
            *slot = v;
            self.next = if self.next + 1 == W { 0 } else { self.next + 1 };
            self.len = (self.len + 1).min(W);
        }
    }

    /// Empties the window (the non-finite counter is kept).
    pub fn clear(&mut self) {
        self.next = 0;
        self.len = 0;
    }

    /// Number of innovations held (at most `W`).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no innovation is held.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether the window holds `W` innovations.
    pub fn is_full(&self) -> bool {
        self.len == W
    }

    /// Non-finite values rejected by [`push`](Self::push) since construction (saturating).
    pub fn non_finite(&self) -> u32 {
        self.non_finite
    }

    /// The innovations held, oldest first.
    pub fn iter(&self) -> impl Iterator<Item = T> + '_ {
        let start = self.start();
        (0..self.len).map(move |i| self.buf[self.wrap(start + i)])
    }

    /// Mean of the window (0 when empty). A mean that is many standard errors from zero is a
    /// bias, which the autocorrelation (computed about this mean) does not show.
    pub fn mean(&self) -> T {
        self.scale().map_or(T::zero(), |(max, scale2)| {
            let (half_first, correction) = self.two_pass_mean(max, scale2);
            (half_first + correction * max * T::of_f64(0.5)) * T::of_f64(2.0)
        })
    }

    /// Sample autocorrelation `ρ(k) = Σₜ dₜ dₜ₊ₖ / Σₜ dₜ²` with `dₜ = xₜ − x̄` (the biased
    /// estimator used by Ljung–Box; `|ρ| ≤ 1`).
    ///
    /// `ρ(0) = 1`. Returns 0 for `lag ≥ len()` and for a window without variance (empty, or all
    /// values equal to within rounding): there is no correlation to measure.
    pub fn autocorrelation(&self, lag: usize) -> T {
        match self.centred() {
            Some(c) if lag < c.n => self.lag_sum(&c, lag) / c.c0,
            _ => T::zero(),
        }
    }

    /// Writes `ρ(1), ρ(2), …` into `out` (`out[k − 1] = ρ(k)`) and returns how many lags could
    /// be estimated; the remaining entries are set to 0 (see
    /// [`autocorrelation`](Self::autocorrelation)).
    pub fn autocorrelations(&self, out: &mut [T]) -> usize {
        out.iter_mut().for_each(|v| *v = T::zero());
        let Some(c) = self.centred() else {
            return 0;
        };
        let m = out.len().min(c.n - 1);
        for (k, v) in out.iter_mut().enumerate().take(m) {
            *v = self.lag_sum(&c, k + 1) / c.c0;
        }
        m
    }

    /// Ljung–Box test over lags `1..=lags`.
    ///
    /// The number of lags is clamped to `W/4` and to a quarter of the samples held: beyond that
    /// the χ² approximation degrades and each `ρ(k)` rests on too few pairs. A common choice is
    /// `L ≈ 20` for `W = 512`. An empty window, one with fewer than 4 samples, or one without
    /// variance gives `q = 0`, `p_value = 1` (nothing to reject).
    ///
    /// The `n (n + 2)` weighting and the p-value are computed in `f64`.
    pub fn ljung_box(&self, lags: usize) -> LjungBox {
        let n = self.len;
        let lags = lags.min(W / 4).min(n / 4);
        let mut out = LjungBox { q: 0.0, p_value: 1.0, lags, samples: n };
        if lags == 0 {
            return out;
        }
        let Some(c) = self.centred() else {
            return out;
        };
        let mut sum = 0.0f64;
        for k in 1..=lags {
            let rho = (self.lag_sum(&c, k) / c.c0).as_f64();
            sum += rho * rho / (n - k) as f64;
        }
        let nf = n as f64;
        out.q = nf * (nf + 2.0) * sum;
        out.p_value = chi2_sf(out.q, lags as f64);
        out
    }

    /// Index in `buf` of the oldest value.
    fn start(&self) -> usize {
        self.wrap(self.next + W - self.len)
    }

    /// `i mod W` for `i < 2W`.
    fn wrap(&self, i: usize) -> usize {
        if i >= W {
            i - W
        } else {
            i
        }
    }

    /// `max|x|` and `2 / max|x|`, or `None` for an empty or all-zero window (or one so close to
    /// zero that the reciprocal overflows).
    fn scale(&self) -> Option<(T, T)> {
        let max = self.iter().fold(T::zero(), |m, v| m.max(v.abs()));
        let scale2 = T::of_f64(2.0) / max;
        (max > T::zero() && scale2.is_finite()).then_some((max, scale2))
    }

    /// First-pass mean (from the values scaled into [−1, 1], so nothing overflows) halved, and
    /// the mean of the scaled deviations from it.
    fn two_pass_mean(&self, max: T, scale2: T) -> (T, T) {
        let half = T::of_f64(0.5);
        let n = T::of_f64(self.len as f64);
        let first = self.iter().fold(T::zero(), |s, v| s + v * (half * scale2)) / n * max;
        let half_first = first * half;
        let correction = self.iter().fold(T::zero(), |s, v| s + (v * half - half_first) * scale2) / n;
        (half_first, correction)
    }

    /// The window centred and scaled, or `None` when it has no usable variance.
    fn centred(&self) -> Option<Centred<T>> {
        let (max, scale2) = self.scale()?;
        let (half_first, correction) = self.two_pass_mean(max, scale2);
        let half = T::of_f64(0.5);
        let c0 = self.iter().fold(T::zero(), |s, v| {
            let d = (v * half - half_first) * scale2 - correction;
            s + d * d
        });
        // Deviations at the rounding level of the data are not a variance: a constant input
        // whose mean rounds to a neighbouring value would otherwise show ρ(k) ≈ 1.
        let floor = T::default_epsilon() * T::of_f64(8.0);
        if !c0.is_finite() || c0 <= floor * floor * T::of_f64(self.len as f64) {
            return None;
        }
        Some(Centred { start: self.start(), n: self.len, half_first, scale2, correction, c0 })
    }

    /// `Σₜ dₜ dₜ₊ₖ` over the `n − k` pairs, for `k < n`.
    fn lag_sum(&self, c: &Centred<T>, k: usize) -> T {
        let mut i = c.start;
        let mut j = self.wrap(c.start + k);
        let mut sum = T::zero();
        let half = T::of_f64(0.5);
        for _ in 0..c.n - k {
            let a = (self.buf[i] * half - c.half_first) * c.scale2 - c.correction;
            let b = (self.buf[j] * half - c.half_first) * c.scale2 - c.correction;
            sum += a * b;
            i = if i + 1 == W { 0 } else { i + 1 };
            j = if j + 1 == W { 0 } else { j + 1 };
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::Rng;
    use super::*;

    /// Fraction of windows with p < 0.05, and the decile counts of the p-values.
    fn white_noise_p_values<T: Real>(seed: u64, windows: usize) -> (f64, [usize; 10]) {
        let mut rng = Rng::new(seed);
        let mut rejected = 0;
        let mut deciles = [0usize; 10];
        for _ in 0..windows {
            let mut w = WhitenessWindow::<T, 512>::new();
            for _ in 0..512 {
                w.push(T::of_f64(0.3 * rng.gauss()));
            }
            let lb = w.ljung_box(20);
            assert_eq!((lb.lags, lb.samples), (20, 512));
            if lb.p_value < 0.05 {
                rejected += 1;
            }
            deciles[((lb.p_value * 10.0) as usize).min(9)] += 1;
        }
        (rejected as f64 / windows as f64, deciles)
    }

    #[test]
    fn white_noise_gives_uniform_p_values() {
        for seed in [1, 2, 3] {
            let (frac64, dec64) = white_noise_p_values::<f64>(seed, 200);
            let (frac32, dec32) = white_noise_p_values::<f32>(seed, 200);
            assert!((0.02..=0.09).contains(&frac64), "seed {seed}: {frac64} {dec64:?}");
            assert!((0.02..=0.09).contains(&frac32), "seed {seed}: {frac32} {dec32:?}");
            // 20 expected per decile; a χ²(9) goodness-of-fit of the deciles stays below its
            // 0.1 % point (27.9).
            let chi2: f64 = dec64.iter().map(|&c| (c as f64 - 20.0).powi(2) / 20.0).sum();
            assert!(chi2 < 27.9, "seed {seed}: {dec64:?}");
        }
    }

    #[test]
    fn ar1_is_rejected() {
        // x_t = 0.3 x_{t−1} + e_t: ρ(k) = 0.3^k, so Q ≈ 512·Σ 0.09^k ≈ 51 plus about L from
        // the estimation noise of the other lags: p ≈ 1e-7 typically. ρ̂(1) itself scatters by
        // ±0.04, so a few windows in a hundred stay above 1e-3 (5.3 % of 2000 seeds did).
        let mut p_values = [0.0f64; 200];
        for (seed, p) in p_values.iter_mut().enumerate() {
            let mut rng = Rng::new(1000 + seed as u64);
            let mut w = WhitenessWindow::<f32, 512>::new();
            let mut x = 0.0;
            for _ in 0..1000 {
                x = 0.3 * x + rng.gauss();
                w.push(x as f32);
            }
            assert!((w.autocorrelation(1) - 0.3).abs() < 0.15);
            *p = w.ljung_box(20).p_value;
        }
        let detected = p_values.iter().filter(|&&p| p < 1e-3).count();
        let below_1e5 = p_values.iter().filter(|&&p| p < 1e-5).count();
        assert!(detected >= 180, "{detected}");
        assert!(below_1e5 >= 100, "median above 1e-5: {below_1e5}");
        // The first seed, as a single case.
        assert!(p_values[0] < 1e-3, "{}", p_values[0]);
    }

    #[test]
    fn f32_matches_f64() {
        // Same samples (rounded to f32), without a bias and with one 100 σ and 10⁴ σ large.
        let mut rng = Rng::new(7);
        let (mut q_rel, mut p_abs) = (0.0f64, 0.0f64);
        for window in 0..150 {
            let bias = [0.0, 100.0, 1e4][window % 3];
            let mut w32 = WhitenessWindow::<f32, 512>::new();
            let mut w64 = WhitenessWindow::<f64, 512>::new();
            let mut x = 0.0;
            for _ in 0..512 {
                // Mildly correlated so that p-values span (0, 1).
                x = 0.05 * x + rng.gauss();
                let v = (bias + x) as f32;
                w32.push(v);
                w64.push(v as f64);
            }
            let (a, b) = (w32.ljung_box(20), w64.ljung_box(20));
            q_rel = q_rel.max((a.q - b.q).abs() / b.q);
            p_abs = p_abs.max((a.p_value - b.p_value).abs());
            assert!((w32.mean() as f64 - w64.mean()).abs() <= f32::EPSILON as f64 * (1.0 + bias));
        }
        // Measured: 2.6e-6 and 2.7e-6.
        assert!(q_rel < 1e-5 && p_abs < 1e-5, "{q_rel:e} {p_abs:e}");
    }

    #[test]
    fn matches_textbook_formula() {
        let mut rng = Rng::new(3);
        let data: [f64; 200] = core::array::from_fn(|_| 2.0 + rng.gauss());
        let mut w = WhitenessWindow::<f64, 200>::new();
        data.iter().for_each(|&v| w.push(v));
        let n = data.len();
        let mean = data.iter().sum::<f64>() / n as f64;
        let c0: f64 = data.iter().map(|v| (v - mean).powi(2)).sum();
        let rho = |k: usize| (0..n - k).map(|t| (data[t] - mean) * (data[t + k] - mean)).sum::<f64>() / c0;
        let mut rhos = [0.0; 10];
        assert_eq!(w.autocorrelations(&mut rhos), 10);
        let mut q = 0.0;
        for k in 1..=10 {
            assert!((w.autocorrelation(k) - rho(k)).abs() < 1e-13);
            assert!((rhos[k - 1] - rho(k)).abs() < 1e-13);
            q += rho(k).powi(2) / (n - k) as f64;
        }
        q *= (n * (n + 2)) as f64;
        let lb = w.ljung_box(10);
        assert!((lb.q - q).abs() < 1e-10 * q);
        assert!((lb.p_value - chi2_sf(q, 10.0)).abs() < 1e-12);
        assert!((w.mean() - mean).abs() < 1e-14);
        assert_eq!(w.autocorrelation(0), 1.0);
    }

    #[test]
    fn ring_keeps_the_last_w_in_order() {
        let mut rng = Rng::new(5);
        let data: [f64; 300] = core::array::from_fn(|_| rng.gauss());
        let mut wrapped = WhitenessWindow::<f64, 128>::new();
        data.iter().for_each(|&v| wrapped.push(v));
        let mut fresh = WhitenessWindow::<f64, 128>::new();
        data[300 - 128..].iter().for_each(|&v| fresh.push(v));
        assert!(wrapped.iter().eq(data[300 - 128..].iter().copied()));
        assert_eq!(wrapped.ljung_box(16), fresh.ljung_box(16));
        for k in 0..130 {
            assert_eq!(wrapped.autocorrelation(k), fresh.autocorrelation(k));
        }
    }

    #[test]
    fn degenerate_windows_are_defined() {
        let empty = WhitenessWindow::<f32, 64>::new();
        assert_eq!(empty.ljung_box(10), LjungBox { q: 0.0, p_value: 1.0, lags: 0, samples: 0 });
        assert_eq!((empty.autocorrelation(0), empty.autocorrelation(1), empty.mean()), (0.0, 0.0, 0.0));
        let mut out = [9.0f32; 4];
        assert_eq!(empty.autocorrelations(&mut out), 0);
        assert_eq!(out, [0.0; 4]);

        // Zero capacity: everything is accepted and nothing is stored.
        let mut none = WhitenessWindow::<f64, 0>::new();
        none.push(1.0);
        assert_eq!((none.len(), none.ljung_box(5).p_value), (0, 1.0));

        // A constant window (whose f32 mean need not round to the constant) has no correlation.
        let mut constant = WhitenessWindow::<f32, 512>::new();
        (0..512).for_each(|_| constant.push(0.1));
        let lb = constant.ljung_box(20);
        assert_eq!((lb.q, lb.p_value, lb.lags), (0.0, 1.0, 20));
        assert!((constant.mean() - 0.1).abs() < 1e-7);

        // Too few samples for any lag.
        let mut short = WhitenessWindow::<f64, 64>::new();
        [1.0, -2.0, 3.0].iter().for_each(|&v| short.push(v));
        assert_eq!(short.ljung_box(10).lags, 0);
        assert_eq!(short.autocorrelation(3), 0.0);
    }

    #[test]
    fn non_finite_and_extreme_inputs() {
        let mut rng = Rng::new(11);
        let mut w = WhitenessWindow::<f32, 256>::new();
        let mut big = WhitenessWindow::<f32, 256>::new();
        for k in 0..256 {
            let v = rng.gauss() as f32;
            w.push(v);
            big.push(v * 1e37);
            if k % 50 == 0 {
                w.push(f32::NAN);
                w.push(f32::NEG_INFINITY);
            }
        }
        assert_eq!((w.len(), w.non_finite()), (256, 12));
        // Scale invariance: values near f32::MAX neither overflow nor change the statistic.
        let (a, b) = (w.ljung_box(32), big.ljung_box(32));
        assert!(b.q.is_finite() && (a.q - b.q).abs() < 1e-4 * a.q, "{a:?} {b:?}");
        // Lags clamped to W/4 = 64 and to n/4 while filling.
        assert_eq!(w.ljung_box(1000).lags, 64);
        let mut filling = WhitenessWindow::<f32, 256>::new();
        (0..40).for_each(|k| filling.push(k as f32));
        assert_eq!(filling.ljung_box(1000).lags, 10);
        // Subnormal-only input has no usable scale: defined, not NaN.
        let mut tiny = WhitenessWindow::<f32, 8>::new();
        (0..8).for_each(|k| tiny.push(if k % 2 == 0 { 1e-45 } else { -1e-45 }));
        assert!(tiny.ljung_box(2).p_value == 1.0 && tiny.mean() == 0.0);
    }
}
