//! Per-thruster change detection (CUSUM) and the declared status (see [`DetectorSettings`]).

use super::settings::DetectorSettings;
use crate::filter::{Innovation, UnscentedKalmanFilter};
use crate::residual::Cusum;
use crate::Real;
use nalgebra::SVector;

/// What the node declares about a thruster.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Status {
    /// Healthy.
    Healthy,
    /// Declared: thrust below the `degraded` fraction.
    Degraded,
    /// Declared: thrust below the `failed` fraction.
    Failed,
}

impl Status {
    /// `healthy`, `degraded` or `failed`, as in the estimate CSV.
    pub const fn name(self) -> &'static str {
        match self {
            Status::Healthy => "healthy",
            Status::Degraded => "degraded",
            Status::Failed => "failed",
        }
    }

    /// Degraded or failed.
    pub const fn declared(self) -> bool {
        !matches!(self, Status::Healthy)
    }
}

/// One thruster's CUSUM (two one-sided [`Cusum`]s on the whitened score) and status.
///
/// ```
/// use edgekf::systems::uuv::{DetectorSettings, Status, ThrusterMonitor};
/// let mut m = ThrusterMonitor::<f64>::new(&DetectorSettings::default());
/// // White scores never alarm; a sustained shift of −4σ does within a few samples.
/// assert!(!m.score(0.5) && !m.score(-0.8));
/// let alarm_after = (1..20).find(|_| m.score(-4.0));
/// assert_eq!(alarm_after, Some(5)); // 3σ a sample above the drift, past 12
/// assert_eq!(m.status(0.05, 0.02), Status::Failed);
/// assert_eq!(m.status(0.5, 0.02), Status::Degraded);
/// assert_eq!(m.status(0.95, 0.02), Status::Healthy);
/// ```
#[derive(Debug, Clone, Copy)]
pub struct ThrusterMonitor<T> {
    /// CUSUMs of the score and of its negative: thrust above and below the model's.
    up: Cusum<T>,
    down: Cusum<T>,
    sigmas: T,
    degraded: T,
    failed: T,
    status: Status,
    alarms: u32,
}

impl<T: Real> ThrusterMonitor<T> {
    /// A monitor of a healthy thruster.
    pub fn new(s: &DetectorSettings) -> Self {
        let t = T::of_f64;
        Self {
            up: Cusum::new(t(s.drift), t(s.threshold)),
            down: Cusum::new(t(s.drift), t(s.threshold)),
            sigmas: t(s.sigmas),
            degraded: t(s.degraded),
            failed: t(s.failed),
            status: Status::Healthy,
            alarms: 0,
        }
    }

    /// Adds one whitened score; `true` when the CUSUM alarms (it then restarts). A non-finite
    /// score is skipped.
    pub fn score(&mut self, z: T) -> bool {
        if !z.is_finite() {
            return false;
        }
        // `s + (−z)` rounds exactly as `s − z`: the same bits as the two sums written out.
        let (up, down) = (self.up.push(z), self.down.push(-z));
        if up || down {
            self.up.reset();
            self.down.reset();
            self.alarms = self.alarms.saturating_add(1);
            true
        } else {
            false
        }
    }

    /// The status after the factor's estimate `k` with standard deviation `sd`.
    pub fn status(&mut self, k: T, sd: T) -> Status {
        let (lo, hi) = (k - self.sigmas * sd, k + self.sigmas * sd);
        self.status = match self.status {
            Status::Healthy if hi < self.failed => Status::Failed,
            Status::Healthy if hi < self.degraded => Status::Degraded,
            Status::Degraded if hi < self.failed => Status::Failed,
            Status::Degraded | Status::Failed if lo > self.degraded => Status::Healthy,
            Status::Failed if lo > self.failed => Status::Degraded,
            s => s,
        };
        self.status
    }

    /// CUSUM alarms so far (each reopened the factor).
    pub fn alarms(&self) -> u32 {
        self.alarms
    }
}

/// How a change of each health factor (state `factors[j]`, if carried) would move measurement
/// `h`, at `prior` (`h` is linear in the factors, so a finite difference of 0.1 is exact but for
/// rounding): what [`watch`] projects the innovation on.
pub fn signatures<T: Real, const N: usize, const K: usize>(
    h: impl Fn(&SVector<T, N>) -> SVector<T, K>,
    prior: &SVector<T, N>,
    factors: [Option<usize>; 2],
) -> [Option<SVector<T, K>>; 2] {
    let base = h(prior);
    let step = T::of_f64(0.1);
    factors.map(|i| {
        i.map(|i| {
            let mut moved = *prior;
            if let Some(k) = moved.get_mut(i) {
                *k += step;
            }
            (h(&moved) - base) / step
        })
    })
}

/// Feeds each thruster's CUSUM the innovation projected on its signature, whitened (the score
/// is N(0, 1) while the model holds), and reopens a factor whose CUSUM alarms: its variance set
/// to `reopen²`, its covariances with the rest cleared.
pub fn watch<T: Real, const N: usize, const K: usize>(
    ukf: &mut UnscentedKalmanFilter<T, N, 6>,
    monitors: &mut [ThrusterMonitor<T>; 2],
    inn: &Innovation<T, K>,
    signatures: &[Option<SVector<T, K>>; 2],
    factors: [Option<usize>; 2],
    reopen: T,
) {
    let Some(l) = crate::linalg::cholesky(&inn.s) else { return };
    let white = crate::linalg::solve_lower(&l, &inn.residual);
    for ((sig, factor), monitor) in signatures.iter().zip(factors).zip(monitors.iter_mut()) {
        let (Some(g), Some(i)) = (sig, factor) else { continue };
        let wg = crate::linalg::solve_lower(&l, g);
        let norm = wg.norm_squared();
        if norm > T::zero() && monitor.score(wg.dot(&white) / norm.sqrt()) {
            open(ukf, i, reopen);
        }
    }
}

/// Sets state `i`'s standard deviation to `sd` and clears its covariances with the rest: a
/// parameter the filter had settled (or held fixed), opened to follow a change. An index
/// outside the state does nothing.
pub fn open<T: Real, const N: usize, const M: usize>(ukf: &mut UnscentedKalmanFilter<T, N, M>, i: usize, sd: T) {
    if i >= N {
        return;
    }
    ukf.edit_covariance(|p| {
        for k in 0..N {
            for at in [(i, k), (k, i)] {
                if let Some(e) = p.get_mut(at) {
                    *e = T::zero();
                }
            }
        }
        if let Some(e) = p.get_mut((i, i)) {
            *e = sd * sd;
        }
    });
}
