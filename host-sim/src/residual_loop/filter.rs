//! A dynamic-size Kalman filter for the host search: exact discretisation (Van Loan), the
//! time-varying gain until the covariance has converged, then that gain frozen (the model is
//! time-invariant, so this is the steady-state filter and costs `O(n²)` per sample).
//!
//! It runs in the transition's real modal form ([`ModalForm`]) where there is one, so that a
//! time-varying step costs `O(n²)` too: a model with undamped, noise-free states (an
//! unbalance) never converges and takes that step at every sample of every evaluation.

use super::modal_form::ModalForm;
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
    /// Records a sample's update: each channel's innovation and its variance, the NIS and
    /// `ln det S`.
    fn push_update(&mut self, e: &[f64], variances: &[f64], nis: f64, logdet: f64) {
        for ((inn, var), (ei, si)) in self.innovation.iter_mut().zip(&mut self.variance).zip(e.iter().zip(variances)) {
            inn.push(*ei);
            var.push(*si);
        }
        self.nis.push(nis);
        self.log_det_s.push(logdet);
    }

    /// Records a sample without an update (a missing value on one of the `m` channels).
    fn push_missing(&mut self, m: usize) {
        for i in 0..m {
            self.innovation[i].push(f64::NAN);
            self.variance[i].push(f64::NAN);
        }
        self.nis.push(f64::NAN);
        self.log_det_s.push(f64::NAN);
    }

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
    run_in(segments, dt, columns, outputs, tracked, true)
}

/// [`run_segments`], in modal coordinates where a transition has them (`modal`), else in the
/// plant's.
fn run_in(
    segments: &[(usize, StateSpace<'_>)],
    dt: f64,
    columns: &[&[f64]],
    outputs: &DMatrix<f64>,
    tracked: &[usize],
    modal: bool,
) -> Result<Run> {
    let Some((_, first)) = segments.first() else { return Err(anyhow!("filter: no model to run")) };
    let (n, m, len) = sizes(segments, columns, outputs, tracked)?;
    let models: Vec<Segment> =
        segments.iter().map(|(k, s)| Segment::new(*k, s, dt, outputs, tracked, modal)).collect::<Result<_>>()?;
    let mut segment = 0;
    let mut seg = &models[0];
    let mut x = DVector::<f64>::zeros(n);
    let mut p = seg.filter_cov(&first.p0.clone());
    let mut switched_at = 0;
    let mut run = Run {
        innovation: vec![Vec::with_capacity(len); m],
        variance: vec![Vec::with_capacity(len); m],
        outputs: vec![Vec::with_capacity(len); outputs.nrows()],
        effect_states: vec![Vec::with_capacity(len); tracked.len()],
        ..Run::default()
    };
    let mut frozen: Option<Frozen> = None;
    let mut updated = false;
    let mut prev_diag: Option<DVector<f64>> = None;
    let max_tv = 3000usize;
    // Work space of the covariance step: `P Cᵀ`, the gain and the dense product's.
    let (mut pct, mut gain, mut work) = (DMatrix::zeros(n, m), DMatrix::zeros(n, m), DMatrix::zeros(n, n));
    let (mut y, mut e) = (DVector::<f64>::zeros(m), DVector::<f64>::zeros(m));
    // The innovations' variances this sample (the diagonal of `S`).
    let mut sdiag = vec![0.0; m];
    for k in 0..len {
        if models.get(segment + 1).is_some_and(|next| k >= next.from) {
            segment += 1;
            let next = &models[segment];
            // The state and covariance carry over, through the plant's own coordinates.
            x = next.filter_vec(&seg.plant_vec(&x));
            p = next.filter_cov(&seg.plant_cov(&p));
            seg = next;
            (frozen, prev_diag, switched_at) = (None, None, k);
        }
        for (i, col) in columns.iter().enumerate() {
            y[i] = col[k];
        }
        if y.iter().all(|v| v.is_finite()) {
            for (i, c_i) in seg.c_t.column_iter().enumerate() {
                e[i] = y[i] - c_i.dot(&x);
            }
            let (nis, logdet) = if let Some(Frozen { gain, sdiag: steady, s_inv, logdet }) = &frozen {
                let nis = quadratic(s_inv, &e);
                x.gemv(1.0, gain, &e, 1.0);
                sdiag.copy_from_slice(steady);
                (nis, *logdet)
            } else {
                let (nis, logdet, s_inv) = update(seg, (&mut x, &mut p), &e, (&mut pct, &mut gain), &mut sdiag)
                    .ok_or_else(|| anyhow!("innovation covariance not positive definite at sample {k}"))?;
                let diag = p.diagonal();
                if let Some(prev) = &prev_diag {
                    if settled(&diag, prev) || k - switched_at >= max_tv {
                        frozen =
                            Some(Frozen { gain: gain.clone(), sdiag: sdiag.clone(), s_inv: s_inv.clone(), logdet });
                        run.frozen_at = Some(k);
                    }
                }
                prev_diag = Some(diag);
                updated = true;
                (nis, logdet)
            };
            run.push_update(e.as_slice(), &sdiag, nis, logdet);
        } else {
            run.push_missing(m);
        }
        for (row, out) in seg.outputs_t.column_iter().zip(run.outputs.iter_mut()) {
            out.push(row.dot(&x));
        }
        for (row, out) in seg.tracked_t.column_iter().zip(run.effect_states.iter_mut()) {
            out.push(row.dot(&x));
        }
        seg.transition.step(&mut x);
        if frozen.is_none() {
            seg.transition.covariance(&mut p, &mut work);
            p += &seg.q;
        }
    }
    let gain = frozen.map(|f| f.gain).or(updated.then_some(gain));
    run.last = gain.map(|gain| FinalFilter {
        transition: seg.phi.clone(),
        gain: seg.w.as_ref().map_or_else(|| gain.clone(), |(w, _)| w * &gain),
        c: seg.plant_c.clone(),
    });
    Ok(run)
}

/// The sizes of a run: states, channels and samples, after checking that the segments, the
/// columns, the output rows and the tracked states agree.
fn sizes(
    segments: &[(usize, StateSpace<'_>)],
    columns: &[&[f64]],
    outputs: &DMatrix<f64>,
    tracked: &[usize],
) -> Result<(usize, usize, usize)> {
    let (n, m) = segments.first().map_or((0, 0), |(_, s)| (s.a.nrows(), s.c.nrows()));
    if segments.iter().any(|(_, s)| s.a.nrows() != n || s.c.nrows() != m || s.c.ncols() != n) {
        return Err(anyhow!("filter: the segments' models differ in size"));
    }
    let len = columns.iter().map(|c| c.len()).min().unwrap_or(0);
    if outputs.ncols() != n || tracked.iter().any(|&i| i >= n) || columns.len() != m {
        return Err(anyhow!(
            "filter: {n} states and {m} channels, given {} columns, output rows of width {} and tracked states {tracked:?}",
            columns.len(),
            outputs.ncols()
        ));
    }
    Ok((n, m, len))
}

/// The time-varying measurement update of `(x, P)` with the innovations `e` on `seg`'s model:
/// `P Cᵀ` and the gain into the work space `(pct, gain)`, the innovations' variances into
/// `sdiag`. The NIS, `ln det S` and `S⁻¹`; `None` if `S` is not positive definite.
fn update(
    seg: &Segment,
    (x, p): (&mut DVector<f64>, &mut DMatrix<f64>),
    e: &DVector<f64>,
    (pct, gain): (&mut DMatrix<f64>, &mut DMatrix<f64>),
    sdiag: &mut [f64],
) -> Option<(f64, f64, DMatrix<f64>)> {
    let m = e.len();
    // `P Cᵀ` by columns (`P` symmetric: row k of `P` is its column k).
    for (i, c_i) in seg.c_t.column_iter().enumerate() {
        for (kk, p_k) in p.column_iter().enumerate() {
            pct[(kk, i)] = p_k.dot(&c_i);
        }
    }
    let s = DMatrix::from_fn(m, m, |a, b| {
        0.5 * (seg.c_t.column(a).dot(&pct.column(b)) + seg.c_t.column(b).dot(&pct.column(a)))
            + 0.5 * (seg.r[(a, b)] + seg.r[(b, a)])
    });
    let chol = s.clone().cholesky()?;
    let logdet = 2.0 * chol.l().diagonal().iter().map(|v| v.ln()).sum::<f64>();
    let s_inv = chol.inverse();
    gain.gemm(1.0, pct, &s_inv, 0.0);
    let nis = quadratic(&s_inv, e);
    x.gemv(1.0, gain, e, 1.0);
    // `P ← P − K (P Cᵀ)ᵀ`, column by column.
    for (j, mut p_j) in p.column_iter_mut().enumerate() {
        for (i, k_i) in gain.column_iter().enumerate() {
            p_j.axpy(-pct[(j, i)], &k_i, 1.0);
        }
    }
    symmetrise(p);
    sdiag.iter_mut().enumerate().for_each(|(i, v)| *v = s[(i, i)]);
    Some((nis, logdet, s_inv))
}

/// Whether the covariance's diagonal has settled since the last update (every element within
/// 1e-7 of its previous value, relatively): the gain can be frozen.
fn settled(diag: &DVector<f64>, prev: &DVector<f64>) -> bool {
    let change = diag.iter().zip(prev.iter()).map(|(a, b)| ((a - b) / b.abs().max(1e-300)).abs()).fold(0.0, f64::max);
    change < 1e-7
}

/// `eᵀ S⁻¹ e`, without a temporary.
fn quadratic(s_inv: &DMatrix<f64>, e: &DVector<f64>) -> f64 {
    s_inv.column_iter().zip(e.iter()).map(|(column, ej)| ej * column.dot(e)).sum()
}

/// `p ← (p + pᵀ) / 2`, in place.
fn symmetrise(p: &mut DMatrix<f64>) {
    for j in 0..p.ncols() {
        for i in 0..j {
            let v = 0.5 * (p[(i, j)] + p[(j, i)]);
            p[(i, j)] = v;
            p[(j, i)] = v;
        }
    }
}

/// How a segment's transition steps: through its modal form's blocks, or as a dense product
/// where it has none.
enum Transition {
    Modal(ModalForm),
    Dense { phi: DMatrix<f64>, phi_t: DMatrix<f64> },
}

impl Transition {
    /// `x ← B x`.
    fn step(&self, x: &mut DVector<f64>) {
        match self {
            Transition::Modal(form) => form.step(x),
            Transition::Dense { phi, .. } => *x = phi * &*x,
        }
    }

    /// `p ← B p Bᵀ` (`work`: an n×n scratch matrix).
    fn covariance(&self, p: &mut DMatrix<f64>, work: &mut DMatrix<f64>) {
        match self {
            Transition::Modal(form) => form.covariance(p),
            Transition::Dense { phi, phi_t } => {
                work.gemm(1.0, phi, p, 0.0);
                p.gemm(1.0, work, phi_t, 0.0);
            }
        }
    }
}

/// One segment's model in the coordinates the filter runs in: `z = W⁻¹ x` where the transition
/// has a modal form, the plant's own `x` otherwise. The innovations, and so the likelihood,
/// do not depend on the coordinates.
struct Segment<'a> {
    /// First sample.
    from: usize,
    /// The plant's transition, for [`FinalFilter`].
    phi: DMatrix<f64>,
    /// The plant's sensor rows, for [`FinalFilter`].
    plant_c: DMatrix<f64>,
    transition: Transition,
    /// `(W, W⁻¹)` where the filter runs in modal coordinates.
    w: Option<(DMatrix<f64>, DMatrix<f64>)>,
    /// Process noise and sensor rows (as columns), in the filter's coordinates.
    q: DMatrix<f64>,
    c_t: DMatrix<f64>,
    /// Output rows and tracked states' rows as columns (one dot product each a sample).
    outputs_t: DMatrix<f64>,
    tracked_t: DMatrix<f64>,
    r: &'a DMatrix<f64>,
}

impl<'a> Segment<'a> {
    fn new(
        from: usize,
        ss: &StateSpace<'a>,
        dt: f64,
        outputs: &DMatrix<f64>,
        tracked: &[usize],
        modal: bool,
    ) -> Result<Self> {
        let Discrete { a: phi, q } = discretise(ss.a, ss.qc, dt)?;
        let n = phi.nrows();
        let selection = DMatrix::from_fn(tracked.len(), n, |i, j| if tracked[i] == j { 1.0 } else { 0.0 });
        let form = if modal { ModalForm::of(&phi) } else { None };
        let w = form.as_ref().map(|f| (f.w.clone(), f.w_inv.clone()));
        let transition = match form {
            Some(form) => Transition::Modal(form),
            None => Transition::Dense { phi_t: phi.transpose(), phi: phi.clone() },
        };
        // Rows on the plant's states read the filter's through `W`.
        let through =
            |rows: &DMatrix<f64>| w.as_ref().map_or_else(|| rows.transpose(), |(w, _)| (rows * w).transpose());
        let mut segment = Segment {
            from,
            plant_c: ss.c.clone(),
            transition,
            q: q.clone(),
            c_t: through(ss.c),
            outputs_t: through(outputs),
            tracked_t: through(&selection),
            r: ss.r,
            phi,
            w,
        };
        segment.q = segment.filter_cov(&q);
        Ok(segment)
    }

    /// A covariance in the plant's coordinates, in the filter's: `W⁻¹ P W⁻ᵀ`, symmetric.
    fn filter_cov(&self, p: &DMatrix<f64>) -> DMatrix<f64> {
        let mut p = self.w.as_ref().map_or_else(|| p.clone(), |(_, w_inv)| w_inv * p * w_inv.transpose());
        symmetrise(&mut p);
        p
    }

    /// A covariance in the filter's coordinates, in the plant's: `W P Wᵀ`.
    fn plant_cov(&self, p: &DMatrix<f64>) -> DMatrix<f64> {
        self.w.as_ref().map_or_else(|| p.clone(), |(w, _)| w * p * w.transpose())
    }

    fn filter_vec(&self, x: &DVector<f64>) -> DVector<f64> {
        self.w.as_ref().map_or_else(|| x.clone(), |(_, w_inv)| w_inv * x)
    }

    fn plant_vec(&self, x: &DVector<f64>) -> DVector<f64> {
        self.w.as_ref().map_or_else(|| x.clone(), |(w, _)| w * x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model like a machine's: five lightly damped modes (displacements in µm, velocities in mm/s)
    /// and an undamped force pair at one speed (two equal eigenvalue pairs, newtons), read by
    /// three channels; a second segment moves a sensor.
    /// `A`, `Q_c`, `C`, `R`, `P_0`.
    type Model = (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>);

    fn model() -> Model {
        let n = 14;
        let mut a = DMatrix::zeros(n, n);
        for (i, hz) in [31.0, 47.0, 120.0, 180.0, 410.0].iter().enumerate() {
            let w = std::f64::consts::TAU * hz;
            let (d, v) = (2 * i, 2 * i + 1);
            a[(d, v)] = 1.0;
            a[(v, d)] = -w * w;
            a[(v, v)] = -2.0 * 0.01 * w;
            // The force pair drives every mode.
            a[(v, 10)] = 1e-3 * (i + 1) as f64;
            a[(v, 12)] = -2e-3;
        }
        let speed = std::f64::consts::TAU * 25.0;
        for f in [10, 12] {
            a[(f, f + 1)] = speed;
            a[(f + 1, f)] = -speed;
        }
        let mut qc = DMatrix::zeros(n, n);
        for i in 0..5 {
            qc[(2 * i + 1, 2 * i + 1)] = 1e-4;
        }
        let mut c = DMatrix::zeros(3, n);
        for j in 0..10 {
            c[(0, j)] = 1.0 / (1 + j) as f64;
            c[(1, j)] = if j % 2 == 0 { 1.0 } else { -0.5 };
            c[(2, j)] = (j as f64 * 0.7).sin();
        }
        let r = DMatrix::from_diagonal(&DVector::from_row_slice(&[1e-6, 2e-6, 5e-7]));
        let p0 = DMatrix::from_fn(n, n, |i, j| {
            if i != j {
                0.0
            } else if i >= 10 {
                4.0
            } else {
                1e-4
            }
        });
        (a, qc, c, r, p0)
    }

    /// Worst difference of two runs' traces (NaN where both are), relative to the largest entry.
    fn worst(x: &[Vec<f64>], y: &[Vec<f64>]) -> f64 {
        let scale = y.iter().flatten().filter(|v| v.is_finite()).fold(0.0f64, |m, v| m.max(v.abs()));
        let mut worst = 0.0f64;
        for (p, q) in x.iter().flatten().zip(y.iter().flatten()) {
            worst = worst.max(if p.is_nan() && q.is_nan() { 0.0 } else { (p - q).abs() / scale });
        }
        worst
    }

    #[test]
    fn modal_coordinates_give_the_dense_filters_innovations() {
        let (a, qc, c, r, p0) = model();
        let mut c2 = c.clone();
        c2.row_mut(2).scale_mut(-2.0);
        let mut seed = 7u64;
        let mut noise = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        // Three channels, a few samples missing.
        let columns: Vec<Vec<f64>> = (0..3)
            .map(|ch| {
                (0..2000)
                    .map(|k| (0.2 * k as f64 * (ch + 1) as f64).sin() * 1e-2 + 1e-3 * noise())
                    .map(|v| if v.to_bits() % 97 == 0 { f64::NAN } else { v })
                    .collect()
            })
            .collect();
        let cols: Vec<&[f64]> = columns.iter().map(Vec::as_slice).collect();
        let outputs = DMatrix::from_fn(2, 14, |i, j| if j == 2 * i { 1.0 } else { 0.0 });
        let dt = 1.0 / 2000.0;
        assert!(ModalForm::of(&discretise(&a, &qc, dt).unwrap().a).is_some());
        let run = |perm: &DMatrix<f64>, tracked: &[usize], modal: bool| {
            let (a, qc, p0) = (perm * &a * perm, perm * &qc * perm, perm * &p0 * perm);
            let (c, c2) = (&c * perm, &c2 * perm);
            let ss = |c| StateSpace { a: &a, qc: &qc, c, r: &r, p0: &p0 };
            run_in(&[(0, ss(&c)), (1200, ss(&c2))], dt, &cols, &(&outputs * perm), tracked, modal).unwrap()
        };
        let dense = run(&DMatrix::identity(14, 14), &[10, 13], false);
        let modal = run(&DMatrix::identity(14, 14), &[10, 13], true);
        assert!(dense.nis.iter().any(|v| v.is_nan()), "some samples missing");
        // The yardstick: the dense filter against itself with its states in reverse order, which
        // rounds differently (the early samples cancel a wide prior against precise channels).
        let reverse = DMatrix::from_fn(14, 14, |i, j| if i + j == 13 { 1.0 } else { 0.0 });
        let reordered = run(&reverse, &[3, 0], false);
        for (what, trace) in [
            ("innovations", (|r: &Run| r.innovation.clone()) as fn(&Run) -> Vec<Vec<f64>>),
            ("variances", |r: &Run| r.variance.clone()),
            ("outputs", |r: &Run| r.outputs.clone()),
            ("effect states", |r: &Run| r.effect_states.clone()),
        ] {
            let (ours, rounding) = (worst(&trace(&modal), &trace(&dense)), worst(&trace(&reordered), &trace(&dense)));
            assert!(rounding < 1e-6 && ours <= 10.0 * rounding + 1e-14, "{what}: {ours:e} against {rounding:e}");
        }
        let (lm, ld, lr) = (modal.log_likelihood(), dense.log_likelihood(), reordered.log_likelihood());
        assert!((lm - ld).abs() <= 10.0 * (lr - ld).abs() + 1e-9 * ld.abs(), "{lm} against {ld} ({lr} reordered)");
        let (fm, fd) = (modal.last.unwrap(), dense.last.unwrap());
        assert!((&fm.gain - &fd.gain).norm() < 1e-6 * fd.gain.norm());
        assert_eq!(fm.transition, fd.transition);
    }
}
