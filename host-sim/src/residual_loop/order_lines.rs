//! The innovations' lines at the running speed's orders, tested where they are expected.
//!
//! A force at an order of the speed leaves a line exactly there. The spectral peaks of
//! [`signature`](super::signature) are looked for everywhere and must stand well above the
//! Welch spectrum's median; at a known frequency the periodogram of N normalised innovations is
//! χ²(2) when nothing is there, so a far weaker line is seen. On the paper rotor a 0.5 N force
//! at 3× passes the bias, NIS and whiteness tests and leaves no Welch peak, yet a force there
//! gains 180 of log-likelihood: this statistic reads it at several hundred.

use serde::Serialize;
use std::f64::consts::TAU;

/// Integer orders tested: 2× to this. Not 1×: a system that names a running speed estimates
/// its 1× excitation (an unbalance, a drive's force) as states, whose tracking leaves a line
/// there on healthy runs too; a 1× force the model lacks raises the NIS and the Welch peak.
pub const ORDERS: u32 = 4;

/// One channel's statistic at one order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OrderLine {
    /// The order of the running speed.
    pub order: u32,
    /// Its frequency, Hz.
    pub frequency_hz: f64,
    /// `2 |Σ z e^{-iωt}|² / Σ z²`: χ²(2) for white innovations.
    pub statistic: f64,
}

/// The statistic at each order of `speed` (rad/s; none when it is 0) below the Nyquist
/// frequency of `rate` (Hz), of the normalised innovations `z` at times `t` (s). It is
/// normalised by the channel's own `Σ z²`, so a model whose variances are off by a factor does
/// not raise it: only a line does.
///
/// ```
/// use edgekf_sim::residual_loop::order_lines::order_lines;
/// let t: Vec<f64> = (0..4000).map(|k| k as f64 / 1000.0).collect();
/// // A line at 3 × 10 Hz of amplitude 0.2 on unit noise (here a deterministic ±1 sequence).
/// let z: Vec<f64> = t.iter().enumerate()
///     .map(|(k, t)| if k % 3 == 0 { 1.0 } else { -1.0 } + 0.2 * (std::f64::consts::TAU * 30.0 * t).cos())
///     .collect();
/// let lines = order_lines(&z, &t, std::f64::consts::TAU * 10.0, 1000.0);
/// assert_eq!(lines.len(), 3);
/// assert_eq!(lines[1].order, 3);
/// assert!(lines[1].statistic > 30.0 && lines[0].statistic < 1.0);
/// ```
pub fn order_lines(z: &[f64], t: &[f64], speed: f64, rate: f64) -> Vec<OrderLine> {
    let power: f64 = z.iter().map(|v| v * v).sum();
    if !(speed > 0.0 && power > 0.0) || z.len() != t.len() {
        return Vec::new();
    }
    (2..=ORDERS)
        .map(|order| (order, order as f64 * speed / TAU))
        .filter(|(_, hz)| *hz < 0.5 * rate)
        .map(|(order, frequency_hz)| {
            let w = TAU * frequency_hz;
            let (re, im) = z.iter().zip(t).fold((0.0, 0.0), |(re, im), (v, t)| {
                let (s, c) = (w * t).sin_cos();
                (re + v * c, im - v * s)
            });
            OrderLine { order, frequency_hz, statistic: 2.0 * (re * re + im * im) / power }
        })
        .collect()
}

/// The level a statistic must pass to be a line when `tests` of them are read at once, each
/// χ²(2) when nothing is there, for a false-alarm probability `alpha` over them all
/// (Bonferroni: `P(χ²(2) > x) = e^{-x/2} = alpha / tests`).
///
/// ```
/// use edgekf_sim::residual_loop::order_lines::threshold;
/// assert!((threshold(0.01, 1) - 9.2103).abs() < 1e-4);
/// assert!(threshold(0.01, 16) > threshold(0.01, 4));
/// ```
pub fn threshold(alpha: f64, tests: usize) -> f64 {
    2.0 * (tests.max(1) as f64 / alpha).ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On white Gaussian noise the statistic exceeds the level for one test at 1 % about once
    /// in a hundred channels, and its mean is 2 (χ²(2)).
    #[test]
    fn white_noise_gives_chi_square_two() {
        let t: Vec<f64> = (0..3000).map(|k| k as f64 / 1000.0).collect();
        let (mut sum, mut over, mut count) = (0.0, 0, 0);
        let mut state: u64 = 12345;
        let mut uniform = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        for _ in 0..400 {
            let z: Vec<f64> = (0..t.len()).map(|_| (-2.0 * uniform().ln()).sqrt() * (TAU * uniform()).cos()).collect();
            for l in order_lines(&z, &t, TAU * 13.7, 1000.0) {
                sum += l.statistic;
                over += usize::from(l.statistic > threshold(0.01, 1));
                count += 1;
            }
        }
        let mean = sum / count as f64;
        assert!((mean - 2.0).abs() < 0.15, "mean {mean}");
        assert!(over <= 40, "{over} of {count} over the 1 % level");
    }
}
