//! The soaks of the oscillator's harmonic-force filter, time-varying and with the
//! steady-state gain its node runs.

use super::OscillatorImage;
use crate::hil::HilImage;
use crate::soak::engine::{not_started, psd_root, swing, Blocks, Drift, Noise, SoakFrame, SoakRow};
use edgekf::systems::oscillator::{GainMode, HarmonicForceEstimator, HarmonicForceParams};
use nalgebra::Vector4;

/// Steps per block of statistics.
const BLOCK: u32 = 10_000;

/// Its rows.
pub const SOAKS: &[SoakRow] = &[OSCILLATOR_VARYING, OSCILLATOR_STEADY];

/// The harmonic-force estimator, time-varying gain.
pub const OSCILLATOR_VARYING: SoakRow = SoakRow {
    name: "oscillator_varying",
    system: "oscillator",
    image: Some(OscillatorImage::NAME),
    what: "harmonic-force KF, time-varying (oscillator)",
    drift: "force 0.5–1.5 N over 10 min, mode frequency ±0.3 % over 20 min",
    error_of: "force amplitude",
    host_steps: 1_000_000,
    qemu_steps: 30_000,
    qemu_long_steps: 1_500_000,
    nis_limit: Some(1.3),
    error_limit: 0.05,
    run: |n| oscillator(GainMode::TimeVarying, n),
};

/// The harmonic-force estimator as the oscillator node runs it, steady-state gain.
pub const OSCILLATOR_STEADY: SoakRow = SoakRow {
    name: "oscillator_steady",
    what: "harmonic-force, steady-state gain (oscillator node)",
    qemu_long_steps: 2_000_000,
    run: |n| oscillator(GainMode::SteadyState, n),
    ..OSCILLATOR_VARYING
};

/// The harmonic-force estimator in `f32` over a 20 Hz mode driven at 14 Hz by a force whose
/// amplitude swings between 0.5 and 1.5 N over 10 minutes, while the mode's true frequency
/// drifts by ±0.3 % over 20 minutes (the truth re-discretised every block); the accelerometer
/// reads it with the ADXL355's noise. The time-varying filter's covariance is checked at every
/// block's end.
#[inline(never)]
pub fn oscillator(gain: GainMode, n: u32) -> SoakFrame {
    let p = HarmonicForceParams { gain, ..HarmonicForceParams::default() };
    let Ok(mut est) = HarmonicForceEstimator::<f32>::new(&p) else { return not_started(n) };
    let fs = p.sample_rate_hz;
    let truth_at = |k: u32| {
        let t = f64::from(k) / fs;
        let hz = p.natural_freq_hz * swing(t, 0.003, 1200.0);
        let m = HarmonicForceParams { natural_freq_hz: hz, ..p }.discrete_model().ok()?;
        Some((m.a.cast::<f32>(), m.c.cast::<f32>(), psd_root(&m.q).cast::<f32>()))
    };
    let Some((mut a, mut c, mut q)) = truth_at(0) else { return not_started(n) };
    let mass = p.modal_mass_kg as f32;
    let sd = p.accel_noise_std as f32;
    let mut amplitude = Drift::new(1.0 / fs);
    let mut x = Vector4::<f32>::new(0.0, 0.0, 1.0 / mass, 0.0);
    let mut noise = Noise(0x50A4_0001);
    let mut blocks = Blocks::new(n, 1.0);
    for k in 0..n {
        // The force phasor turns with the model; its size follows the schedule (per unit mass).
        let truth = amplitude.at(k, |t| swing(t, 0.5, 600.0));
        let size = libm::sqrtf(x[2] * x[2] + x[3] * x[3]).max(1e-12);
        let scale = truth / mass / size;
        x[2] *= scale;
        x[3] *= scale;
        let y = (c * x)[0] + sd * noise.unit();
        let s = est.step(Some(y));
        let nis = s.nis.unwrap_or(f32::NAN);
        if !(s.force_amplitude.is_finite() && s.displacement.is_finite() && nis.is_finite()) {
            blocks.non_finite();
        }
        let e = f64::from(s.force_amplitude) - f64::from(truth);
        blocks.push(nis, e * e, f64::from(truth) * f64::from(truth));
        let w = q * noise.vector::<4>();
        x = a * x + Vector4::new(0.0, w[1], 0.0, 0.0);
        if (k + 1) % BLOCK == 0 {
            blocks.close();
            if let Some(kf) = est.kalman() {
                blocks.covariance(kf.covariance());
            }
            if let Some(m) = truth_at(k + 1) {
                (a, c, q) = m;
            }
        }
    }
    blocks.finish(est.counters().filter)
}
