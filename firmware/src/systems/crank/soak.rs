//! The soak of the crank's clearance estimator. It is not a Kalman filter: what can degrade
//! over a long run is its streaming sums in `f32` (the window's power sums about a running
//! shift, the recording's running means). So the soak feeds it a long synthetic crank
//! acceleration whose speed, and whose impacts' amplitude, drift slowly, and checks that every
//! window's estimate is finite and within the model's range, that a late window gives the
//! statistics a fresh estimator gives on the same samples, and that the recording's features
//! (`f32` running means) stay with the same means accumulated in `f64`.

use super::CrankImage;
use crate::hil::HilImage;
use super::{Storage, MODEL, SAMPLE_RATE_HZ, WINDOW};
use crate::soak::engine::{Blocks, Drift, Noise, SoakFrame, SoakRow};
use edgekf::systems::crank::{ClearanceEstimator, CrankFeatures, CLEARANCE_RANGE, FEATURES};

/// Its rows.
pub const SOAKS: &[SoakRow] = &[CRANK];

/// The clearance estimator's row.
pub const CRANK: SoakRow = SoakRow {
    name: "crank",
    system: "crank",
    image: Some(CrankImage::NAME),
    what: "clearance estimator (window sums, 10 kHz, 0.25 s windows)",
    drift: "crank speed 10 Hz ±20 % over 15 min, impact amplitude ±30 % over 10 min",
    error_of: "a late window's statistics against a fresh estimator's",
    host_steps: 1_000_000,
    qemu_steps: 200_000,
    qemu_long_steps: 40_000_000,
    nis_limit: None,
    error_limit: 1e-3,
    run: crank,
};

/// Windows between the checks against a fresh estimator (10 s).
const CHECK_EVERY: u32 = 40;

/// Samples of an impact's ringing.
const RING: usize = 24;

/// A crank's angular acceleration at 10 kHz: two harmonics of the crank angle, white noise,
/// and two impacts a revolution (at the angles 0 and π, as a loose joint's contacts), each a
/// short decaying ringing. Copy it to replay a stretch.
#[derive(Clone, Copy)]
struct CrankSignal {
    noise: Noise,
    /// `cos θ, sin θ` of the crank angle.
    phasor: (f32, f32),
    /// `cos, sin` of the angle a sample turns, drifting.
    turn: (Drift, Drift),
    amplitude: Drift,
    ring: [f32; RING],
    /// The impact ringing now: its sample and size.
    impact: (usize, f32),
    k: u32,
}

impl CrankSignal {
    fn new() -> Self {
        let dt = 1.0 / f64::from(SAMPLE_RATE_HZ);
        let ring = core::array::from_fn(|j| {
            let j = j as f32;
            libm::expf(-j / 4.0) * libm::sinf(1.9 * j + 0.3)
        });
        Self {
            noise: Noise(0x50A4_0004),
            phasor: (1.0, 0.0),
            turn: (Drift::new(dt), Drift::new(dt)),
            amplitude: Drift::new(dt),
            ring,
            impact: (RING, 0.0),
            k: 0,
        }
    }

    /// The next sample, rad/s².
    fn next(&mut self) -> f32 {
        let k = self.k;
        self.k = k.wrapping_add(1);
        // 10 rev/s ±20 % over 15 minutes.
        let step =
            |t: f64| core::f64::consts::TAU * 10.0 * crate::soak::engine::swing(t, 0.2, 900.0) / f64::from(SAMPLE_RATE_HZ);
        let (cd, sd) = (self.turn.0.at(k, |t| libm::cos(step(t))), self.turn.1.at(k, |t| libm::sin(step(t))));
        let (c, s) = self.phasor;
        let (c1, s1) = (c * cd - s * sd, s * cd + c * sd);
        let g = 1.5 - 0.5 * (c1 * c1 + s1 * s1);
        self.phasor = (c1 * g, s1 * g);
        let size = 2000.0 * self.amplitude.at(k, |t| crate::soak::engine::swing(t, 0.3, 600.0));
        if s < 0.0 && s1 >= 0.0 && c1 > 0.0 {
            self.impact = (0, size);
        } else if s > 0.0 && s1 <= 0.0 && c1 < 0.0 {
            self.impact = (0, 0.6 * size);
        }
        let (j, a) = self.impact;
        let ringing = self.ring.get(j).map_or(0.0, |r| a * r);
        self.impact.0 = j.saturating_add(1);
        200.0 * s1 + 160.0 * s1 * c1 + ringing + 5.0 * self.noise.unit()
    }
}

/// The largest difference of `a` from `b`, relative to `b`'s size.
fn relative(a: &[f32; FEATURES], b: &[f32; FEATURES]) -> f32 {
    a.iter().zip(b).fold(0.0f32, |m, (x, y)| m.max((x - y).abs() / y.abs().max(1e-6)))
}

/// The soak (see the module docs); `n` samples.
#[inline(never)]
pub fn crank(n: u32) -> SoakFrame {
    let mut storage: Storage = [0.0; WINDOW - 1];
    let mut fresh_storage: Storage = [0.0; WINDOW - 1];
    let rate = f64::from(SAMPLE_RATE_HZ);
    let Ok(mut est) = ClearanceEstimator::new(&MODEL, &mut storage, rate) else { return crate::soak::engine::not_started(n) };
    let mut signal = CrankSignal::new();
    let mut window_start = signal;
    let mut blocks = Blocks::new(n, 1.0);
    let mut means = [0.0f64; FEATURES];
    let (lo, hi) = (CLEARANCE_RANGE.0 as f32, CLEARANCE_RANGE.1 as f32);
    for _ in 0..n {
        let alpha = signal.next();
        let Some(e) = est.push(alpha) else { continue };
        let f = est.features();
        let windows = f.windows();
        let finite = e.scores.iter().chain(&e.per_joint).chain(&f.features()).all(|v| v.is_finite());
        if !finite {
            blocks.non_finite();
        }
        if e.joint >= 3 || !(e.clearance >= lo && e.clearance <= hi) {
            blocks.out_of_bounds();
        }
        // The recording's features against the same means in `f64`.
        let last = f.last_window();
        let ln: [f32; FEATURES] = core::array::from_fn(|i| {
            let m = means.get_mut(i);
            let v = f64::from(last.get(i).copied().unwrap_or(0.0));
            let sum = m.map_or(0.0, |m| {
                *m += v;
                *m
            });
            libm::log((sum / f64::from(windows.max(1))).max(1e-12)) as f32
        });
        let drift = f.features().iter().zip(&ln).fold(0.0f32, |m, (a, b)| m.max((a - b).abs()));
        blocks.drift(drift);
        // A late window against a fresh estimator on the same samples.
        if windows % CHECK_EVERY == 0 {
            let mut replay = window_start;
            if let Ok(mut fresh) = CrankFeatures::new(&mut fresh_storage, WINDOW, rate as f32) {
                let mut done = false;
                for _ in 0..WINDOW {
                    done = fresh.push(replay.next());
                }
                if done {
                    blocks.error(relative(&last, &fresh.last_window()));
                    blocks.close_check();
                } else {
                    blocks.non_finite();
                }
            }
        }
        window_start = signal;
    }
    blocks.finish(Default::default())
}
