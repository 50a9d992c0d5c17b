//! A resonance rung by periodic impacts, fitted to one channel's normalised innovations by
//! maximum likelihood.
//!
//! Where a fault's impacts ring a structural resonance far above the model's own dynamics (a
//! bearing defect exciting a housing mode at kilohertz, against shaft modes at tens of hertz),
//! the model's filter passes that band through to its innovations nearly unchanged, so the
//! effect can be fitted on the innovations `u_k` (normalised to unit variance by the filter's
//! own `S`) instead of inside the full filter:
//!
//! `u_k = v_k + n_k`, `n_k ~ N(0, r)`, with `v` the velocity of a mode `(f, ζ)` driven by white
//! noise of intensity `4ζω (σ_b² + σ_d² g_k)`: a background `σ_b²` (the resonance rung by
//! broadband forces, which a healthy machine shows too) and the impacts `σ_d² g_k`, where `g`
//! (mean 1) is the impacts' intensity over time, read from the lines of the squared envelope
//! that named the fault ([`intensity`]). `σ_b²` and `σ_d²` are the stationary variances each
//! gives the output. The model is linear with a time-varying process noise, so a two-state
//! Kalman filter gives its exact likelihood. The fault is the gain of the impacts model over
//! both the innovations as they are (`r` alone) and the resonance without impacts (`σ_d = 0`).

use crate::residual_loop::optimize::maximise;
use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use std::f64::consts::TAU;

/// The parameters of the impacts model (variances in the normalised innovations' units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Resonance {
    /// Mode frequency, Hz.
    pub hz: f64,
    /// Its damping ratio.
    pub damping: f64,
    /// Variance of the white part `r`.
    pub noise: f64,
    /// Stationary output variance of the broadband excitation `σ_b²`.
    pub background: f64,
    /// Stationary output variance of the impacts `σ_d²` (0: no impacts).
    pub impacts: f64,
}

/// A fitted model and its log-likelihood (whole run and each half).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit {
    /// The parameters.
    pub model: Resonance,
    /// `−½ Σ (ln S + e²/S)` over the finite samples.
    pub log_likelihood: f64,
    /// The same over the first and the second half of the samples.
    pub halves: [f64; 2],
}

/// The log-likelihood of `u` with no resonance: white with its own variance (maximum
/// likelihood), whole run and halves.
///
/// ```
/// use edgekf_sim::diagnostics::bearings::cyclic::white;
/// let (ll, halves) = white(&[1.0, -1.0, 1.0, -1.0]);
/// assert_eq!(ll, -2.0);
/// assert_eq!(halves, [-1.0, -1.0]);
/// ```
pub fn white(u: &[f64]) -> (f64, [f64; 2]) {
    let finite: Vec<(usize, f64)> = u.iter().copied().enumerate().filter(|(_, v)| v.is_finite()).collect();
    let r = (finite.iter().map(|(_, v)| v * v).sum::<f64>() / finite.len().max(1) as f64).max(1e-300);
    let half = u.len() / 2;
    let mut halves = [0.0; 2];
    for &(k, v) in &finite {
        halves[usize::from(k >= half)] -= 0.5 * (r.ln() + v * v / r);
    }
    (halves[0] + halves[1], halves)
}

/// Mean of `u²` over the finite samples (the innovations' variance about zero).
fn mean_square(u: &[f64]) -> f64 {
    let finite = || u.iter().filter(|v| v.is_finite());
    finite().map(|v| v * v).sum::<f64>() / finite().count().max(1) as f64
}

/// The exact discrete mode for unit intensity: transition `A` and the process noise `Q₁` of
/// white acceleration of density 1 over one sample.
fn discrete(hz: f64, damping: f64, fs: f64) -> Option<([f64; 4], [f64; 4])> {
    use nalgebra::{DMatrix, Dyn};
    let w = TAU * hz;
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -w * w, -2.0 * damping * w]);
    let qc = DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, 1.0]);
    let (ad, qd) = edgekf::linalg::van_loan_with(&a, &qc, 1.0 / fs, Dyn(4)).ok()?;
    Some(([ad[(0, 0)], ad[(0, 1)], ad[(1, 0)], ad[(1, 1)]], [qd[(0, 0)], qd[(0, 1)], qd[(1, 0)], qd[(1, 1)]]))
}

/// Runs the impacts model's filter over `u` with intensity `g` (`None`: constant 1): the
/// log-likelihood, its halves, and, if `predictions` is given, the one-step predictions of the
/// mode's output `v̂_{k|k−1}` (what the model expects of each sample before seeing it).
fn filter(u: &[f64], fs: f64, m: &Resonance, g: Option<&[f64]>, mut predictions: Option<&mut Vec<f64>>) -> Option<Fit> {
    let ok = |v: f64| v.is_finite() && v >= 0.0;
    if !(m.hz > 0.0 && m.hz < fs / 2.0 && m.damping > 0.0 && m.noise > 0.0 && ok(m.background) && ok(m.impacts)) {
        return None;
    }
    let ([a00, a01, a10, a11], q1) = discrete(m.hz, m.damping, fs)?;
    let scale = 4.0 * m.damping * TAU * m.hz;
    let var = m.background + m.impacts;
    let (mut x0, mut x1) = (0.0, 0.0);
    let w = TAU * m.hz;
    let (mut p00, mut p01, mut p11) = (var / (w * w), 0.0, var);
    let half = u.len() / 2;
    let mut halves = [0.0; 2];
    for (k, &y) in u.iter().enumerate() {
        if let Some(p) = predictions.as_deref_mut() {
            p.push(x1);
        }
        if y.is_finite() {
            let s = p11 + m.noise;
            let e = y - x1;
            halves[usize::from(k >= half)] -= 0.5 * (s.ln() + e * e / s);
            let (k0, k1) = (p01 / s, p11 / s);
            x0 += k0 * e;
            x1 += k1 * e;
            (p00, p01, p11) = (p00 - k0 * p01, p01 - k0 * p11, p11 - k1 * p11);
        }
        let q = scale * (m.background + m.impacts * g.map_or(1.0, |g| g.get(k).copied().unwrap_or(1.0)));
        (x0, x1) = (a00 * x0 + a01 * x1, a10 * x0 + a11 * x1);
        let (b00, b01, b10, b11) =
            (a00 * p00 + a01 * p01, a00 * p01 + a01 * p11, a10 * p00 + a11 * p01, a10 * p01 + a11 * p11);
        p00 = b00 * a00 + b01 * a01 + q * q1[0];
        p01 = b00 * a10 + b01 * a11 + q * q1[1];
        p11 = b10 * a10 + b11 * a11 + q * q1[3];
    }
    let ll = halves[0] + halves[1];
    ll.is_finite().then_some(Fit { model: *m, log_likelihood: ll, halves })
}

/// The one-step predictions `v̂_{k|k−1}` of the mode's output under `fit` with intensity `g`:
/// subtracted from the innovations they leave the impacts model's own (white) innovations.
pub fn predictions(u: &[f64], fs: f64, fit: &Fit, g: Option<&[f64]>) -> Vec<f64> {
    let mut out = Vec::with_capacity(u.len());
    if filter(u, fs, &fit.model, g, Some(&mut out)).is_none() {
        out.clear();
        out.resize(u.len(), 0.0);
    }
    out
}

/// Which of a [`Resonance`]'s parameters a coordinate of the fit moves (each in a log scale but
/// the frequency).
#[derive(Debug, Clone, Copy)]
enum Coordinate {
    Hz,
    Damping,
    Noise,
    Background,
    Impacts,
}

/// Coordinate ascent of the log-likelihood over `coords`, each by [`maximise`] within its
/// range, three sweeps, from `start`.
fn ascend(
    u: &[f64],
    fs: f64,
    band: (f64, f64),
    g: Option<&[f64]>,
    start: Resonance,
    coords: &[Coordinate],
) -> Option<Fit> {
    let variance = mean_square(u);
    let mut m = start;
    let mut best = filter(u, fs, &m, g, None)?;
    for _ in 0..3 {
        for &c in coords {
            let set = |m: &mut Resonance, x: f64| match c {
                Coordinate::Hz => m.hz = x,
                Coordinate::Damping => m.damping = x.exp(),
                Coordinate::Noise => m.noise = x.exp(),
                Coordinate::Background => m.background = x.exp(),
                Coordinate::Impacts => m.impacts = x.exp(),
            };
            let (low, high, tol) = match c {
                Coordinate::Hz => (band.0, band.1, 1e-4 * (band.1 - band.0)),
                Coordinate::Damping => (0.002f64.ln(), 0.5f64.ln(), 1e-3),
                Coordinate::Noise => ((1e-3 * variance).ln(), (2.0 * variance).ln(), 1e-4),
                Coordinate::Background | Coordinate::Impacts => ((1e-5 * variance).ln(), (20.0 * variance).ln(), 1e-3),
            };
            let found = maximise(
                |x| {
                    let mut trial = m;
                    set(&mut trial, x);
                    filter(u, fs, &trial, g, None).map(|f| f.log_likelihood)
                },
                low,
                high,
                5,
                tol,
            )?;
            let mut trial = m;
            set(&mut trial, found.x);
            if let Some(f) = filter(u, fs, &trial, g, None).filter(|f| f.log_likelihood > best.log_likelihood) {
                (m, best) = (trial, f);
            }
        }
    }
    Some(best)
}

/// The resonance without impacts (`σ_d = 0`) fitted to `u` in `band` (Hz): the alternative a
/// fault's impacts must beat.
pub fn fit_background(u: &[f64], fs: f64, band: (f64, f64)) -> Option<Fit> {
    let variance = mean_square(u);
    let centre = 0.5 * (band.0 + band.1);
    let damping = (0.25 * (band.1 - band.0) / centre).clamp(0.005, 0.2);
    let start = Resonance { hz: centre, damping, noise: variance, background: 0.05 * variance, impacts: 0.0 };
    use Coordinate::*;
    ascend(u, fs, band, None, start, &[Background, Hz, Damping, Noise])
}

/// The resonance with impacts of intensity `g`, fitted from the background fit `from`.
pub fn fit_impacts(u: &[f64], fs: f64, band: (f64, f64), g: &[f64], from: &Fit) -> Option<Fit> {
    let start = Resonance { impacts: 0.1 * from.model.noise, ..from.model };
    use Coordinate::*;
    ascend(u, fs, band, Some(g), start, &[Impacts, Background, Hz, Damping, Noise])
}

/// The impacts' intensity over time, mean 1, from the squared envelope `env` (sampled at
/// `fs`): the envelope rebuilt from its lines at the fault's rate `line_hz` and its harmonics
/// up to `harmonics`, with their sidebands at `±modulation_hz` and the modulation's own line (a
/// fault carried through a load zone); floored at 5 % of the mean. Each line is taken where the
/// envelope's spectrum peaks within `±tolerance` of its nominal frequency, with the bins within
/// `±width` of it (a fraction of the line, at least a bin and a half: slip smears a line's
/// harmonics). Returns the intensity and the number of spectral bins it kept (each a complex
/// amplitude the fit took from the data).
///
/// ```
/// use edgekf_sim::diagnostics::bearings::cyclic::intensity;
/// // An envelope pulsing at 100 Hz (and noise-free): rebuilt from its line (3 bins), it pulses
/// // too, from 0.05 (the floor) to 2 (a hair under: the floor lifts the mean a little).
/// let fs = 2000.0;
/// let env: Vec<f64> = (0..2000).map(|k| 1.0 + (std::f64::consts::TAU * 100.0 * k as f64 / fs).cos()).collect();
/// let (g, bins) = intensity(&env, fs, 100.0, 1, None, 0.02, 0.003);
/// assert!((g[0] - 2.0).abs() < 0.01 && g[10] < 0.06 && bins == 3);
/// ```
pub fn intensity(
    env: &[f64],
    fs: f64,
    line_hz: f64,
    harmonics: u32,
    modulation_hz: Option<f64>,
    tolerance: f64,
    width: f64,
) -> (Vec<f64>, usize) {
    let n = env.len();
    if n < 4 {
        return (vec![1.0; n], 0);
    }
    let mut planner = FftPlanner::<f64>::new();
    let mut spec: Vec<Complex<f64>> =
        env.iter().map(|v| Complex::new(if v.is_finite() { *v } else { 0.0 }, 0.0)).collect();
    planner.plan_fft_forward(n).process(&mut spec);
    let df = fs / n as f64;
    let mut keep = vec![false; n / 2 + 1];
    keep[0] = true;
    let sidebands: &[f64] = if modulation_hz.is_some() { &[-1.0, 0.0, 1.0] } else { &[0.0] };
    let bin_range = |lo: f64, hi: f64| ((lo / df).ceil().max(1.0) as usize, ((hi / df).floor() as usize).min(n / 2));
    for h in 0..=harmonics {
        for &j in sidebands {
            let centre = h as f64 * line_hz + j * modulation_hz.unwrap_or(0.0);
            if centre <= 0.0 {
                continue;
            }
            let (lo, hi) = bin_range(centre * (1.0 - tolerance), centre * (1.0 + tolerance));
            let Some(peak) = (lo..=hi).max_by(|&a, &b| spec[a].norm().total_cmp(&spec[b].norm())) else { continue };
            let reach = (width * centre).max(1.5 * df);
            let (lo, hi) = bin_range(peak as f64 * df - reach, peak as f64 * df + reach);
            for k in keep.iter_mut().take(hi + 1).skip(lo) {
                *k = true;
            }
        }
    }
    let bins = keep.iter().skip(1).filter(|k| **k).count();
    for (j, s) in spec.iter_mut().enumerate() {
        let mirror = if j <= n / 2 { j } else { n - j };
        if !keep[mirror] {
            *s = Complex::new(0.0, 0.0);
        }
    }
    planner.plan_fft_inverse(n).process(&mut spec);
    let raw: Vec<f64> = spec.iter().map(|z| z.re / n as f64).collect();
    let mean = raw.iter().sum::<f64>() / n as f64;
    if !(mean.is_finite() && mean > 0.0) {
        return (vec![1.0; n], bins);
    }
    let floored: Vec<f64> = raw.iter().map(|v| v.max(0.05 * mean)).collect();
    let mean = floored.iter().sum::<f64>() / n as f64;
    (floored.iter().map(|v| v / mean).collect(), bins)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnostics::bearings::envelope::{squared_envelope, Band};
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// Unit white noise plus a 3 kHz mode (ζ 3 %) rung by impacts at `rate` Hz (none if 0)
    /// and by a weak broadband force, at 12 kHz.
    fn innovations(rate: f64, seed: u64) -> Vec<f64> {
        let fs = 12_000.0;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let unit = Normal::new(0.0, 1.0).unwrap();
        let ([a00, a01, a10, a11], _) = discrete(3000.0, 0.03, fs).unwrap();
        let (mut x0, mut x1) = (0.0, 0.0);
        let period = if rate > 0.0 { (fs / rate).round() as usize } else { usize::MAX };
        (0..48_000)
            .map(|k| {
                let kick = if k % period == 0 { 40.0 * unit.sample(&mut rng) } else { 0.0 };
                let y = x1 + unit.sample(&mut rng);
                (x0, x1) = (a00 * x0 + a01 * x1, a10 * x0 + a11 * x1 + kick + 0.05 * unit.sample(&mut rng));
                y
            })
            .collect()
    }

    fn gain(u: &[f64], rate: f64) -> (f64, f64) {
        let fs = 12_000.0;
        let band = Band { low_hz: 2250.0, high_hz: 3750.0, kurtosis: 0.0 };
        let env = squared_envelope(u, fs, &band);
        let (g, _) = intensity(&env, fs, rate, 3, None, 0.02, 0.003);
        let b = fit_background(u, fs, (band.low_hz, band.high_hz)).unwrap();
        let d = fit_impacts(u, fs, (band.low_hz, band.high_hz), &g, &b).unwrap();
        assert!(d.log_likelihood >= b.log_likelihood - 1e-6 && b.log_likelihood >= white(u).0 - 1e-6);
        (d.log_likelihood - b.log_likelihood, d.model.hz)
    }

    #[test]
    fn impacts_are_worth_far_more_than_a_plain_resonance_only_where_they_are() {
        let (with, hz) = gain(&innovations(100.0, 1), 100.0);
        assert!(with > 10_000.0, "Δ log-likelihood {with}");
        assert!((hz - 3000.0).abs() < 30.0, "{hz} Hz");
        // No impacts: rebuilding the intensity from noise lines buys little, far less than the
        // ~100 envelope bins it took cost in the BIC (about 1 100 here).
        let (without, _) = gain(&innovations(0.0, 1), 100.0);
        assert!(without < 100.0, "Δ log-likelihood {without}");
    }
}
