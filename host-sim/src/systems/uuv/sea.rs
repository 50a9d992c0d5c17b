//! The ocean current: a mean drawn per seed plus three slow oscillations per component, smooth
//! so its rate (which the reference's added mass feels) is exact.

use super::config::CurrentConfig;
use rand::Rng;

/// A current over ground, north and east.
///
/// ```
/// use edgekf_sim::systems::uuv::{sea::Current, config::CurrentConfig};
/// use rand::SeedableRng;
/// let c = Current::draw(&CurrentConfig::default(), &mut rand_chacha::ChaCha8Rng::seed_from_u64(1));
/// for t in [0.0, 60.0, 300.0] {
///     let [n, e] = c.at(t);
///     let speed = n.hypot(e);
///     assert!((0.0..=0.4).contains(&speed), "{speed}");
/// }
/// ```
#[derive(Debug, Clone)]
pub struct Current {
    mean: [f64; 2],
    /// (amplitude, angular frequency, phase) per component.
    waves: [[(f64, f64, f64); 3]; 2],
}

impl Current {
    /// A current drawn from `config`.
    pub fn draw(config: &CurrentConfig, rng: &mut impl Rng) -> Self {
        let speed = config.speed[0] + (config.speed[1] - config.speed[0]) * rng.gen::<f64>();
        let heading = std::f64::consts::TAU * rng.gen::<f64>();
        let mut waves = [[(0.0, 0.0, 0.0); 3]; 2];
        for component in &mut waves {
            for w in component.iter_mut() {
                let period = config.periods[0] + (config.periods[1] - config.periods[0]) * rng.gen::<f64>();
                // Three waves of a third of the amplitude each: their sum stays within ±variation.
                *w = (config.variation / 3.0, std::f64::consts::TAU / period, std::f64::consts::TAU * rng.gen::<f64>());
            }
        }
        Self { mean: [speed * heading.cos(), speed * heading.sin()], waves }
    }

    /// No current.
    pub fn still() -> Self {
        Self { mean: [0.0; 2], waves: [[(0.0, 0.0, 0.0); 3]; 2] }
    }

    /// The current at `t`, m/s.
    pub fn at(&self, t: f64) -> [f64; 2] {
        let mut c = self.mean;
        for (ci, waves) in c.iter_mut().zip(&self.waves) {
            *ci += waves.iter().map(|(a, w, p)| a * (w * t + p).sin()).sum::<f64>();
        }
        c
    }

    /// Its rate at `t`, m/s².
    pub fn rate(&self, t: f64) -> [f64; 2] {
        let mut d = [0.0; 2];
        for (di, waves) in d.iter_mut().zip(&self.waves) {
            *di = waves.iter().map(|(a, w, p)| a * w * (w * t + p).cos()).sum::<f64>();
        }
        d
    }
}
