//! edgekf's `KalmanFilter` and `UnscentedKalmanFilter` against filterpy, step by step, in `f64`.
//!
//! The fixtures (`tests/fixtures/filterpy_*.json`) are written by `tools/fixtures/gen_filterpy.py`
//! with filterpy's `KalmanFilter` (Joseph-form update) and `UnscentedKalmanFilter` with
//! `MerweScaledSigmaPoints`; they hold each problem's definition, its measurements and filterpy's
//! `x`, `P` after every predict and update, and the innovation `y`, `S` and NIS of every update.
//! No Python is needed here: the JSON is committed and compiled in.
//!
//! Agreement criterion, for every element `a` (edgekf) of `x`, `P`, `y`, `S` and NIS against `b`
//! (the reference) after every predict and every update:
//!
//! ```text
//! |a − b| ≤ tol · max(|b|, scale)
//! ```
//!
//! with `tol = 1e-9`, and each element's natural scale: `√(Pᵢᵢ Pⱼⱼ)` for `Pᵢⱼ` (≥ |Pᵢⱼ| by
//! Cauchy–Schwarz, so diagonals and correlated pairs are held to 1e-9 *relative*; a near-zero
//! correlation carries round-off of order ε·√(Pᵢᵢ Pⱼⱼ) in any implementation, filterpy included),
//! `√(Sᵢᵢ Sⱼⱼ)` for `Sᵢⱼ`, `√Sᵢᵢ` for the innovation `yᵢ`, `M` (its expected value) for the NIS,
//! and for a state component the largest magnitude that component takes in the reference run.
//!
//! The UKF with α = 1e-3 is ill-conditioned: its weights are about −1e6 and 2.5e5, so the
//! rounding of `f`'s and `h`'s outputs reaches the means amplified by `|Wm₀| ≈ 1e6`, in filterpy
//! as in edgekf. For every UKF problem the fixtures also hold the exact filter (60-digit mpmath,
//! same float inputs), and the tolerance is `max(1e-9, 100 · ε · |Wm₀|)`: 1e-9 for the
//! well-conditioned problems, 2.2e-8 at α = 1e-3. edgekf is checked against both filterpy and the
//! exact trajectory. `cargo test -p edgekf --test filterpy -- --nocapture` prints the measured
//! worst errors.
//!
//! The UKF process and measurement models below are written with the same operations in the same
//! order as their Python twins.

use edgekf::filter::{FilterHealth, KalmanFilter, LinearModel, MerweSigmaPoints, UkfModel, UnscentedKalmanFilter};
use edgekf::Real;
use nalgebra::{SMatrix, SVector};
use serde::Deserialize;

const KF_JSON: &str = include_str!("fixtures/filterpy_kf.json");
const UKF_JSON: &str = include_str!("fixtures/filterpy_ukf.json");

/// Relative tolerance of the agreement criterion (see the module documentation).
const REL_TOL: f64 = 1e-9;

type Mat = Vec<Vec<f64>>;

#[derive(Deserialize)]
struct Fixture<P> {
    filterpy: String,
    problems: Vec<P>,
}

/// One reference step: after predict (`prior`) and after update (`post`), with the innovation
/// (filterpy's runs; the exact UKF reference has none).
#[derive(Deserialize)]
struct Step {
    x_prior: Vec<f64>,
    #[serde(rename = "P_prior")]
    p_prior: Mat,
    x_post: Vec<f64>,
    #[serde(rename = "P_post")]
    p_post: Mat,
    y: Option<Vec<f64>>,
    #[serde(rename = "S")]
    s: Option<Mat>,
    nis: Option<f64>,
}

#[derive(Deserialize)]
struct KfProblem {
    name: String,
    #[serde(rename = "F")]
    f: Mat,
    #[serde(rename = "H")]
    h: Mat,
    #[serde(rename = "Q")]
    q: Mat,
    #[serde(rename = "R")]
    r: Mat,
    x0: Vec<f64>,
    #[serde(rename = "P0")]
    p0: Mat,
    zs: Vec<Vec<f64>>,
    steps: Vec<Step>,
}

#[derive(Deserialize)]
struct UkfProblem {
    name: String,
    model: String,
    constants: serde_json::Value,
    alpha: f64,
    beta: f64,
    kappa: f64,
    #[serde(rename = "Wm")]
    wm: Vec<f64>,
    #[serde(rename = "Wc")]
    wc: Vec<f64>,
    #[serde(rename = "Q")]
    q: Mat,
    #[serde(rename = "R")]
    r: Mat,
    x0: Vec<f64>,
    #[serde(rename = "P0")]
    p0: Mat,
    zs: Vec<Vec<f64>>,
    steps: Vec<Step>,
    exact: Vec<Step>,
}

fn matrix<const R: usize, const C: usize>(rows: &Mat) -> SMatrix<f64, R, C> {
    assert_eq!(rows.len(), R, "row count");
    assert!(rows.iter().all(|r| r.len() == C), "column count");
    SMatrix::from_fn(|i, j| rows[i][j])
}

fn vector<const R: usize>(v: &[f64]) -> SVector<f64, R> {
    assert_eq!(v.len(), R, "vector length");
    SVector::from_fn(|i, _| v[i])
}

/// The worst agreement seen for one quantity of one problem.
#[derive(Default)]
struct Worst {
    /// Largest `|a − b| / max(|b|, scale)`.
    rel: f64,
    at: String,
}

/// What edgekf produced in one step, for comparison with a reference [`Step`].
struct Produced<const N: usize, const M: usize> {
    x_prior: SVector<f64, N>,
    p_prior: SMatrix<f64, N, N>,
    x_post: SVector<f64, N>,
    p_post: SMatrix<f64, N, N>,
    y: SVector<f64, M>,
    s: SMatrix<f64, M, M>,
    nis: f64,
}

/// Checks edgekf's run against one reference run (filterpy's or the exact one) and keeps the
/// worst error per quantity.
struct Checker {
    label: String,
    tol: f64,
    worst: std::collections::BTreeMap<&'static str, Worst>,
    failures: Vec<String>,
}

impl Checker {
    fn new(label: String, tol: f64) -> Self {
        Self { label, tol, worst: Default::default(), failures: Vec::new() }
    }

    fn element(&mut self, what: &'static str, step: usize, idx: (usize, usize), a: f64, b: f64, scale: f64) {
        let rel = if a == b { 0.0 } else { (a - b).abs() / b.abs().max(scale) };
        let worst = self.worst.entry(what).or_default();
        // A NaN is recorded and fails.
        if rel.is_nan() || rel > worst.rel {
            *worst = Worst { rel, at: format!("step {step} {what}[{},{}]: edgekf {a:e}, ref {b:e}", idx.0, idx.1) };
        }
        if rel.is_nan() || rel > self.tol {
            self.failures.push(format!(
                "{}: step {step} {what}[{},{}]: edgekf {a:e}, reference {b:e} (error {rel:.2e} > {:.1e})",
                self.label, idx.0, idx.1, self.tol
            ));
        }
    }

    /// A state vector; `scales[i]` is the largest `|xᵢ|` of the reference run.
    fn state<const N: usize>(
        &mut self,
        what: &'static str,
        step: usize,
        a: &SVector<f64, N>,
        b: &[f64],
        scales: &[f64],
    ) {
        let b = vector::<N>(b);
        for i in 0..N {
            self.element(what, step, (i, 0), a[i], b[i], scales[i]);
        }
    }

    /// A covariance; element `(i, j)` is scaled by `√(bᵢᵢ bⱼⱼ)`.
    fn covariance<const N: usize>(&mut self, what: &'static str, step: usize, a: &SMatrix<f64, N, N>, b: &Mat) {
        let b = matrix::<N, N>(b);
        for i in 0..N {
            for j in 0..N {
                let scale = (b[(i, i)] * b[(j, j)]).abs().sqrt();
                self.element(what, step, (i, j), a[(i, j)], b[(i, j)], scale);
            }
        }
    }

    fn step<const N: usize, const M: usize>(
        &mut self,
        k: usize,
        ours: &Produced<N, M>,
        r: &Step,
        scales: &[[f64; N]; 2],
    ) {
        self.state("x_prior", k, &ours.x_prior, &r.x_prior, &scales[0]);
        self.covariance("P_prior", k, &ours.p_prior, &r.p_prior);
        self.state("x_post", k, &ours.x_post, &r.x_post, &scales[1]);
        self.covariance("P_post", k, &ours.p_post, &r.p_post);
        if let (Some(y), Some(s), Some(nis)) = (&r.y, &r.s, r.nis) {
            let s_ref = matrix::<M, M>(s);
            let y_ref = vector::<M>(y);
            for i in 0..M {
                self.element("y", k, (i, 0), ours.y[i], y_ref[i], s_ref[(i, i)].abs().sqrt());
            }
            self.covariance("S", k, &ours.s, s);
            self.element("nis", k, (0, 0), ours.nis, nis, M as f64);
        }
    }

    /// Checks a whole run and prints the worst error per quantity.
    fn run<const N: usize, const M: usize>(mut self, ours: &[Produced<N, M>], reference: &[Step]) -> Vec<String> {
        assert_eq!(ours.len(), reference.len(), "{}: step count", self.label);
        let mut scales = [[0.0f64; N]; 2];
        for r in reference {
            for (scale, x) in scales.iter_mut().zip([&r.x_prior, &r.x_post]) {
                for (s, v) in scale.iter_mut().zip(x) {
                    *s = s.max(v.abs());
                }
            }
        }
        for (k, (o, r)) in ours.iter().zip(reference).enumerate() {
            self.step(k, o, r, &scales);
        }
        let overall = self.worst.values().fold(0.0f64, |m, w| m.max(w.rel));
        println!("{}: worst error {overall:.2e} (tolerance {:.1e})", self.label, self.tol);
        for (what, w) in &self.worst {
            println!("    {what:8} {:.2e}  ({})", w.rel, w.at);
        }
        self.failures
    }
}

// ---------------------------------------------------------------------------------------------
// Linear Kalman filter
// ---------------------------------------------------------------------------------------------

fn run_kf<const N: usize, const M: usize>(p: &KfProblem) -> Vec<String> {
    let model = LinearModel::<f64, N, M> { a: matrix(&p.f), c: matrix(&p.h), q: matrix(&p.q), r: matrix(&p.r) };
    let mut kf = KalmanFilter::new(model, vector(&p.x0), matrix(&p.p0));
    let mut ours = Vec::new();
    for z in &p.zs {
        kf.predict();
        let (x_prior, p_prior) = (*kf.state(), *kf.covariance());
        let inn = kf.update(&vector::<M>(z)).expect("update refused");
        let (x_post, p_post) = (*kf.state(), *kf.covariance());
        ours.push(Produced { x_prior, p_prior, x_post, p_post, y: inn.residual, s: inn.s, nis: inn.nis });
    }
    assert_eq!(kf.health(), FilterHealth::default(), "{}", p.name);
    Checker::new(format!("KF {} vs filterpy", p.name), REL_TOL).run(&ours, &p.steps)
}

#[test]
fn kalman_filter_matches_filterpy() {
    let fixture: Fixture<KfProblem> = serde_json::from_str(KF_JSON).expect("fixture JSON");
    println!("fixtures from filterpy {}", fixture.filterpy);
    let mut failures = Vec::new();
    let mut names = Vec::new();
    for p in &fixture.problems {
        failures.extend(match p.name.as_str() {
            "constant_velocity_2d" => run_kf::<4, 2>(p),
            "coupled_6state" => run_kf::<6, 3>(p),
            other => panic!("unknown KF problem {other}"),
        });
        names.push(p.name.as_str());
    }
    assert_eq!(names, ["constant_velocity_2d", "coupled_6state"]);
    assert!(failures.is_empty(), "{} disagreements, first: {:#?}", failures.len(), &failures[..failures.len().min(10)]);
}

// ---------------------------------------------------------------------------------------------
// Unscented Kalman filter. Keep f and h identical to tools/fixtures/gen_filterpy.py.
// ---------------------------------------------------------------------------------------------

/// A point on a spring with quadratic drag in the plane, state `(px, py, vx, vy)`, ranged from
/// two beacons. Symplectic Euler: velocity first, then position with the new velocity.
struct SpringDragRanges<T> {
    dt: T,
    omega2: T,
    drag: T,
    beacons: [(T, T); 2],
}

impl<T: Real> SpringDragRanges<T> {
    const DT: f64 = 0.1;
    const OMEGA2: f64 = 0.04;
    const DRAG: f64 = 0.05;
    const BEACONS: [(f64, f64); 2] = [(-50.0, -50.0), (50.0, -50.0)];

    fn new() -> Self {
        let c = T::of_f64;
        Self {
            dt: c(Self::DT),
            omega2: c(Self::OMEGA2),
            drag: c(Self::DRAG),
            beacons: Self::BEACONS.map(|(x, y)| (c(x), c(y))),
        }
    }
}

impl<T: Real> UkfModel<T, 4, 2> for SpringDragRanges<T> {
    fn f(&self, x: &SVector<T, 4>) -> SVector<T, 4> {
        let (px, py, vx, vy) = (x[0], x[1], x[2], x[3]);
        let speed = (vx * vx + vy * vy).sqrt();
        let nvx = vx + self.dt * (-self.omega2 * px - self.drag * speed * vx);
        let nvy = vy + self.dt * (-self.omega2 * py - self.drag * speed * vy);
        SVector::<T, 4>::new(px + self.dt * nvx, py + self.dt * nvy, nvx, nvy)
    }

    fn h(&self, x: &SVector<T, 4>) -> SVector<T, 2> {
        let range = |(bx, by): (T, T)| {
            let dx = x[0] - bx;
            let dy = x[1] - by;
            (dx * dx + dy * dy).sqrt()
        };
        SVector::<T, 2>::new(range(self.beacons[0]), range(self.beacons[1]))
    }
}

/// A Duffing oscillator, state `(position, velocity)`, seen through a cubic sensor.
struct DuffingCubic {
    dt: f64,
    linear: f64,
    cubic: f64,
    damping: f64,
    sensor_cubic: f64,
}

const DUFFING: DuffingCubic = DuffingCubic { dt: 0.05, linear: 1.0, cubic: 0.5, damping: 0.1, sensor_cubic: 0.25 };

impl UkfModel<f64, 2, 1> for DuffingCubic {
    fn f(&self, x: &SVector<f64, 2>) -> SVector<f64, 2> {
        let (p, v) = (x[0], x[1]);
        let nv = v + self.dt * (-self.linear * p - self.cubic * p * p * p - self.damping * v);
        SVector::<f64, 2>::new(p + self.dt * nv, nv)
    }

    fn h(&self, x: &SVector<f64, 2>) -> SVector<f64, 1> {
        let p = x[0];
        SVector::<f64, 1>::new(p + self.sensor_cubic * p * p * p)
    }
}

/// The Python constants must be the ones compiled in here.
fn check_constants(p: &UkfProblem) {
    let c = &p.constants;
    let num = |k: &str| c[k].as_f64().unwrap_or_else(|| panic!("{}: constant {k}", p.name));
    match p.model.as_str() {
        "spring_drag_ranges" => {
            type S = SpringDragRanges<f64>;
            assert_eq!((num("dt"), num("omega2"), num("drag")), (S::DT, S::OMEGA2, S::DRAG));
            let b: Vec<(f64, f64)> = c["beacons"]
                .as_array()
                .expect("beacons")
                .iter()
                .map(|xy| (xy[0].as_f64().expect("bx"), xy[1].as_f64().expect("by")))
                .collect();
            assert_eq!(b, S::BEACONS);
        }
        "duffing_cubic" => {
            let d = &DUFFING;
            let ours = (d.dt, d.linear, d.cubic, d.damping, d.sensor_cubic);
            assert_eq!((num("dt"), num("linear"), num("cubic"), num("damping"), num("sensor_cubic")), ours);
        }
        other => panic!("unknown UKF model {other}"),
    }
}

fn run_ukf<F: UkfModel<f64, N, M>, const N: usize, const M: usize>(p: &UkfProblem, model: &F) -> Vec<String> {
    check_constants(p);
    let points = MerweSigmaPoints { alpha: p.alpha, beta: p.beta, kappa: p.kappa };
    let mut ukf =
        UnscentedKalmanFilter::<f64, N, M>::new(points, matrix(&p.q), matrix(&p.r), vector(&p.x0), matrix(&p.p0))
            .expect("valid UKF problem");
    let w = *ukf.weights();
    assert_eq!(p.wm.len(), 2 * N + 1);
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    assert!(rel(w.mean_center, p.wm[0]) < 1e-15 && rel(w.cov_center, p.wc[0]) < 1e-15, "{}: centre weights", p.name);
    assert!(p.wm[1..].iter().chain(&p.wc[1..]).all(|v| rel(w.side, *v) < 1e-15), "{}: side weights", p.name);

    let mut ours = Vec::new();
    for z in &p.zs {
        ukf.predict(model);
        let (x_prior, p_prior) = (*ukf.state(), *ukf.covariance());
        let inn = ukf.update(model, &vector::<M>(z)).expect("update refused");
        let (x_post, p_post) = (*ukf.state(), *ukf.covariance());
        ours.push(Produced { x_prior, p_prior, x_post, p_post, y: inn.residual, s: inn.s, nis: inn.nis });
    }
    assert_eq!(ukf.health(), FilterHealth::default(), "{}", p.name);
    // 1e-9, or 100× the rounding floor of the unscented sums when that is larger (α = 1e-3).
    let tol = REL_TOL.max(100.0 * f64::EPSILON * w.mean_center.abs());
    let mut failures = Checker::new(format!("UKF {} vs filterpy", p.name), tol).run(&ours, &p.steps);
    failures.extend(Checker::new(format!("UKF {} vs exact", p.name), tol).run(&ours, &p.exact));
    failures
}

#[test]
fn unscented_filter_matches_filterpy() {
    let fixture: Fixture<UkfProblem> = serde_json::from_str(UKF_JSON).expect("fixture JSON");
    println!("fixtures from filterpy {}", fixture.filterpy);
    let mut failures = Vec::new();
    let mut names = Vec::new();
    for p in &fixture.problems {
        failures.extend(match p.model.as_str() {
            "spring_drag_ranges" => run_ukf::<_, 4, 2>(p, &SpringDragRanges::<f64>::new()),
            "duffing_cubic" => run_ukf::<_, 2, 1>(p, &DUFFING),
            other => panic!("unknown UKF model {other}"),
        });
        names.push(p.name.as_str());
    }
    assert_eq!(names, ["spring_drag_ranges", "duffing_alpha_1e-3", "duffing_alpha_0.5_kappa_1"]);
    assert!(failures.is_empty(), "{} disagreements, first: {:#?}", failures.len(), &failures[..failures.len().min(10)]);
}

// ---------------------------------------------------------------------------------------------
// The same UKF problem in f32, long.
// ---------------------------------------------------------------------------------------------

/// Deterministic standard normal draws (SplitMix64 + Box–Muller).
struct Normal(u64);

impl Normal {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn next(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform(); // (0, 1]
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }

    fn vector<const N: usize>(&mut self, cov: &SMatrix<f64, N, N>) -> SVector<f64, N> {
        let l = cov.cholesky().expect("positive definite").unpack();
        l * SVector::<f64, N>::from_fn(|_, _| self.next())
    }
}

/// The spring/drag/ranges problem of the fixtures (same α, β, κ, Q, R, x₀, P₀), run for 10 000
/// steps (1000 s) in `f32` and in `f64` on one simulated truth: `f32` must never reset its
/// covariance nor refuse an update, stay consistent (mean NIS ≈ 2, mean NEES ≈ 4, errors within
/// 5σ), and stay within 1 % of its σ of the `f64` filter.
#[test]
fn unscented_filter_runs_10000_steps_in_f32_without_resets() {
    let fixture: Fixture<UkfProblem> = serde_json::from_str(UKF_JSON).expect("fixture JSON");
    let p = fixture.problems.iter().find(|p| p.name == "spring_drag_ranges").expect("problem");
    let (q, r) = (matrix::<4, 4>(&p.q), matrix::<2, 2>(&p.r));
    let (x0, p0) = (vector::<4>(&p.x0), matrix::<4, 4>(&p.p0));
    let c = |v: f64| v as f32;
    let points32 = MerweSigmaPoints { alpha: c(p.alpha), beta: c(p.beta), kappa: c(p.kappa) };
    let mut ukf32 = UnscentedKalmanFilter::<f32, 4, 2>::new(points32, q.map(c), r.map(c), x0.map(c), p0.map(c))
        .expect("valid in f32");
    let points64 = MerweSigmaPoints { alpha: p.alpha, beta: p.beta, kappa: p.kappa };
    let mut ukf64 = UnscentedKalmanFilter::<f64, 4, 2>::new(points64, q, r, x0, p0).expect("valid");
    let (m32, m64) = (SpringDragRanges::<f32>::new(), SpringDragRanges::<f64>::new());

    let mut rng = Normal(11);
    let mut truth = SVector::<f64, 4>::new(10.0, 0.0, 0.0, 2.0);
    let (mut nis_sum, mut nees_sum, mut worst_err_sigma, mut worst_32_64_sigma) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    const STEPS: usize = 10_000;
    for _ in 0..STEPS {
        truth = m64.f(&truth) + rng.vector(&q);
        let z = m64.h(&truth) + rng.vector(&r);
        ukf32.predict(&m32);
        ukf64.predict(&m64);
        let inn = ukf32.update(&m32, &z.map(c)).expect("f32 update refused");
        ukf64.update(&m64, &z).expect("f64 update refused");
        nis_sum += f64::from(inn.nis);
        let (x32, p32) = (ukf32.state().map(f64::from), ukf32.covariance().map(f64::from));
        let err = x32 - truth;
        nees_sum += err.dot(&p32.cholesky().expect("P positive definite").solve(&err));
        for i in 0..4 {
            let sigma = p32[(i, i)].sqrt();
            worst_err_sigma = worst_err_sigma.max((x32[i] - truth[i]).abs() / sigma);
            worst_32_64_sigma = worst_32_64_sigma.max((x32[i] - ukf64.state()[i]).abs() / sigma);
        }
    }
    let (mean_nis, mean_nees) = (nis_sum / STEPS as f64, nees_sum / STEPS as f64);
    println!(
        "f32, {STEPS} steps: mean NIS {mean_nis:.3}, mean NEES {mean_nees:.3}, worst |x − truth|/σ {worst_err_sigma:.2}, \
         worst |x32 − x64|/σ {worst_32_64_sigma:.2e}, health {:?}",
        ukf32.health()
    );
    assert_eq!(ukf32.health(), FilterHealth::default());
    assert_eq!(ukf64.health(), FilterHealth::default());
    // χ²(2) has mean 2 and standard deviation 2: over 10 000 nearly independent samples the mean
    // is 2 ± 0.02; ±0.2 leaves room for the filter's own approximation.
    assert!((mean_nis - 2.0).abs() < 0.2, "mean NIS {mean_nis}");
    // The estimation error against the truth: NEES ≈ n = 4 (seeds 1…11 gave 3.8…4.1).
    assert!((mean_nees - 4.0).abs() < 0.4, "mean NEES {mean_nees}");
    // 40 000 normalised errors: beyond 5σ would be a broken covariance.
    assert!(worst_err_sigma < 5.0, "worst error {worst_err_sigma} σ");
    assert!(worst_32_64_sigma < 0.01, "f32 departs from f64 by {worst_32_64_sigma} σ");
}
