//! The paper's clearance feature: the amplitude spectrum of the crank angular acceleration over
//! a window, fitted by `y = a · e^{b f}`; `a` grows with the clearance.
//!
//! Impacts in a clearance joint put broadband energy into the angular acceleration; the larger
//! the clearance, the harder the impacts and the higher the spectrum. Single impacts cannot be
//! compared between simulations (they never line up, the paper's Figure 2), but the window's
//! spectral level can, which is why the paper's UKF compares one such number per 0.25 s window.
//!
//! The fit is a nonlinear least-squares fit of the amplitudes (as MATLAB's `fit(…, 'exp1')`,
//! which we take the paper to have used), started from the log-linear fit and refined by
//! Levenberg–Marquardt. Least squares on the amplitudes weighs the strong low-frequency bins
//! most; [`fit_exponential_log`] (least squares on `ln y`) weighs every bin alike and is given
//! for comparison.
//!
//! Measured (`spectral_feature_rises_with_clearance` in `host-sim/tests/crank.rs`: clearance at
//! A, symplectic Euler at 1e-5 s, 5 rad/s² noise, 10 kHz, 160 windows of 0.25 s from four
//! release angles): `a` = 86.1 ± 1.1, 113.0 ± 1.4, 149.8 ± 2.9 and 170.8 ± 4.0 rad/s² for
//! 0.05, 0.1, 0.25 and 0.5 mm, with a window-to-window spread that grows with the clearance
//! (std 13.5 → 50.9), as the paper observes. Two caveats for an estimator: without impacts the
//! fit locks onto the low-frequency swing and `a` means something else (ideal mechanism:
//! a ≈ 276); and `a` falls as the motion loses energy (from 30°, over 20 s instead of 10 s,
//! 0.25 and 0.5 mm give 129 and 132), so sigma points must be compared over the same motion.
//!
//! ```
//! use edgekf_sim::systems::crank::feature::fit_exponential;
//! let f: Vec<f64> = (1..=100).map(|k| 50.0 * k as f64).collect();
//! let y: Vec<f64> = f.iter().map(|f| 30.0 * (-1.2e-3 * f).exp()).collect();
//! let fit = fit_exponential(&f, &y).unwrap();
//! assert!((fit.a - 30.0).abs() < 1e-9 && (fit.b + 1.2e-3).abs() < 1e-12);
//! ```

use super::spectrum::amplitude_spectrum;

/// `y ≈ a · e^{b f}` with `f` in Hz.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExpFit {
    /// Amplitude at 0 Hz, in the signal's unit (rad/s² for the crank acceleration).
    pub a: f64,
    /// Decay rate, 1/Hz (negative for a decaying spectrum).
    pub b: f64,
}

impl ExpFit {
    /// The fitted curve at `f` Hz.
    pub fn eval(&self, f: f64) -> f64 {
        self.a * (self.b * f).exp()
    }
}

/// Least-squares fit of `ln y = ln a + b f` over the points with `y > 0`; `None` with fewer
/// than two such points or degenerate frequencies.
pub fn fit_exponential_log(f: &[f64], y: &[f64]) -> Option<ExpFit> {
    let pts: Vec<(f64, f64)> = f
        .iter()
        .zip(y)
        .filter(|(f, y)| **y > 0.0 && y.is_finite() && f.is_finite())
        .map(|(f, y)| (*f, y.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let mf = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sff = pts.iter().map(|p| (p.0 - mf).powi(2)).sum::<f64>();
    if !(sff.is_finite() && sff > 0.0) {
        return None;
    }
    let sfy = pts.iter().map(|p| (p.0 - mf) * (p.1 - my)).sum::<f64>();
    let b = sfy / sff;
    let fit = ExpFit { a: (my - b * mf).exp(), b };
    (fit.a.is_finite() && fit.b.is_finite()).then_some(fit)
}

/// Nonlinear least-squares fit of `y = a e^{b f}` (Levenberg–Marquardt from the log-linear
/// fit); `None` when there is nothing to fit.
pub fn fit_exponential(f: &[f64], y: &[f64]) -> Option<ExpFit> {
    let start = fit_exponential_log(f, y)?;
    let fmax = f.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if !(fmax.is_finite() && fmax > 0.0) || f.len() != y.len() {
        return None;
    }
    // Work in x = f / fmax so that both parameters are of order one.
    let x: Vec<f64> = f.iter().map(|v| v / fmax).collect();
    let cost = |a: f64, beta: f64| x.iter().zip(y).map(|(x, y)| (y - a * (beta * x).exp()).powi(2)).sum::<f64>();
    let (mut a, mut beta) = (start.a, start.b * fmax);
    let mut c = cost(a, beta);
    let mut lambda = 1e-3;
    for _ in 0..200 {
        // Normal equations of the Gauss–Newton step, with J = ∂model/∂(a, β).
        let (mut jtj00, mut jtj01, mut jtj11, mut jtr0, mut jtr1) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (xi, yi) in x.iter().zip(y) {
            let e = (beta * xi).exp();
            let (ja, jb) = (e, a * xi * e);
            let r = yi - a * e;
            jtj00 += ja * ja;
            jtj01 += ja * jb;
            jtj11 += jb * jb;
            jtr0 += ja * r;
            jtr1 += jb * r;
        }
        let mut improved = false;
        for _ in 0..20 {
            let (d0, d1) = (jtj00 * (1.0 + lambda), jtj11 * (1.0 + lambda));
            let det = d0 * d1 - jtj01 * jtj01;
            if !(det.is_finite() && det != 0.0) {
                break;
            }
            let da = (jtr0 * d1 - jtj01 * jtr1) / det;
            let db = (d0 * jtr1 - jtj01 * jtr0) / det;
            let (na, nb) = (a + da, beta + db);
            let nc = cost(na, nb);
            if nc.is_finite() && nc <= c {
                let done = (c - nc) <= 1e-15 * c.max(1e-300) && da.abs() <= 1e-12 * a.abs() && db.abs() <= 1e-12;
                a = na;
                beta = nb;
                c = nc;
                lambda = (lambda * 0.3).max(1e-12);
                improved = !done;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    let fit = ExpFit { a, b: beta / fmax };
    (fit.a.is_finite() && fit.b.is_finite()).then_some(fit)
}

/// The feature of one window: amplitude spectrum (without DC) fitted by [`fit_exponential`].
pub fn spectral_feature(signal: &[f64], sample_rate: f64) -> Option<ExpFit> {
    let (f, amp) = amplitude_spectrum(signal, sample_rate);
    fit_exponential(&f, &amp)
}

/// The feature of every whole, non-overlapping window of `window_s` seconds (the paper: 0.25 s).
/// A window whose spectrum cannot be fitted (e.g. all zeros) gives `None`.
///
/// ```
/// use edgekf_sim::systems::crank::feature::window_features;
/// let x: Vec<f64> = (0..10_000).map(|n| if n % 97 == 0 { 100.0 } else { 0.0 }).collect();
/// let w = window_features(&x, 10_000.0, 0.25);
/// assert_eq!(w.len(), 4);
/// assert!(w.iter().all(|f| f.is_some()));
/// ```
pub fn window_features(signal: &[f64], sample_rate: f64, window_s: f64) -> Vec<Option<ExpFit>> {
    let len = (window_s * sample_rate).round();
    if !(len.is_finite() && len >= 4.0) {
        return vec![];
    }
    signal.chunks_exact(len as usize).map(|w| spectral_feature(w, sample_rate)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_noisy_exponential_and_rejects_nothing_to_fit() {
        let f: Vec<f64> = (1..=500).map(|k| 10.0 * k as f64).collect();
        // Deterministic ±5 % wiggle.
        let y: Vec<f64> = f
            .iter()
            .enumerate()
            .map(|(i, f)| 12.0 * (-8e-4 * f).exp() * (1.0 + 0.05 * ((i * 37 % 11) as f64 / 5.0 - 1.0)))
            .collect();
        let fit = fit_exponential(&f, &y).unwrap();
        assert!((fit.a / 12.0 - 1.0).abs() < 0.03, "{fit:?}");
        assert!((fit.b / -8e-4 - 1.0).abs() < 0.03, "{fit:?}");
        assert!(fit_exponential(&f, &vec![0.0; f.len()]).is_none());
        assert!(fit_exponential(&[], &[]).is_none());
        assert!(spectral_feature(&[1.0], 1000.0).is_none());
    }
}
