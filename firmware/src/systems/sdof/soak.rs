//! The soak of the mount's 2-state filter as its node runs it.

use super::{params, SdofImage};
use crate::hil::HilImage;
use crate::soak::engine::{not_started, psd_root, swing, Blocks, Drift, Noise, SoakFrame, SoakRow};
use edgekf::systems::sdof::{SdofEstimator, SdofParams};
use nalgebra::Vector2;

/// Steps per block of statistics.
const BLOCK: u32 = 10_000;

/// Its rows.
pub const SOAKS: &[SoakRow] = &[SDOF];

/// The mount's Kalman filter, time-varying gain, in `f32`.
pub const SDOF: SoakRow = SoakRow {
    name: "sdof",
    system: "sdof",
    image: Some(SdofImage::NAME),
    what: "mount KF, 2 states (sdof, a test system)",
    drift: "base density 0.6–1.0× the tuning over 10 min, natural frequency ±0.3 % over 20 min",
    error_of: "relative displacement",
    host_steps: 1_000_000,
    qemu_steps: 50_000,
    qemu_long_steps: 5_000_000,
    nis_limit: Some(1.3),
    error_limit: 0.01,
    run: sdof,
};

/// The node's filter in `f32` on its own model whose base shaking swings between 0.6 and 1.0
/// times its tuned density over 10 minutes (more than the tuning would raise the NIS above the
/// row's limit by design, not by arithmetic), while the mount's true natural
/// frequency drifts by ±0.3 % over 20 minutes (the displacement read from the spring errs by
/// twice that) (the truth re-discretised
/// every block); the accelerometer reads it with the ADXL355's noise. The covariance is
/// checked at every block's end.
#[inline(never)]
pub fn sdof(n: u32) -> SoakFrame {
    let p = params();
    let Ok(mut est) = SdofEstimator::<f32>::new(&p) else { return not_started(n) };
    let fs = p.sample_rate_hz;
    let truth_at = |k: u32| {
        let t = f64::from(k) / fs;
        let hz = p.natural_freq_hz * swing(t, 0.003, 1200.0);
        let m = SdofParams { natural_freq_hz: hz, ..p }.discrete_model().ok()?;
        // The truth's scaled state is `ωt² z` at its own drifted `ωt`: `ωn²/ωt²` turns it into
        // a displacement at the filter's `ωn²`.
        let rescale = (p.natural_freq_hz / hz) * (p.natural_freq_hz / hz);
        Some((m.a.cast::<f32>(), m.c.cast::<f32>(), psd_root(&m.q).cast::<f32>(), rescale))
    };
    let Some((mut a, mut c, mut q, mut rescale)) = truth_at(0) else { return not_started(n) };
    let sd = p.accel_noise_std as f32;
    let wn2 = (p.omega_n() * p.omega_n()) as f32;
    let mut shaking = Drift::new(1.0 / fs);
    let mut x = Vector2::<f32>::zeros();
    let mut noise = Noise(0x5D0F_0001);
    let mut blocks = Blocks::new(n, 1.0);
    for k in 0..n {
        let y = (c * x)[0] + sd * noise.unit();
        let s = est.step(Some(y));
        let nis = s.nis.unwrap_or(f32::NAN);
        if !(s.displacement.is_finite() && s.velocity.is_finite() && nis.is_finite()) {
            blocks.non_finite();
        }
        // The truth's displacement: its scaled state over its own ωn², here `x₀ rescale / ωn²`.
        let truth = x[0] * rescale as f32 / wn2;
        let e = f64::from(s.displacement) - f64::from(truth);
        blocks.push(nis, e * e, f64::from(truth) * f64::from(truth));
        let size = libm::sqrtf(shaking.at(k, |t| 0.8 * swing(t, 0.25, 600.0)));
        x = a * x + q * noise.vector::<2>() * size;
        if (k + 1) % BLOCK == 0 {
            blocks.close();
            blocks.covariance(est.kalman().covariance());
            if let Some(m) = truth_at(k + 1) {
                (a, c, q, rescale) = m;
            }
        }
    }
    blocks.finish(est.counters().filter)
}

#[cfg(test)]
mod tests {
    /// A short soak (20 blocks) within the row's limits: the full row runs in
    /// `tests/tests/soak.rs` and in QEMU.
    #[test]
    fn a_short_soak_is_sound() {
        let f = super::sdof(200_000);
        std::eprintln!("sdof soak, 2e5 steps: {f:?}");
        assert_eq!((f.steps, f.blocks, f.non_finite, f.not_positive_definite), (200_000, 19, 0, 0));
        assert_eq!((f.covariance_resets, f.refused_updates), (0, 0));
        assert!(f.worst_nis < 1.3 && f.worst_nis > 0.7, "{f:?}");
        assert!(f.worst_error < super::SDOF.error_limit, "{f:?}");
    }
}
