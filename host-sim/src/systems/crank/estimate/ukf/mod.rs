//! The paper's clearance estimator: a one-state unscented Kalman filter on the radial clearance
//! of joint A whose sigma points are clearance simulations, measuring the spectral feature `a`
//! ([`crate::systems::crank::feature`]) of each 0.25 s window.
//!
//! * State: the clearance `c` (m), a random walk (`f` is the identity, process noise
//!   [`UkfOptions::process_std`] per step).
//! * Sigma points: Van der Merwe's `c`, `c ± √((1+λ) P)` (`1 + λ = α²(1+κ)`, the paper's
//!   `ξ² = 1 + γ`), weights of [`edgekf::filter::MerweSigmaPoints`], clamped to
//!   [`UkfOptions::bounds`].
//! * `h(cᵢ)`: the feature of the window simulated with clearance `cᵢ`, continuing from the
//!   state the sigma point reached at the end of the previous window
//!   ([`Mechanism::transfer_state`](crate::systems::crank::Mechanism::transfer_state)).
//!
//! What limits the filter, and the choices made here (figures from `cargo run --release -p
//! edgekf-sim --features studies --example crank_study -- information | release-curve | ukf 10 3`):
//!
//! * The scatter of `a` is intrinsic to the chaotic impacts, not to the gross motion: over 24
//!   releases 30.000°…30.046° a window's `a` spreads by 20–40 rad/s² (0.25 mm), and that
//!   spread does not follow the crank's speed or energy in the window (within-window
//!   correlation −0.02 and 0.07). Starting a simulation from the window's own gross state
//!   would therefore not predict it.
//! * After the release window `a` hardly depends on the clearance: its mean over windows 1–39
//!   of 10 s is 141.2 / 144.1 / 144.4 ± 3.6 rad/s² at 0.225 / 0.25 / 0.275 mm, a clearance std
//!   of ~0.04 mm (16 %) however the windows are combined. **The information is in the release
//!   window**: released centred and at rest, the journal first crosses the clearance in free
//!   flight, and the first 0.25 s give `a` = 112 → 229 rad/s² between 0.20 and 0.29 mm (± 5–15,
//!   ~1 300 rad/s² per mm: a clearance std of ~0.007 mm, 3 %). But that curve has branches: 0.15,
//!   ~0.16 and 0.36–0.40 mm give the same `a` as 0.25 mm.
//! * Hence (documented deviations within the paper's scheme):
//!   1. [`UkfOptions::members`] simulations per sigma point (releases 0.002° apart, the same
//!      noise seeds in every sigma point), each carrying its own state; the predicted feature
//!      is their mean, not one chaotic realisation, and `R` per window is their pooled spread
//!      (× (1 + 1/M) for the mean's own error), which weighs the release window correctly.
//!   2. Sigma points are simulated with the adaptive integrator ([`UkfOptions::adaptive`]):
//!      symplectic Euler at 1e-5 s gains energy at contact onsets and raises the later
//!      windows' `a` by ~2 rad/s², which at ~100 rad/s² per mm is a 0.02 mm (8 %) bias against
//!      an accurate simulator or the real mechanism.
//!   3. The update is the statistical linear regression of `h` over the sigma points, with the
//!      side points at least [`UkfOptions::min_spread`] from the centre: closer, the three
//!      ensemble means would measure their own error rather than the slope.
//!   4. The release window is measured last ([`UkfOptions::release_last`]; the clearance is
//!      constant, so the order of the measurements does not change the posterior, only how
//!      well a Gaussian can follow it). The later windows first bring the estimate onto the
//!      right branch (±0.03–0.04 mm); the release window then sharpens it by an iterated
//!      update (Gauss–Newton on the posterior, sigma points ± [`UkfOptions::release_delta`]
//!      about the iterate, re-simulated from the release state).
//!   5. The initial std is 0.2 mm, so the start (0.01, 0.1 or 0.2 mm) weighs little against
//!      40 windows.
//!
//! Measured (recordings of 0.25 mm at A from the adaptive integrator at 1e-9, released 30° +
//! 0.0013°·r; `crank_study -- ukf 4 2` and `ukf 10 3`): 4 s, 6 of 6 runs (2 recordings × 3
//! starts) within ±3.5 %; 10 s, 4 of 9 within ±5 % (+3.5, −0.1, +4.9, +1.2 %), 8 of 9 within ±11 %, one at −35 % (the
//! later windows left that run at 0.22 mm, on the edge of the branch, and the release window
//! took it to the 0.16 mm branch). About 8 M integration steps and 1 000 simulations of 0.25 s
//! per 10 s recording (~20 s on two threads), against 3 M for the paper's single-simulation
//! filter ([`UkfOptions::paper`], `edgekf crank estimate --method ukf --paper`), which reached
//! only ±25 % (4 s) and ±35 % (10 s). The recording must start at release, like the paper's.
//!
//! The recording's windows must be whole: a missing sample (a row lost from the time column, or
//! an empty cell) is refused with its time ([`CrankError::Data`]), because a window's spectrum
//! with a hole in it is not the spectrum of that window, and the release window, which carries
//! almost all the information, cannot be left out. The fast estimator ([`super::model`]) steps
//! through missing samples.

use super::{EstimateRow, Recording};
use crate::systems::crank::feature::spectral_feature;
use crate::systems::crank::integrate::Integrator;
use crate::systems::crank::{CrankConfig, CrankError};
use edgekf::filter::MerweSigmaPoints;

mod ensembles;
use ensembles::{Carried, Ensembles, Simulator};

/// Settings of the paper's UKF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UkfOptions {
    /// Initial clearance guess, m.
    pub initial: f64,
    /// Standard deviation of the initial guess, m.
    pub initial_std: f64,
    /// Random-walk standard deviation of the clearance per step, m.
    pub process_std: f64,
    /// Standard deviation of the measured feature `a`, rad/s² (`None`: per window, from the
    /// spread of the sigma points' simulated ensembles).
    pub measurement_std: Option<f64>,
    /// Window (one UKF step), s.
    pub window: f64,
    /// Sigma-point parameters.
    pub sigma: MerweSigmaPoints<f64>,
    /// Sigma points and the estimate are kept in `[lo, hi]`, m.
    pub bounds: (f64, f64),
    /// The whole-recording estimate is the mean of the filtered estimates over this last
    /// fraction of the windows (0: the last estimate, release window included).
    pub average_fraction: f64,
    /// Simulations per sigma point (1: the paper's single simulation). Member `m` is released
    /// at the configured angle plus `m ·` [`UkfOptions::member_spacing_deg`] and carries its own
    /// state from window to window; the sigma point's predicted feature is the members' mean.
    pub members: usize,
    /// Release-angle spacing of the members, degrees.
    pub member_spacing_deg: f64,
    /// Measure the release window (the first) last, after all the others, by iterated
    /// posterior linearisation ([`UkfOptions::release_iterations`] at most); `false`: in
    /// order, like every other window.
    pub release_last: bool,
    /// Iterations of the release-window update.
    pub release_iterations: usize,
    /// Threads for the sigma-point simulations.
    pub threads: usize,
    /// Smallest distance of the side sigma points from the centre, m (windows after the
    /// release window). A sigma point's feature is an ensemble mean with an error of its own;
    /// closer than this, the three would measure that error rather than the slope of `h`.
    pub min_spread: f64,
    /// Half-distance of the sigma points about the iterate in the release-window update, m.
    pub release_delta: f64,
    /// Simulate the sigma points with the adaptive integrator at the configuration's tolerance
    /// (`false`: with the configuration's integrator).
    pub adaptive: bool,
    /// Each sigma point's members continue from their own states (the paper's choice); `false`:
    /// every sigma point continues from the centre's members.
    pub carry_own: bool,
}

impl Default for UkfOptions {
    /// Initial guess 0.1 mm ± 0.1 mm, process noise 1 µm per window, `R` from the ensembles,
    /// 0.25 s windows, α = 1, β = 2, κ = 2 (`ξ = √3`, the Gaussian choice `n + κ = 3`), sigma
    /// points within 5 µm … 0.9 mm, 8 members 0.002° apart, the release window measured last
    /// (8 iterations at most), the last estimate reported, 2 threads.
    fn default() -> Self {
        Self {
            initial: 0.1e-3,
            initial_std: 0.2e-3,
            process_std: 1e-6,
            measurement_std: None,
            window: 0.25,
            sigma: MerweSigmaPoints { alpha: 1.0, beta: 2.0, kappa: 2.0 },
            bounds: (5e-6, 0.9e-3),
            average_fraction: 0.0,
            members: 8,
            member_spacing_deg: 0.002,
            release_last: true,
            release_iterations: 8,
            threads: 2,
            min_spread: 0.04e-3,
            release_delta: 0.01e-3,
            adaptive: true,
            carry_own: true,
        }
    }
}

impl UkfOptions {
    /// The paper's filter as first written here: one simulation per sigma point, `R` from the
    /// recording's window-to-window differences, windows in order, process noise 2 µm, the
    /// mean over the last half of the windows reported.
    pub fn paper() -> Self {
        Self {
            process_std: 2e-6,
            average_fraction: 0.5,
            members: 1,
            release_last: false,
            min_spread: 0.0,
            adaptive: false,
            ..Self::default()
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
    /// Their simulated features `a` (ensemble means).
    pub sigma_feature: [f64; 3],
    /// The recording's feature `a` (`None`: no fit, or the window is measured later; the step
    /// only predicted).
    pub measured: Option<f64>,
    /// Predicted measurement `ẑ`.
    pub predicted: f64,
    /// Measurement standard deviation used, rad/s².
    pub measurement_std: f64,
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
    /// One entry per window, in time order (the release window's entry only predicts when
    /// [`UkfOptions::release_last`]).
    pub steps: Vec<UkfStep>,
    /// The delayed release-window update (last iteration), if it was made.
    pub release: Option<UkfStep>,
    /// Iterations the release-window update took.
    pub release_iterations: usize,
    /// Whole-recording estimate (see [`UkfOptions::average_fraction`]), m.
    pub estimate: f64,
    /// Its standard deviation, m.
    pub estimate_std: f64,
    /// Root mean square of the measurement standard deviations used, rad/s².
    pub measurement_std: f64,
    /// Integration steps spent over all sigma points, members, windows and iterations.
    pub integration_steps: u64,
    /// Simulations of one window run.
    pub simulations: u64,
}

impl UkfRun {
    /// What the release window added, in mm: `windows after the release 0.2400 ± 0.0100 mm,
    /// with the release window 0.2500 ± 0.0050 mm` (the last window's estimate, then the
    /// whole-recording one).
    pub fn release_effect(&self) -> String {
        let before = self.steps.last().map_or((f64::NAN, f64::NAN), |s| (s.clearance, s.std));
        format!(
            "windows after the release {:.4} ± {:.4} mm, with the release window {:.4} ± {:.4} mm",
            before.0 * 1e3,
            before.1 * 1e3,
            self.estimate * 1e3,
            self.estimate_std * 1e3
        )
    }

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
/// after each window (and with `k` = the number of windows for the release-window update).
pub fn run(
    config: &CrankConfig,
    rec: &Recording,
    opts: &UkfOptions,
    progress: &mut dyn FnMut(usize, &UkfStep),
) -> Result<UkfRun, CrankError> {
    let n = window_samples(rec, opts)?;
    let filter = Filter::new(config, rec, opts, n)?;
    let mut post = Posterior {
        x: opts.initial.clamp(filter.lo, filter.hi),
        p: opts.initial_std * opts.initial_std,
        carried: None,
        work: 0,
        sims: 0,
        r_sum: 0.0,
    };
    let mut steps = Vec::with_capacity(filter.measured.len());
    for (k, y) in filter.measured.iter().enumerate() {
        let step = filter.window_step(k, *y, &mut post)?;
        progress(k, &step);
        steps.push(step);
    }
    let (release, release_iterations) = match (opts.release_last, filter.measured[0], filter.measured.len() > 1) {
        (true, Some(y0), true) => filter.release_update(y0, steps.len(), &mut post, progress)?,
        _ => (None, 0),
    };
    Ok(finish(opts, steps, release, release_iterations, &post))
}

/// Samples per window, once the recording and the options are checked: whole windows of at
/// least 4 samples, no sample missing from them, options in range.
fn window_samples(rec: &Recording, opts: &UkfOptions) -> Result<usize, CrankError> {
    let n = rec.window_len(opts.window);
    if n < 4 || rec.crank_alpha.len() < n {
        return Err(CrankError::Options(format!(
            "the recording ({} samples) must hold at least one {} s window of 4 samples or more",
            rec.crank_alpha.len(),
            opts.window
        )));
    }
    let why = "the UKF compares the spectra of whole windows and needs every sample; \
               `--method fast` (the learned model) steps through missing ones";
    rec.require_every_sample(rec.crank_alpha.len() / n * n, why).map_err(CrankError::Data)?;
    let (lo, hi) = opts.bounds;
    if !(lo > 0.0
        && hi > lo
        && opts.initial.is_finite()
        && opts.initial_std > 0.0
        && opts.process_std >= 0.0
        && opts.members >= 1
        && opts.member_spacing_deg.is_finite())
    {
        return Err(CrankError::Options(format!("invalid UKF options {opts:?}")));
    }
    Ok(n)
}

/// What stays fixed over a run: the options, the sigma-point weights, the measured features
/// and the simulator of the windows.
struct Filter<'a> {
    opts: &'a UkfOptions,
    lo: f64,
    hi: f64,
    /// `1 + λ`: the squared spread of the side sigma points in prior stds.
    spread: f64,
    wm: [f64; 3],
    wc: [f64; 3],
    /// The recording's feature `a` per window.
    measured: Vec<Option<f64>>,
    /// `R`'s std when it comes from the recording ([`feature_spread`]).
    recording_spread: f64,
    sim: Simulator<'a>,
    /// Start of the recording, s.
    t0: f64,
}

/// Where the filter stands between windows, and what it has spent.
struct Posterior {
    x: f64,
    p: f64,
    /// The members' states at the end of the last window, per sigma point.
    carried: Option<Vec<Vec<Carried>>>,
    work: u64,
    sims: u64,
    /// Sum of the `R`s of the updates made.
    r_sum: f64,
}

impl Posterior {
    /// Counts a window's simulations.
    fn spent(&mut self, ens: &Ensembles, members: usize) {
        self.work += ens.steps;
        self.sims += 3 * members as u64;
    }
}

impl<'a> Filter<'a> {
    fn new(config: &'a CrankConfig, rec: &Recording, opts: &'a UkfOptions, n: usize) -> Result<Self, CrankError> {
        let w = opts.sigma.weights::<1>().map_err(|e| CrankError::Options(format!("sigma points: {e:?}")))?;
        let measured: Vec<Option<f64>> =
            rec.crank_alpha.chunks_exact(n).map(|x| spectral_feature(x, rec.sample_rate).map(|f| f.a)).collect();
        let recording_spread = feature_spread(&measured).unwrap_or(37.0);
        let sim = Simulator {
            config,
            opts,
            sample_rate: rec.sample_rate,
            window_s: n as f64 / rec.sample_rate,
            integrator: if opts.adaptive {
                Integrator::Adaptive { tolerance: config.integrator.tolerance, max_step: config.integrator.max_step }
            } else {
                Integrator::from_config(&config.integrator)
            },
        };
        Ok(Self {
            opts,
            lo: opts.bounds.0,
            hi: opts.bounds.1,
            spread: w.spread,
            wm: [w.mean_center, w.side, w.side],
            wc: [w.cov_center, w.side, w.side],
            measured,
            recording_spread,
            sim,
            t0: rec.t.first().copied().unwrap_or(0.0),
        })
    }

    /// R: the given value; with one member, the recording's spread; else the ensembles' spread
    /// (a member's scatter about the ensemble mean) plus the ensemble mean's own error.
    fn r_var(&self, var: f64) -> f64 {
        let m = self.opts.members.max(1) as f64;
        match self.opts.measurement_std {
            Some(s) => s * s,
            None if self.opts.members <= 1 => self.recording_spread * self.recording_spread,
            None => var * (1.0 + 1.0 / m),
        }
    }

    /// One window: predict, simulate the sigma points, and update with its feature `y` unless
    /// it is the release window kept for last.
    fn window_step(&self, k: usize, y: Option<f64>, post: &mut Posterior) -> Result<UkfStep, CrankError> {
        let opts = self.opts;
        post.p += opts.process_std * opts.process_std;
        let later = k == 0 && opts.release_last && self.measured.len() > 1;
        let s = (self.spread * post.p).sqrt().max(if k > 0 { opts.min_spread } else { 0.0 });
        let x = post.x;
        let xs = [x, x + s, x - s].map(|v| v.clamp(self.lo, self.hi));
        let ens = self.sim.window(k, xs, post.carried.as_ref())?;
        post.spent(&ens, opts.members);
        let z = ens.mean;
        let r = self.r_var(ens.var);
        let (h, xm, zm, pzz) = self.regression(xs, z, post.p, r);
        let mut gain = 0.0;
        let y = if later { None } else { y };
        if let Some(y) = y {
            gain = post.p * h / pzz;
            post.x += gain * (y - zm - h * (post.x - xm));
            post.p = (post.p - gain * gain * pzz).max(1e-18);
            post.r_sum += r;
        }
        post.x = post.x.clamp(self.lo, self.hi);
        // Every sigma point continues from the centre's members: the states of the motion the
        // estimate describes.
        post.carried = Some(if opts.carry_own {
            ens.carried
        } else {
            let centre = ens.carried.into_iter().next().expect("three sigma points");
            vec![centre.clone(), centre.clone(), centre]
        });
        Ok(UkfStep {
            t: self.t0 + (k + 1) as f64 * self.sim.window_s,
            sigma: xs,
            sigma_feature: z,
            measured: y,
            predicted: zm,
            measurement_std: r.sqrt(),
            gain,
            clearance: post.x,
            std: post.p.sqrt(),
        })
    }

    /// Statistical linear regression of h over the sigma points (the unscented update when
    /// their spread is √((1+λ)P); with the spread floor, the slope over the wider set): the
    /// slope `h`, the weighted means of the sigma points and their features, and the
    /// innovation variance for prior variance `p` and measurement variance `r`.
    fn regression(&self, xs: [f64; 3], z: [f64; 3], p: f64, r: f64) -> (f64, f64, f64, f64) {
        let (wm, wc) = (self.wm, self.wc);
        let xm: f64 = (0..3).map(|i| wm[i] * xs[i]).sum();
        let zm: f64 = (0..3).map(|i| wm[i] * z[i]).sum();
        let pxx: f64 = (0..3).map(|i| wc[i] * (xs[i] - xm).powi(2)).sum::<f64>().max(1e-30);
        let pxz: f64 = (0..3).map(|i| wc[i] * (xs[i] - xm) * (z[i] - zm)).sum();
        let pzz_s: f64 = (0..3).map(|i| wc[i] * (z[i] - zm).powi(2)).sum();
        let h = pxz / pxx;
        let omega = (pzz_s - h * h * pxx).max(0.0);
        (h, xm, zm, h * h * p + omega + r)
    }

    /// The release window's delayed update, `y0` its feature: iterated (Gauss–Newton on the
    /// maximum-a-posteriori cost, derivative-free): the slope of h over sigma points
    /// ± release_delta about the iterate, applied to the prior, repeated until the estimate
    /// settles. Each step moves at most one prior std. Returns the last iteration's step and
    /// the iterations taken; `post` ends at the last iterate.
    fn release_update(
        &self,
        y0: f64,
        k: usize,
        post: &mut Posterior,
        progress: &mut dyn FnMut(usize, &UkfStep),
    ) -> Result<(Option<UkfStep>, usize), CrankError> {
        let (lo, hi) = (self.lo, self.hi);
        let (x0, p0) = (post.x, post.p);
        let mut xi = x0;
        let mut pi = p0;
        let mut release = None;
        let mut release_iterations = 0;
        for it in 0..self.opts.release_iterations.max(1) {
            let d = self.opts.release_delta.max(1e-9);
            let xs = [xi, xi + d, xi - d].map(|v| v.clamp(lo, hi));
            let ens = self.sim.window(0, xs, None)?;
            post.spent(&ens, self.opts.members);
            let z = ens.mean;
            let r = self.r_var(ens.var);
            let h = (z[1] - z[2]) / (xs[1] - xs[2]).max(1e-12);
            let s_tot = h * h * p0 + r;
            let gain = p0 * h / s_tot;
            let target = x0 + gain * (y0 - z[0] - h * (x0 - xs[0]));
            let x_new = (xi + (target - xi).clamp(-p0.sqrt(), p0.sqrt())).clamp(lo, hi);
            let p_new = (p0 - gain * gain * s_tot).max(1e-18);
            release_iterations = it + 1;
            let moved = (x_new - xi).abs();
            let step = UkfStep {
                t: self.t0 + self.sim.window_s,
                sigma: xs,
                sigma_feature: z,
                measured: Some(y0),
                predicted: z[0],
                measurement_std: r.sqrt(),
                gain,
                clearance: x_new,
                std: p_new.sqrt(),
            };
            progress(k, &step);
            release = Some(step);
            xi = x_new;
            pi = p_new;
            if moved < 0.5 * p_new.sqrt() {
                break;
            }
        }
        post.r_sum += release.map_or(0.0, |s: UkfStep| s.measurement_std.powi(2));
        post.x = xi;
        post.p = pi;
        Ok((release, release_iterations))
    }
}

/// The run's result: the whole-recording estimate (the last, or the mean over the last
/// [`UkfOptions::average_fraction`] of the windows) and what was spent.
fn finish(
    opts: &UkfOptions,
    steps: Vec<UkfStep>,
    release: Option<UkfStep>,
    release_iterations: usize,
    post: &Posterior,
) -> UkfRun {
    let from = ((steps.len() as f64 * (1.0 - opts.average_fraction.clamp(0.0, 1.0))).floor() as usize)
        .min(steps.len().saturating_sub(1));
    let estimate = if opts.average_fraction > 0.0 {
        let tail = &steps[from..];
        tail.iter().map(|s| s.clearance).sum::<f64>() / tail.len() as f64
    } else {
        post.x
    };
    let updates = steps.iter().filter(|s| s.measured.is_some()).count() + usize::from(release.is_some());
    UkfRun {
        steps,
        release,
        release_iterations,
        estimate,
        estimate_std: post.p.sqrt(),
        measurement_std: (post.r_sum / updates.max(1) as f64).sqrt(),
        integration_steps: post.work,
        simulations: post.sims,
    }
}
