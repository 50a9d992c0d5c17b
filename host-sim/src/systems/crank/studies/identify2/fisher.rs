//! The study's statistics over simulated ensembles: pooled covariance, precision, Fisher
//! information over the clearances of a stencil, and the expected log-likelihood surface (see
//! the method in [`super`]).

use super::{Design, Ensemble, FeatureSet};
use nalgebra::{DMatrix, DVector};

/// Pooled within-point covariance of the features `idx` over `ensembles`, and its degrees of
/// freedom.
pub fn pooled_covariance(ensembles: &[&Ensemble], idx: &[usize]) -> (DMatrix<f64>, usize) {
    let p = idx.len();
    let mut s = DMatrix::zeros(p, p);
    let mut dof = 0;
    for e in ensembles {
        let mu = e.mean(idx);
        for f in &e.features {
            let x = DVector::from_iterator(p, idx.iter().map(|&i| f[i])) - &mu;
            s += &x * x.transpose();
        }
        dof += e.features.len().saturating_sub(1);
    }
    (s / dof.max(1) as f64, dof)
}

/// Per-run paired differences `(b − a) / h` of the features `idx` (runs in the same order).
fn paired(a: &Ensemble, b: &Ensemble, idx: &[usize], h: f64) -> Vec<DVector<f64>> {
    a.features
        .iter()
        .zip(&b.features)
        .map(|(x, y)| DVector::from_iterator(idx.len(), idx.iter().map(|&i| (y[i] - x[i]) / h)))
        .collect()
}

/// Mean of vectors and the covariance of that mean.
fn mean_and_error(v: &[DVector<f64>]) -> (DVector<f64>, DMatrix<f64>) {
    let n = v.len();
    let p = v[0].len();
    let mu = v.iter().fold(DVector::zeros(p), |s, x| s + x) / n as f64;
    let mut c = DMatrix::zeros(p, p);
    for x in v {
        let e = x - &mu;
        c += &e * e.transpose();
    }
    (mu, c / ((n - 1).max(1) * n) as f64)
}

/// Cross-covariance of the means of two paired lists.
fn cross_error(a: &[DVector<f64>], b: &[DVector<f64>]) -> DMatrix<f64> {
    let n = a.len();
    let (ma, _) = mean_and_error(a);
    let (mb, _) = mean_and_error(b);
    let mut c = DMatrix::zeros(ma.len(), ma.len());
    for (x, y) in a.iter().zip(b) {
        c += (x - &ma) * (y - &mb).transpose();
    }
    c / ((n - 1).max(1) * n) as f64
}

/// The inverse of the covariance for a `record_s` recording: `Σ` scaled by `duration /
/// record_s`, inverted, times the Wishart factor `(n − p − 1) / n`. `None` if singular or too
/// few degrees of freedom.
pub fn precision(cov: &DMatrix<f64>, dof: usize, design: &Design) -> Option<DMatrix<f64>> {
    let p = cov.nrows();
    if dof < p + 2 {
        return None;
    }
    let scaled = cov * (design.duration / design.record_s);
    let inv = scaled.cholesky()?.inverse();
    Some(inv * ((dof - p - 1) as f64 / dof as f64))
}

/// Fisher information over the clearances of a stencil, and what follows from it.
#[derive(Debug, Clone, PartialEq)]
pub struct Fisher {
    /// Features used.
    pub set: FeatureSet,
    /// True values of the parameters, m.
    pub truth: Vec<f64>,
    /// Half-width of the central differences per parameter, m.
    pub step: Vec<f64>,
    /// Information matrix, 1/m² (bias-corrected), for a recording of [`Design::record_s`].
    pub info: DMatrix<f64>,
    /// The same without the correction for the ensembles' own error.
    pub info_raw: DMatrix<f64>,
    /// Degrees of freedom of the pooled covariance.
    pub dof: usize,
}

impl Fisher {
    /// `I⁻¹` (`None` if `I` is not positive definite).
    pub fn bound_covariance(&self) -> Option<DMatrix<f64>> {
        let c = self.info.clone().cholesky()?;
        Some(c.inverse())
    }

    /// Cramér–Rao bounds relative to the true values (∞ if `I` is not positive definite).
    pub fn crb_relative(&self) -> Vec<f64> {
        match self.bound_covariance() {
            Some(c) => (0..self.truth.len()).map(|i| c[(i, i)].sqrt() / self.truth[i]).collect(),
            None => vec![f64::INFINITY; self.truth.len()],
        }
    }

    /// Correlation of the first two estimates from `I⁻¹` (NaN with one parameter or a singular
    /// `I`).
    pub fn correlation(&self) -> f64 {
        match (self.truth.len(), self.bound_covariance()) {
            (2.., Some(c)) => c[(0, 1)] / (c[(0, 0)] * c[(1, 1)]).sqrt(),
            _ => f64::NAN,
        }
    }

    /// Eigenvalues of `I` (ascending) and the unit eigenvector of the smallest.
    pub fn weakest(&self) -> (Vec<f64>, Vec<f64>) {
        let e = self.info.clone().symmetric_eigen();
        let mut order: Vec<usize> = (0..e.eigenvalues.len()).collect();
        order.sort_by(|a, b| e.eigenvalues[*a].total_cmp(&e.eigenvalues[*b]));
        let mut v: Vec<f64> = e.eigenvectors.column(order[0]).iter().copied().collect();
        if v[0] < 0.0 {
            v.iter_mut().for_each(|x| *x = -*x);
        }
        (order.iter().map(|&i| e.eigenvalues[i]).collect(), v)
    }

    /// Largest relative asymmetry `|I − Iᵀ| / max |I|` (0 by construction; a check).
    pub fn asymmetry(&self) -> f64 {
        let m = self.info.amax().max(1e-300);
        (&self.info - self.info.transpose()).amax() / m
    }
}

/// Fisher information at `centre` from the neighbour pairs `(minus, plus)` per parameter, whose
/// half-distances are `step` (m); `truth` the centre's parameters (m). The covariance is pooled
/// over the centre and every neighbour.
pub fn fisher(
    centre: &Ensemble,
    neighbours: &[(&Ensemble, &Ensemble)],
    step: &[f64],
    truth: &[f64],
    set: FeatureSet,
    design: &Design,
) -> Option<Fisher> {
    let idx = set.indices();
    let mut all = vec![centre];
    for (m, p) in neighbours {
        all.push(m);
        all.push(p);
    }
    let (cov, dof) = pooled_covariance(&all, &idx);
    let a = precision(&cov, dof, design)?;
    let diffs: Vec<Vec<DVector<f64>>> =
        neighbours.iter().zip(step).map(|((m, p), h)| paired(m, p, &idx, 2.0 * h)).collect();
    let k = neighbours.len();
    let j: Vec<DVector<f64>> = diffs.iter().map(|d| mean_and_error(d).0).collect();
    let mut info = DMatrix::zeros(k, k);
    let mut info_raw = DMatrix::zeros(k, k);
    for r in 0..k {
        for c in 0..k {
            let raw = (j[r].transpose() * &a * &j[c])[(0, 0)];
            let bias = (&a * cross_error(&diffs[r], &diffs[c])).trace();
            info_raw[(r, c)] = raw;
            info[(r, c)] = raw - bias;
        }
    }
    // Symmetrise the rounding (the bias terms are symmetric up to it).
    let info = (&info + info.transpose()) * 0.5;
    Some(Fisher { set, truth: truth.to_vec(), step: step.to_vec(), info, info_raw, dof })
}

/// Expected log-likelihood ratio `E ln L(g) − E ln L(ref)` of a recording from `reference`
/// against each of `grid` (bias-corrected for the ensembles' error), with the precision `a`
/// ([`precision`]) of the features `idx`.
pub fn surface(reference: &Ensemble, grid: &[Ensemble], idx: &[usize], a: &DMatrix<f64>) -> Vec<f64> {
    grid.iter()
        .map(|g| {
            if g.clearance == reference.clearance {
                return 0.0;
            }
            let d = paired(reference, g, idx, 1.0);
            let (mu, err) = mean_and_error(&d);
            let q = (mu.transpose() * a * &mu)[(0, 0)] - (a * err).trace();
            -0.5 * q
        })
        .collect()
}

/// The figures of a two-parameter Fisher matrix as text.
pub fn fisher_text(f: &Fisher) -> String {
    let crb = f.crb_relative();
    let (ev, v) = f.weakest();
    let i = &f.info;
    let mut s = format!(
        "  Fisher (1/mm², bias-corrected; raw) [[{:.1}, {:.1}], [{:.1}, {:.1}]]; raw [[{:.1}, {:.1}], [·, {:.1}]]; covariance dof {}\n",
        i[(0, 0)] * 1e-6,
        i[(0, 1)] * 1e-6,
        i[(1, 0)] * 1e-6,
        i[(1, 1)] * 1e-6,
        f.info_raw[(0, 0)] * 1e-6,
        f.info_raw[(0, 1)] * 1e-6,
        f.info_raw[(1, 1)] * 1e-6,
        f.dof
    );
    s += &format!(
        "  CRB cA {:.1} %, cB {:.1} %; correlation {:+.3}; eigenvalues {:.2e}, {:.2e} /mm²; weakest direction (cA, cB) = ({:+.3}, {:+.3}), std along it {:.3} mm\n",
        crb[0] * 100.0,
        crb[1] * 100.0,
        f.correlation(),
        ev[0] * 1e-6,
        ev[1] * 1e-6,
        v[0],
        v[1],
        if ev[0] > 0.0 { 1e3 / ev[0].sqrt() } else { f64::INFINITY }
    );
    s
}
