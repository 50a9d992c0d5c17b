//! Cepstral prewhitening (Borghesani, Pennacchi, Randall, Sawalhi & Ricci 2013, "Application of
//! cepstrum pre-whitening for the diagnosis of bearing faults under variable speed
//! conditions", MSSP 36): every spectral line and resonance of a vibration is flattened by
//! dividing its spectrum by its own magnitude, `x_w = IFFT(X / |X|)`, which is the same as
//! setting the whole real cepstrum but its zero quefrency to zero. What survives is the
//! phase: impacts that recur stay impacts, while the shaft-synchronous (discrete) lines and
//! the structure's resonances no longer dominate the envelope. Smith & Randall's CWRU
//! benchmark (MSSP 2015) names most of its diagnosable records this way.
//!
//! Its one parameter-free step is why it is used here instead of a discrete/random separation
//! (which needs a filter length and a delay): the result does not depend on anything chosen
//! per record.

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;

/// `x` prewhitened: the inverse FFT of `X/|X|` (bins of zero magnitude stay zero), scaled so
/// that its mean square is 1. Non-finite samples are read as 0; the mean is removed first.
///
/// ```
/// use edgekf_sim::diagnostics::bearings::prewhiten::prewhiten;
/// // A strong tone (50 whole cycles) plus a weak impulse: after prewhitening the impulse
/// // dominates.
/// let w50 = std::f64::consts::TAU * 50.0 / 1024.0;
/// let mut x: Vec<f64> = (0..1024).map(|k| 100.0 * (w50 * k as f64).sin()).collect();
/// x[500] += 5.0;
/// let w = prewhiten(&x);
/// let peak = (0..w.len()).max_by(|&a, &b| w[a].abs().total_cmp(&w[b].abs())).unwrap();
/// assert_eq!(peak, 500);
/// ```
pub fn prewhiten(x: &[f64]) -> Vec<f64> {
    let n = x.len();
    if n == 0 {
        return Vec::new();
    }
    let finite = |v: &f64| if v.is_finite() { *v } else { 0.0 };
    let mean = x.iter().map(finite).sum::<f64>() / n as f64;
    let mut buf: Vec<Complex<f64>> = x.iter().map(|v| Complex::new(finite(v) - mean, 0.0)).collect();
    let mut planner = FftPlanner::<f64>::new();
    planner.plan_fft_forward(n).process(&mut buf);
    for b in buf.iter_mut() {
        let m = b.norm();
        *b = if m > 0.0 && m.is_finite() { *b / m } else { Complex::new(0.0, 0.0) };
    }
    planner.plan_fft_inverse(n).process(&mut buf);
    let w: Vec<f64> = buf.iter().map(|z| z.re).collect();
    let rms = (w.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    if rms > 0.0 {
        w.iter().map(|v| v / rms).collect()
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use rand::{Rng, SeedableRng};

    fn kurtosis(x: &[f64]) -> f64 {
        let n = x.len() as f64;
        let m2 = x.iter().map(|v| v * v).sum::<f64>() / n;
        x.iter().map(|v| v.powi(4)).sum::<f64>() / n / (m2 * m2)
    }

    #[test]
    fn a_whitened_signal_shows_the_impacts_that_tones_hid() {
        // Tones 300 times the impacts' level over noise, and impacts ringing every 100 ± 2
        // samples.
        let n = 8000;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut x: Vec<f64> = (0..n)
            .map(|k| 300.0 * (0.05 * k as f64).sin() + 150.0 * (0.71 * k as f64).cos() + 0.1 * (rng.gen::<f64>() - 0.5))
            .collect();
        let mut at = 37usize;
        while at + 40 < n {
            for j in 0..40 {
                x[at + j] += (-0.15 * j as f64).exp() * (2.5 * j as f64).sin();
            }
            at += 98 + rng.gen_range(0..5);
        }
        let w = prewhiten(&x);
        let ms = w.iter().map(|v| v * v).sum::<f64>() / n as f64;
        assert!((ms - 1.0).abs() < 1e-9);
        // Tones have a kurtosis of 1.5–2; the whitened record is impulsive.
        assert!(kurtosis(&x) < 2.0 && kurtosis(&w) > 4.0, "{} → {}", kurtosis(&x), kurtosis(&w));
        assert!(prewhiten(&[]).is_empty());
        assert!(prewhiten(&[0.0; 8]).iter().all(|v| *v == 0.0));
    }
}
