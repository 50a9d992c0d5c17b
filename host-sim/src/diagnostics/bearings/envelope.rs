//! Envelope analysis of innovations, the standard diagnosis of impulsive faults (Randall &
//! Antoni 2011, "Rolling element bearing diagnostics — a tutorial"): a periodic train of
//! impacts shows almost nothing at its own rate in a spectrum, but rings a structural resonance
//! whose envelope carries the rate. So: pick the most impulsive band by spectral kurtosis
//! ([`kurtogram`]), demodulate it ([`squared_envelope`]), and look for the expected line and its
//! harmonics in the envelope's spectrum ([`find_line`]) within a tolerance that allows for slip
//! (a fraction of the line, not a number of bins).
//!
//! The kurtogram here is the STFT form of the spectral kurtosis (Antoni 2006): for each window
//! length of a dyadic set, `SK(f) = ⟨|X|⁴⟩ / ⟨|X|²⟩² − 2` over the frames, 0 for Gaussian noise
//! at every frequency and large where transients recur; the band is the bin and window length
//! with the largest SK.

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use serde::Serialize;

/// A frequency band, Hz.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Band {
    /// Lower edge, Hz.
    pub low_hz: f64,
    /// Upper edge, Hz.
    pub high_hz: f64,
    /// Spectral kurtosis there (0 for Gaussian noise).
    pub kurtosis: f64,
}

impl Band {
    /// Centre, Hz.
    pub fn centre_hz(&self) -> f64 {
        0.5 * (self.low_hz + self.high_hz)
    }

    /// Width, Hz.
    pub fn width_hz(&self) -> f64 {
        self.high_hz - self.low_hz
    }
}

/// Fewest STFT frames for a spectral kurtosis worth reading (its standard deviation under
/// Gaussian noise is about `2/√frames`).
const MIN_FRAMES: usize = 32;

/// The most impulsive band of `x` (sampled at `fs`): the largest spectral kurtosis over STFT
/// window lengths 16 … 1024, among bands at least `min_width_hz` wide (an envelope carries lines
/// up to about its band's width) whose lower edge is above `min_hz`. Non-finite samples are
/// read as 0. `None` if `x` is too short for any window.
///
/// ```
/// use edgekf_sim::diagnostics::bearings::envelope::kurtogram;
/// // Gaussian-like noise with impacts ringing at 3 kHz every 10 ms, at 12 kHz.
/// let fs = 12_000.0;
/// let mut x: Vec<f64> = (0..24_000u64).map(|k| ((k * 7919 % 1000) as f64 / 500.0 - 1.0) * 0.3).collect();
/// for k in 0..x.len() {
///     let tau = (k % 120) as f64 / fs;
///     x[k] += (-600.0 * tau).exp() * (std::f64::consts::TAU * 3000.0 * tau).sin();
/// }
/// let band = kurtogram(&x, fs, 500.0, 400.0).unwrap();
/// // The most impulsive band is where the impacts ring or just above (their sharp onsets reach
/// // higher than the ringing), far from the noise's kurtosis of about 0.
/// assert!(band.low_hz >= 2000.0 && band.kurtosis > 1.0, "{band:?}");
/// ```
pub fn kurtogram(x: &[f64], fs: f64, min_hz: f64, min_width_hz: f64) -> Option<Band> {
    kurtogram_bands(x, fs, min_hz, min_width_hz, 1).into_iter().next()
}

/// The `count` most impulsive bands of `x` as [`kurtogram`] finds them, most impulsive first,
/// none of them overlapping a better one by more than half its width: the candidates for the
/// band a fault rings in (the most impulsive band may carry little of its energy).
pub fn kurtogram_bands(x: &[f64], fs: f64, min_hz: f64, min_width_hz: f64, count: usize) -> Vec<Band> {
    let x: Vec<f64> = x.iter().map(|v| if v.is_finite() { *v } else { 0.0 }).collect();
    let mut planner = FftPlanner::<f64>::new();
    let mut all: Vec<Band> = Vec::new();
    for nw in [16usize, 32, 64, 128, 256, 512, 1024] {
        let half_width = fs / nw as f64;
        let hop = nw / 4;
        if 2.0 * half_width < min_width_hz || x.len() < nw {
            continue;
        }
        let frames = (x.len() - nw) / hop + 1;
        if frames < MIN_FRAMES {
            continue;
        }
        let fft = planner.plan_fft_forward(nw);
        let window: Vec<f64> =
            (0..nw).map(|i| 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / nw as f64).cos()).collect();
        let (mut s2, mut s4) = (vec![0.0; nw / 2], vec![0.0; nw / 2]);
        let mut buf = vec![Complex::new(0.0, 0.0); nw];
        for f in 0..frames {
            let seg = &x[f * hop..f * hop + nw];
            let mean = seg.iter().sum::<f64>() / nw as f64;
            for ((b, v), w) in buf.iter_mut().zip(seg).zip(&window) {
                *b = Complex::new((v - mean) * w, 0.0);
            }
            fft.process(&mut buf);
            for (j, b) in buf.iter().take(nw / 2).enumerate() {
                let p = b.norm_sqr();
                s2[j] += p;
                s4[j] += p * p;
            }
        }
        let n = frames as f64;
        for j in 1..nw / 2 {
            let f = j as f64 * fs / nw as f64;
            if f - half_width < min_hz || f + half_width > fs / 2.0 || s2[j] <= 0.0 {
                continue;
            }
            let sk = (s4[j] / n) / (s2[j] / n).powi(2) - 2.0;
            if sk.is_finite() {
                all.push(Band { low_hz: f - half_width, high_hz: f + half_width, kurtosis: sk });
            }
        }
    }
    all.sort_by(|a, b| b.kurtosis.total_cmp(&a.kurtosis));
    let mut chosen: Vec<Band> = Vec::new();
    for b in all {
        if chosen.len() >= count {
            break;
        }
        let overlap = |c: &Band| (b.high_hz.min(c.high_hz) - b.low_hz.max(c.low_hz)).max(0.0);
        if chosen.iter().all(|c| overlap(c) <= 0.5 * b.width_hz().min(c.width_hz())) {
            chosen.push(b);
        }
    }
    chosen
}

/// The squared envelope of `x` in `band`: `|z|²` of the analytic signal `z` of `x` band-passed
/// (an ideal filter in the frequency domain, over the whole record). Non-finite samples are
/// read as 0.
///
/// ```
/// use edgekf_sim::diagnostics::bearings::envelope::{squared_envelope, Band};
/// // A 2 kHz carrier, amplitude-modulated at 50 Hz: the envelope is the modulation.
/// let fs = 10_000.0;
/// let x: Vec<f64> = (0..10_000)
///     .map(|k| { let t = k as f64 / fs; (1.0 + 0.5 * (std::f64::consts::TAU * 50.0 * t).cos()) * (std::f64::consts::TAU * 2000.0 * t).cos() })
///     .collect();
/// let env = squared_envelope(&x, fs, &Band { low_hz: 1800.0, high_hz: 2200.0, kurtosis: 0.0 });
/// assert!((env[0] - 2.25).abs() < 1e-6 && (env[100] - 0.25).abs() < 1e-6);
/// ```
pub fn squared_envelope(x: &[f64], fs: f64, band: &Band) -> Vec<f64> {
    let n = x.len();
    if n == 0 {
        return Vec::new();
    }
    let mut planner = FftPlanner::<f64>::new();
    let mut buf: Vec<Complex<f64>> =
        x.iter().map(|v| Complex::new(if v.is_finite() { *v } else { 0.0 }, 0.0)).collect();
    planner.plan_fft_forward(n).process(&mut buf);
    let df = fs / n as f64;
    for (j, b) in buf.iter_mut().enumerate() {
        let f = j as f64 * df;
        let inside = j <= n / 2 && f >= band.low_hz && f <= band.high_hz;
        *b = if inside { *b * 2.0 } else { Complex::new(0.0, 0.0) };
    }
    planner.plan_fft_inverse(n).process(&mut buf);
    let scale = 1.0 / n as f64;
    buf.iter().map(|z| (z * scale).norm_sqr()).collect()
}

/// A one-sided amplitude spectrum at `df` Hz per bin.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectrum {
    /// Bin spacing, Hz.
    pub df: f64,
    /// Amplitude per bin, from 0 Hz.
    pub amplitude: Vec<f64>,
}

/// The amplitude spectrum of `x` minus its mean (Hann window, one-sided).
pub fn spectrum(x: &[f64], fs: f64) -> Spectrum {
    let n = x.len();
    if n < 2 {
        return Spectrum { df: fs, amplitude: Vec::new() };
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let mut buf: Vec<Complex<f64>> = x
        .iter()
        .enumerate()
        .map(|(i, v)| Complex::new((v - mean) * (0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / n as f64).cos()), 0.0))
        .collect();
    FftPlanner::<f64>::new().plan_fft_forward(n).process(&mut buf);
    let scale = 4.0 / n as f64; // Hann's coherent gain 1/2, one-sided ×2
    Spectrum { df: fs / n as f64, amplitude: buf.iter().take(n / 2 + 1).map(|b| b.norm() * scale).collect() }
}

/// How a line is looked for in an envelope spectrum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineSearch {
    /// The `h`-th harmonic is looked for within `±tolerance · h · line` of `h · line` (slip,
    /// and the running speed's own uncertainty).
    pub tolerance: f64,
    /// Harmonics looked at (1 = the line alone).
    pub harmonics: u32,
    /// A harmonic is present when its peak stands this far above the median of its
    /// neighbourhood, dB.
    pub min_db: f64,
    /// A line's width, as a fraction of its frequency: the bins within it around each peak
    /// make the impacts' intensity over time (slip smears the harmonics).
    pub width: f64,
}

impl Default for LineSearch {
    /// ±2 %, three harmonics, 12 dB, lines 0.3 % wide.
    fn default() -> Self {
        Self { tolerance: 0.02, harmonics: 3, min_db: 12.0, width: 0.003 }
    }
}

/// A line found in an envelope spectrum.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LineEvidence {
    /// The line as measured (its fundamental's peak), Hz.
    pub hz: f64,
    /// The harmonics present (1 = the line itself).
    pub harmonics: Vec<u32>,
    /// Prominence of the fundamental over its neighbourhood, dB.
    pub prominence_db: f64,
}

/// The line near `nominal_hz` in `spec`, if its fundamental stands out (by `search.min_db`) and
/// either a second harmonic does too or the fundamental stands out by 6 dB more. Each
/// harmonic's neighbourhood, for the median it is measured against, is `±½ line` around it
/// (at least 20 bins), its search window left out.
///
/// ```
/// use edgekf_sim::diagnostics::bearings::envelope::{find_line, LineSearch, Spectrum};
/// // A flat floor with lines at 101 Hz and 202 Hz (bins of 0.5 Hz).
/// let mut amplitude = vec![1.0; 2000];
/// amplitude[202] = 10.0;
/// amplitude[404] = 6.0;
/// let spec = Spectrum { df: 0.5, amplitude };
/// let line = find_line(&spec, 100.0, &LineSearch::default()).unwrap();
/// assert_eq!(line.hz, 101.0);
/// assert_eq!(line.harmonics, vec![1, 2]);
/// assert!(find_line(&spec, 120.0, &LineSearch::default()).is_none());
/// ```
pub fn find_line(spec: &Spectrum, nominal_hz: f64, search: &LineSearch) -> Option<LineEvidence> {
    let bins = spec.amplitude.len();
    let bin = |f: f64| (f / spec.df).round().max(0.0) as usize;
    let peak_near = |centre: f64| -> Option<(usize, f64)> {
        let (lo, hi) = (bin(centre * (1.0 - search.tolerance)), bin(centre * (1.0 + search.tolerance)));
        let (lo, hi) = (lo.max(1), hi.min(bins.checked_sub(1)?));
        if lo > hi {
            return None;
        }
        let k = (lo..=hi).max_by(|&a, &b| spec.amplitude[a].total_cmp(&spec.amplitude[b]))?;
        let reach = bin(0.5 * nominal_hz).max(20);
        let mut around: Vec<f64> = (k.saturating_sub(reach)..=(k + reach).min(bins - 1))
            .filter(|&j| j < lo || j > hi)
            .map(|j| spec.amplitude[j])
            .collect();
        if around.len() < 5 {
            return None;
        }
        around.sort_by(f64::total_cmp);
        let median = around[around.len() / 2];
        (median > 0.0).then(|| (k, 20.0 * (spec.amplitude[k] / median).log10()))
    };
    let (k1, db1) = peak_near(nominal_hz)?;
    if db1 < search.min_db {
        return None;
    }
    let hz = k1 as f64 * spec.df;
    let mut harmonics = vec![1];
    for h in 2..=search.harmonics {
        if let Some((_, db)) = peak_near(h as f64 * hz) {
            if db >= search.min_db {
                harmonics.push(h);
            }
        }
    }
    (harmonics.len() >= 2 || db1 >= search.min_db + 6.0).then_some(LineEvidence { hz, harmonics, prominence_db: db1 })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Impacts at `rate` Hz with 1 % slip, ringing 3 kHz, in noise, at 12 kHz.
    fn impacts(rate: f64, seconds: f64, amplitude: f64) -> Vec<f64> {
        use rand::{Rng, SeedableRng};
        let fs = 12_000.0;
        let n = (seconds * fs) as usize;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut x: Vec<f64> = (0..n).map(|_| rng.gen::<f64>() - 0.5).collect();
        let mut t = 0.01;
        while t < seconds {
            let k0 = (t * fs).ceil() as usize;
            for (k, v) in x.iter_mut().enumerate().skip(k0).take(200) {
                let tau = k as f64 / fs - t;
                *v += amplitude * (-900.0 * tau).exp() * (std::f64::consts::TAU * 3000.0 * tau).sin();
            }
            t += (1.0 + 0.01 * (rng.gen::<f64>() - 0.5)) / rate;
        }
        x
    }

    #[test]
    fn the_envelope_of_an_impact_train_shows_its_rate_and_noise_shows_none() {
        let fs = 12_000.0;
        let x = impacts(107.3, 4.0, 1.0);
        let band = kurtogram(&x, fs, 1000.0, 600.0).unwrap();
        assert!(band.low_hz < 3000.0 && band.high_hz > 3000.0, "{band:?}");
        let spec = spectrum(&squared_envelope(&x, fs, &band), fs);
        let line = find_line(&spec, 107.3 * 1.01, &LineSearch::default()).unwrap();
        assert!((line.hz - 107.3).abs() < 0.5, "{line:?}");
        assert!(line.harmonics.contains(&2) && line.harmonics.contains(&3), "{line:?}");
        // Nothing at another bearing line.
        assert!(find_line(&spec, 162.2, &LineSearch::default()).is_none());
        // Plain noise: no band stands out, no line is found.
        let noise = impacts(107.3, 4.0, 0.0);
        let band = kurtogram(&noise, fs, 1000.0, 600.0).unwrap();
        assert!(band.kurtosis < 0.5, "{band:?}");
        let spec = spectrum(&squared_envelope(&noise, fs, &band), fs);
        assert!(find_line(&spec, 107.3, &LineSearch::default()).is_none());
    }
}
