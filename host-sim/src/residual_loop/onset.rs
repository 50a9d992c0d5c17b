//! Effects that start mid-run: where an onset may lie, where the gain of a fit starts to
//! accumulate, and the halves test on the stretch after it.
//!
//! A fault that begins at 220 s of a 300 s recording gains nothing in the first half of the
//! run, so a test of "pays in both halves" over the whole run refuses it. Fitted with an onset,
//! the effect is absent before it and the halves are those of the stretch it acts on; the onset
//! costs one more parameter in the BIC.

use super::filter::Run;

/// Samples at either end where no onset is placed: before 5 % of the run (that is an effect
/// present from the start) or after 90 % (too little is left to test in two halves).
///
/// ```
/// use edgekf_sim::residual_loop::onset::window;
/// assert_eq!(window(1000), Some((50, 900)));
/// assert_eq!(window(10), None);
/// ```
pub fn window(samples: usize) -> Option<(usize, usize)> {
    let (lo, hi) = (samples / 20, samples * 9 / 10);
    (samples >= 40 && hi > lo + 1).then_some((lo, hi))
}

/// Eight onsets spread over `lo..=hi`, for when there is no whole-run fit to read one from.
pub fn grid(lo: usize, hi: usize) -> impl Iterator<Item = usize> {
    (0..8).map(move |i| lo + (hi - lo) * i / 7)
}

/// The per-sample log-likelihood of `run` (0 where the sample was missing).
fn log_likelihood(run: &Run, k: usize) -> f64 {
    match (run.nis.get(k), run.log_det_s.get(k)) {
        (Some(n), Some(l)) if n.is_finite() && l.is_finite() => -0.5 * (n + l),
        _ => 0.0,
    }
}

/// Gain in log-likelihood of `run` over `base` in the two halves of the samples from `from` on.
///
/// ```
/// use edgekf_sim::residual_loop::filter::Run;
/// use edgekf_sim::residual_loop::onset::halves;
/// let base = Run { nis: vec![1.0; 8], log_det_s: vec![0.0; 8], ..Run::default() };
/// // Better by 1 in NIS (½ in log-likelihood) on the last four samples only.
/// let nis = vec![1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0];
/// let late = Run { nis, log_det_s: vec![0.0; 8], ..Run::default() };
/// assert_eq!(halves(&late, &base, 0), [0.0, 2.0]);
/// assert_eq!(halves(&late, &base, 4), [1.0, 1.0]);
/// ```
pub fn halves(run: &Run, base: &Run, from: usize) -> [f64; 2] {
    let n = run.nis.len().min(base.nis.len());
    let from = from.min(n);
    let mid = from + (n - from) / 2;
    let gain = |lo: usize, hi: usize| (lo..hi).map(|k| log_likelihood(run, k) - log_likelihood(base, k)).sum();
    [gain(from, mid), gain(mid, n)]
}

/// The sample in `lo..=hi` from which on `run` gains most over `base` (the largest suffix sum of
/// the per-sample gain): where an effect fitted to the whole run starts to pay.
///
/// ```
/// use edgekf_sim::residual_loop::filter::Run;
/// use edgekf_sim::residual_loop::onset::change_point;
/// let base = Run { nis: vec![1.0; 100], log_det_s: vec![0.0; 100], ..Run::default() };
/// // Slightly worse before sample 60, better after it.
/// let nis = (0..100).map(|k| if k < 60 { 1.1 } else { 0.5 }).collect();
/// let run = Run { nis, log_det_s: vec![0.0; 100], ..Run::default() };
/// assert_eq!(change_point(&run, &base, 5, 90), 60);
/// ```
pub fn change_point(run: &Run, base: &Run, lo: usize, hi: usize) -> usize {
    let n = run.nis.len().min(base.nis.len());
    let mut suffix = 0.0;
    let mut best = (hi.min(n.saturating_sub(1)), f64::NEG_INFINITY);
    for k in (lo..n).rev() {
        suffix += log_likelihood(run, k) - log_likelihood(base, k);
        if k <= hi && suffix > best.1 {
            best = (k, suffix);
        }
    }
    best.0
}

/// The mean of `series` over the second half of the samples from `from` on, ignoring NaN: an
/// effect state's size once its estimate has settled (NaN if nothing is left).
///
/// ```
/// use edgekf_sim::residual_loop::onset::settled_mean;
/// let s = [0.0, 0.0, 5.0, 1.0, 2.0, 2.0];
/// assert_eq!(settled_mean(&s, 0), 5.0 / 3.0);
/// assert_eq!(settled_mean(&s, 2), 2.0);
/// ```
pub fn settled_mean(series: &[f64], from: usize) -> f64 {
    let from = from.min(series.len());
    let tail = &series[from + (series.len() - from) / 2..];
    let finite: Vec<f64> = tail.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        f64::NAN
    } else {
        finite.iter().sum::<f64>() / finite.len() as f64
    }
}
