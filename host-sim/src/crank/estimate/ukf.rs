//! The paper's clearance estimator: a one-state unscented Kalman filter on the radial clearance
//! of joint A whose sigma points are full clearance simulations.
//!
//! * State: the clearance `c` (m), a random walk (`f` is the identity, process noise
//!   [`UkfOptions::process_std`] per step).
//! * One step per window of [`UkfOptions::window`] s (the paper: 0.25 s, 25 000 integration
//!   steps of 1e-5 s per sigma point).
//! * Sigma points: Van der Merwe's `c`, `c ± √((1+λ) P)` (for one state `1 + λ = α²(1+κ)`, the
//!   paper's `ξ² = 1 + γ`), with the weights of [`edgekf::filter::MerweSigmaPoints`].
//! * Measurement: the feature `a` of the fit `y = a e^{b f}` to the amplitude spectrum of the
//!   window ([`crate::crank::feature::spectral_feature`]). `h(cᵢ)` is the same feature of the
//!   window simulated by sigma point `i`: its mechanism (clearance `cᵢ`) continues from the
//!   state sigma point `i` reached at the end of the previous window, carried to the new
//!   clearance by [`Mechanism::transfer_state`] (an indentation is kept, so a shrinking
//!   clearance starts no sudden contact force). The first window starts from the release
//!   state.
//! * Measurement noise `R`: the window-to-window variance of `a` in the recording itself,
//!   `mean((aₖ₊₁ − aₖ)²)/2` (differences, so the slow fall of `a` as the motion loses energy is
//!   not counted), unless [`UkfOptions::measurement_std`] is given.
//!
//! Why the filter is written out here instead of driving
//! [`edgekf::filter::UnscentedKalmanFilter`]: that filter's `h(x)` sees only the sigma point's
//! value, but here `h` is a simulation that needs the sigma point's *identity* (which carried
//! mechanism state to continue from), and the three simulations are independent and run on
//! parallel threads. With one state the UKF is a few lines; the weights are edgekf's.
//!
//! Sigma points are clamped to [`UkfOptions::bounds`] before they are simulated (a negative
//! clearance has no meaning), and the clamped values enter the cross-covariance, so a clamped
//! point counts with the sensitivity it actually had.

use super::{EstimateRow, Recording};
use crate::crank::feature::spectral_feature;
use crate::crank::integrate::Integrator;
use crate::crank::{CrankConfig, CrankError, Mechanism, SimOptions, State};
use edgekf::filter::MerweSigmaPoints;

/// Settings of the paper's UKF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UkfOptions {
    /// Initial clearance guess, m.
    pub initial: f64,
    /// Standard deviation of the initial guess, m.
    pub initial_std: f64,
    /// Random-walk standard deviation of the clearance per step, m.
    pub process_std: f64,
    /// Standard deviation of the measured feature `a`, rad/s² (`None`: from the recording).
    pub measurement_std: Option<f64>,
    /// Window (one UKF step), s.
    pub window: f64,
    /// Sigma-point parameters.
    pub sigma: MerweSigmaPoints<f64>,
    /// Sigma points and the estimate are kept in `[lo, hi]`, m.
    pub bounds: (f64, f64),
    /// The whole-recording estimate is the mean of the filtered estimates over this last
    /// fraction of the windows (the per-window estimate keeps oscillating with the feature's
    /// scatter, as the paper observes).
    pub average_fraction: f64,
}

impl Default for UkfOptions {
    /// Initial guess 0.1 mm ± 0.1 mm, process noise 2 µm per window, `R` from the recording,
    /// 0.25 s windows, α = 1, β = 2, κ = 2 (`ξ = √3`, the Gaussian choice `n + κ = 3`), sigma
    /// points within 5 µm … 0.9 mm, the last half of the windows averaged.
    fn default() -> Self {
        Self {
            initial: 0.1e-3,
            initial_std: 0.1e-3,
            process_std: 2e-6,
            measurement_std: None,
            window: 0.25,
            sigma: MerweSigmaPoints { alpha: 1.0, beta: 2.0, kappa: 2.0 },
            bounds: (5e-6, 0.9e-3),
            average_fraction: 0.5,
        }
    }
}

/// What one UKF step saw and did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UkfStep {
    /// End of the window, s.
    pub t: f64,
    /// Sigma points (clamped), m: centre, plus, minus.
    pub sigma: [f64; 3],
    /// Their simulated features `a`.
    pub sigma_feature: [f64; 3],
    /// The recording's feature `a` (`None`: no fit, the step only predicted).
    pub measured: Option<f64>,
    /// Predicted measurement `ẑ`.
    pub predicted: f64,
    /// Kalman gain, m per rad/s².
    pub gain: f64,
    /// Clearance estimate after the step, m.
    pub clearance: f64,
    /// Its standard deviation, m.
    pub std: f64,
}

/// A finished UKF run.
#[derive(Debug, Clone, PartialEq)]
pub struct UkfRun {
    /// One entry per window.
    pub steps: Vec<UkfStep>,
    /// Whole-recording estimate (see [`UkfOptions::average_fraction`]), m.
    pub estimate: f64,
    /// Measurement standard deviation used, rad/s².
    pub measurement_std: f64,
    /// Integration steps spent over all sigma points and windows.
    pub integration_steps: u64,
}

impl UkfRun {
    /// The estimate file's rows: one per window, then the whole-recording estimate (B and C
    /// are taken as tight: the paper's filter estimates A only).
    pub fn rows(&self) -> Vec<EstimateRow> {
        let mut rows: Vec<EstimateRow> =
            self.steps.iter().map(|s| EstimateRow { t: s.t, clearance: [s.clearance, 0.0, 0.0] }).collect();
        if let Some(last) = self.steps.last() {
            rows.push(EstimateRow { t: last.t, clearance: [self.estimate, 0.0, 0.0] });
        }
        rows
    }
}

/// `R` from the recording: half the mean squared difference of successive window features.
pub fn feature_spread(a: &[Option<f64>]) -> Option<f64> {
    let d: Vec<f64> = a.windows(2).filter_map(|w| Some(w[1]? - w[0]?)).collect();
    (d.len() >= 2).then(|| (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64 / 2.0).sqrt())
}

/// Runs the paper's UKF over `rec` with the mechanism of `config` (clearance at A only, the
/// configuration's integrator, release state and sensor noise). `progress(k, step)` is called
/// after each window.
pub fn run(
    config: &CrankConfig,
    rec: &Recording,
    opts: &UkfOptions,
    progress: &mut dyn FnMut(usize, &UkfStep),
) -> Result<UkfRun, CrankError> {
    let n = rec.window_len(opts.window);
    if n < 4 || rec.crank_alpha.len() < n {
        return Err(CrankError::Options(format!(
            "the recording ({} samples) must hold at least one {} s window of 4 samples or more",
            rec.crank_alpha.len(),
            opts.window
        )));
    }
    let (lo, hi) = opts.bounds;
    if !(lo > 0.0 && hi > lo && opts.initial.is_finite() && opts.initial_std > 0.0 && opts.process_std >= 0.0) {
        return Err(CrankError::Options(format!("invalid UKF options {opts:?}")));
    }
    let w = opts.sigma.weights::<1>().map_err(|e| CrankError::Options(format!("sigma points: {e:?}")))?;
    let measured: Vec<Option<f64>> =
        rec.crank_alpha.chunks_exact(n).map(|x| spectral_feature(x, rec.sample_rate).map(|f| f.a)).collect();
    let r_std = opts.measurement_std.or_else(|| feature_spread(&measured)).unwrap_or(37.0);
    let window_s = n as f64 / rec.sample_rate;
    let integrator = Integrator::from_config(&config.integrator);
    let t0 = rec.t.first().copied().unwrap_or(0.0);

    let mut x = opts.initial.clamp(lo, hi);
    let mut p = opts.initial_std * opts.initial_std;
    let mut carried: [Option<(Mechanism, State)>; 3] = [None, None, None];
    let mut steps = Vec::with_capacity(measured.len());
    let mut work = 0u64;
    for (k, y) in measured.iter().enumerate() {
        p += opts.process_std * opts.process_std;
        let s = (w.spread * p).sqrt();
        let xs = [x, x + s, x - s].map(|v| v.clamp(lo, hi));
        let sims: Vec<Result<(Mechanism, State, f64, u64), CrankError>> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..3)
                .map(|i| {
                    let from = carried[i].as_ref();
                    let c = xs[i];
                    scope.spawn(move || -> Result<(Mechanism, State, f64, u64), CrankError> {
                        let mech = Mechanism::new(config, [Some(c), None, None])?;
                        let start = match from {
                            Some((m, st)) => mech.transfer_state(m, st),
                            None => mech.release_state(),
                        };
                        let sim = SimOptions {
                            duration: window_s,
                            sample_rate: rec.sample_rate,
                            noise_std: config.sensor.noise_std,
                            seed: 1 + 3 * k as u64 + i as u64,
                            integrator,
                            initial: Some(start),
                        };
                        let out = mech.simulate(&sim)?;
                        let a = spectral_feature(&out.crank_alpha, rec.sample_rate).map(|f| f.a).ok_or_else(|| {
                            CrankError::Diverged { t: out.final_state.t, reason: "no spectral feature".into() }
                        })?;
                        Ok((mech, out.final_state, a, out.stats.steps))
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().expect("sigma-point simulation panicked")).collect()
        });
        let mut z = [0.0; 3];
        for (i, r) in sims.into_iter().enumerate() {
            let (mech, state, a, st) = r?;
            z[i] = a;
            work += st;
            carried[i] = Some((mech, state));
        }
        let wm = [w.mean_center, w.side, w.side];
        let wc = [w.cov_center, w.side, w.side];
        let xm: f64 = (0..3).map(|i| wm[i] * xs[i]).sum();
        let zm: f64 = (0..3).map(|i| wm[i] * z[i]).sum();
        let pzz: f64 = (0..3).map(|i| wc[i] * (z[i] - zm).powi(2)).sum::<f64>() + r_std * r_std;
        let pxz: f64 = (0..3).map(|i| wc[i] * (xs[i] - xm) * (z[i] - zm)).sum();
        let mut gain = 0.0;
        if let Some(y) = y {
            gain = pxz / pzz;
            x += gain * (y - zm);
            p = (p - gain * gain * pzz).max(1e-18);
        }
        x = x.clamp(lo, hi);
        let step = UkfStep {
            t: t0 + (k + 1) as f64 * window_s,
            sigma: xs,
            sigma_feature: z,
            measured: *y,
            predicted: zm,
            gain,
            clearance: x,
            std: p.sqrt(),
        };
        progress(k, &step);
        steps.push(step);
    }
    let from = ((steps.len() as f64 * (1.0 - opts.average_fraction.clamp(0.0, 1.0))).floor() as usize)
        .min(steps.len().saturating_sub(1));
    let tail = &steps[from..];
    let estimate = tail.iter().map(|s| s.clearance).sum::<f64>() / tail.len() as f64;
    Ok(UkfRun { steps, estimate, measurement_std: r_std, integration_steps: work })
}
