//! The running speed refined to a fraction of a spectral bin from the shaft harmonics of the raw
//! vibration: the strongest line near the nominal speed, then the interpolated peaks of orders
//! 1…[`ORDERS`] that stand out, each read as `f_h / h` and weighted by `h² · SNR` (an
//! interpolated peak's error is about `df / √SNR`, and dividing by `h` shrinks it `h` times).
//! A bearing family is told from a synchronous modulation by lines a few tenths of a per cent
//! apart (Randall & Antoni 2011, § 3), so the speed must be right to better than that.
//!
//! Orders whose estimate disagrees with the weighted median by more than half a bin at their
//! own frequency are left out: a mains harmonic one bin from a shaft order (CWRU's 2 × 29.95 Hz
//! against 60 Hz) would otherwise pull the estimate.

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use serde::Serialize;

/// Shaft orders read.
pub const ORDERS: usize = 10;

/// An order's peak is read when it stands this many times above the median of its
/// neighbourhood (10 dB).
const MIN_SNR: f64 = 10.0;

/// The refined running speed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ShaftSpeed {
    /// Hz.
    pub hz: f64,
    /// Its standard uncertainty, Hz (the weighted spread of the orders' estimates over the
    /// root of their number, at least a fiftieth of a bin over the highest order used).
    pub uncertainty_hz: f64,
    /// The orders it was read from.
    pub orders: usize,
}

/// The one-sided power spectrum (Hann window, mean removed) of the sum of the channels' power
/// spectra; bin spacing `fs / n`.
pub fn power_spectrum(channels: &[&[f64]], fs: f64) -> (f64, Vec<f64>) {
    let n = channels.iter().map(|c| c.len()).min().unwrap_or(0);
    if n < 4 {
        return (fs, Vec::new());
    }
    let mut planner = FftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(n);
    let mut total = vec![0.0; n / 2 + 1];
    for x in channels {
        let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
        let mean = x[..n].iter().map(|v| finite(*v)).sum::<f64>() / n as f64;
        let mut buf: Vec<Complex<f64>> = x[..n]
            .iter()
            .enumerate()
            .map(|(i, v)| {
                let w = 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / n as f64).cos();
                Complex::new((finite(*v) - mean) * w, 0.0)
            })
            .collect();
        fft.process(&mut buf);
        total.iter_mut().zip(&buf).for_each(|(t, b)| *t += b.norm_sqr());
    }
    (fs / n as f64, total)
}

/// The peak's position in bins, interpolated by a parabola through the logarithms of the
/// three highest bins (exact for a Gaussian main lobe, a few hundredths of a bin for Hann's).
pub fn interpolated_peak(p: &[f64], k: usize) -> f64 {
    if k == 0 || k + 1 >= p.len() || p[k - 1] <= 0.0 || p[k + 1] <= 0.0 || p[k] <= 0.0 {
        return k as f64;
    }
    let (a, b, c) = (p[k - 1].ln(), p[k].ln(), p[k + 1].ln());
    let denom = a - 2.0 * b + c;
    if denom < 0.0 {
        k as f64 + (0.5 * (a - c) / denom).clamp(-0.5, 0.5)
    } else {
        k as f64
    }
}

/// The bin of the largest value of `p` in `lo..=hi` (clipped to `p`).
fn argmax(p: &[f64], lo: usize, hi: usize) -> Option<usize> {
    let hi = hi.min(p.len().checked_sub(1)?);
    (lo.max(1)..=hi).max_by(|&a, &b| p[a].total_cmp(&p[b]))
}

/// The median of `p` over `±reach` bins around `k`, the three bins each side of `k` left out.
fn local_median(p: &[f64], k: usize, reach: usize) -> f64 {
    let mut v: Vec<f64> =
        (k.saturating_sub(reach)..=(k + reach).min(p.len() - 1)).filter(|&j| j.abs_diff(k) > 3).map(|j| p[j]).collect();
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// The running speed of `channels` (sampled at `fs`), searched within `±band` (a fraction) of
/// `nominal_hz` and refined from its harmonics. `None` if no line stands out there.
///
/// ```
/// use edgekf_sim::diagnostics::bearings::shaft::shaft_speed;
/// let fs = 12_000.0;
/// let x: Vec<f64> = (0..24_000)
///     .map(|k| { let t = k as f64 / fs; (1..=6).map(|h| (std::f64::consts::TAU * 29.437 * h as f64 * t + h as f64).sin() / h as f64).sum::<f64>() + 1e-3 * ((k * 7919 % 997) as f64 - 498.0) })
///     .collect();
/// let s = shaft_speed(&[&x], fs, 30.0, 0.1).unwrap();
/// assert!((s.hz - 29.437).abs() < 0.005, "{s:?}"); // a hundredth of a 0.5 Hz bin
/// ```
pub fn shaft_speed(channels: &[&[f64]], fs: f64, nominal_hz: f64, band: f64) -> Option<ShaftSpeed> {
    let (df, p) = power_spectrum(channels, fs);
    if p.len() < 16 || nominal_hz.is_nan() || nominal_hz <= 0.0 {
        return None;
    }
    let bin = |f: f64| (f / df).round().max(0.0) as usize;
    let reach = bin(0.5 * nominal_hz).max(20);
    let k1 = argmax(&p, bin(nominal_hz * (1.0 - band)), bin(nominal_hz * (1.0 + band)))?;
    let f1 = interpolated_peak(&p, k1) * df;
    // (order, estimate of the speed, weight)
    let mut est: Vec<(f64, f64, f64)> = Vec::new();
    for h in 1..=ORDERS {
        let centre = h as f64 * f1;
        let half = (0.002 * centre).max(2.0 * df);
        let Some(k) = argmax(&p, bin(centre - half), bin(centre + half)) else { continue };
        let floor = local_median(&p, k, reach);
        let snr = if floor > 0.0 { p[k] / floor } else { 0.0 };
        if snr >= MIN_SNR && k > 1 {
            let hf = h as f64;
            est.push((hf, interpolated_peak(&p, k) * df / hf, hf * hf * snr));
        }
    }
    if est.is_empty() {
        return None;
    }
    let median = median(&est);
    est.retain(|(h, e, _)| h * (e - median).abs() <= 0.5 * df);
    let sw: f64 = est.iter().map(|x| x.2).sum();
    let hz = est.iter().map(|(_, e, w)| e * w).sum::<f64>() / sw;
    let spread = (est.iter().map(|(_, e, w)| w * (e - hz).powi(2)).sum::<f64>() / sw).sqrt();
    let top = est.iter().map(|x| x.0).fold(1.0, f64::max);
    let uncertainty_hz = (spread / (est.len() as f64).sqrt()).max(0.02 * df / top);
    Some(ShaftSpeed { hz, uncertainty_hz, orders: est.len() })
}

/// The median of the estimates `(order, value, weight)`, each counted once (a strong mains
/// line one bin from an order must not outweigh the others).
fn median(est: &[(f64, f64, f64)]) -> f64 {
    let mut v: Vec<f64> = est.iter().map(|x| x.1).collect();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[cfg(test)]
mod tests {
    use super::*;

    use rand::{Rng, SeedableRng};

    #[test]
    fn a_mains_line_a_bin_from_an_order_does_not_pull_the_speed() {
        // 29.95 Hz with harmonics, and a strong 60 Hz line 0.1 Hz from its 2×, 10 s at 2 kHz.
        let fs = 2000.0;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let x: Vec<f64> = (0..20_000)
            .map(|k| {
                let t = k as f64 / fs;
                let shaft: f64 =
                    (1..=8).map(|h| (std::f64::consts::TAU * 29.95 * h as f64 * t + 0.3 * h as f64).sin()).sum();
                shaft + 20.0 * (std::f64::consts::TAU * 60.0 * t).sin() + (rng.gen::<f64>() - 0.5)
            })
            .collect();
        let s = shaft_speed(&[&x], fs, 30.0, 0.1).unwrap();
        assert!((s.hz - 29.95).abs() < 0.002, "{s:?}");
        assert!(s.uncertainty_hz < 0.01, "{s:?}");
        // Nothing but noise near the nominal speed: no speed.
        let noise: Vec<f64> = (0..20_000).map(|_| rng.gen::<f64>() - 0.5).collect();
        assert!(shaft_speed(&[&noise], fs, 30.0, 0.1).is_none_or(|s| s.orders <= 1));
    }
}
