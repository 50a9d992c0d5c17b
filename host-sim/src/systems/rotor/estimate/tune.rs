//! Tuning the filter's noise parameters from data: the paper's compromise objective under
//! differential evolution, and the maximum likelihood of the innovations.
//!
//! The parameters are `θ = [log10 force_psd, log10 modal_psd, log10 measurement_scale]` (the
//! last scales the datasheet `R`). Both objectives run the same filter ([`super::run`]) over
//! one training record:
//!
//! * **compromise** (de Rezende et al.): `f = Σ_channels (1 − |R²_a|) + (1 − |R²_b|)`, with
//!   `R²_a` between the measured channel and its filtered estimate `C x̂`, and `R²_b` between
//!   the measured channel and the channel re-simulated from the estimated forces alone (the
//!   reduced model driven by `F̂`, from rest). The first term rewards following the sensors,
//!   the second forces that explain them.
//! * **likelihood**: `L = ½ Σ_k (ln det S_k + r_kᵀ S_k⁻¹ r_k)`, the negative log-likelihood of
//!   the innovations (up to a constant). It asks for a filter whose predicted innovation
//!   covariance matches what it sees, and needs no truth and no re-simulation.
//!
//! Optimisers, both written here (a few dozen lines each; no crate needed): differential
//! evolution (DE/rand/1/bin, bounds by reflection) and Nelder–Mead (bounds by clamping).

use super::filter::{run, Estimates, FilterPrecision};
use super::reduce::{reduce, ReducedRotor, Tuning};
use crate::io::data::DataFile;
use crate::systems::rotor::{RotorModel, SimOptions};
use anyhow::Result;
use nalgebra::DVector;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Search box of `θ = [log10 force_psd, log10 modal_psd, log10 measurement_scale]`.
pub const BOUNDS: [(f64, f64); 3] = [(-6.0, 3.0), (-13.0, -3.0), (-2.0, 2.0)];

/// What is minimised.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Objective {
    /// The paper's `Σ (1 − |R²|)` over the filtered and the re-simulated sensor channels.
    Compromise,
    /// The innovations' negative log-likelihood.
    Likelihood,
}

/// Which optimiser.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Optimiser {
    /// Differential evolution with this population and generation count.
    DifferentialEvolution {
        /// Population size (≥ 4).
        population: usize,
        /// Generations after the initial population.
        generations: usize,
    },
    /// Nelder–Mead from the centre of the box, at most this many evaluations.
    NelderMead {
        /// Evaluation budget.
        max_evals: usize,
    },
}

/// The outcome of a tuning run.
#[derive(Debug, Clone, PartialEq)]
pub struct TuneResult {
    /// The best `θ` found.
    pub theta: [f64; 3],
    /// Its objective value.
    pub value: f64,
    /// Objective evaluations (filter runs) spent.
    pub evaluations: usize,
    /// The tuning `θ` stands for.
    pub tuning: Tuning,
}

/// `base` with the noise parameters of `θ`.
pub fn tuning_of(base: &Tuning, theta: &[f64; 3]) -> Tuning {
    Tuning {
        force_psd: 10f64.powf(theta[0]),
        modal_psd: 10f64.powf(theta[1]),
        measurement_scale: 10f64.powf(theta[2]),
        ..*base
    }
}

/// `1 − SS_res / SS_tot` of `fit` against `y` (finite samples only).
fn r_squared(y: &[f64], fit: &[f64]) -> f64 {
    let pairs: Vec<(f64, f64)> =
        y.iter().zip(fit).filter(|(a, b)| a.is_finite() && b.is_finite()).map(|(a, b)| (*a, *b)).collect();
    if pairs.is_empty() {
        return f64::NAN;
    }
    let mean = pairs.iter().map(|p| p.0).sum::<f64>() / pairs.len() as f64;
    let ss_tot: f64 = pairs.iter().map(|p| (p.0 - mean).powi(2)).sum();
    let ss_res: f64 = pairs.iter().map(|p| (p.0 - p.1).powi(2)).sum();
    1.0 - ss_res / ss_tot
}

/// The sensor channels of the reduced model driven by the estimated forces alone, from rest:
/// `x_{k+1} = A_d x_k` with the force states overwritten by `F̂_k` at every step (exact over the
/// step for a rotating phasor).
pub fn resimulate(red: &ReducedRotor, est: &Estimates) -> Vec<Vec<f64>> {
    let n = red.states();
    let ad = (&red.a * (1.0 / red.sample_rate)).exp();
    let force_cols: Vec<usize> =
        (0..red.force.nrows()).map(|j| (0..n).position(|c| red.force[(j, c)] != 0.0).unwrap_or(0)).collect();
    let mut x = DVector::<f64>::zeros(n);
    let mut out = vec![Vec::with_capacity(est.t.len()); red.c.nrows()];
    for k in 0..est.t.len() {
        for (j, &c) in force_cols.iter().enumerate() {
            x[c] = est.force[j][k];
        }
        let y = &red.c * &x;
        for (i, o) in out.iter_mut().enumerate() {
            o.push(y[i] + red.offsets[i]);
        }
        x = &ad * &x;
    }
    out
}

/// The paper's compromise objective of a filter run.
pub fn compromise(red: &ReducedRotor, data: &DataFile, est: &Estimates) -> f64 {
    let resim = resimulate(red, est);
    let mut f = 0.0;
    for (i, name) in red.channels.iter().enumerate() {
        let Some(y) = data.column(name) else { return f64::INFINITY };
        f += 1.0 - r_squared(y, &est.sensor[i]).abs();
        f += 1.0 - r_squared(y, &resim[i]).abs();
    }
    if f.is_finite() {
        f
    } else {
        f64::INFINITY
    }
}

/// `½ Σ (ln det S + NIS)` of a filter run (missing samples skipped).
pub fn neg_log_likelihood(est: &Estimates) -> f64 {
    let v: f64 =
        est.log_det_s.iter().zip(&est.nis).filter(|(a, b)| a.is_finite() && b.is_finite()).map(|(a, b)| a + b).sum();
    if v.is_finite() {
        0.5 * v
    } else {
        f64::INFINITY
    }
}

/// The objective at `θ` (∞ where the model cannot be built or run).
pub fn evaluate(
    model: &RotorModel,
    speed: f64,
    base: &Tuning,
    data: &DataFile,
    objective: Objective,
    theta: &[f64; 3],
) -> f64 {
    let run_at = || -> Result<f64> {
        let red = reduce(model, speed, &tuning_of(base, theta))?;
        let est = run(&red, data, FilterPrecision::F64)?;
        if est.repairs != (0, 0) {
            return Ok(f64::INFINITY);
        }
        Ok(match objective {
            Objective::Compromise => compromise(&red, data, &est),
            Objective::Likelihood => neg_log_likelihood(&est),
        })
    };
    run_at().unwrap_or(f64::INFINITY)
}

/// Minimises `f` over [`BOUNDS`] with DE/rand/1/bin (F = 0.7, CR = 0.9), seeded.
pub fn differential_evolution(
    f: &mut dyn FnMut(&[f64; 3]) -> f64,
    population: usize,
    generations: usize,
    seed: u64,
) -> ([f64; 3], f64, usize) {
    let np = population.max(4);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut pop: Vec<[f64; 3]> =
        (0..np).map(|_| std::array::from_fn(|d| rng.gen_range(BOUNDS[d].0..=BOUNDS[d].1))).collect();
    let mut val: Vec<f64> = pop.iter().map(&mut *f).collect();
    let mut evals = np;
    for _ in 0..generations {
        for i in 0..np {
            let pick = |rng: &mut ChaCha8Rng, not: &[usize]| loop {
                let j = rng.gen_range(0..np);
                if !not.contains(&j) {
                    break j;
                }
            };
            let a = pick(&mut rng, &[i]);
            let b = pick(&mut rng, &[i, a]);
            let c = pick(&mut rng, &[i, a, b]);
            let forced = rng.gen_range(0..3);
            let mut trial = pop[i];
            for d in 0..3 {
                if d == forced || rng.gen::<f64>() < 0.9 {
                    let (lo, hi) = BOUNDS[d];
                    let mut v = pop[a][d] + 0.7 * (pop[b][d] - pop[c][d]);
                    if v < lo {
                        v = lo + (lo - v).min(hi - lo);
                    }
                    if v > hi {
                        v = hi - (v - hi).min(hi - lo);
                    }
                    trial[d] = v;
                }
            }
            let fv = f(&trial);
            evals += 1;
            if fv <= val[i] {
                pop[i] = trial;
                val[i] = fv;
            }
        }
    }
    let best = (0..np).min_by(|&a, &b| val[a].total_cmp(&val[b])).unwrap_or(0);
    (pop[best], val[best], evals)
}

/// Minimises `f` with Nelder–Mead from `start` (initial steps of 1 decade), clamped to
/// [`BOUNDS`], until the simplex's values agree to `1e-6` relative or `max_evals` is spent.
pub fn nelder_mead(f: &mut dyn FnMut(&[f64; 3]) -> f64, start: [f64; 3], max_evals: usize) -> ([f64; 3], f64, usize) {
    let clamp = |p: [f64; 3]| -> [f64; 3] { std::array::from_fn(|d| p[d].clamp(BOUNDS[d].0, BOUNDS[d].1)) };
    let mut evals = 0;
    let mut eval = |p: &[f64; 3], evals: &mut usize| {
        *evals += 1;
        f(p)
    };
    let mut simplex: Vec<([f64; 3], f64)> = Vec::new();
    let s0 = clamp(start);
    simplex.push((s0, eval(&s0, &mut evals)));
    for d in 0..3 {
        let mut p = s0;
        p[d] = if p[d] + 1.0 <= BOUNDS[d].1 { p[d] + 1.0 } else { p[d] - 1.0 };
        simplex.push((p, eval(&p, &mut evals)));
    }
    let comb = |a: &[f64; 3], b: &[f64; 3], t: f64| clamp(std::array::from_fn(|d| a[d] + t * (b[d] - a[d])));
    while evals < max_evals {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (best, worst) = (simplex[0].1, simplex[3].1);
        if (worst - best).abs() <= 1e-6 * best.abs().max(1e-12) {
            break;
        }
        let centroid: [f64; 3] = std::array::from_fn(|d| (0..3).map(|i| simplex[i].0[d]).sum::<f64>() / 3.0);
        let w = simplex[3].0;
        let reflected = comb(&centroid, &w, -1.0);
        let fr = eval(&reflected, &mut evals);
        if fr < simplex[0].1 {
            let expanded = comb(&centroid, &w, -2.0);
            let fe = eval(&expanded, &mut evals);
            simplex[3] = if fe < fr { (expanded, fe) } else { (reflected, fr) };
        } else if fr < simplex[2].1 {
            simplex[3] = (reflected, fr);
        } else {
            let contracted = if fr < simplex[3].1 { comb(&centroid, &w, -0.5) } else { comb(&centroid, &w, 0.5) };
            let fc = eval(&contracted, &mut evals);
            if fc < fr.min(simplex[3].1) {
                simplex[3] = (contracted, fc);
            } else {
                let b = simplex[0].0;
                for s in simplex.iter_mut().skip(1) {
                    let p = comb(&b, &s.0, 0.5);
                    *s = (p, eval(&p, &mut evals));
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    (simplex[0].0, simplex[0].1, evals)
}

/// Tunes `base`'s noise parameters on `data` (from the rotor `model` at `speed`).
pub fn tune(
    model: &RotorModel,
    speed: f64,
    base: &Tuning,
    data: &DataFile,
    objective: Objective,
    optimiser: Optimiser,
    seed: u64,
) -> TuneResult {
    let mut f = |theta: &[f64; 3]| evaluate(model, speed, base, data, objective, theta);
    let (theta, value, evaluations) = match optimiser {
        Optimiser::DifferentialEvolution { population, generations } => {
            differential_evolution(&mut f, population, generations, seed)
        }
        Optimiser::NelderMead { max_evals } => {
            let start = std::array::from_fn(|d| 0.5 * (BOUNDS[d].0 + BOUNDS[d].1));
            nelder_mead(&mut f, start, max_evals)
        }
    };
    TuneResult { theta, value, evaluations, tuning: tuning_of(base, &theta) }
}

/// How a tuning does on held-out data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeldOut {
    /// Worst RMS displacement error over the force (disk) nodes, x and y, for t ≥ 1 s, m;
    /// the mean over the seeds.
    pub disk_rms: f64,
    /// Mean NIS for t ≥ 1 s, mean over the seeds (the number of channels when consistent).
    pub nis_mean: f64,
}

/// Runs `tuning` on fresh reference simulations (the FE model `truth`, `duration` s, one per
/// seed) with the filter built from `filter_model` at `speed`.
pub fn held_out(
    truth: &RotorModel,
    filter_model: &RotorModel,
    speed: f64,
    tuning: &Tuning,
    seeds: &[u64],
    duration: f64,
) -> Result<HeldOut> {
    let red = reduce(filter_model, speed, tuning)?;
    let (mut rms_sum, mut nis_sum) = (0.0, 0.0);
    for &seed in seeds {
        let rec = truth.simulate(&SimOptions { duration, seed, ..SimOptions::default() })?;
        let est = run(&red, &rec.to_data_file(), FilterPrecision::F64)?;
        let mut worst = 0.0f64;
        for &node in &red.force_nodes {
            for (d, truth) in [(0, &rec.x[node]), (1, &rec.y[node])] {
                let e = &est.displacement[2 * node + d];
                let (mut s, mut n) = (0.0, 0usize);
                for k in 0..e.len() {
                    if est.t[k] >= 1.0 {
                        s += (e[k] - truth[k]).powi(2);
                        n += 1;
                    }
                }
                worst = worst.max((s / n.max(1) as f64).sqrt());
            }
        }
        let nis: Vec<f64> =
            est.t.iter().zip(&est.nis).filter(|(t, v)| **t >= 1.0 && v.is_finite()).map(|(_, v)| *v).collect();
        rms_sum += worst;
        nis_sum += nis.iter().sum::<f64>() / nis.len().max(1) as f64;
    }
    let n = seeds.len().max(1) as f64;
    Ok(HeldOut { disk_rms: rms_sum / n, nis_mean: nis_sum / n })
}
