//! The soak of the boom's Kalman filter (14 states) as the node runs it: the truth steps with
//! the model the filter ran its last step on ([`LastStep`]: transition, the luffing drive's
//! input, process noise, and the readings' matrix and noise), so it is the filter's own model
//! at the boom's current length and angle; the model changes by far less than its noise in a
//! sample, so the one sample it lags the filter's is immaterial. The boom telescopes between 25
//! and 35 m over 20 minutes and luffs between about 0.3 and 0.9 rad over 15 (a commanded rate,
//! with a weak hold on the angle so the drive's noise does not walk it away); the filter is
//! re-reduced as the length and angle move.

use super::BoomImage;
use crate::hil::HilImage;
use super::{estimators, GYRO, INCLINOMETER, SAMPLE_RATE_HZ};
use crate::soak::engine::{psd_root, Blocks, Drift, Noise, SoakFrame, SoakRow};
use edgekf::systems::boom::{slot, MEASUREMENTS, MODES, STATES};
use nalgebra::SVector;

/// Its rows.
pub const SOAKS: &[SoakRow] = &[BOOM];

/// The boom's row.
pub const BOOM: SoakRow = SoakRow {
    name: "boom",
    system: "boom",
    image: Some(BoomImage::NAME),
    what: "boom tip-vibration KF (14 states, gyro and inclinometer, 100 Hz)",
    drift: "length 25–35 m over 20 min, angle 0.3–0.9 rad over 15 min (re-reduced as it moves)",
    error_of: "tip vibration",
    host_steps: 100_000,
    qemu_steps: 20_000,
    qemu_long_steps: 150_000,
    nis_limit: Some(1.3),
    // The tip vibration is read through a gyro and an inclinometer only: the error is 23 % of
    // its RMS in every block of the first runs; a regression shows as a rise above 35 %.
    error_limit: 0.35,
    run: boom,
};

/// Samples per block (100 s).
const BLOCK: u32 = 10_000;

/// The soak (see the module docs); `n` samples.
#[inline(never)]
pub fn boom(n: u32) -> SoakFrame {
    let Ok((mut est, _)) = estimators() else { return crate::soak::engine::not_started(n) };
    let dt = 1.0 / f64::from(SAMPLE_RATE_HZ);
    let mut length = Drift::new(dt);
    let (mut feed, mut feed_rate) = (Drift::new(dt), Drift::new(dt));
    let mut x = SVector::<f32, STATES>::zeros();
    let angle0 = 0.6f32;
    x[slot::ANGLE] = angle0;
    x[slot::LAGGED] = angle0;
    x[slot::BIAS] = GYRO.mean as f32;
    let offset = INCLINOMETER.1 as f32;
    let mut noise = Noise(0x50A4_0006);
    let mut blocks = Blocks::new(n, MEASUREMENTS as f64);
    let mut command = 0.0f32;
    for k in 0..n {
        let l = length.at(k, |t| 30.0 + 5.0 * libm::sin(core::f64::consts::TAU * t / 1200.0));
        let (gyro, incl) = if k == 0 {
            (x[slot::BIAS] + x[slot::NOISE], x[slot::LAGGED] + offset)
        } else {
            let last = est.last_step();
            let m = last.model;
            x = m.a * x + last.input + psd_root(&m.q) * noise.vector::<STATES>();
            let y = m.c * x;
            let sd = |i: usize| libm::sqrtf(m.r.get((i, i)).copied().unwrap_or(0.0).max(0.0));
            (y[0] + last.gyro_offset + sd(0) * noise.unit(), y[1] + offset + sd(1) * noise.unit())
        };
        let e = est.step(gyro, incl, l, command);
        // The truth's vibration, from the tip deflections of the step just taken.
        let tip = est.last_step().tip;
        let truth: f32 = (0..MODES).map(|i| tip[i] * x.get(slot::MODE + 2 * i).copied().unwrap_or(0.0)).sum();
        if !(e.vibration.is_finite() && e.tip_angle.is_finite() && e.nis.is_finite()) {
            blocks.non_finite();
        }
        let err = f64::from(e.vibration) - f64::from(truth);
        blocks.push(e.nis, err * err, f64::from(truth) * f64::from(truth));
        // The operator's rate for the next sample: the angle's schedule fed forward, a weak hold.
        let w = core::f64::consts::TAU / 900.0;
        let want = feed.at(k, |t| 0.6 + 0.3 * libm::sin(w * t));
        let rate = feed_rate.at(k, |t| 0.3 * w * libm::cos(w * t));
        command = rate + 0.05 * (want - x[slot::ANGLE]);
        if (k + 1) % BLOCK == 0 {
            blocks.close();
            blocks.covariance(est.covariance());
        }
    }
    let mut frame = blocks.finish(est.health());
    // A failed reduction is a failure of the run.
    frame.non_finite = frame.non_finite.saturating_add(est.reduce_failures());
    frame
}
