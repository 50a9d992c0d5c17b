//! The ten window features of the crank angular acceleration, computed sample by sample.

use super::select::select_nth;
use super::ClearanceFloat;
use super::FEATURES;

/// Shortest window accepted, samples: the high-pass term needs 8 samples of context and the
/// statistics divide by `n − 8`.
pub const MIN_WINDOW: usize = 16;

/// Why a [`CrankFeatures`] could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FeatureError {
    /// The window is shorter than [`MIN_WINDOW`] samples.
    WindowTooShort,
    /// The storage holds fewer than `window − 1` values.
    StorageTooSmall,
    /// The sample rate is not a positive finite number.
    BadRate,
}

/// The features of [`super::FEATURE_NAMES`], pushed one sample at a time.
///
/// Per window of `n` samples (windows do not overlap; a trailing partial window is not used):
///
/// 0. RMS of α about the window mean;
/// 1. RMS of the first difference `Δα`;
/// 2. RMS of the second difference;
/// 3. RMS of α minus its centred 8-sample mean (a high-pass residual);
/// 4. kurtosis of `Δα` (about zero);
/// 5. kurtosis of α about the window mean;
/// 6. impacts per second: upward crossings of `|Δα|` over 6 × the window's median `|Δα|`;
/// 7. the mean impact peak of `|Δα|` over that median (6 without impacts);
/// 8. the mean impact width, samples above the threshold per impact (1 without impacts);
/// 9. the median of `|Δα|`.
///
/// The recording's features ([`CrankFeatures::features`]) are the natural logarithms of the
/// means of these over the completed windows (floored at 1e-12).
///
/// Memory: the storage `S` holds the window's `|Δα|` in time order (`n − 1` values: 2 499
/// `f32`, 10 KB, for 0.25 s at 10 kHz), because the median must be known before the impact
/// pass over the same window. Everything else is a fixed handful of sums. The median is exact
/// ([`select_nth`], in place, no second buffer).
///
/// Why the moments of α come from shifted power sums `Σ (α − K)ᵖ`, `p = 1…4`: one pass and four
/// multiply-adds per sample instead of a second pass over a stored window, with `K` the
/// previous window's mean (the first sample for the first window), so the expansion into
/// central moments cancels little: the mean moves little from one 0.25 s window to the next.
///
/// Non-finite samples are skipped and counted ([`CrankFeatures::skipped`]): the next difference
/// then spans the gap, which changes one window's statistics by one sample's worth.
///
/// ```
/// use edgekf::systems::crank::{CrankFeatures, FEATURES};
/// // 0.25 s windows at 1 kHz: 250 samples, storage for 249 differences.
/// let mut f = CrankFeatures::new([0.0f32; 249], 250, 1000.0).unwrap();
/// for k in 0..600 {
///     let impact = if k % 50 == 0 { 400.0 } else { 0.0 };
///     f.push((0.05 * k as f32).sin() * 100.0 + impact);
/// }
/// f.push(f32::NAN);
/// assert_eq!((f.windows(), f.skipped()), (2, 1));
/// let ln = f.features();
/// assert!((ln[6] - 20f32.ln()).abs() < 1e-5); // 5 impacts per 0.25 s window: 20 per second
/// assert!(ln.iter().all(|v| v.is_finite()) && ln.len() == FEATURES);
/// ```
#[derive(Debug, Clone)]
pub struct CrankFeatures<T: ClearanceFloat, S: AsRef<[T]> + AsMut<[T]>> {
    storage: S,
    window: usize,
    rate: T,
    /// Samples of the current window so far.
    k: usize,
    /// The window's last 8 samples, sample `k` at `k mod 8`.
    history: [T; 8],
    shift: T,
    window_sums: WindowSums<T>,
    sums: [T; FEATURES],
    last: [T; FEATURES],
    windows: u32,
    skipped: u32,
}

/// The running sums of one window.
#[derive(Debug, Clone, Copy)]
struct WindowSums<T> {
    /// `Σ (α − K)ᵖ`, `p = 1…4`.
    power: [T; 4],
    /// `Σ Δα²`, `Σ Δα⁴`.
    diff: [T; 2],
    /// `Σ (Δ²α)²`.
    second: T,
    /// `Σ e²` of the high-pass residual.
    highpass: T,
}

impl<T: ClearanceFloat> WindowSums<T> {
    fn zero() -> Self {
        let z = T::zero();
        Self { power: [z; 4], diff: [z; 2], second: z, highpass: z }
    }
}

fn count<T: ClearanceFloat>(n: usize) -> T {
    T::from_usize(n).unwrap_or_else(T::zero)
}

/// `num / den`, or 0 where the denominator vanishes (a constant signal: the numerator is 0 too).
fn ratio<T: ClearanceFloat>(num: T, den: T) -> T {
    if den > T::zero() {
        num / den
    } else {
        T::zero()
    }
}

impl<T: ClearanceFloat, S: AsRef<[T]> + AsMut<[T]>> CrankFeatures<T, S> {
    /// Windows of `window` samples at `rate` Hz; `storage` must hold at least `window − 1`
    /// values (its contents are overwritten).
    pub fn new(storage: S, window: usize, rate: T) -> Result<Self, FeatureError> {
        if window < MIN_WINDOW {
            return Err(FeatureError::WindowTooShort);
        }
        if storage.as_ref().len() < window - 1 {
            return Err(FeatureError::StorageTooSmall);
        }
        if !(rate.is_finite() && rate > T::zero()) {
            return Err(FeatureError::BadRate);
        }
        let z = T::zero();
        let (history, sums, last) = ([z; 8], [z; FEATURES], [z; FEATURES]);
        let window_sums = WindowSums::zero();
        Ok(Self { storage, window, rate, k: 0, history, shift: z, window_sums, sums, last, windows: 0, skipped: 0 })
    }

    /// Adds one sample (rad/s²); returns `true` if it completed a window.
    pub fn push(&mut self, x: T) -> bool {
        if !x.is_finite() {
            self.skipped = self.skipped.saturating_add(1);
            return false;
        }
        let k = self.k;
        if k == 0 && self.windows == 0 {
            self.shift = x;
        }
        let w = &mut self.window_sums;
        let y = x - self.shift;
        let y2 = y * y;
        w.power[0] += y;
        w.power[1] += y2;
        w.power[2] += y2 * y;
        w.power[3] += y2 * y2;
        if k >= 1 {
            let p1 = self.history[(k - 1) & 7];
            let d = x - p1;
            let d2 = d * d;
            w.diff[0] += d2;
            w.diff[1] += d2 * d2;
            if let Some(slot) = self.storage.as_mut().get_mut(k - 1) {
                *slot = d.abs();
            }
            if k >= 2 {
                let s = x - T::of_f64(2.0) * p1 + self.history[(k - 2) & 7];
                w.second += s * s;
            }
        }
        self.history[k & 7] = x;
        // Centre `k − 3` of the 8 samples `k − 7 … k`, for centres 4 … n − 5.
        if k >= 7 && k + 1 < self.window {
            let h = &self.history;
            let sum = ((h[0] + h[1]) + (h[2] + h[3])) + ((h[4] + h[5]) + (h[6] + h[7]));
            let e = self.history[(k - 3) & 7] - sum * T::of_f64(0.125);
            w.highpass += e * e;
        }
        self.k = k + 1;
        if self.k < self.window {
            return false;
        }
        self.close();
        true
    }

    /// Ends the window: its median, its impacts and its ten statistics. Out of line: its large
    /// frame (the median's histogram) and saved registers would otherwise be paid on every
    /// sample (with [`super::ClearanceEstimator::estimate`] out of line too: 176 → 138
    /// instructions per ordinary sample on the Cortex-M4F, `cargo xtask bench`).
    #[inline(never)]
    fn close(&mut self) {
        let n = self.window;
        let w = self.window_sums;
        let (m, md) = (count::<T>(n), count::<T>(n - 1));
        let mu = w.power[0] / m;
        let (a, b, c) = (w.power[1] / m, w.power[2] / m, w.power[3] / m);
        let var = (a - mu * mu).max(T::zero());
        let (three, four, six) = (T::of_f64(3.0), T::of_f64(4.0), T::of_f64(6.0));
        let m4 = (c - mu * (four * b - mu * (six * a - three * mu * mu))).max(T::zero());
        let mags = self.storage.as_ref().get(..n.saturating_sub(1)).unwrap_or(&[]);
        let median = select_nth(mags, (n - 1) / 2).unwrap_or_else(T::zero);
        // Impacts: runs of |Δα| above 6 × the median; each run's peak.
        let threshold = six * median;
        let (mut impacts, mut above_n, mut peak_sum, mut peak) = (0usize, 0usize, T::zero(), T::zero());
        let mut above = false;
        for &v in mags {
            if v > threshold {
                if !above {
                    impacts += 1;
                    peak = T::zero();
                }
                above_n += 1;
                peak = peak.max(v);
            } else if above {
                peak_sum += peak;
            }
            above = v > threshold;
        }
        if above {
            peak_sum += peak;
        }
        let d2 = w.diff[0] / md;
        let hits = count::<T>(impacts);
        let values = [
            var.sqrt(),
            d2.sqrt(),
            (w.second / (m - T::of_f64(2.0))).sqrt(),
            (w.highpass / (m - T::of_f64(8.0))).sqrt(),
            ratio(w.diff[1] / md, d2 * d2),
            ratio(m4, var * var),
            hits * self.rate / m,
            if impacts > 0 { peak_sum / hits / median.max(T::of_f64(1e-12)) } else { six },
            if impacts > 0 { count::<T>(above_n) / hits } else { T::one() },
            median,
        ];
        for (s, v) in self.sums.iter_mut().zip(values) {
            *s += v;
        }
        self.last = values;
        self.windows = self.windows.saturating_add(1);
        self.shift += mu;
        self.k = 0;
        self.window_sums = WindowSums::zero();
    }

    /// The recording's features so far: `ln` of each statistic's mean over the completed
    /// windows, floored at 1e-12 (`ln 1e-12` everywhere before the first window).
    pub fn features(&self) -> [T; FEATURES] {
        let k = count::<T>(self.windows.max(1) as usize);
        self.sums.map(|s| (s / k).max(T::of_f64(1e-12)).ln_m())
    }

    /// The statistics of the last completed window (not logarithms; zeros before the first).
    pub fn last_window(&self) -> [T; FEATURES] {
        self.last
    }

    /// Completed windows.
    pub fn windows(&self) -> u32 {
        self.windows
    }

    /// Non-finite samples skipped.
    pub fn skipped(&self) -> u32 {
        self.skipped
    }

    /// Window length, samples.
    pub fn window(&self) -> usize {
        self.window
    }

    /// Samples of the current, unfinished window.
    pub fn pending(&self) -> usize {
        self.k
    }
}
