//! Identifiability of two simultaneous clearances (A and B) from the crank angular
//! acceleration: an ensemble likelihood surface over (cA, cB) and the Fisher information at a
//! reference point, for the features the estimators use.
//!
//! **Verdict: with these features a 10 s recording cannot give both clearances within ±10 %.**
//! The limit is not that B is invisible (the features flag it, and the surface falls steeply
//! towards smaller cB) but that the features see mostly one combination of the two clearances,
//! and the chaotic scatter of 10 s of impacts leaves the other direction at a std of ~0.036 mm.
//!
//! The measured tables (Cramér–Rao bounds per feature set, the likelihood surfaces) are in
//! `docs/crank_two_clearances.md`, each with the command that makes it.
//!
//! Method. The dynamics are chaotic, so a feature of one run is a draw from a distribution; the
//! ensemble of runs at a clearance pair is the measurement model.
//!
//! * Runs: [`Design::runs`] per grid point, run `r` released at `30° + spread · u_r`
//!   (`u_r` uniform in −1…1) with noise seed `seed_base + r`; the **same** `(angle, seed)` list at
//!   every grid point (common random numbers, so that differences between grid points are
//!   paired). Adaptive integrator at the configuration's tolerance, the configured sensor noise.
//! * Features per run ([`FEATURE_NAMES`]): the fast model's ten ([`model::feature_vector`],
//!   window means in logarithms) and the paper's spectral feature `a` ([`crate::systems::crank::feature`])
//!   in logarithms, of the release window and averaged over the later windows. Three sets are
//!   analysed ([`FeatureSet`]).
//! * Covariance `Σ`: pooled within-point covariance of the reference point and its four
//!   neighbours (the Fisher stencil), `n = 5 (runs − 1)` degrees of freedom; its inverse is
//!   unbiased by the Wishart factor `(n − p − 1) / n`. Runs shorter than the recording
//!   ([`Design::record_s`]) have their covariance scaled by `duration / record_s` (features
//!   are window means: their variance falls as 1 / the number of windows).
//! * Surface: for each grid point `g`, the expected log-likelihood ratio of a recording from the
//!   reference, `E ln L(g) − E ln L(ref) = −½ dᵀ Σ⁻¹ d` with `d = μ_g − μ_ref` (a common `Σ`);
//!   `dᵀ Σ⁻¹ d` is unbiased for the ensembles' own error by subtracting `tr(Σ⁻¹ Cov d̂)`, `Cov d̂`
//!   from the spread of the paired differences. Points above −3.0 (χ²₂ 95 %: 5.99 / 2) are not
//!   excluded by a 10 s recording.
//! * Fisher: `I = Jᵀ Σ⁻¹ J`, `J` the central differences of the ensemble means at the grid
//!   neighbours (`±` [`Fisher::step`]), unbiased the same way (`E[Jᵢᵀ A Jₖ] = true + tr(A Cov(Jᵢ,
//!   Jₖ))`); the covariance's own dependence on the clearance (`½ tr(Σ⁻¹∂Σ Σ⁻¹∂Σ)`) is left out.
//!   Cramér–Rao bounds `√diag I⁻¹`, the correlation of the two estimates from `I⁻¹`, and the
//!   eigenvector of the smallest eigenvalue of `I`: the direction in (cA, cB) the features do
//!   not see.

use crate::systems::crank::config::Method;
use crate::systems::crank::estimate::model::{self, feature_vector};
use crate::systems::crank::feature::window_features;
use crate::systems::crank::parallel::map_in_order;
use crate::systems::crank::{CrankConfig, Mechanism, SimOptions};
use nalgebra::DVector;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::sync::atomic::{AtomicUsize, Ordering};

mod fisher;
pub use fisher::{fisher, fisher_text, pooled_covariance, precision, surface, Fisher};

/// Number of features per run.
pub const FEATURES: usize = model::FEATURES + 2;

/// The features of a run: the fast model's ten, then `ln a` of the release window and of the
/// mean over the later windows.
///
/// ```
/// use edgekf_sim::systems::crank::studies::identify2::FEATURE_NAMES;
/// assert_eq!((FEATURE_NAMES[0], FEATURE_NAMES[9]), ("ln_rms", "ln_diff_median"));
/// assert_eq!(&FEATURE_NAMES[10..], ["ln_a_release", "ln_a_later"]);
/// ```
pub const FEATURE_NAMES: [&str; FEATURES] = {
    let mut names = [""; FEATURES];
    let mut i = 0;
    while i < model::FEATURES {
        names[i] = model::FEATURE_NAMES[i];
        i += 1;
    }
    names[FEATURES - 2] = "ln_a_release";
    names[FEATURES - 1] = "ln_a_later";
    names
};

/// Which features a likelihood or Fisher matrix uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FeatureSet {
    /// The fast model's ten.
    Fast,
    /// The paper's spectral `a`: release window and later windows.
    Spectral,
    /// All twelve.
    All,
}

impl FeatureSet {
    /// The three sets.
    pub const ALL: [FeatureSet; 3] = [FeatureSet::Fast, FeatureSet::Spectral, FeatureSet::All];

    /// Indices into [`FEATURE_NAMES`].
    pub fn indices(self) -> Vec<usize> {
        match self {
            FeatureSet::Fast => (0..10).collect(),
            FeatureSet::Spectral => vec![10, 11],
            FeatureSet::All => (0..FEATURES).collect(),
        }
    }

    /// A short name.
    pub fn name(self) -> &'static str {
        match self {
            FeatureSet::Fast => "fast (10)",
            FeatureSet::Spectral => "spectral a (2)",
            FeatureSet::All => "all (12)",
        }
    }
}

/// How the ensembles are simulated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Design {
    /// Length of each run, s.
    pub duration: f64,
    /// The recording the figures are for, s (covariance × `duration / record_s`).
    pub record_s: f64,
    /// Runs per grid point.
    pub runs: usize,
    /// Release angle of the centre, degrees.
    pub release_deg: f64,
    /// Release angles are drawn uniformly within `± release_spread_deg` of the centre.
    pub release_spread_deg: f64,
    /// Seed of the angle draws and base of the noise seeds.
    pub seed_base: u64,
    /// Threads.
    pub threads: usize,
}

impl Default for Design {
    /// 16 runs of 10 s per point released within 30 ± 10°, for a 10 s recording, 2 threads.
    fn default() -> Self {
        Self {
            duration: 10.0,
            record_s: 10.0,
            runs: 16,
            release_deg: 30.0,
            release_spread_deg: 10.0,
            seed_base: 900_000,
            threads: 2,
        }
    }
}

impl Design {
    /// `(release angle, noise seed)` of every run (the same at every grid point).
    pub fn draws(&self) -> Vec<(f64, u64)> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed_base);
        (0..self.runs)
            .map(|r| {
                let u: f64 = rng.gen_range(-1.0..1.0);
                (self.release_deg + self.release_spread_deg * u, self.seed_base + r as u64)
            })
            .collect()
    }
}

/// The features of one run ([`FEATURE_NAMES`]) with clearances `clearance` (m), adaptive
/// integrator.
pub fn run_features(
    base: &CrankConfig,
    clearance: [Option<f64>; 3],
    release_deg: f64,
    seed: u64,
    duration: f64,
) -> anyhow::Result<[f64; FEATURES]> {
    let mut cfg = *base;
    cfg.release.crank_angle_deg = release_deg;
    cfg.integrator.method = Method::Adaptive;
    let m = Mechanism::new(&cfg, clearance)?;
    let rec = m.simulate(&SimOptions { seed, ..SimOptions::from_config(&cfg, duration) })?;
    let rate = cfg.sensor.sample_rate;
    let fast = feature_vector(&rec.crank_alpha, rate, 0.25);
    let a: Vec<f64> =
        window_features(&rec.crank_alpha, rate, 0.25).iter().map(|f| f.map_or(f64::NAN, |f| f.a)).collect();
    if a.len() < 2 || a.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        anyhow::bail!("run of {duration} s: the spectral feature needs two windows with a fit");
    }
    let mut out = [0.0; FEATURES];
    out[..10].copy_from_slice(&fast.values);
    out[10] = a[0].ln();
    out[11] = (a[1..].iter().sum::<f64>() / (a.len() - 1) as f64).ln();
    Ok(out)
}

/// The runs of one grid point.
#[derive(Debug, Clone, PartialEq)]
pub struct Ensemble {
    /// Clearances A, B, C, m.
    pub clearance: [Option<f64>; 3],
    /// Features of each run, in the order of [`Design::draws`].
    pub features: Vec<[f64; FEATURES]>,
}

impl Ensemble {
    /// Mean of the features `idx`.
    pub fn mean(&self, idx: &[usize]) -> DVector<f64> {
        let n = self.features.len() as f64;
        DVector::from_iterator(idx.len(), idx.iter().map(|&i| self.features.iter().map(|f| f[i]).sum::<f64>() / n))
    }
}

/// Simulates every grid point's ensemble on [`Design::threads`] threads; `progress(done, total)`.
pub fn simulate_ensembles(
    base: &CrankConfig,
    points: &[[Option<f64>; 3]],
    design: &Design,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> anyhow::Result<Vec<Ensemble>> {
    let draws = design.draws();
    let jobs: Vec<(usize, usize)> = (0..points.len()).flat_map(|p| (0..draws.len()).map(move |r| (p, r))).collect();
    let done = AtomicUsize::new(0);
    let feats = map_in_order(design.threads, &jobs, |_, &(p, r)| {
        let (angle, seed) = draws[r];
        let f = run_features(base, points[p], angle, seed, design.duration);
        progress(done.fetch_add(1, Ordering::Relaxed) + 1, jobs.len());
        f
    });
    let mut feats = feats.into_iter();
    points
        .iter()
        .map(|&clearance| {
            let features = feats.by_ref().take(draws.len()).collect::<anyhow::Result<Vec<_>>>()?;
            Ok(Ensemble { clearance, features })
        })
        .collect()
}

/// The standard analysis: a grid `ca × cb` (m) with the reference at grid indices
/// `(ia, ib)`, the Fisher matrices of each feature set over (cA, cB) there, and — when
/// `single` is given, ensembles at A alone `[cA − h, cA, cA + h]` — the one-parameter Fisher of
/// the single-clearance case.
#[derive(Debug, Clone, PartialEq)]
pub struct Analysis {
    /// Clearances at A of the grid, m.
    pub ca: Vec<f64>,
    /// Clearances at B, m.
    pub cb: Vec<f64>,
    /// Reference indices into `ca`, `cb`.
    pub reference: (usize, usize),
    /// Ensembles, `ca`-major (`ensembles[i * cb.len() + j]`).
    pub ensembles: Vec<Ensemble>,
    /// Single-clearance ensembles at A (`cA − h, cA, cA + h`, B and C tight), if simulated.
    pub single: Vec<Ensemble>,
    /// The design.
    pub design: Design,
}

impl Analysis {
    /// Simulates the grid (and the single-clearance stencil if `single`).
    pub fn simulate(
        base: &CrankConfig,
        ca: &[f64],
        cb: &[f64],
        reference: (usize, usize),
        single: bool,
        design: &Design,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> anyhow::Result<Self> {
        let (ia, ib) = reference;
        if !(1..ca.len().saturating_sub(1)).contains(&ia) || !(1..cb.len().saturating_sub(1)).contains(&ib) {
            anyhow::bail!("the reference must have a grid neighbour on each side in cA and cB");
        }
        let mut points: Vec<[Option<f64>; 3]> =
            ca.iter().flat_map(|&a| cb.iter().map(move |&b| [Some(a), Some(b), None])).collect();
        if single {
            points.extend([ca[ia - 1], ca[ia], ca[ia + 1]].map(|a| [Some(a), None, None]));
        }
        let mut ensembles = simulate_ensembles(base, &points, design, progress)?;
        let single = ensembles.split_off(ca.len() * cb.len());
        Ok(Self { ca: ca.to_vec(), cb: cb.to_vec(), reference, ensembles, single, design: *design })
    }

    /// The ensemble at grid indices `(i, j)`.
    pub fn at(&self, i: usize, j: usize) -> &Ensemble {
        &self.ensembles[i * self.cb.len() + j]
    }

    /// Fisher over (cA, cB) at the reference (central differences over the grid neighbours;
    /// the grid must be evenly spaced there).
    pub fn fisher2(&self, set: FeatureSet) -> Option<Fisher> {
        let (i, j) = self.reference;
        let ha = 0.5 * (self.ca[i + 1] - self.ca[i - 1]);
        let hb = 0.5 * (self.cb[j + 1] - self.cb[j - 1]);
        fisher(
            self.at(i, j),
            &[(self.at(i - 1, j), self.at(i + 1, j)), (self.at(i, j - 1), self.at(i, j + 1))],
            &[ha, hb],
            &[self.ca[i], self.cb[j]],
            set,
            &self.design,
        )
    }

    /// Fisher over cA alone with A the only clearance (`None` without the single stencil).
    pub fn fisher_single(&self, set: FeatureSet) -> Option<Fisher> {
        let [m, c, p] = self.single.as_slice() else { return None };
        let h = 0.5 * (p.clearance[0]? - m.clearance[0]?);
        fisher(c, &[(m, p)], &[h], &[c.clearance[0]?], set, &self.design)
    }

    /// The surface ([`surface`]) of the reference against the grid, `ca`-major, with the
    /// covariance pooled over the Fisher stencil.
    pub fn surface(&self, set: FeatureSet) -> Option<Vec<f64>> {
        let (i, j) = self.reference;
        let idx = set.indices();
        let stencil = [self.at(i, j), self.at(i - 1, j), self.at(i + 1, j), self.at(i, j - 1), self.at(i, j + 1)];
        let (cov, dof) = pooled_covariance(&stencil, &idx);
        let a = precision(&cov, dof, &self.design)?;
        Some(surface(self.at(i, j), &self.ensembles, &idx, &a))
    }

    /// The analysis with the runs `runs` (indices into [`Design::draws`], repeats allowed) at
    /// every point: a resample (jackknife, bootstrap) that keeps the grid points paired.
    pub fn resampled(&self, runs: &[usize]) -> Self {
        let pick =
            |e: &Ensemble| Ensemble { clearance: e.clearance, features: runs.iter().map(|&r| e.features[r]).collect() };
        Self {
            ensembles: self.ensembles.iter().map(pick).collect(),
            single: self.single.iter().map(pick).collect(),
            ..self.clone()
        }
    }

    /// Delete-one jackknife over the runs (the same run left out at every point): standard
    /// errors of the relative bounds of cA and cB and of the correlation (NaN when a
    /// leave-one-out `I` is not positive definite).
    pub fn jackknife(&self, set: FeatureSet) -> [f64; 3] {
        let n = self.ensembles.first().map_or(0, |e| e.features.len());
        let mut v: [Vec<f64>; 3] = Default::default();
        for leave in 0..n {
            let runs: Vec<usize> = (0..n).filter(|&r| r != leave).collect();
            let f = self.resampled(&runs).fisher2(set);
            let (crb, rho) = f.map_or((vec![f64::NAN; 2], f64::NAN), |f| (f.crb_relative(), f.correlation()));
            v[0].push(crb[0]);
            v[1].push(crb[1]);
            v[2].push(rho);
        }
        v.map(|x| {
            let m = x.iter().sum::<f64>() / x.len() as f64;
            let se = ((x.len() as f64 - 1.0) / x.len() as f64 * x.iter().map(|y| (y - m).powi(2)).sum::<f64>()).sqrt();
            if se.is_finite() {
                se
            } else {
                f64::NAN
            }
        })
    }

    /// A text report: per feature set the surface table, the Fisher matrix, the bounds, the
    /// correlation and the weakest direction; the single-clearance bound.
    pub fn report(&self) -> String {
        let mut s = String::new();
        let (ri, rj) = self.reference;
        let d = &self.design;
        s += &format!(
            "grid cA {:?} mm × cB {:?} mm, reference A {:.2} + B {:.2} mm; {} runs of {} s per point released {}° ± {}°, for a {} s recording\n",
            self.ca.iter().map(|c| c * 1e3).collect::<Vec<_>>(),
            self.cb.iter().map(|c| c * 1e3).collect::<Vec<_>>(),
            self.ca[ri] * 1e3,
            self.cb[rj] * 1e3,
            d.runs,
            d.duration,
            d.release_deg,
            d.release_spread_deg,
            d.record_s
        );
        for set in FeatureSet::ALL {
            s += &format!("\n== features: {} ==\n", set.name());
            if let Some(sf) = self.surface(set) {
                s += "expected ln L(grid) − ln L(reference), 10 s recording of the reference (rows cA, columns cB, mm):\n";
                s += &format!(
                    "  cA\\cB {}\n",
                    self.cb.iter().map(|c| format!("{:>8.2}", c * 1e3)).collect::<Vec<_>>().join("")
                );
                for (i, a) in self.ca.iter().enumerate() {
                    s += &format!(
                        "  {:5.2} {}\n",
                        a * 1e3,
                        (0..self.cb.len()).map(|j| format!("{:>8.1}", sf[i * self.cb.len() + j])).collect::<String>()
                    );
                }
                let inside = sf.iter().filter(|v| **v > -3.0).count();
                s += &format!("  grid points not excluded at 95 % (> −3.0): {inside} of {}\n", sf.len());
            }
            match self.fisher2(set) {
                Some(f) => {
                    s += &fisher_text(&f);
                    let [a, b, r] = self.jackknife(set);
                    s += &format!(
                        "  jackknife over the runs: ± {:.1} % (cA), ± {:.1} % (cB), ± {:.2} (correlation)\n",
                        a * 100.0,
                        b * 100.0,
                        r
                    );
                }
                None => s += "  (too few runs for this many features)\n",
            }
            if let Some(f) = self.fisher_single(set) {
                let crb = f.crb_relative()[0];
                s += &format!(
                    "  single clearance (A {:.2} mm alone, ±{:.2} mm): I = {:.3e} /m² → CRB {:.1} %\n",
                    f.truth[0] * 1e3,
                    f.step[0] * 1e3,
                    f.info[(0, 0)],
                    crb * 100.0
                );
            }
        }
        s
    }
}
