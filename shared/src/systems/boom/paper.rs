//! The paper's method, as the paper gives it, one sample at a time:
//!
//! 1. the gyro less its static bias, through a 2-state Kalman filter whose state is the AR(2)
//!    process identified at rest (`X = [y_k, y_{k−1}]`, `C = [1 0]`);
//! 2. Simpson's rule on the filtered rate to the tip angle;
//! 3. fusion with the inclinometer at the equilibrium instants: the boom is taken to be straight
//!    where the gyro's rate less the boom's own luffing rate (from the inclinometer) peaks, once
//!    a half-cycle, and the integrated angle is reset to the inclinometer's there (on the chip,
//!    once the half-cycle is over: the offset at its peak is taken out from then on);
//! 4. the deflection `y = α l (θ_tip − θ_root)`, `α = 2/3` from a cantilever with a tip load;
//! 5. a moving average.
//!
//! Where it breaks on a realistic boom is the point of reproducing it: the AR filter treats the
//! vibration as noise, the straight-boom assumption ignores the sag's slope, the lagged
//! inclinometer is read as the root's angle, and `α` holds for a tip load only.

use super::ar::Ar2;
use crate::Real;

/// Longest moving average, samples.
pub const SMOOTHING_MAX: usize = 64;
/// Samples over which the boom's own luffing rate is read from the inclinometer.
const ROOT_WINDOW: usize = 10;

/// The method's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PaperSettings {
    /// Sample interval, s.
    pub dt: f64,
    /// The gyro noise's AR(2) model and bias, from the static record.
    pub ar: Ar2,
    /// Standard deviation of the filter's measurement noise, rad/s (the paper gives none; the
    /// AR's driving noise by default).
    pub measurement_noise: f64,
    /// The gyro's declared scale factor.
    pub scale: f64,
    /// `α` of `y = α l θ`.
    pub alpha: f64,
    /// Moving-average length, samples (1 to [`SMOOTHING_MAX`]).
    pub smoothing: usize,
    /// Relative rate a pass through equilibrium must reach, rad/s (below it the boom is at rest
    /// and nothing is fused).
    pub fusion_threshold: f64,
    /// Whether the gyro goes through the AR filter (step 1; off for the ablation).
    pub ar_filter: bool,
}

impl PaperSettings {
    /// The paper's choices at `dt` with `ar` from the static record: `α = 2/3`, a 0.1 s moving
    /// average, fusion above 0.01 rad/s.
    pub fn new(dt: f64, ar: Ar2, scale: f64) -> Self {
        let smoothing = (libm::round(0.1 / dt) as usize).clamp(1, SMOOTHING_MAX);
        Self {
            dt,
            ar,
            measurement_noise: ar.sigma,
            scale,
            alpha: 2.0 / 3.0,
            smoothing,
            fusion_threshold: 0.01,
            ar_filter: true,
        }
    }
}

/// One sample's output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PaperEstimate<T> {
    /// The tip's angle from the horizontal, rad.
    pub tip_angle: T,
    /// The tip's vibration, m (smoothed `α l (θ_tip − θ_root)`).
    pub vibration: T,
    /// Whether this sample was an equilibrium instant (a fusion).
    pub fused: bool,
}

/// The paper's estimator.
///
/// ```
/// use edgekf::systems::boom::{Ar2, PaperEstimator, PaperSettings};
/// let ar = Ar2 { a: [-0.6538, 0.06745], sigma: 3e-4, mean: 0.002 };
/// let mut est = PaperEstimator::<f32>::new(&PaperSettings::new(0.01, ar, 1.0));
/// // A boom at rest, straight at 0.5 rad: the tip angle stays there, no vibration.
/// let mut last = None;
/// for _ in 0..500 { last = Some(est.step(0.002, 0.5, 30.0)); }
/// let e = last.unwrap();
/// assert!((e.tip_angle - 0.5).abs() < 1e-4 && e.vibration.abs() < 1e-3);
/// ```
#[derive(Debug, Clone)]
pub struct PaperEstimator<T: Real> {
    settings: PaperSettings,
    /// AR state estimate and covariance.
    x: [T; 2],
    p: [[T; 2]; 2],
    /// Filtered rates at k−1, k−2 and angles at k−1, k−2 (Simpson's two chains).
    rate: [T; 2],
    angle: [T; 2],
    /// The last `ROOT_WINDOW + 1` inclinometer readings (ring) and how many there are.
    incl: [T; ROOT_WINDOW + 1],
    /// Sign of the current half-cycle of the relative rate (0: none yet).
    swing: i8,
    /// In the current half-cycle, the largest |relative rate| so far, and the inclinometer's
    /// and the integrated angle there.
    best: [T; 3],
    /// Moving-average ring of the deflection and its running sum.
    ring: [T; SMOOTHING_MAX],
    sum: T,
    k: usize,
}

impl<T: Real> PaperEstimator<T> {
    /// An estimator that starts at its first sample.
    pub fn new(settings: &PaperSettings) -> Self {
        let z = T::zero();
        let s = settings.ar.sigma;
        let var = T::of_f64(2.0 * s * s);
        Self {
            settings: PaperSettings { smoothing: settings.smoothing.clamp(1, SMOOTHING_MAX), ..*settings },
            x: [z; 2],
            p: [[var, z], [z, var]],
            rate: [z; 2],
            angle: [z; 2],
            incl: [z; ROOT_WINDOW + 1],
            swing: 0,
            best: [z; 3],
            ring: [z; SMOOTHING_MAX],
            sum: z,
            k: 0,
        }
    }

    /// The AR filter's step on the gyro reading less its bias; the filtered rate.
    fn filter(&mut self, z: T) -> T {
        let t = T::of_f64;
        let [a1, a2] = self.settings.ar.a.map(t);
        let q = t(self.settings.ar.sigma * self.settings.ar.sigma);
        let r = t(self.settings.measurement_noise * self.settings.measurement_noise);
        // x⁻ = A x, P⁻ = A P Aᵀ + Q, A = [[a1, a2], [1, 0]], Q = diag(q, 0).
        let xp = [a1 * self.x[0] + a2 * self.x[1], self.x[0]];
        let p = self.p;
        let ap = [[a1 * p[0][0] + a2 * p[1][0], a1 * p[0][1] + a2 * p[1][1]], [p[0][0], p[0][1]]];
        let pp = [[ap[0][0] * a1 + ap[0][1] * a2 + q, ap[0][0]], [ap[1][0] * a1 + ap[1][1] * a2, ap[1][0]]];
        let s = pp[0][0] + r;
        let gain = [pp[0][0] / s, pp[1][0] / s];
        let e = z - xp[0];
        self.x = [xp[0] + gain[0] * e, xp[1] + gain[1] * e];
        self.p = [
            [pp[0][0] - gain[0] * pp[0][0], pp[0][1] - gain[0] * pp[0][1]],
            [pp[1][0] - gain[1] * pp[0][0], pp[1][1] - gain[1] * pp[0][1]],
        ];
        self.x[0]
    }

    /// Takes one sample: the gyro's rate (rad/s), the inclinometer's angle (rad) and the boom's
    /// length (m). A non-finite reading holds the last value of its channel.
    pub fn step(&mut self, gyro: T, incl: T, length: T) -> PaperEstimate<T> {
        self.step_with(gyro, incl, length, T::of_f64(self.settings.alpha))
    }

    /// [`step`](Self::step) with `alpha` for this sample in place of the settings' (the ablation
    /// gives it the mode shape's ratio at the current length).
    pub fn step_with(&mut self, gyro: T, incl: T, length: T, alpha: T) -> PaperEstimate<T> {
        let t = T::of_f64;
        let dt = t(self.settings.dt);
        let last_incl = self.incl[(self.k + ROOT_WINDOW) % (ROOT_WINDOW + 1)];
        let incl = if incl.is_finite() || self.k == 0 { incl } else { last_incl };
        let z = if gyro.is_finite() { gyro / t(self.settings.scale) - t(self.settings.ar.mean) } else { self.rate[0] };
        let rate = if self.settings.ar_filter { self.filter(z) } else { z };
        let slot = self.k % (ROOT_WINDOW + 1);
        if self.k == 0 {
            self.incl = [incl; ROOT_WINDOW + 1];
            self.angle = [incl; 2];
            self.rate = [rate; 2];
        }
        self.incl[slot] = incl;
        // Simpson over the last two intervals (the trapezoid for the first).
        let mut angle = if self.k < 2 {
            self.angle[0] + dt * t(0.5) * (self.rate[0] + rate)
        } else {
            self.angle[1] + dt / t(3.0) * (self.rate[1] + t(4.0) * self.rate[0] + rate)
        };
        // The boom's own luffing rate over the root window.
        let oldest = self.incl[(self.k + 1) % (ROOT_WINDOW + 1)];
        let span = (self.k.min(ROOT_WINDOW)) as f64;
        let root_rate = if span > 0.0 { (incl - oldest) / (dt * t(span)) } else { T::zero() };
        let relative = rate - root_rate;
        // The equilibrium instant of a half-cycle is where |relative| peaked in it; it is known
        // when the next half-cycle begins (the relative rate past the threshold the other way),
        // and the integrated angle is then shifted by the offset it had there.
        let threshold = t(self.settings.fusion_threshold);
        let sign: i8 = if relative > threshold {
            1
        } else if relative < -threshold {
            -1
        } else {
            0
        };
        let mut fused = false;
        if sign != 0 && sign != self.swing {
            if self.swing != 0 {
                let correction = self.best[1] - self.best[2];
                angle += correction;
                self.angle[0] += correction;
                fused = true;
            }
            self.swing = sign;
            self.best = [relative.abs(), incl, angle];
        } else if sign == self.swing && relative.abs() > self.best[0] {
            self.best = [relative.abs(), incl, angle];
        }
        self.rate = [rate, self.rate[0]];
        self.angle = [angle, self.angle[0]];
        // y = α l (θ_tip − θ_root), smoothed.
        let y = alpha * length * (angle - incl);
        let n = self.settings.smoothing.max(1);
        if let Some(slot) = self.ring.get_mut(self.k % n) {
            self.sum = self.sum - *slot + y;
            *slot = y;
        }
        self.k += 1;
        let count = self.k.min(n);
        PaperEstimate { tip_angle: angle, vibration: self.sum / t(count as f64), fused }
    }
}
