//! The release transient: the clearance from the first contact after the mechanism is let go.
//!
//! The mechanism is released at rest with every journal centred in its bearing, so the journal
//! of the clearance joint first flies freely across the clearance and touches after
//! `t₁ ≈ √(2c / a)`, `a` the relative acceleration of journal and bearing at release (about
//! 10 m/s² at A: 0.25 mm touches after 7.1 ms, 0.1 mm after 4.5 ms). Nothing has hit anything
//! before that, so `t₁` is not chaotic: any simulator of the mechanism, or the mechanism
//! itself, gives the same `t₁` for the same clearance and release, whatever impact sequence
//! follows. `a` depends on the release angle, which the crank acceleration before the contact
//! gives (at A −79, −27 and +12 rad/s² for 20°, 30° and 40°). So
//! `ln c = 2 ln t₁ + ln(a(θ₀)/2)`, learned per joint as a cubic in the pre-contact level.
//!
//! A contact lasts 70–190 µs, about one sample at 10 kHz, and the sensor samples the crank's
//! acceleration at instants: the first contact can fall between two samples and be missed. The
//! first contact *seen* is then the second one, whose time follows another smooth law (at C,
//! `2c/t²` is about 12 for the first contact and about 4 for the second). The model holds one
//! law per hypothesis, and the estimate takes the hypothesis that agrees with the window
//! features' clearance ([`ReleaseModel::refine`]); the two differ by a factor 1.7–3 in `c`,
//! far more than the features' error.
//!
//! [`ReleaseDetector`] finds the contact: a least-squares quadratic through the samples since
//! release predicts the next one, and the first sample off the prediction by more than
//! [`THRESHOLD_SIGMAS`] times the fit's own residual scatter (inflated for the extrapolation)
//! is the contact. It works for the first [`RELEASE_SPAN`] only; about 40 operations per
//! sample until the contact, nothing after.
//!
//! A missing sample (non-finite: a lost line or an empty cell, which the host's timeline and the
//! node's line source both step as missing samples) is left out of the fit but its time is
//! counted: the quadratic is in time, and `t₁` is a time, so a sample lost before the contact
//! must not move the contact earlier by one period.

use super::ClearanceFloat;

/// Regressors of a [`ReleaseModel`] law: `1, l, u, u², u³, l·u`, with `l = ln(t₁ / 5 ms)` and
/// `u = (α₀ − centre) / 100 rad/s²` ([`release_regressors`]).
pub const RELEASE_TERMS: usize = 6;

/// Hypotheses of a [`ReleaseModel`]: the contact seen is the first (0), the second (1) or the
/// third (2).
pub const RELEASE_HYPOTHESES: usize = 4;

/// How long after release the detector looks for the contact, s.
pub const RELEASE_SPAN: f64 = 0.1;

/// Samples the quadratic needs before it predicts (2.4 ms at 10 kHz: clearances down to about
/// 0.03 mm at A).
pub const MIN_FIT: usize = 24;

/// The contact threshold, in residual standard deviations of the fit.
pub const THRESHOLD_SIGMAS: f64 = 7.0;

/// Smallest residual standard deviation assumed, rad/s²: a noise-free recording would
/// otherwise take any rounding for a contact.
pub const MIN_SIGMA: f64 = 0.1;

/// What the release transient shows.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ReleaseFeatures<T> {
    /// Time of the first sample that shows a contact, s after release (the first sample is at 0).
    pub contact: T,
    /// Mean crank acceleration before it, rad/s².
    pub release_alpha: T,
}

/// Finds the first contact after release, one sample at a time (see the module's text).
///
/// ```
/// use edgekf::systems::crank::ReleaseDetector;
/// let mut d = ReleaseDetector::<f64>::new(10_000.0);
/// for k in 0..200 {
///     let t = k as f64 * 1e-4;
///     let wobble = if k % 2 == 0 { 0.5 } else { -0.5 }; // ±0.5 rad/s² "noise"
///     d.push(if k == 71 { 9_000.0 } else { -27.0 - 100.0 * t + wobble });
/// }
/// let f = d.features().unwrap();
/// assert!((f.contact - 71e-4).abs() < 1e-12);
/// assert!((f.release_alpha - (-27.0 - 100.0 * 35e-4)).abs() < 0.01);
/// ```
#[derive(Debug, Clone)]
pub struct ReleaseDetector<T> {
    /// Scale of the fit's abscissa: `τ = index · step`, so `τ ≤ 1` over the span.
    step: T,
    /// Samples (missing ones included) examined at most.
    limit: usize,
    /// Samples seen, missing ones included: the time index of the next one.
    index: usize,
    /// Finite samples fitted.
    k: usize,
    /// The first sample: the fit runs on `y = x − x₀`.
    origin: T,
    /// `Σ τᵖ`, `p = 0…4`.
    s: [T; 5],
    /// `Σ τᵖ y`, `p = 0…2`.
    ty: [T; 3],
    /// `Σ y²`.
    yy: T,
    found: Option<ReleaseFeatures<T>>,
    rate: T,
}

impl<T: ClearanceFloat> ReleaseDetector<T> {
    /// A detector for samples at `rate` Hz, the first sample at release.
    pub fn new(rate: f64) -> Self {
        let limit = if rate.is_finite() && rate > 0.0 { libm::round(RELEASE_SPAN * rate) as usize } else { 0 };
        let z = T::zero();
        Self {
            step: T::of_f64(1.0 / limit.max(1) as f64),
            limit,
            index: 0,
            k: 0,
            origin: z,
            s: [z; 5],
            ty: [z; 3],
            yy: z,
            found: None,
            rate: T::of_f64(rate),
        }
    }

    /// Adds a sample (rad/s²). A non-finite sample is a missing one: not fitted (the
    /// recording's own counter reports it), but its time passes. After the contact or the
    /// span, samples cost a comparison.
    ///
    /// ```
    /// use edgekf::systems::crank::ReleaseDetector;
    /// // The contact at sample 71, with samples 30 and 50 missing: still seen at 7.1 ms.
    /// let mut d = ReleaseDetector::<f64>::new(10_000.0);
    /// for k in 0..200 {
    ///     let wobble = if k % 2 == 0 { 0.5 } else { -0.5 };
    ///     let x = if k == 71 { 9_000.0 } else { -27.0 + wobble };
    ///     d.push(if k == 30 || k == 50 { f64::NAN } else { x });
    /// }
    /// assert!((d.features().unwrap().contact - 71e-4).abs() < 1e-12);
    /// assert_eq!(d.examined(), 69); // samples fitted: 71 before the contact, 2 missing
    /// ```
    pub fn push(&mut self, x: T) {
        if self.found.is_some() || self.index >= self.limit {
            return;
        }
        let index = self.index;
        self.index = index + 1;
        if !x.is_finite() {
            return;
        }
        let k = self.k;
        if k == 0 {
            self.origin = x;
        }
        let y = x - self.origin;
        let tau = T::of_f64(index as f64) * self.step;
        if k >= MIN_FIT {
            if let Some((beta, sigma)) = self.fit() {
                let n = T::of_f64(k as f64);
                let predicted = beta[0] + tau * (beta[1] + tau * beta[2]);
                let inflate = (T::one() + T::of_f64(9.0) / n).sqrt();
                if (y - predicted).abs() > T::of_f64(THRESHOLD_SIGMAS) * sigma * inflate {
                    let release_alpha = self.origin + self.ty[0] / n;
                    let contact = T::of_f64(index as f64) / self.rate;
                    self.found = Some(ReleaseFeatures { contact, release_alpha });
                    return;
                }
            }
        }
        let t2 = tau * tau;
        let p = [T::one(), tau, t2, t2 * tau, t2 * t2];
        for (s, v) in self.s.iter_mut().zip(p) {
            *s += v;
        }
        for (s, v) in self.ty.iter_mut().zip(p) {
            *s += v * y;
        }
        self.yy += y * y;
        self.k = k + 1;
    }

    /// The quadratic's coefficients and the residual standard deviation (at least
    /// [`MIN_SIGMA`]); `None` if the normal equations are singular.
    fn fit(&self) -> Option<([T; 3], T)> {
        let s = &self.s;
        let (a, b, c, d, e) = (s[0], s[1], s[2], s[3], s[4]);
        // The symmetric 3 × 3 [[a b c] [b c d] [c d e]]: cofactors, determinant, inverse.
        let (c00, c01, c02) = (c * e - d * d, c * d - b * e, b * d - c * c);
        let (c11, c12, c22) = (a * e - c * c, b * c - a * d, a * c - b * b);
        let det = a * c00 + b * c01 + c * c02;
        if det.abs() <= T::zero() || !det.is_finite() {
            return None;
        }
        let r = &self.ty;
        let beta = [
            (c00 * r[0] + c01 * r[1] + c02 * r[2]) / det,
            (c01 * r[0] + c11 * r[1] + c12 * r[2]) / det,
            (c02 * r[0] + c12 * r[1] + c22 * r[2]) / det,
        ];
        let rss = (self.yy - (beta[0] * r[0] + beta[1] * r[1] + beta[2] * r[2])).max(T::zero());
        let sigma = (rss / (a - T::of_f64(3.0))).sqrt().max(T::of_f64(MIN_SIGMA));
        Some((beta, sigma))
    }

    /// The contact, once seen.
    pub fn features(&self) -> Option<ReleaseFeatures<T>> {
        self.found
    }

    /// Samples fitted (the finite ones before the contact, or over the whole span).
    pub fn examined(&self) -> usize {
        self.k
    }
}

/// The regressors of a [`ReleaseModel`] law for features `f` and a pre-contact level centre.
///
/// ```
/// use edgekf::systems::crank::{release_regressors, ReleaseFeatures};
/// let f = ReleaseFeatures { contact: 5e-3f64, release_alpha: -127.0 };
/// let r = release_regressors(&f, -27.0);
/// assert_eq!(r, [1.0, 0.0, -1.0, 1.0, -1.0, 0.0]);
/// ```
pub fn release_regressors<T: ClearanceFloat>(f: &ReleaseFeatures<T>, centre: T) -> [T; RELEASE_TERMS] {
    let l = (f.contact / T::of_f64(5e-3)).ln_m();
    let u = (f.release_alpha - centre) / T::of_f64(100.0);
    [T::one(), l, u, u * u, u * u * u, l * u]
}

/// Per joint and hypothesis, `ln(c / m)` from the release features; learned on the host
/// (`edgekf crank train`), where every training run is labelled with the hypothesis that is
/// true for it.
///
/// Which hypothesis holds is chosen against the window features' clearance `c₀`: the one with
/// the largest `prior − ½ ((ln c_h − ln c₀) / spread)²`, its prior the share of training runs
/// it held for (a missed first contact is rare: about 12 % at A, 1 % at B and 25 % at C; two
/// missed, rarer still), `spread` the window features' own error in `ln c`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReleaseModel<T> {
    /// Largest `|ln c_release − ln c_features|` for which the release law is taken; 0 turns the
    /// stage off.
    pub max_step: T,
    /// Standard deviation of the window features' `ln c` on recordings of `windows` windows.
    pub spread: T,
    /// Windows of the recordings `spread` was measured on. After fewer windows the window
    /// features scatter more, by `√(windows / n)` (their windows' statistics average out), and
    /// `spread` and `max_step` widen by that factor.
    pub windows: T,
    /// Per joint A, B, C: the centre of the pre-contact level, rad/s².
    pub centre: [T; 3],
    /// Per joint A, B, C: the range of pre-contact levels the laws were fitted on, rad/s².
    /// A level outside it means a release the laws do not describe (e.g. a journal already
    /// resting in its bearing at release, where the crank moves as the ideal mechanism's from
    /// the first sample), and the release stage stays out.
    pub level: [[T; 2]; 3],
    /// Per joint A, B, C and hypothesis: the natural logarithm of its prior probability.
    pub prior: [[T; RELEASE_HYPOTHESES]; 3],
    /// Per joint A, B, C and hypothesis: weights on [`release_regressors`].
    pub weights: [[[T; RELEASE_TERMS]; RELEASE_HYPOTHESES]; 3],
}

impl<T: ClearanceFloat> ReleaseModel<T> {
    /// A model that never refines.
    pub fn off() -> Self {
        let z = T::zero();
        Self {
            max_step: z,
            spread: T::one(),
            windows: T::one(),
            centre: [z; 3],
            level: [[z; 2]; 3],
            prior: [[z; RELEASE_HYPOTHESES]; 3],
            weights: [[[z; RELEASE_TERMS]; RELEASE_HYPOTHESES]; 3],
        }
    }

    /// `ln c` of `joint` under each hypothesis.
    pub fn ln_clearances(&self, joint: usize, f: &ReleaseFeatures<T>) -> [T; RELEASE_HYPOTHESES] {
        let r = release_regressors(f, self.centre[joint]);
        self.weights[joint].map(|w| w.iter().zip(r).fold(T::zero(), |s, (w, r)| s + *w * r))
    }

    /// The clearance of `joint` (m) and the hypothesis it came from: the most probable
    /// hypothesis given the window features' clearance `first` after `windows` windows (see
    /// the type's text), if its law is within [`ReleaseModel::max_step`] of `first` in `ln c`
    /// (both widened for fewer windows than [`ReleaseModel::windows`]).
    ///
    /// ```
    /// use edgekf::systems::crank::{ReleaseFeatures, ReleaseModel};
    /// let mut m = ReleaseModel::<f64>::off();
    /// m.max_step = 0.3;
    /// m.spread = 0.1;
    /// // Joint A: ln c = ln 0.25 mm + 2 l (first contact), or ln 0.25 mm + 2 l − 1 (second).
    /// m.weights[0][0][0] = 0.25e-3f64.ln();
    /// m.weights[0][0][1] = 2.0;
    /// m.weights[0][1] = m.weights[0][0];
    /// m.weights[0][1][0] -= 1.0;
    /// m.weights[0][2][0] = 5.0; // laws never near (c = e⁵ m)
    /// m.weights[0][3][0] = 5.0;
    /// m.prior[0] = [0.9f64.ln(), 0.1f64.ln(), -10.0, -10.0];
    /// m.level[0] = [-50.0, 50.0]; // pre-contact levels the laws hold for
    /// let f = ReleaseFeatures { contact: 5e-3, release_alpha: 0.0 };
    /// let (c, h) = m.refine(0, 0.1e-3, &f, 1).unwrap();
    /// assert_eq!(h, 1);
    /// assert!((c - 0.25e-3 * (-1.0f64).exp()).abs() < 1e-12);
    /// assert!(m.refine(0, 1e-3, &f, 1).is_none()); // no law near 1 mm
    /// m.windows = 100.0; // after 1 of 100 windows, steps up to 10 × 0.3 are taken
    /// assert_eq!(m.refine(0, 1e-3, &f, 1).map(|(_, h)| h), Some(0));
    /// let resting = ReleaseFeatures { contact: 5e-3, release_alpha: -160.0 };
    /// assert!(m.refine(0, 0.1e-3, &resting, 1).is_none()); // a level the laws never saw
    /// ```
    pub fn refine(&self, joint: usize, first: T, f: &ReleaseFeatures<T>, windows: u32) -> Option<(T, usize)> {
        if !(self.max_step > T::zero() && self.spread > T::zero()) || joint >= 3 {
            return None;
        }
        let [lo, hi] = self.level[joint];
        if !(f.release_alpha >= lo && f.release_alpha <= hi) {
            return None;
        }
        let widen = (self.windows / T::of_f64(f64::from(windows.max(1)))).max(T::one()).sqrt();
        let (spread, max_step) = (self.spread * widen, self.max_step * widen);
        let target = first.ln_m();
        let laws = self.ln_clearances(joint, f);
        let mut best: Option<(T, usize)> = None;
        for (h, &l) in laws.iter().enumerate() {
            let z = (l - target) / spread;
            let score = self.prior[joint][h] - T::of_f64(0.5) * z * z;
            if score.is_finite() && best.is_none_or(|(s, _)| score > s) {
                best = Some((score, h));
            }
        }
        let (_, h) = best?;
        ((laws[h] - target).abs() <= max_step).then(|| (laws[h].exp_m(), h))
    }
}
