//! The reduced boom's pieces between re-reductions: linearised in length and angle around the
//! last reduction ([`Linearised`]), and discretised exactly over one sample ([`Discrete`]).

use super::{ModelSettings, RECENTRE, STEP, VALUES};
use crate::systems::boom::reduced::{BoomConstants, ReducedBoom, ReducedError, MODES};
use crate::Real;

/// The reduced boom at one length and angle with its gradients in both.
#[derive(Debug, Clone, Copy)]
pub(super) struct Linearised {
    pub(super) length: f64,
    pub(super) angle: f64,
    pub(super) values: [f64; VALUES],
    pub(super) per_length: [f64; VALUES],
    pub(super) per_angle: [f64; VALUES],
}

fn flatten(r: &ReducedBoom) -> [f64; VALUES] {
    let mut v = [0.0; VALUES];
    for (i, m) in r.modes.iter().enumerate() {
        v[4 * i..4 * i + 4].copy_from_slice(&[m.omega, m.tip_deflection, m.tip_slope, m.participation]);
    }
    v[4 * MODES] = r.sag.0;
    v[4 * MODES + 1] = r.sag.1;
    v
}

impl Linearised {
    pub(super) fn new(c: &BoomConstants, length: f64, angle: f64) -> Result<Self, ReducedError> {
        let values = flatten(&c.reduce(length, angle)?);
        // Towards the retracted length (always buildable) and up or down, whichever stays in
        // the range a boom luffs through.
        let dl = if length > STEP.0 { -STEP.0 } else { STEP.0 };
        let da = if angle > 0.0 { -STEP.1 } else { STEP.1 };
        let by_l = flatten(&c.reduce(length + dl, angle)?);
        let by_a = flatten(&c.reduce(length, angle + da)?);
        let per_length = core::array::from_fn(|i| (by_l[i] - values[i]) / dl);
        let per_angle = core::array::from_fn(|i| (by_a[i] - values[i]) / da);
        Ok(Self { length, angle, values, per_length, per_angle })
    }

    pub(super) fn covers(&self, length: f64, angle: f64) -> bool {
        (length - self.length).abs() <= RECENTRE.0 && (angle - self.angle).abs() <= RECENTRE.1
    }

    pub(super) fn at(&self, length: f64, angle: f64) -> [f64; VALUES] {
        let (dl, da) = (length - self.length, angle - self.angle);
        core::array::from_fn(|i| self.values[i] + self.per_length[i] * dl + self.per_angle[i] * da)
    }
}

/// The exact discrete pieces at one length and angle, in the filter's precision.
#[derive(Debug, Clone, Copy)]
pub(super) struct Discrete<T> {
    pub(super) length: f64,
    pub(super) angle: f64,
    /// Each mode's transition `[[φ11, φ12], [φ21, φ22]]` and its response to a unit luffing
    /// acceleration held over the sample (already times `−p`).
    pub(super) modes: [([[T; 2]; 2], [T; 2]); MODES],
    /// Each mode's tip deflection and slope per unit coordinate.
    pub(super) tip: [(T, T); MODES],
    /// The sag's tip slope's change per rad of luffing and per m of length.
    pub(super) sag_slope_rate: (T, T),
}

/// The exact transition over `dt` of `η̈ + 2ζω η̇ + ω² η = 0` (`ζ < 1`).
pub(super) fn transition(w: f64, zeta: f64, dt: f64) -> [[f64; 2]; 2] {
    let (sigma, wd) = (zeta * w, w * libm::sqrt(1.0 - zeta * zeta));
    let e = libm::exp(-sigma * dt);
    let (s, c) = libm::sincos(wd * dt);
    [[e * (c + sigma / wd * s), e * s / wd], [-e * w * w / wd * s, e * (c - sigma / wd * s)]]
}

pub(super) fn discretise<T: Real>(
    values: &[f64; VALUES],
    lin: &Linearised,
    settings: &ModelSettings,
    length: f64,
    angle: f64,
) -> Discrete<T> {
    let dt = settings.dt;
    let t = T::of_f64;
    // Rayleigh's ζ(ω) = (a/ω + b ω)/2 through the two declared ζ.
    let (w1, w2) = (values[0].max(1e-6), values[4].max(2e-6));
    let [z1, z2] = settings.zeta;
    let b = 2.0 * (z2 * w2 - z1 * w1) / (w2 * w2 - w1 * w1);
    let a = 2.0 * z1 * w1 - b * w1 * w1;
    let modes = core::array::from_fn(|i| {
        let (w, p) = (values[4 * i].max(1e-6), values[4 * i + 3]);
        let zeta = match i {
            0 => z1,
            1 => z2,
            _ => 0.5 * (a / w + b * w),
        };
        let zeta = if zeta.is_finite() { zeta.clamp(0.0, 0.99) } else { z2.clamp(0.0, 0.99) };
        let [[f11, f12], [f21, f22]] = transition(w, zeta, dt);
        // A unit acceleration held over dt: η = (1 − φ11)/ω², η̇ = φ12; the load is −p φ̈.
        let g = [(1.0 - f11) / (w * w) * -p, f12 * -p];
        ([[t(f11), t(f12)], [t(f21), t(f22)]], [t(g[0]), t(g[1])])
    });
    let tip = core::array::from_fn(|i| (t(values[4 * i + 1]), t(values[4 * i + 2])));
    let s = 4 * MODES + 1;
    Discrete { length, angle, modes, tip, sag_slope_rate: (t(lin.per_angle[s]), t(lin.per_length[s])) }
}
