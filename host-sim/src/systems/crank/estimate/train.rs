//! Training the fast model ([`super::model::FastModel`]) from simulations: a grid of clearance
//! runs (joint × clearance × release angle × journal radius × noise seed), simulated with the
//! adaptive integrator (symplectic Euler at 1e-5 s can diverge with clearance at B or C), the
//! features of each, and two fits on the standardised features: a linear discriminant for the
//! joint (pooled within-joint covariance, ridge-regularised) and, per joint, a ridge regression
//! of `ln c`.

use super::model::{feature_vector, regressor, FastModel, FeatureVector, FEATURES, FEATURE_NAMES};
use super::release::{missed_contacts, ReleaseFeatures, RELEASE_SPAN};
use super::runs::{grid, Run};
use crate::systems::crank::parallel::map_in_order;
use crate::systems::crank::CrankConfig;
use nalgebra::{DMatrix, DVector};

/// The release laws' training grid: every joint × every clearance × `variants` draws as in
/// [`super::runs::grid`], each run only as long as the release detector looks ([`RELEASE_SPAN`] + 10 ms).
pub fn release_grid(clearances: &[f64], variants: usize, seed_base: u64) -> Vec<Run> {
    grid(clearances, variants, seed_base, RELEASE_SPAN + 0.01)
}

/// The features of every run, on `threads` threads, in the order of `runs`, each labelled with
/// the contacts its recording missed before the release detector's ([`FeatureVector::missed`]).
pub fn features_of(
    base: &CrankConfig,
    runs: &[Run],
    window: f64,
    threads: usize,
    progress: &(dyn Fn(usize, &Run) + Sync),
) -> anyhow::Result<Vec<FeatureVector>> {
    map_in_order(threads, runs, |k, run| {
        let f = run.simulate_with_eccentricity(base).map(|(r, e)| {
            let mut f = feature_vector(&r.crank_alpha, r.sample_rate, window);
            f.missed =
                f.release.map(|x| missed_contacts(&e, run.clearance, (x.contact * r.sample_rate).round() as usize));
            f
        });
        progress(k, run);
        f
    })
    .into_iter()
    .collect()
}

/// Fits the model to runs and their features. `ridge`: added to the standardised covariance
/// and normal equations.
pub fn fit(
    runs: &[Run],
    feats: &[FeatureVector],
    window: f64,
    ridge: f64,
    quadratic: bool,
    trained_on: String,
) -> FastModel {
    let n = runs.len() as f64;
    let mut mean = vec![0.0; FEATURES];
    let mut scale = [0.0; FEATURES];
    for f in feats {
        for (m, v) in mean.iter_mut().zip(&f.values) {
            *m += v / n;
        }
    }
    for f in feats {
        for ((s, v), m) in scale.iter_mut().zip(&f.values).zip(&mean) {
            *s += (v - m).powi(2) / n;
        }
    }
    let scale: Vec<f64> = scale.iter().map(|v| v.sqrt().max(1e-9)).collect();
    let z: Vec<DVector<f64>> = feats
        .iter()
        .map(|f| DVector::from_iterator(FEATURES, (0..FEATURES).map(|i| (f.values[i] - mean[i]) / scale[i])))
        .collect();
    // Linear discriminant.
    let mut mu = vec![DVector::zeros(FEATURES); 3];
    let mut count = [0.0_f64; 3];
    for (r, z) in runs.iter().zip(&z) {
        mu[r.joint.index()] += z;
        count[r.joint.index()] += 1.0;
    }
    for j in 0..3 {
        mu[j] /= count[j].max(1.0);
    }
    let mut cov = DMatrix::<f64>::identity(FEATURES, FEATURES) * ridge;
    for (r, z) in runs.iter().zip(&z) {
        let e = z - &mu[r.joint.index()];
        cov += &e * e.transpose() / n;
    }
    let inv = cov.clone().cholesky().map(|c| c.inverse()).unwrap_or_else(|| DMatrix::identity(FEATURES, FEATURES));
    let discriminant: Vec<Vec<f64>> = (0..3)
        .map(|j| {
            let w = &inv * &mu[j];
            let b = -0.5 * mu[j].dot(&w);
            std::iter::once(b).chain(w.iter().copied()).collect()
        })
        .collect();
    // Ridge regression of ln c per joint.
    let regression: Vec<Vec<f64>> = (0..3)
        .map(|j| {
            let rows: Vec<usize> = (0..runs.len()).filter(|&k| runs[k].joint.index() == j).collect();
            let p = if quadratic { 2 * FEATURES + 1 } else { FEATURES + 1 };
            let x = DMatrix::from_fn(rows.len(), p, |r, c| regressor(z[rows[r]].as_slice(), c));
            let y = DVector::from_iterator(rows.len(), rows.iter().map(|&k| runs[k].clearance.ln()));
            let mut a = x.transpose() * &x;
            for i in 1..p {
                a[(i, i)] += ridge * rows.len() as f64;
            }
            let rhs = x.transpose() * y;
            let w = a.lu().solve(&rhs).unwrap_or_else(|| DVector::zeros(p));
            w.iter().copied().collect()
        })
        .collect();
    FastModel {
        trained_on,
        window,
        features: FEATURE_NAMES.iter().map(|s| s.to_string()).collect(),
        mean,
        scale,
        discriminant,
        regression,
        release: None,
        trained_for: None,
    }
}

/// Scores of a model on runs: (share of runs with the right joint, largest and RMS relative
/// clearance error of the runs whose joint was named right).
pub fn score(model: &FastModel, runs: &[Run], feats: &[FeatureVector]) -> (f64, f64, f64) {
    let (mut right, mut worst, mut sq) = (0usize, 0.0_f64, 0.0);
    for (r, f) in runs.iter().zip(feats) {
        let e = model.estimate_features(*f);
        if e.joint == r.joint {
            right += 1;
            let err = e.clearance[r.joint.index()] / r.clearance - 1.0;
            worst = worst.max(err.abs());
            sq += err * err;
        }
    }
    (right as f64 / runs.len().max(1) as f64, worst, (sq / right.max(1) as f64).sqrt())
}

/// Writes runs and their features as CSV (`joint,clearance,release_deg,radius,seed,duration,`
/// then the features), to refit without simulating ([`read_features`]).
pub fn write_features(path: &std::path::Path, runs: &[Run], feats: &[FeatureVector]) -> std::io::Result<()> {
    let mut text = format!(
        "joint,clearance,release_deg,radius,seed,duration,windows,operations,{},contact,release_alpha,missed\n",
        FEATURE_NAMES.join(",")
    );
    for (r, f) in runs.iter().zip(feats) {
        text += &format!(
            "{},{:?},{:?},{:?},{},{:?},{},{},{},{},{}\n",
            r.joint,
            r.clearance,
            r.release_deg,
            r.radius,
            r.seed,
            r.duration,
            f.windows,
            f.operations,
            f.values.iter().map(|v| format!("{v:?}")).collect::<Vec<_>>().join(","),
            f.release.map_or("NaN,NaN".to_string(), |r| format!("{:?},{:?}", r.contact, r.release_alpha)),
            f.missed.map_or("NaN".to_string(), |m| m.to_string())
        );
    }
    crate::io::output::write_atomic(path, text)
}

/// Reads what [`write_features`] wrote.
pub fn read_features(path: &std::path::Path) -> anyhow::Result<(Vec<Run>, Vec<FeatureVector>)> {
    let text = std::fs::read_to_string(path).map_err(|e| anyhow::anyhow!("{}: cannot read: {e}", path.display()))?;
    let (mut runs, mut feats) = (Vec::new(), Vec::new());
    for (k, line) in text.lines().enumerate().skip(1) {
        let bad = || anyhow::anyhow!("{}: line {}: not a feature row", path.display(), k + 1);
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != 11 + FEATURES {
            return Err(bad());
        }
        let num = |i: usize| cells[i].trim().parse::<f64>().map_err(|_| bad());
        let int = |i: usize| cells[i].trim().parse::<u64>().map_err(|_| bad());
        runs.push(Run {
            joint: cells[0].parse().map_err(|_| bad())?,
            clearance: num(1)?,
            release_deg: num(2)?,
            radius: num(3)?,
            seed: int(4)?,
            duration: num(5)?,
        });
        let mut values = [0.0; FEATURES];
        for (i, v) in values.iter_mut().enumerate() {
            *v = num(8 + i)?;
        }
        let (contact, release_alpha) = (num(8 + FEATURES)?, num(9 + FEATURES)?);
        let release = contact.is_finite().then_some(ReleaseFeatures { contact, release_alpha });
        let missed = cells[10 + FEATURES].trim().parse::<usize>().ok();
        feats.push(FeatureVector { values, windows: int(6)? as usize, operations: int(7)?, release, missed });
    }
    Ok((runs, feats))
}
