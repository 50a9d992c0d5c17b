//! The soak engine: the frame a soak reports ([`SoakFrame`]), a filter's row ([`SoakRow`]), the
//! drifts and noise its truth is made of, and the block statistics and covariance checks it is
//! judged by. It names no system: each system's soak (`systems/<name>/soak.rs`) builds on it,
//! and the registry above it ([`super::SOAKS`]) gathers their rows, so the systems depend on
//! the engine and not on the registry that depends on them.

use edgekf::Real;
use nalgebra::SMatrix;

crate::frame! {
    /// One filter's soak figures: what every check of the soak reads.
    pub struct SoakFrame = "soak {=u8} {=u32} {=u32} {=f32} {=f32} {=f32} {=f32} {=u32} {=u32} {=u32} {=u32} {=u32} {=u32}" {
        /// The filter: its index in [`super::SOAKS`].
        pub filter: u8,
        /// Steps run.
        pub steps: u32,
        /// Blocks whose statistics were taken (the first, the start-up, is left out).
        pub blocks: u32,
        /// The largest block mean of the NIS per measurement (0 for the crank, which has none).
        pub worst_nis: f32,
        /// The largest block RMS error against the truth, relative to the truth's RMS (for the
        /// crank: the largest relative difference of a late window's statistics from a fresh
        /// estimator's on the same samples).
        pub worst_error: f32,
        /// The covariance's largest relative asymmetry at a check.
        pub worst_asymmetry: f32,
        /// For the crank: the recording's features (`f32` running means) against the same means
        /// accumulated in `f64`, largest difference; 0 for the filters.
        pub worst_drift: f32,
        /// Covariance checks made (symmetric positive definite, in `f64`).
        pub checks: u32,
        /// Checks that found the covariance not positive definite.
        pub not_positive_definite: u32,
        /// The filter's covariance resets.
        pub covariance_resets: u32,
        /// Its refused updates.
        pub refused_updates: u32,
        /// Steps with a non-finite output.
        pub non_finite: u32,
        /// Steps whose estimate left its physical bounds (a crank clearance outside the model's
        /// range, a thruster declared faulty while healthy).
        pub out_of_bounds: u32,
    }
}

/// One filter's soak: what it is, where it runs on the node, and how long it runs.
#[derive(Clone, Copy)]
pub struct SoakRow {
    /// A short name, as the soak image's input names it.
    pub name: &'static str,
    /// Its system: the module of [`crate::systems`] that runs it (`"core"` for a shared
    /// filter no node runs as such).
    pub system: &'static str,
    /// The HIL image that runs it ([`crate::hil::HilImage::NAME`]).
    pub image: Option<&'static str>,
    /// What it is, for the README's table.
    pub what: &'static str,
    /// What drifts.
    pub drift: &'static str,
    /// What the error is of.
    pub error_of: &'static str,
    /// Steps of the short host soak (CI); the long one runs 10⁷.
    pub host_steps: u32,
    /// Steps of the short QEMU soak (CI).
    pub qemu_steps: u32,
    /// Steps of the long QEMU soak: about 10¹⁰ instructions' worth (`cargo xtask bench`'s
    /// counts), at least 10⁶ for the cheap filters.
    pub qemu_long_steps: u32,
    /// The block NIS mean must stay below this (per measurement; `None`: no NIS).
    pub nis_limit: Option<f32>,
    /// The block error must stay below this.
    pub error_limit: f32,
    /// Runs the soak for that many steps.
    pub run: fn(u32) -> SoakFrame,
}

/// A soak that could not start: every step counted non-finite, so that it fails its check.
pub fn not_started(steps: u32) -> SoakFrame {
    SoakFrame { steps, non_finite: steps.max(1), ..SoakFrame::default() }
}

/// A zero-mean uniform number generator of unit variance, in `f32` (the LCG of
/// [`edgekf::models::synthetic::Lcg`], its 24 high bits exact in `f32`).
#[derive(Debug, Clone, Copy)]
pub struct Noise(pub u32);

impl Noise {
    /// The next number: uniform on [−√3, √3).
    pub fn unit(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        let u = (self.0 >> 8) as f32 * (1.0 / 8_388_608.0) - 1.0;
        u * 1.732_050_8
    }

    /// `n` numbers.
    pub fn vector<const N: usize>(&mut self) -> nalgebra::SVector<f32, N> {
        nalgebra::SVector::from_fn(|_, _| self.unit())
    }
}

/// Steps between the knots of a [`Drift`].
const KNOT: u32 = 1000;

/// A slowly drifting parameter, `f(t)` computed in `f64` (with `libm`, the same bits on the
/// host and the chip) at knots [`KNOT`] steps apart and interpolated linearly in `f32` in
/// between: a `sin` per step in soft-float would cost the chip more than the filter.
#[derive(Debug, Clone, Copy)]
pub struct Drift {
    /// Seconds a step.
    dt: f64,
    knot: u32,
    value: f32,
    slope: f32,
    started: bool,
}

impl Drift {
    /// A drift sampled every `dt` seconds.
    pub const fn new(dt: f64) -> Self {
        Self { dt, knot: 0, value: 0.0, slope: 0.0, started: false }
    }

    /// The value at step `k` (steps must come in order).
    pub fn at(&mut self, k: u32, f: impl Fn(f64) -> f64) -> f32 {
        if !self.started || k.wrapping_sub(self.knot) >= KNOT {
            let t0 = f64::from(k) * self.dt;
            let (v0, v1) = (f(t0), f(t0 + f64::from(KNOT) * self.dt));
            (self.knot, self.value, self.slope, self.started) =
                (k, v0 as f32, ((v1 - v0) / f64::from(KNOT)) as f32, true);
        }
        self.value + self.slope * k.wrapping_sub(self.knot) as f32
    }
}

/// `1 + amplitude · sin(2π t / period)`.
pub fn swing(t: f64, amplitude: f64, period: f64) -> f64 {
    1.0 + amplitude * libm::sin(core::f64::consts::TAU * t / period)
}

/// Block statistics and the soak's counters.
#[derive(Debug, Clone, Copy)]
pub struct Blocks {
    frame: SoakFrame,
    /// Measurements per NIS (to give it per measurement).
    measurements: f64,
    nis: f64,
    err2: f64,
    truth2: f64,
    n: u32,
    /// Blocks closed so far, the start-up included.
    closed: u32,
}

impl Blocks {
    /// Statistics of a soak of `steps` steps, the NIS over `measurements` measurements.
    pub fn new(steps: u32, measurements: f64) -> Self {
        let frame = SoakFrame { steps, ..SoakFrame::default() };
        Self { frame, measurements, nis: 0.0, err2: 0.0, truth2: 0.0, n: 0, closed: 0 }
    }

    /// One step: its NIS, squared error and squared truth.
    pub fn push(&mut self, nis: f32, err2: f64, truth2: f64) {
        self.nis += f64::from(nis);
        self.err2 += err2;
        self.truth2 += truth2;
        self.n = self.n.saturating_add(1);
    }

    /// Counts a non-finite output.
    pub fn non_finite(&mut self) {
        self.frame.non_finite = self.frame.non_finite.saturating_add(1);
    }

    /// Counts an estimate out of its bounds.
    pub fn out_of_bounds(&mut self) {
        self.frame.out_of_bounds = self.frame.out_of_bounds.saturating_add(1);
    }

    /// Ends a block: folds its statistics in, except the first block's (the start-up).
    pub fn close(&mut self) {
        if self.closed > 0 && self.n > 0 {
            let f = &mut self.frame;
            let nis = self.nis / f64::from(self.n) / self.measurements;
            let err = libm::sqrt(self.err2 / self.truth2.max(1e-300));
            f.worst_nis = f.worst_nis.max(nis as f32);
            f.worst_error = f.worst_error.max(err as f32);
            f.blocks = f.blocks.saturating_add(1);
        }
        self.closed = self.closed.saturating_add(1);
        (self.nis, self.err2, self.truth2, self.n) = (0.0, 0.0, 0.0, 0);
    }

    /// Records a worst error taken otherwise than by [`Blocks::push`].
    pub fn error(&mut self, e: f32) {
        self.frame.worst_error = self.frame.worst_error.max(if e.is_nan() { f32::INFINITY } else { e });
    }

    /// Counts a check taken otherwise than by blocks of [`Blocks::push`] (the crank's).
    pub fn close_check(&mut self) {
        self.frame.blocks = self.frame.blocks.saturating_add(1);
    }

    /// Records a drift of the accumulated figures (the crank).
    pub fn drift(&mut self, d: f32) {
        self.frame.worst_drift = self.frame.worst_drift.max(if d.is_nan() { f32::INFINITY } else { d });
    }

    /// Checks covariance `p` symmetric and positive definite, in `f64`.
    pub fn covariance<const N: usize>(&mut self, p: &SMatrix<f32, N, N>) {
        let p = p.map(f64::from);
        let scale = p.iter().fold(0.0f64, |m, v| m.max(libm::fabs(*v)));
        let asym = (p - p.transpose()).iter().fold(0.0f64, |m, v| m.max(libm::fabs(*v)));
        let f = &mut self.frame;
        f.checks = f.checks.saturating_add(1);
        f.worst_asymmetry = f.worst_asymmetry.max((asym / scale.max(1e-300)) as f32);
        if !positive_definite(&p) {
            f.not_positive_definite = f.not_positive_definite.saturating_add(1);
        }
    }

    /// The figures, with the filter's counters.
    pub fn finish(mut self, health: edgekf::filter::FilterHealth) -> SoakFrame {
        self.frame.covariance_resets = health.covariance_resets;
        self.frame.refused_updates = health.refused_updates;
        self.frame
    }
}

/// Whether `p` (symmetrised) has a Cholesky factor with positive pivots.
fn positive_definite<const N: usize>(p: &SMatrix<f64, N, N>) -> bool {
    let mut l = SMatrix::<f64, N, N>::zeros();
    for j in 0..N {
        let mut d = at(p, j, j);
        for k in 0..j {
            d -= at(&l, j, k) * at(&l, j, k);
        }
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let root = libm::sqrt(d);
        set(&mut l, j, j, root);
        for i in j + 1..N {
            let mut s = 0.5 * (at(p, i, j) + at(p, j, i));
            for k in 0..j {
                s -= at(&l, i, k) * at(&l, j, k);
            }
            set(&mut l, i, j, s / root);
        }
    }
    true
}

/// A factor `L` with `L Lᵀ = Q` of a positive semi-definite `Q`: Cholesky, a pivot not above
/// `1e-12` of the largest diagonal giving a zero column (the truth's process noise, whose
/// covariance may be singular).
pub fn psd_root<T: Real, const N: usize>(q: &SMatrix<T, N, N>) -> SMatrix<T, N, N> {
    let largest = (0..N).fold(T::zero(), |m, i| m.max(at(q, i, i)));
    let floor = largest * T::of_f64(1e-12);
    let mut l = SMatrix::<T, N, N>::zeros();
    for j in 0..N {
        let mut d = at(q, j, j);
        for k in 0..j {
            d -= at(&l, j, k) * at(&l, j, k);
        }
        if d <= floor || !d.is_finite() {
            continue;
        }
        let root = d.sqrt();
        set(&mut l, j, j, root);
        for i in j + 1..N {
            let mut s = at(q, i, j);
            for k in 0..j {
                s -= at(&l, i, k) * at(&l, j, k);
            }
            set(&mut l, i, j, s / root);
        }
    }
    l
}

/// `m[(i, j)]`, 0 out of range (no panic path).
fn at<T: Real, const R: usize, const C: usize>(m: &SMatrix<T, R, C>, i: usize, j: usize) -> T {
    m.get((i, j)).copied().unwrap_or_else(T::zero)
}

fn set<T: Real, const R: usize, const C: usize>(m: &mut SMatrix<T, R, C>, i: usize, j: usize, v: T) {
    if let Some(e) = m.get_mut((i, j)) {
        *e = v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_noise_has_unit_variance_and_a_semi_definite_root_rebuilds_its_matrix() {
        let mut noise = Noise(7);
        let v: f64 = (0..100_000).map(|_| f64::from(noise.unit()).powi(2)).sum::<f64>() / 1e5;
        assert!((v - 1.0).abs() < 0.02, "{v}");
        let b = nalgebra::Matrix3x2::new(1.0, 0.5, -2.0, 0.1, 0.3, 4.0);
        let q = b * b.transpose();
        let l = psd_root(&q);
        assert!((l * l.transpose() - q).abs().max() < 1e-12);
        assert!(positive_definite(&(q + nalgebra::Matrix3::identity())));
        assert!(!positive_definite(&(q - nalgebra::Matrix3::identity() * 0.1)));
    }
}
