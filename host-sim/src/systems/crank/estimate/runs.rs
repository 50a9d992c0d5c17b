//! The simulated runs a fit trains on: one clearance at one joint, a release angle, a journal
//! radius and a noise seed, and the grids of them. Kept apart from [`super::train`] so that the
//! release laws ([`super::release`]) can read runs without depending on the fits that use them.

use super::Recording;
use crate::systems::crank::config::Method;
use crate::systems::crank::{CrankConfig, Joint, Mechanism, SimOptions};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One simulated run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Run {
    /// The joint with the clearance.
    pub joint: Joint,
    /// Its clearance, m.
    pub clearance: f64,
    /// Release angle, degrees.
    pub release_deg: f64,
    /// Journal radius factor (× the configured radius).
    pub radius: f64,
    /// Noise seed.
    pub seed: u64,
    /// Length, s.
    pub duration: f64,
}

impl std::fmt::Display for Run {
    /// `A 0.300 mm (release 30.0°, radius ×1.00, seed 7)`: how a run is named in reports.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} {:.3} mm (release {:.1}°, radius ×{:.2}, seed {})",
            self.joint,
            self.clearance * 1e3,
            self.release_deg,
            self.radius,
            self.seed
        )
    }
}

impl Run {
    /// The recording of this run from `base` (adaptive integrator).
    pub fn simulate(&self, base: &CrankConfig) -> anyhow::Result<Recording> {
        self.simulate_with_eccentricity(base).map(|(r, _)| r)
    }

    /// The recording and the sampled journal eccentricity (m) of the clearance joint.
    pub fn simulate_with_eccentricity(&self, base: &CrankConfig) -> anyhow::Result<(Recording, Vec<f64>)> {
        let mut cfg = *base;
        cfg.release.crank_angle_deg = self.release_deg;
        cfg.contact.journal_radius *= self.radius;
        for r in
            [&mut cfg.contact.journal_radius_a, &mut cfg.contact.journal_radius_b, &mut cfg.contact.journal_radius_c]
                .into_iter()
                .flatten()
        {
            *r *= self.radius;
        }
        cfg.integrator.method = Method::Adaptive;
        let mut c = [None; 3];
        c[self.joint.index()] = Some(self.clearance);
        let m = Mechanism::new(&cfg, c)?;
        let mut rec = m.simulate(&SimOptions { seed: self.seed, ..SimOptions::from_config(&cfg, self.duration) })?;
        let e = std::mem::take(&mut rec.truth_eccentricity[self.joint.index()]);
        Ok((Recording::from_simulation(&rec, cfg.sensor.sample_rate), e))
    }
}

/// Release angles the grids draw from, degrees.
pub const RELEASE_RANGE_DEG: [f64; 2] = [20.0, 40.0];

/// Factors on the journal radius the grids draw from.
pub const RADIUS_RANGE: [f64; 2] = [0.8, 1.2];

/// A grid: every joint × every clearance × `variants` random (release 20–40°, journal radius
/// × 0.8–1.2) draws, noise seeds `seed_base + i`; the draws come from `seed_base` too, so
/// training and test grids with different bases share no seed.
pub fn grid(clearances: &[f64], variants: usize, seed_base: u64, duration: f64) -> Vec<Run> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed_base);
    let mut runs = Vec::new();
    let mut i = 0;
    for joint in Joint::ALL {
        for &c in clearances {
            for _ in 0..variants {
                runs.push(Run {
                    joint,
                    clearance: c,
                    release_deg: rng.gen_range(RELEASE_RANGE_DEG[0]..RELEASE_RANGE_DEG[1]),
                    radius: rng.gen_range(RADIUS_RANGE[0]..RADIUS_RANGE[1]),
                    seed: seed_base + i,
                    duration,
                });
                i += 1;
            }
        }
    }
    runs
}
