//! A dynamic-size Kalman filter for the host search: exact discretisation (Van Loan), the
//! time-varying gain until the covariance has converged, then that gain frozen (the model is
//! time-invariant, so this is the steady-state filter and costs `O(n²)` per sample).

use anyhow::{anyhow, Result};
use edgekf::linalg::van_loan_with;
use nalgebra::{DMatrix, DVector, Dyn};

/// The discrete model.
#[derive(Debug, Clone)]
pub struct Discrete {
    /// Transition.
    pub a: DMatrix<f64>,
    /// Process noise per step.
    pub q: DMatrix<f64>,
}

/// Exact discretisation of `a`, `qc` over `dt` (Van Loan), by the shared core's
/// [`van_loan_with`]: the reduced model the loop diagnoses is discretised by the same code as
/// the systems' estimators and the node.
pub fn discretise(a: &DMatrix<f64>, qc: &DMatrix<f64>, dt: f64) -> Result<Discrete> {
    let (a, q) = van_loan_with(a, qc, dt, Dyn(2 * a.nrows())).map_err(|e| anyhow!("cannot discretise: {e}"))?;
    Ok(Discrete { a, q })
}

/// The converged filter: gain, diagonal of `S`, `S⁻¹`, `ln det S`.
struct Frozen {
    gain: DMatrix<f64>,
    sdiag: Vec<f64>,
    s_inv: DMatrix<f64>,
    logdet: f64,
}

/// What one run produced.
#[derive(Debug, Clone, Default)]
pub struct Run {
    /// `innovation[channel][k]` (NaN where missing).
    pub innovation: Vec<Vec<f64>>,
    /// `variance[channel][k]`: the diagonal of `S` (NaN where missing).
    pub variance: Vec<Vec<f64>>,
    /// NIS per sample (NaN where missing).
    pub nis: Vec<f64>,
    /// `ln det S` per sample (NaN where missing).
    pub log_det_s: Vec<f64>,
    /// Displacement estimates of the requested rows, `[row][k]`.
    pub outputs: Vec<Vec<f64>>,
    /// Estimates of the effects' states, `[effect state][k]`.
    pub effect_states: Vec<Vec<f64>>,
    /// Sample at which the gain was frozen (`None`: time-varying throughout).
    pub frozen_at: Option<usize>,
    /// The filter as it ended (the last model's transition and rows, the last gain used): what
    /// [`direction`](super::direction) reads an unmodelled input's innovations from.
    pub last: Option<FinalFilter>,
}

/// The filter a run ended with: `x̂⁻ₖ₊₁ = Φ (x̂⁻ₖ + K eₖ)`, `eₖ = yₖ − C x̂⁻ₖ`.
#[derive(Debug, Clone)]
pub struct FinalFilter {
    /// The transition `Φ` over one sample.
    pub transition: DMatrix<f64>,
    /// The gain `K`.
    pub gain: DMatrix<f64>,
    /// The sensor rows `C`.
    pub c: DMatrix<f64>,
}

impl Run {
    /// `−½ Σ (ln det S + NIS)` over the updated samples (the constant `−½ m ln 2π` left out).
    pub fn log_likelihood(&self) -> f64 {
        -0.5 * self
            .log_det_s
            .iter()
            .zip(&self.nis)
            .filter(|(l, n)| l.is_finite() && n.is_finite())
            .map(|(l, n)| l + n)
            .sum::<f64>()
    }

    /// Scalar measurements used.
    pub fn measurements(&self) -> usize {
        self.nis.iter().filter(|v| v.is_finite()).count() * self.innovation.len()
    }
}

/// A continuous linear time-invariant model as the filter reads it: `ẋ = A x + w`,
/// `E[w wᵀ] = Q_c δ(t)`, `y_k = C x_k + v_k`, `E[v vᵀ] = R`, `x_0 ~ (0, P_0)`. Any system of
/// edgekf whose diagnostic filter is linear runs through [`run_state_space`].
#[derive(Debug, Clone, Copy)]
pub struct StateSpace<'a> {
    /// `A`.
    pub a: &'a DMatrix<f64>,
    /// `Q_c`.
    pub qc: &'a DMatrix<f64>,
    /// `C`.
    pub c: &'a DMatrix<f64>,
    /// `R` per sample.
    pub r: &'a DMatrix<f64>,
    /// `P_0`.
    pub p0: &'a DMatrix<f64>,
}

/// Runs the filter of `ss` over `columns` at `dt`; [`Run::outputs`] are the rows of
/// `outputs · x̂` and [`Run::effect_states`] the states `tracked`.
///
/// ```
/// use edgekf_sim::residual_loop::filter::{run_state_space, StateSpace};
/// use nalgebra::DMatrix;
/// // A constant observed directly: the filter's estimate settles on the data's mean.
/// let (a, qc) = (DMatrix::zeros(1, 1), DMatrix::zeros(1, 1));
/// let (c, r, p0) = (DMatrix::identity(1, 1), DMatrix::from_element(1, 1, 0.01), DMatrix::from_element(1, 1, 100.0));
/// let y: Vec<f64> = (0..400).map(|k| 2.0 + if k % 2 == 0 { 0.1 } else { -0.1 }).collect();
/// let ss = StateSpace { a: &a, qc: &qc, c: &c, r: &r, p0: &p0 };
/// let run = run_state_space(&ss, 1e-3, &[&y], &DMatrix::identity(1, 1), &[0]).unwrap();
/// assert!((run.outputs[0][399] - 2.0).abs() < 0.01);
/// assert_eq!(run.effect_states[0], run.outputs[0]);
/// ```
pub fn run_state_space(
    ss: &StateSpace<'_>,
    dt: f64,
    columns: &[&[f64]],
    outputs: &DMatrix<f64>,
    tracked: &[usize],
) -> Result<Run> {
    run_segments(&[(0, *ss)], dt, columns, outputs, tracked)
}

/// Runs the filter over `columns` with a model that changes mid-run: `segments` are
/// `(first sample, model)` in increasing order, all with the same states (an effect that
/// starts mid-run is decoupled before its onset, not absent). The state and its covariance
/// carry over a switch; the gain is time-varying again after it until it has converged.
/// `P_0` is the first segment's.
///
/// ```
/// use edgekf_sim::residual_loop::filter::{run_segments, StateSpace};
/// use nalgebra::DMatrix;
/// // A level observed directly that steps from 0 to 1 at sample 200, with a bias state that is
/// // unobserved (decoupled) before it: the second model sees level + bias.
/// let diagonal = |d: &[f64]| DMatrix::from_diagonal(&nalgebra::DVector::from_row_slice(d));
/// let (a, qc, r) = (DMatrix::zeros(2, 2), diagonal(&[1e-6, 0.0]), DMatrix::from_element(1, 1, 1e-4));
/// let p0 = diagonal(&[1.0, 4.0]);
/// let (before, after) = (DMatrix::from_row_slice(1, 2, &[1.0, 0.0]), DMatrix::from_row_slice(1, 2, &[1.0, 1.0]));
/// let y: Vec<f64> = (0..400).map(|k| if k < 200 { 0.0 } else { 1.0 }).collect();
/// let model = |c| StateSpace { a: &a, qc: &qc, c, r: &r, p0: &p0 };
/// let run = run_segments(&[(0, model(&before)), (200, model(&after))], 1e-3, &[&y], &DMatrix::identity(2, 2), &[1]).unwrap();
/// assert!(run.effect_states[0][199].abs() < 1e-12); // unobserved before the switch
/// assert!((run.effect_states[0][399] - 1.0).abs() < 0.05); // the step is taken up by the bias
/// ```
pub fn run_segments(
    segments: &[(usize, StateSpace<'_>)],
    dt: f64,
    columns: &[&[f64]],
    outputs: &DMatrix<f64>,
    tracked: &[usize],
) -> Result<Run> {
    let Some((_, first)) = segments.first() else { return Err(anyhow!("filter: no model to run")) };
    let n = first.a.nrows();
    let m = first.c.nrows();
    if segments.iter().any(|(_, s)| s.a.nrows() != n || s.c.nrows() != m || s.c.ncols() != n) {
        return Err(anyhow!("filter: the segments' models differ in size"));
    }
    let models: Vec<(usize, Discrete, &StateSpace<'_>)> =
        segments.iter().map(|(k, s)| Ok((*k, discretise(s.a, s.qc, dt)?, s))).collect::<Result<_>>()?;
    let model = |i: usize| (&models[i].1, models[i].2.c, models[i].2.r, models[i].2.c.transpose());
    let len = columns.iter().map(|c| c.len()).min().unwrap_or(0);
    let out_rows = outputs;
    let effect_idx = tracked;
    if out_rows.ncols() != n || effect_idx.iter().any(|&i| i >= n) || columns.len() != m {
        return Err(anyhow!(
            "filter: {n} states and {m} channels, given {} columns, output rows of width {} and tracked states {effect_idx:?}",
            columns.len(),
            out_rows.ncols()
        ));
    }
    let mut x = DVector::<f64>::zeros(n);
    let mut p = first.p0.clone();
    let mut segment = 0;
    let (mut d, mut c, mut r, mut ct) = model(0);
    let mut switched_at = 0;
    let mut run = Run {
        innovation: vec![Vec::with_capacity(len); m],
        variance: vec![Vec::with_capacity(len); m],
        outputs: vec![Vec::with_capacity(len); out_rows.nrows()],
        effect_states: vec![Vec::with_capacity(len); effect_idx.len()],
        ..Run::default()
    };
    let mut frozen: Option<Frozen> = None;
    let mut last_gain: Option<DMatrix<f64>> = None;
    let mut prev_diag: Option<DVector<f64>> = None;
    let max_tv = 3000usize;
    #[allow(clippy::needless_range_loop)]
    for k in 0..len {
        if models.get(segment + 1).is_some_and(|(from, _, _)| k >= *from) {
            segment += 1;
            (d, c, r, ct) = model(segment);
            (frozen, prev_diag, switched_at) = (None, None, k);
        }
        let y = DVector::from_fn(m, |i, _| columns[i][k]);
        let finite = y.iter().all(|v| v.is_finite());
        if finite {
            let e = &y - c * &x;
            let (nis, logdet, sdiag) = if let Some(Frozen { gain, sdiag, s_inv, logdet }) = &frozen {
                let nis = (e.transpose() * s_inv * &e)[(0, 0)];
                x += gain * &e;
                (nis, *logdet, sdiag.clone())
            } else {
                let pct = &p * &ct;
                let s = c * &pct + r;
                let s = (&s + s.transpose()) * 0.5;
                let chol = s
                    .clone()
                    .cholesky()
                    .ok_or_else(|| anyhow!("innovation covariance not positive definite at sample {k}"))?;
                let logdet = 2.0 * chol.l().diagonal().iter().map(|v| v.ln()).sum::<f64>();
                let s_inv = chol.inverse();
                let gain = &pct * &s_inv;
                let nis = (e.transpose() * &s_inv * &e)[(0, 0)];
                x += &gain * &e;
                p -= &gain * &s * gain.transpose();
                p = (&p + p.transpose()) * 0.5;
                let sdiag: Vec<f64> = (0..m).map(|i| s[(i, i)]).collect();
                let diag = p.diagonal();
                if let Some(prev) = &prev_diag {
                    let change = diag
                        .iter()
                        .zip(prev.iter())
                        .map(|(a, b)| ((a - b) / b.abs().max(1e-300)).abs())
                        .fold(0.0, f64::max);
                    if change < 1e-7 || k - switched_at >= max_tv {
                        frozen =
                            Some(Frozen { gain: gain.clone(), sdiag: sdiag.clone(), s_inv: s_inv.clone(), logdet });
                        run.frozen_at = Some(k);
                    }
                }
                prev_diag = Some(diag);
                last_gain = Some(gain);
                (nis, logdet, sdiag)
            };
            for i in 0..m {
                run.innovation[i].push(e[i]);
                run.variance[i].push(sdiag[i]);
            }
            run.nis.push(nis);
            run.log_det_s.push(logdet);
        } else {
            for i in 0..m {
                run.innovation[i].push(f64::NAN);
                run.variance[i].push(f64::NAN);
            }
            run.nis.push(f64::NAN);
            run.log_det_s.push(f64::NAN);
        }
        let o = out_rows * &x;
        for (i, out) in run.outputs.iter_mut().enumerate() {
            out.push(o[i]);
        }
        for (j, &s) in effect_idx.iter().enumerate() {
            run.effect_states[j].push(x[s]);
        }
        x = &d.a * &x;
        if frozen.is_none() {
            p = &d.a * &p * d.a.transpose() + &d.q;
        }
    }
    let gain = frozen.map(|f| f.gain).or(last_gain);
    run.last = gain.map(|gain| FinalFilter { transition: d.a.clone(), gain, c: c.clone() });
    Ok(run)
}
