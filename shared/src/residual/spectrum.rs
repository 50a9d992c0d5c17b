//! Power spectrum of the innovations (Welch's method) and its peaks.
//!
//! [`Welch`] averages Hann-windowed periodograms of consecutive blocks of `N` samples, sample by
//! sample, in fixed memory; [`find_peaks`] picks the strongest local maxima out of the result with
//! sub-bin frequencies. The scaling and precision conventions are documented on [`Welch`].

use crate::Real;
use microfft::Complex32;

/// Marker type naming an FFT length; `FftLen<N>` implements [`FftSize`] for the lengths
/// `microfft` provides and this crate enables: 64, 128, 256, 512, 1024, 2048 and 4096.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FftLen<const N: usize>;

/// An FFT length [`Welch`] supports (sealed: implemented for `FftLen<64>` … `FftLen<4096>`).
///
/// It carries the buffer types: stable Rust cannot spell `[f32; N / 2 + 1]` for a generic `N`,
/// so each supported length names its own. Generic code over the length needs the bound
/// `FftLen<N>: FftSize`.
pub trait FftSize: sealed::Sealed {}

mod sealed {
    use microfft::Complex32;

    pub trait Sealed {
        /// `[f32; N]`.
        type Block: Copy + core::fmt::Debug + AsRef<[f32]> + AsMut<[f32]>;
        /// `[f32; N / 2 + 1]`.
        type Bins: Copy + core::fmt::Debug + AsRef<[f32]> + AsMut<[f32]>;
        const BLOCK: Self::Block;
        const BINS: Self::Bins;
        /// In-place real FFT: DC in `re` and Nyquist in `im` of element 0.
        fn rfft(block: &mut Self::Block) -> &mut [Complex32];
    }
}

macro_rules! fft_sizes {
    ($($n:literal => $rfft:ident),* $(,)?) => {$(
        impl sealed::Sealed for FftLen<$n> {
            type Block = [f32; $n];
            type Bins = [f32; $n / 2 + 1];
            const BLOCK: Self::Block = [0.0; $n];
            const BINS: Self::Bins = [0.0; $n / 2 + 1];
            fn rfft(block: &mut Self::Block) -> &mut [Complex32] {
                microfft::real::$rfft(block)
            }
        }
        impl FftSize for FftLen<$n> {}
    )*};
}

fft_sizes! {
    64 => rfft_64,
    128 => rfft_128,
    256 => rfft_256,
    512 => rfft_512,
    1024 => rfft_1024,
    2048 => rfft_2048,
    4096 => rfft_4096,
}

type Block<const N: usize> = <FftLen<N> as sealed::Sealed>::Block;
type Bins<const N: usize> = <FftLen<N> as sealed::Sealed>::Bins;

/// Welch power-spectrum estimator: the running average of Hann-windowed periodograms of
/// consecutive, non-overlapping blocks of `N` samples (`N` = 64 … 4096, see [`FftSize`]).
///
/// The Ljung–Box test says *that* the innovations are coloured; the spectrum says *where*: a
/// narrow line at twice the running speed points at a missing harmonic force, a broad hump at a
/// structural frequency at an unmodelled mode (see [`find_peaks`] and
/// [`locate_peak`](crate::residual::locate_peak)).
///
/// Scaling: one-sided power spectral density in units²/Hz, so that the PSD integrated over
/// frequency (`Σ psd · Δf`, see [`band_power`](Self::band_power)) is the mean square of the
/// samples. White noise of variance σ² has a flat PSD of `2σ²/fs`; a sine of amplitude `A` puts
/// `A²/2` under its peak. Bin `k` is at `k·fs/N` Hz, from DC (`k = 0`) to Nyquist (`k = N/2`);
/// those two bins are not doubled. The window is the periodic Hann window (`Σ w² = 3N/8`), and
/// the block mean is not removed: a bias shows at DC (and, through the window, half as strong
/// in bin 1).
///
/// Precision: everything is `f32`, whatever the filter's [`Real`] type — the FFT (`microfft`)
/// works in `f32`, which is native on the Cortex-M4F and ample for diagnosis: a block's PSD
/// agrees with an `f64` DFT to 6e-6 relative (N = 256, with a bias of 3σ), far below the ±1/√M
/// scatter of an M-block average.
///
/// Memory: `N + N/2 + 1` `f32`s (6 KB for `N = 1024`), no allocation. Cost per block: `N/2`
/// `cosf` for the window, one `N`-point real FFT and `N/2` multiply-adds into the average,
/// spread over the `N` pushes that fill it (done in the push that completes the block).
///
/// Frequency resolution is `fs/N` (the Hann main lobe is ±2 bins wide); each bin of an
/// `M`-block average scatters by about `±1/√M` relative around its expectation.
///
/// Non-finite samples are counted and skipped, so the block closes one sample later (a phase
/// jump of one sample for any sine in it: a small leakage, where zero-filling would dent the
/// block's power instead). A block whose spectrum overflows `f32` (samples beyond about
/// `±1e15`) is counted and left out of the average.
///
/// ```
/// use edgekf::residual::Welch;
/// let fs = 1000.0;
/// let mut welch = Welch::<1024>::new(fs).unwrap();
/// for k in 0..4096 {
///     let t = k as f64 / fs as f64;
///     welch.push(0.5 * libm::sin(2.0 * core::f64::consts::PI * 50.0 * t));
/// }
/// assert_eq!(welch.blocks(), 4);
/// let peaks = welch.peaks::<3>(20.0);
/// assert!((peaks[0].frequency_hz - 50.0).abs() < 0.05);
/// assert!((peaks[0].amplitude() - 0.5).abs() < 0.01);
/// ```
#[derive(Debug, Clone)]
pub struct Welch<const N: usize>
where
    FftLen<N>: FftSize,
{
    block: Block<N>,
    fill: usize,
    psd: Bins<N>,
    blocks: u32,
    non_finite: u32,
    discarded: u32,
    sample_rate_hz: f32,
}

impl<const N: usize> Welch<N>
where
    FftLen<N>: FftSize,
{
    /// An empty estimator for samples at `sample_rate_hz`; `None` unless the rate is finite
    /// and positive.
    pub fn new(sample_rate_hz: f32) -> Option<Self> {
        (sample_rate_hz.is_finite() && sample_rate_hz > 0.0).then_some(Self {
            block: <FftLen<N> as sealed::Sealed>::BLOCK,
            fill: 0,
            psd: <FftLen<N> as sealed::Sealed>::BINS,
            blocks: 0,
            non_finite: 0,
            discarded: 0,
            sample_rate_hz,
        })
    }

    /// Adds one sample (converted to `f32`). Returns `true` when it completed a block and the
    /// average was updated.
    pub fn push<T: Real>(&mut self, x: T) -> bool {
        let x = x.as_f64() as f32;
        if !x.is_finite() {
            self.non_finite = self.non_finite.saturating_add(1);
            return false;
        }
        let block = self.block.as_mut();
        let Some(slot) = block.get_mut(self.fill) else {
            return false;
        };
        *slot = x;
        self.fill += 1;
        if self.fill < N {
            return false;
        }
        self.fill = 0;
        self.close_block();
        true
    }

    /// Forgets the average and the partly filled block (the counters are kept).
    pub fn reset(&mut self) {
        self.fill = 0;
        self.blocks = 0;
        self.psd.as_mut().iter_mut().for_each(|p| *p = 0.0);
    }

    /// The averaged one-sided PSD, units²/Hz, bins `0..=N/2` (all zero before the first block).
    pub fn psd(&self) -> &[f32] {
        self.psd.as_ref()
    }

    /// Number of blocks in the average (saturates at `u32::MAX`; the average then stops
    /// moving, as it nearly has long before: the newest block's weight is `1/blocks`).
    pub fn blocks(&self) -> u32 {
        self.blocks
    }

    /// Samples pushed into the current, incomplete block.
    pub fn pending(&self) -> usize {
        self.fill
    }

    /// Non-finite samples skipped since construction (saturating).
    pub fn non_finite(&self) -> u32 {
        self.non_finite
    }

    /// Blocks left out of the average because their spectrum overflowed `f32` (saturating).
    pub fn discarded_blocks(&self) -> u32 {
        self.discarded
    }

    /// The sample rate given at construction, Hz.
    pub fn sample_rate_hz(&self) -> f32 {
        self.sample_rate_hz
    }

    /// Spacing of the bins, `fs/N` Hz.
    pub fn bin_width_hz(&self) -> f32 {
        self.sample_rate_hz / N as f32
    }

    /// Frequency of a (possibly fractional) bin index, Hz.
    pub fn frequency_hz(&self, bin: f32) -> f32 {
        bin * self.bin_width_hz()
    }

    /// Median PSD over the bins strictly between DC and Nyquist: the noise floor that peak
    /// prominences are measured against (see [`median_level`]).
    pub fn median_psd(&self) -> f32 {
        median_level(self.psd())
    }

    /// Power (units²) in the band `[low_hz, high_hz]`: `Σ psd · Δf` over the bins whose centre
    /// lies in it. The whole band gives the mean square of the samples.
    pub fn band_power(&self, low_hz: f32, high_hz: f32) -> f32 {
        let df = self.bin_width_hz();
        let sum: f32 = self
            .psd()
            .iter()
            .enumerate()
            .filter(|(k, _)| {
                let f = *k as f32 * df;
                f >= low_hz && f <= high_hz
            })
            .map(|(_, p)| *p)
            .sum();
        sum * df
    }

    /// The `K` strongest peaks at least `threshold_db` above the median level; see
    /// [`find_peaks`].
    pub fn peaks<const K: usize>(&self, threshold_db: f32) -> heapless::Vec<SpectralPeak, K> {
        find_peaks(self.psd(), self.bin_width_hz(), threshold_db)
    }

    /// Windows, transforms and averages the full block.
    fn close_block(&mut self) {
        let block = self.block.as_mut();
        // Periodic Hann window w[i] = ½ − ½ cos(2πi/N), applied by symmetry w[i] = w[N − i].
        let step = core::f32::consts::TAU / N as f32;
        block[0] = 0.0;
        for i in 1..N / 2 {
            let w = 0.5 - 0.5 * libm::cosf(step * i as f32);
            block[i] *= w;
            block[N - i] *= w;
        }
        // Σ w² = 3N/8 for the periodic Hann window; ×2 folds the negative frequencies in.
        let one_sided = 2.0 / (self.sample_rate_hz * (3 * N) as f32 / 8.0);
        let spectrum = <FftLen<N> as sealed::Sealed>::rfft(&mut self.block);
        let bin = |k: usize| -> f32 {
            match (k, spectrum.get(k)) {
                (0, Some(c)) => 0.5 * one_sided * c.re * c.re,
                (k, _) if k == N / 2 => spectrum.first().map_or(0.0, |c| 0.5 * one_sided * c.im * c.im),
                (_, Some(c)) => one_sided * (c.re * c.re + c.im * c.im),
                (_, None) => 0.0,
            }
        };
        if !(0..=N / 2).all(|k| bin(k).is_finite()) {
            self.discarded = self.discarded.saturating_add(1);
            return;
        }
        let Some(m) = self.blocks.checked_add(1) else {
            return;
        };
        self.blocks = m;
        let weight = 1.0 / m as f32;
        for (k, avg) in self.psd.as_mut().iter_mut().enumerate() {
            *avg += (bin(k) - *avg) * weight;
        }
    }
}

/// One peak of a power spectrum.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SpectralPeak {
    /// Index of the local-maximum bin.
    pub bin: usize,
    /// Frequency, Hz, refined between bins by a parabola through the logarithms of the three
    /// bins around the maximum (for a Hann-windowed sine: exact at bin centres and half-way,
    /// at most 0.016 bin off in between).
    pub frequency_hz: f32,
    /// PSD at the interpolated maximum, units²/Hz.
    pub psd: f32,
    /// Power under the peak, units²: `Σ psd · Δf` over the maximum bin ± 2 (the Hann main
    /// lobe). For a sine of amplitude `A` this is `A²/2`, plus the noise in those 5 bins.
    pub power: f32,
    /// `10 log₁₀(psd / median level)`, dB.
    pub prominence_db: f32,
}

impl SpectralPeak {
    /// Amplitude of the sine that would carry [`power`](Self::power): `√(2 · power)`.
    pub fn amplitude(&self) -> f32 {
        libm::sqrtf(2.0 * self.power)
    }
}

/// The lower median of the PSD over the bins strictly between DC and Nyquist (`psd[1..len−1]`;
/// the whole slice if it has fewer than 3 bins; 0 if empty).
///
/// DC and Nyquist are left out because a bias piles up at DC and they are not one-sided-doubled.
/// The median, unlike the mean, ignores a few strong peaks, so it is the noise floor. For a
/// single periodogram of white noise (each bin exponentially distributed) it is `ln 2 ≈ 0.69`
/// times the mean level; averaging many blocks brings it to the mean.
///
/// Found without sorting or scratch memory, by bisection on the bit patterns of the values
/// (which order like the values for non-negative floats): 32 counting passes over the bins.
/// Negative values count as 0 and NaN as larger than everything.
///
/// ```
/// use edgekf::residual::median_level;
/// assert_eq!(median_level(&[9.0, 3.0, 1.0, 2.0, 100.0, 9.0]), 2.0);
/// assert_eq!(median_level(&[]), 0.0);
/// ```
pub fn median_level(psd: &[f32]) -> f32 {
    let inner = match psd.len() {
        0 => return 0.0,
        1 | 2 => psd,
        n => &psd[1..n - 1],
    };
    kth_smallest(inner, (inner.len() - 1) / 2)
}

/// The `k`-th smallest value (0-based) of a non-empty slice, for `k < len`.
fn kth_smallest(values: &[f32], k: usize) -> f32 {
    let key = |x: f32| {
        if x.is_nan() {
            u32::MAX
        } else if x <= 0.0 {
            0
        } else {
            x.to_bits()
        }
    };
    // Smallest key t with more than k values at or below it: that value's own key.
    let (mut lo, mut hi) = (0u32, u32::MAX);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        let at_or_below = values.iter().filter(|&&x| key(x) <= mid).count();
        if at_or_below > k {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    f32::from_bits(lo)
}

/// The `K` strongest local maxima of a one-sided PSD (bins from DC to Nyquist, spaced
/// `bin_width_hz`) that stand at least `threshold_db` above its median level, strongest first.
///
/// A local maximum is a bin strictly above its left neighbour and at least its right one
/// (DC and Nyquist are never peaks). Its frequency comes from a parabola through the
/// logarithms of the three bins (see [`SpectralPeak`]). The reference level is
/// [`median_level`], floored at `f32::MIN_POSITIVE` so that a noiseless spectrum gives large but
/// finite prominences.
///
/// Choosing the threshold: in one periodogram of white noise a bin exceeds the median by
/// 10 dB with probability `2^−10 ≈ 1e-3` (0.5 false peaks per 512 bins); averaging `M` blocks
/// shrinks the scatter like `1/√M`, so 6 dB is already safe for `M ≈ 30`.
///
/// ```
/// use edgekf::residual::find_peaks;
/// let psd = [0.0, 1.0, 1.0, 50.0, 2.0, 1.0, 1.0, 8.0, 1.0, 0.0];
/// let peaks = find_peaks::<4>(&psd, 0.5, 6.0);
/// assert_eq!(peaks.len(), 2);
/// assert_eq!((peaks[0].bin, peaks[1].bin), (3, 7));
/// assert!((peaks[0].prominence_db - 17.0).abs() < 0.5);
/// ```
pub fn find_peaks<const K: usize>(psd: &[f32], bin_width_hz: f32, threshold_db: f32) -> heapless::Vec<SpectralPeak, K> {
    let mut peaks = heapless::Vec::new();
    if K == 0 || psd.len() < 3 {
        return peaks;
    }
    let reference = median_level(psd).max(f32::MIN_POSITIVE);
    let threshold = reference * libm::powf(10.0, threshold_db / 10.0);
    for (k, bins) in psd.windows(3).enumerate().map(|(j, b)| (j + 1, b)) {
        let &[left, p, right] = bins else { continue };
        if !(p > left && p >= right && p >= threshold) {
            continue;
        }
        let peak = interpolate(psd, k, bin_width_hz, reference);
        // Keep the K strongest, sorted by decreasing PSD.
        let pos = peaks.iter().position(|q: &SpectralPeak| peak.psd > q.psd).unwrap_or(peaks.len());
        if pos == K {
            continue;
        }
        if peaks.is_full() {
            peaks.pop();
        }
        // Cannot fail: there is room and pos ≤ len.
        let _ = peaks.insert(pos, peak);
    }
    peaks
}

/// Peak at local maximum `k` (with `0 < k < len − 1`).
fn interpolate(psd: &[f32], k: usize, bin_width_hz: f32, reference: f32) -> SpectralPeak {
    let ln = |v: f32| libm::logf(v.max(f32::MIN_POSITIVE));
    let (a, b, c) = (ln(psd[k - 1]), ln(psd[k]), ln(psd[k + 1]));
    let curvature = a - 2.0 * b + c;
    let mut delta = 0.5 * (a - c) / curvature;
    let mut peak_ln = b - 0.25 * (a - c) * delta;
    if !(delta.is_finite() && peak_ln.is_finite()) {
        // An infinite bin: no shape to fit.
        delta = 0.0;
        peak_ln = b;
    }
    let delta = delta.clamp(-0.5, 0.5);
    let peak_psd = libm::expf(peak_ln).max(psd[k]);
    let lobe = &psd[k.saturating_sub(2)..(k + 3).min(psd.len())];
    SpectralPeak {
        bin: k,
        frequency_hz: (k as f32 + delta) * bin_width_hz,
        psd: peak_psd,
        power: lobe.iter().sum::<f32>() * bin_width_hz,
        prominence_db: 10.0 * libm::log10f(peak_psd / reference),
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::super::testutil::Rng;
    use super::*;
    use core::f64::consts::PI;

    fn sine_welch<const N: usize>(amp: f64, freq_hz: f64, noise: f64, fs: f64, samples: usize) -> Welch<N>
    where
        FftLen<N>: FftSize,
    {
        let mut rng = Rng::new(42);
        let mut w = Welch::<N>::new(fs as f32).unwrap();
        for k in 0..samples {
            let t = k as f64 / fs;
            w.push(amp * libm::sin(2.0 * PI * freq_hz * t + 0.3) + noise * rng.gauss());
        }
        w
    }

    fn mean_interior(psd: &[f32]) -> f64 {
        let inner = &psd[1..psd.len() - 1];
        inner.iter().map(|&p| p as f64).sum::<f64>() / inner.len() as f64
    }

    #[test]
    fn white_noise_level_is_two_sigma_squared_over_fs() {
        fn check<const N: usize>(blocks: usize)
        where
            FftLen<N>: FftSize,
        {
            let w = sine_welch::<N>(0.0, 0.0, 0.01, 1000.0, N * blocks);
            assert_eq!(w.blocks() as usize, blocks);
            let level = mean_interior(w.psd());
            assert!((level / 2e-7 - 1.0).abs() < 0.05, "N {N}: {level:e}");
            // Averaged: the median is near the mean (within the χ² skew left after M blocks).
            let median = w.median_psd() as f64;
            assert!((median / 2e-7 - 1.0).abs() < 0.1, "N {N}: median {median:e}");
            // Parseval: the whole band holds the variance.
            assert!((w.band_power(0.0, 500.0) as f64 / 1e-4 - 1.0).abs() < 0.05);
        }
        check::<64>(400);
        check::<256>(200);
        check::<1024>(100);
        check::<4096>(30);
    }

    #[test]
    fn sine_power_is_half_amplitude_squared() {
        for freq in [13.999, 50.0, 100.0, 100.49, 237.3] {
            let w = sine_welch::<1024>(0.5, freq, 0.0, 1000.0, 8 * 1024);
            let peaks = w.peaks::<2>(20.0);
            let p = peaks[0];
            assert!((p.power / 0.125 - 1.0).abs() < 0.01, "{freq}: {}", p.power);
            assert!((p.amplitude() - 0.5).abs() < 0.005);
            assert!((p.frequency_hz as f64 - freq).abs() < 0.02, "{freq}: {}", p.frequency_hz);
            assert!((w.band_power(freq as f32 - 5.0, freq as f32 + 5.0) / 0.125 - 1.0).abs() < 0.01);
        }
    }

    #[test]
    fn running_speed_line_is_located_to_a_twentieth_of_a_hertz() {
        // 87.96 rad/s = 13.99944 Hz, 0.335 bin off a bin centre at N = 1024, fs = 1000 Hz; in
        // noise 20 dB below the line, and alone.
        let f = 87.96 / (2.0 * PI);
        for noise in [0.0, 0.05, 0.2] {
            let w = sine_welch::<1024>(0.1, f, noise * 0.1, 1000.0, 16 * 1024);
            let p = w.peaks::<1>(10.0)[0];
            assert!((p.frequency_hz as f64 - f).abs() < 0.05, "{noise}: {}", p.frequency_hz);
        }
        // Worst case over the bin: log-parabolic interpolation on a Hann window is biased by at
        // most 0.016 bin.
        let mut worst = 0.0f64;
        for i in 0..=20 {
            let f = (100.0 + i as f64 / 20.0) * 1000.0 / 1024.0;
            let w = sine_welch::<1024>(1.0, f, 0.0, 1000.0, 1024);
            worst = worst.max((w.peaks::<1>(10.0)[0].frequency_hz as f64 - f).abs());
        }
        assert!(worst < 0.017 * 1000.0 / 1024.0, "{worst}");
    }

    #[test]
    fn strongest_peaks_first() {
        let mut rng = Rng::new(9);
        let mut w = Welch::<512>::new(1000.0).unwrap();
        for k in 0..512 * 20 {
            let t = k as f64 / 1000.0;
            let x = 0.1 * libm::sin(2.0 * PI * 120.0 * t) + 1.0 * libm::sin(2.0 * PI * 50.0 * t) + 0.01 * rng.gauss();
            w.push(x as f32);
        }
        let peaks = w.peaks::<4>(10.0);
        assert_eq!(peaks.len(), 2, "{peaks:?}");
        assert!((peaks[0].frequency_hz - 50.0).abs() < 0.1 && (peaks[1].frequency_hz - 120.0).abs() < 0.1);
        assert!((peaks[0].prominence_db - peaks[1].prominence_db - 20.0).abs() < 0.5);
        // White noise of σ = 0.01 at 1 kHz: floor 2e-7 /Hz; a unit sine: 0.5 over the Hann
        // equivalent noise bandwidth 1.5 · fs/N = 2.93 Hz, so about 59 dB.
        assert!((peaks[0].prominence_db - 59.3).abs() < 1.0, "{}", peaks[0].prominence_db);
        let one = w.peaks::<1>(10.0);
        assert_eq!((one.len(), one[0].bin), (1, peaks[0].bin));
        assert!(w.peaks::<0>(10.0).is_empty());
        assert!(w.peaks::<4>(70.0).is_empty());
    }

    #[test]
    fn average_is_the_mean_of_the_blocks() {
        let mut rng = Rng::new(3);
        let data: [f32; 3 * 256] = core::array::from_fn(|_| rng.gauss() as f32);
        let mut all = Welch::<256>::new(100.0).unwrap();
        for &x in &data {
            all.push(x);
        }
        let mut mean = [0.0f64; 129];
        for b in 0..3 {
            let mut one = Welch::<256>::new(100.0).unwrap();
            for &x in &data[b * 256..(b + 1) * 256] {
                one.push(x);
            }
            mean.iter_mut().zip(one.psd()).for_each(|(m, &p)| *m += p as f64 / 3.0);
        }
        for (a, m) in all.psd().iter().zip(mean) {
            assert!((*a as f64 - m).abs() <= 1e-6 * m + 1e-12, "{a} {m}");
        }
    }

    #[test]
    fn degenerate_inputs_are_defined() {
        assert!(Welch::<64>::new(0.0).is_none());
        assert!(Welch::<64>::new(f32::NAN).is_none());
        assert!(Welch::<64>::new(-1.0).is_none());
        let mut w = Welch::<64>::new(100.0).unwrap();
        assert_eq!((w.blocks(), w.median_psd()), (0, 0.0));
        assert!(w.psd().iter().all(|&p| p == 0.0) && w.psd().len() == 33);
        assert!(w.peaks::<3>(0.0).is_empty());
        // Non-finite samples are skipped: 64 finite ones still make exactly one block.
        for k in 0..64 {
            assert!(!w.push(f64::NAN));
            let closed = w.push(k as f64);
            assert_eq!(closed, k == 63);
        }
        assert_eq!((w.blocks(), w.non_finite(), w.pending()), (1, 64, 0));
        // A block whose spectrum overflows is left out.
        (0..64).for_each(|_| {
            w.push(3e37f32);
        });
        assert_eq!((w.blocks(), w.discarded_blocks()), (1, 1));
        assert!(w.psd().iter().all(|p| p.is_finite()));
        w.reset();
        assert_eq!((w.blocks(), w.pending()), (0, 0));
        // A constant: everything at DC and its Hann leakage into bin 1 (half the DC level).
        (0..64).for_each(|_| {
            w.push(2.0f32);
        });
        let psd = w.psd();
        assert!((psd[1] / psd[0] - 0.5).abs() < 1e-5 && psd[2..].iter().all(|&p| p < 1e-12 * psd[0]));
        // DC holds the mean square: ∫ = 4 over the two bins.
        assert!((w.band_power(0.0, 2.0) - 4.0).abs() < 1e-5);
    }

    #[test]
    fn f32_fft_matches_an_f64_dft() {
        // One block of noise plus a line, against a direct f64 DFT with the same scaling.
        const N: usize = 256;
        let fs = 1000.0;
        let mut rng = Rng::new(23);
        let x: [f64; N] = core::array::from_fn(|k| 3.0 + libm::sin(0.7 * k as f64) + rng.gauss());
        let mut w = Welch::<N>::new(fs as f32).unwrap();
        for &v in &x {
            w.push(v);
        }
        let hann = |k: usize| 0.5 - 0.5 * libm::cos(2.0 * PI * k as f64 / N as f64);
        let scale = 2.0 / (fs * 3.0 * N as f64 / 8.0);
        let mut worst = 0.0f64;
        let mean = mean_interior(w.psd());
        for bin in 0..=N / 2 {
            let (mut re, mut im) = (0.0, 0.0);
            for (k, &v) in x.iter().enumerate() {
                let phase = -2.0 * PI * (bin * k) as f64 / N as f64;
                re += hann(k) * v * libm::cos(phase);
                im += hann(k) * v * libm::sin(phase);
            }
            let fold = if bin == 0 || bin == N / 2 { 0.5 } else { 1.0 };
            let reference = fold * scale * (re * re + im * im);
            let got = w.psd()[bin] as f64;
            // Relative to the bin, or to the mean level for bins far below it.
            worst = worst.max((got - reference).abs() / reference.max(0.01 * mean));
        }
        // Measured: 6e-6.
        assert!(worst < 2e-5, "{worst:e}");
    }

    #[test]
    fn median_matches_sorting() {
        let mut rng = Rng::new(17);
        for len in [1usize, 2, 3, 4, 5, 10, 513] {
            let mut v = std::vec::Vec::new();
            for i in 0..len {
                v.push(if i % 7 == 3 { 0.0 } else { (rng.gauss() * 3.0).exp() as f32 });
            }
            let inner: std::vec::Vec<f32> = if len < 3 { v.clone() } else { v[1..len - 1].to_vec() };
            let mut sorted = inner.clone();
            sorted.sort_by(|a, b| a.partial_cmp(b).unwrap());
            assert_eq!(median_level(&v), sorted[(sorted.len() - 1) / 2], "{len}");
        }
        assert!(median_level(&[1.0, f32::NAN, f32::NAN, 5.0]).is_nan());
        assert_eq!(median_level(&[1.0, f32::NAN, 3.0, 2.0, 5.0]), 3.0);
        assert_eq!(median_level(&[0.0, -1.0, -2.0, 4.0, 0.0]), 0.0);
        assert_eq!(median_level(&[0.0, f32::INFINITY, 2.0, f32::INFINITY, 0.0]), f32::INFINITY);
    }
}
