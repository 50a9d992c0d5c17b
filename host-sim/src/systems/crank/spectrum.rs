//! Discrete Fourier transform of any length, for the spectral clearance feature.
//!
//! The paper's windows (0.25 s) hold 2 500 samples at 10 kHz: not a power of two. Zero-padding
//! would change the bin spacing and smear the spectrum the feature is fitted to, so lengths
//! that are not powers of two go through Bluestein's chirp-z algorithm (three radix-2 FFTs of
//! the next power of two ≥ 2N − 1): the exact N-point DFT in O(N log N).

use std::f64::consts::PI;

/// A complex number.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Complex {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
}

impl Complex {
    fn new(re: f64, im: f64) -> Self {
        Self { re, im }
    }
    fn mul(self, o: Complex) -> Complex {
        Complex::new(self.re * o.re - self.im * o.im, self.re * o.im + self.im * o.re)
    }
    fn conj(self) -> Complex {
        Complex::new(self.re, -self.im)
    }
    /// Modulus.
    pub fn abs(self) -> f64 {
        self.re.hypot(self.im)
    }
}

/// In-place iterative radix-2 FFT (`inverse` without the 1/N factor). `a.len()` must be a
/// power of two.
fn fft_pow2(a: &mut [Complex], inverse: bool) {
    let n = a.len();
    debug_assert!(n.is_power_of_two());
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            a.swap(i, j);
        }
    }
    let sign = if inverse { 1.0 } else { -1.0 };
    let mut len = 2;
    while len <= n {
        let ang = sign * 2.0 * PI / len as f64;
        let half = len / 2;
        // Twiddles computed directly (not by recurrence) to keep the error at rounding level.
        let tw: Vec<Complex> =
            (0..half).map(|k| Complex::new((ang * k as f64).cos(), (ang * k as f64).sin())).collect();
        for start in (0..n).step_by(len) {
            for k in 0..half {
                let u = a[start + k];
                let v = a[start + k + half].mul(tw[k]);
                a[start + k] = Complex::new(u.re + v.re, u.im + v.im);
                a[start + k + half] = Complex::new(u.re - v.re, u.im - v.im);
            }
        }
        len <<= 1;
    }
}

/// The DFT `X_k = Σ x_n e^{−2πi nk/N}` of a real sequence, all N bins.
///
/// ```
/// use edgekf_sim::systems::crank::spectrum::dft;
/// // A cosine of amplitude 2 in bin 3 of a 10-point sequence: |X_3| = 2 · 10 / 2.
/// let x: Vec<f64> = (0..10).map(|n| 2.0 * (2.0 * std::f64::consts::PI * 3.0 * n as f64 / 10.0).cos()).collect();
/// let big = dft(&x);
/// assert!((big[3].abs() - 10.0).abs() < 1e-12);
/// assert!(big[2].abs() < 1e-12);
/// ```
pub fn dft(x: &[f64]) -> Vec<Complex> {
    let n = x.len();
    if n == 0 {
        return vec![];
    }
    if n.is_power_of_two() {
        let mut a: Vec<Complex> = x.iter().map(|&v| Complex::new(v, 0.0)).collect();
        fft_pow2(&mut a, false);
        return a;
    }
    // Bluestein: nk = (n² + k² − (k − n)²) / 2, chirp w_n = e^{−iπ n²/N}.
    let m = (2 * n - 1).next_power_of_two();
    let two_n = 2 * n as u128;
    let chirp: Vec<Complex> = (0..n)
        .map(|k| {
            let k2 = (k as u128 * k as u128) % two_n;
            let ang = -PI * k2 as f64 / n as f64;
            Complex::new(ang.cos(), ang.sin())
        })
        .collect();
    let mut a = vec![Complex::default(); m];
    for k in 0..n {
        a[k] = chirp[k].mul(Complex::new(x[k], 0.0));
    }
    let mut b = vec![Complex::default(); m];
    b[0] = chirp[0].conj();
    for k in 1..n {
        b[k] = chirp[k].conj();
        b[m - k] = chirp[k].conj();
    }
    fft_pow2(&mut a, false);
    fft_pow2(&mut b, false);
    for k in 0..m {
        a[k] = a[k].mul(b[k]);
    }
    fft_pow2(&mut a, true);
    let scale = 1.0 / m as f64;
    (0..n).map(|k| chirp[k].mul(Complex::new(a[k].re * scale, a[k].im * scale))).collect()
}

/// Single-sided amplitude spectrum of a real signal sampled at `sample_rate` Hz, without the
/// DC bin: frequencies `k · rate / N` (Hz) for `k = 1 … ⌊N/2⌋`, and amplitudes `2 |X_k| / N`
/// (the amplitude of a sinusoid in that bin; the Nyquist bin `|X_k| / N`), in the signal's
/// unit.
///
/// ```
/// use edgekf_sim::systems::crank::spectrum::amplitude_spectrum;
/// let rate = 1000.0;
/// let x: Vec<f64> = (0..250).map(|n| 3.0 + 5.0 * (2.0 * std::f64::consts::PI * 100.0 * n as f64 / rate).sin()).collect();
/// let (f, amp) = amplitude_spectrum(&x, rate);
/// assert_eq!(f.len(), 125);
/// assert_eq!(f[24], 100.0); // bin 25 of 4 Hz
/// assert!((amp[24] - 5.0).abs() < 1e-9);
/// ```
pub fn amplitude_spectrum(x: &[f64], sample_rate: f64) -> (Vec<f64>, Vec<f64>) {
    let n = x.len();
    if n < 2 {
        return (vec![], vec![]);
    }
    let big = dft(x);
    let half = n / 2;
    let f = (1..=half).map(|k| k as f64 * sample_rate / n as f64).collect();
    let amp = (1..=half)
        .map(|k| {
            let s = if 2 * k == n { 1.0 } else { 2.0 };
            s * big[k].abs() / n as f64
        })
        .collect();
    (f, amp)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn naive(x: &[f64]) -> Vec<Complex> {
        let n = x.len();
        (0..n)
            .map(|k| {
                let mut s = Complex::default();
                for (j, &v) in x.iter().enumerate() {
                    let ang = -2.0 * PI * ((j * k) % n) as f64 / n as f64;
                    s.re += v * ang.cos();
                    s.im += v * ang.sin();
                }
                s
            })
            .collect()
    }

    #[test]
    fn matches_the_definition_for_any_length() {
        for n in [1usize, 2, 3, 7, 16, 100, 250, 1024, 2500] {
            let x: Vec<f64> = (0..n).map(|i| ((i * 7919) % 113) as f64 / 113.0 - 0.4).collect();
            let fast = dft(&x);
            let slow = naive(&x);
            let scale = x.iter().map(|v| v.abs()).sum::<f64>().max(1.0);
            for (a, b) in fast.iter().zip(&slow) {
                assert!((a.re - b.re).abs() < 1e-11 * scale && (a.im - b.im).abs() < 1e-11 * scale, "n = {n}");
            }
        }
    }
}
