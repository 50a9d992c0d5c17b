//! Discretisation of the reduced rotor and the filter run over a data file, at any size the
//! configuration gives: shared's Kalman filter with sizes compiled in where the chip has them,
//! with dynamic sizes elsewhere (one implementation, generic over nalgebra's dimensions).

use super::reduce::ReducedRotor;
use crate::io::data::DataFile;
use anyhow::{anyhow, bail, Result};
use edgekf::filter::{
    solve_riccati, DLinearModel, FilterAllocator, FilterDim, GenericKalmanFilter, GenericLinearModel,
    GenericSteadyStateFilter, LinearModel,
};
use edgekf::linalg::{van_loan, van_loan_with};
use edgekf::Real;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DefaultAllocator, Dim, Dyn, OMatrix, OVector, SMatrix, U1};

/// Arithmetic of the filter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FilterPrecision {
    /// Host reference.
    F64,
    /// The chip's arithmetic.
    F32,
}

/// What the filter produced, per sample.
#[derive(Debug, Clone, Default)]
pub struct Estimates {
    /// Sample times, s.
    pub t: Vec<f64>,
    /// Names of the displacement outputs (`n0_x`, `n0_y`, …).
    pub displacement_names: Vec<String>,
    /// `displacement[output][k]`, m.
    pub displacement: Vec<Vec<f64>>,
    /// Names of the force outputs (`f12_x`, …).
    pub force_names: Vec<String>,
    /// `force[output][k]`, N.
    pub force: Vec<Vec<f64>>,
    /// `sensor[channel][k]`: the filtered estimate of each sensor channel (`C x̂` after the
    /// update, plus the channel's offset), in the channel's unit.
    pub sensor: Vec<Vec<f64>>,
    /// `innovation[channel][k]`, in the channel's unit (NaN where the sample was missing).
    pub innovation: Vec<Vec<f64>>,
    /// NIS per sample (NaN where missing).
    pub nis: Vec<f64>,
    /// `ln det S` of the innovation covariance per sample (NaN where missing): with the NIS,
    /// the innovations' negative log-likelihood is `½ Σ (ln det S + NIS) + const`.
    pub log_det_s: Vec<f64>,
    /// Samples whose measurement was missing (NaN in the file) and were bridged by prediction.
    pub missing: usize,
    /// Covariance resets and refused updates of the filter (both 0 in a healthy run); after a
    /// switch to the steady-state gain the first also counts that filter's state resets.
    pub repairs: (u32, u32),
}

impl Estimates {
    /// Appends the estimates of the next stretch of the same recording (after a restart).
    pub fn append(&mut self, next: Estimates) {
        self.t.extend(next.t);
        let pairs = [(&mut self.displacement, next.displacement), (&mut self.force, next.force)];
        for (mine, theirs) in
            pairs.into_iter().chain([(&mut self.sensor, next.sensor), (&mut self.innovation, next.innovation)])
        {
            for (m, t) in mine.iter_mut().zip(theirs) {
                m.extend(t);
            }
        }
        self.nis.extend(next.nis);
        self.log_det_s.extend(next.log_det_s);
        self.missing += next.missing;
        self.repairs = (self.repairs.0 + next.repairs.0, self.repairs.1 + next.repairs.1);
    }
}

fn fixed<const R: usize, const C: usize>(m: &DMatrix<f64>) -> Result<SMatrix<f64, R, C>> {
    if m.nrows() != R || m.ncols() != C {
        bail!("matrix is {}×{}, expected {R}×{C}", m.nrows(), m.ncols());
    }
    Ok(SMatrix::from_fn(|i, j| m[(i, j)]))
}

/// The discrete model of `red` at its sample rate (exact discretisation, Van Loan), at a size
/// compiled in (the chip's: what `rotor export` writes).
pub fn discrete<const N: usize, const M: usize, const N2: usize>(red: &ReducedRotor) -> Result<LinearModel<f64, N, M>> {
    let dt = 1.0 / red.sample_rate;
    let (a, q) = van_loan::<f64, N, N2>(&fixed(&red.a)?, &fixed(&red.qc)?, dt)
        .map_err(|e| anyhow!("cannot discretise the reduced model: {e}"))?;
    Ok(LinearModel { a, c: fixed(&red.c)?, q, r: fixed(&red.r)? })
}

/// The discrete model of `red` at any size (the same Van Loan code on `DMatrix`), for the sizes
/// no build compiles in.
pub fn discrete_dynamic(red: &ReducedRotor) -> Result<DLinearModel<f64>> {
    let dt = 1.0 / red.sample_rate;
    let (a, q) = van_loan_with(&red.a, &red.qc, dt, Dyn(2 * red.a.nrows()))
        .map_err(|e| anyhow!("cannot discretise the reduced model: {e}"))?;
    let model = DLinearModel { a, c: red.c.clone(), q, r: red.r.clone() };
    if !model.sizes_agree() {
        bail!(
            "the reduced model's matrices do not fit: A {:?}, C {:?}, R {:?}",
            red.a.shape(),
            red.c.shape(),
            red.r.shape()
        );
    }
    Ok(model)
}

/// How the filter runs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RunOptions {
    /// Switch from the time-varying gain to the steady-state gain (the DARE's, solved once in
    /// f64) at this time, s; `None`: time-varying throughout.
    pub steady_after: Option<f64>,
}

/// Runs the filter of `red` over `data` (channels named as the sensors); time-varying gain.
pub fn run(red: &ReducedRotor, data: &DataFile, precision: FilterPrecision) -> Result<Estimates> {
    run_with(red, data, precision, &RunOptions::default())
}

/// The sizes the firmware can run, compiled in on the host too: 8 modes, 2 unbalance nodes and
/// 4 sensors: 20 states (displacement probes), 24 (accelerometers with 1st-order low-passes)
/// and 28 (2nd-order low-passes).
pub const CHIP_SIZES: [(usize, usize); 3] = [(20, 4), (24, 4), (28, 4)];

/// Runs the filter of `red` over `data` with `options`, at any size the configuration gives.
///
/// The chip's sizes ([`CHIP_SIZES`]) run the fixed-size filter, in `f64` or in the chip's `f32`
/// (bit for bit what the node computes). Any other size runs the same filter with dynamic sizes
/// (shared's `DKalmanFilter`), in `f64` only: `f32` is the chip's arithmetic, and the chip has
/// no filter of that size to compare with.
pub fn run_with(
    red: &ReducedRotor,
    data: &DataFile,
    precision: FilterPrecision,
    options: &RunOptions,
) -> Result<Estimates> {
    let o = *options;
    match (red.states(), red.c.nrows(), precision) {
        (20, 4, FilterPrecision::F64) => run_model::<f64, _, _>(red, data, discrete::<20, 4, 40>(red)?, o),
        (20, 4, FilterPrecision::F32) => run_model::<f32, _, _>(red, data, discrete::<20, 4, 40>(red)?, o),
        (24, 4, FilterPrecision::F64) => run_model::<f64, _, _>(red, data, discrete::<24, 4, 48>(red)?, o),
        (24, 4, FilterPrecision::F32) => run_model::<f32, _, _>(red, data, discrete::<24, 4, 48>(red)?, o),
        (28, 4, FilterPrecision::F64) => run_model::<f64, _, _>(red, data, discrete::<28, 4, 56>(red)?, o),
        (28, 4, FilterPrecision::F32) => run_model::<f32, _, _>(red, data, discrete::<28, 4, 56>(red)?, o),
        (_, _, FilterPrecision::F64) => run_dynamic(red, data, o),
        (n, m, FilterPrecision::F32) => bail!(
            "the f32 filter (the chip's arithmetic) exists only for the chip's sizes, {} states × 4 sensors \
             (8 modes, 2 unbalance nodes); this configuration gives {n} states × {m} sensors: run it in f64",
            CHIP_SIZES.map(|(n, _)| n.to_string()).join(", ")
        ),
    }
}

/// [`run_with`] in `f64` through the dynamic-size filter, whatever the size (the chip's sizes
/// included, which is how a test ties it to the fixed-size filter).
pub fn run_dynamic(red: &ReducedRotor, data: &DataFile, options: RunOptions) -> Result<Estimates> {
    run_model::<f64, Dyn, Dyn>(red, data, discrete_dynamic(red)?, options)
}

/// `m` (from the reduced model's `DMatrix`) at the filter's dimensions, checked.
fn sized<R: Dim, C: Dim>(m: &DMatrix<f64>, r: R, c: C) -> Result<OMatrix<f64, R, C>>
where
    DefaultAllocator: Allocator<R, C>,
{
    if m.shape() != (r.value(), c.value()) {
        bail!("matrix is {}×{}, expected {}×{}", m.nrows(), m.ncols(), r.value(), c.value());
    }
    Ok(OMatrix::from_fn_generic(r, c, |i, j| m[(i, j)]))
}

/// The filter run over `data`, for any sizes: one code for the fixed sizes and the dynamic ones.
fn run_model<T: Real, N: FilterDim<M>, M: Dim>(
    red: &ReducedRotor,
    data: &DataFile,
    model: GenericLinearModel<f64, N, M>,
    options: RunOptions,
) -> Result<Estimates>
where
    DefaultAllocator: FilterAllocator<N, M>,
{
    let (n, _) = model.a.shape_generic();
    let (m, _) = model.c.shape_generic();
    let channels = m.value();
    let steady = match options.steady_after {
        Some(t) => {
            let ss = solve_riccati(&model, 1e-10, 200_000).map_err(|e| anyhow!("no steady-state gain: {e:?}"))?;
            Some((t, ss))
        }
        None => None,
    };
    let mut ssf: Option<GenericSteadyStateFilter<T, N, M>> = None;
    let mut ss_log_det = f64::NAN;
    let columns: Vec<&[f64]> = red
        .channels
        .iter()
        .map(|name| data.column(name).ok_or_else(|| anyhow!("the data file has no channel {name}")))
        .collect::<Result<_>>()?;
    if columns.len() != channels || red.offsets.len() != channels {
        bail!("{} channels and {} offsets for a model with {channels} measurements", columns.len(), red.offsets.len());
    }
    let p0 = sized(&red.p0, n, n)?;
    let mut kf =
        GenericKalmanFilter::<T, N, M>::try_new(model.cast(), OVector::zeros_generic(n, U1), p0.map(T::of_f64))
            .map_err(|e| anyhow!("cannot build the filter: {e:?}"))?;
    let d_rows: DMatrix<f64> = red.displacement.clone();
    let f_rows: DMatrix<f64> = red.force.clone();
    if d_rows.ncols() != n.value() || f_rows.ncols() != n.value() || red.c.ncols() != n.value() {
        bail!("the output rows do not fit the {}-state model", n.value());
    }
    let nodes = d_rows.nrows() / 2;
    let mut est = Estimates {
        t: data.t.clone(),
        displacement_names: (0..nodes).flat_map(|n| [format!("n{n}_x"), format!("n{n}_y")]).collect(),
        displacement: vec![Vec::with_capacity(data.t.len()); d_rows.nrows()],
        force_names: red.force_nodes.iter().flat_map(|n| [format!("f{n}_x"), format!("f{n}_y")]).collect(),
        force: vec![Vec::with_capacity(data.t.len()); f_rows.nrows()],
        innovation: vec![Vec::with_capacity(data.t.len()); channels],
        sensor: vec![Vec::with_capacity(data.t.len()); channels],
        nis: Vec::with_capacity(data.t.len()),
        log_det_s: Vec::with_capacity(data.t.len()),
        ..Estimates::default()
    };
    for k in 0..data.t.len() {
        let y = OVector::<f64, M>::from_fn_generic(m, U1, |i, _| {
            columns[i].get(k).copied().unwrap_or(f64::NAN) - red.offsets[i]
        });
        if let Some((t_switch, ss)) = &steady {
            if ssf.is_none() && data.t[k] >= *t_switch {
                ssf = Some(
                    GenericSteadyStateFilter::from_gain(&model, &ss.gain, &ss.innovation, kf.state().clone())
                        .map_err(|e| anyhow!("steady-state filter: {e:?}"))?,
                );
                ss_log_det = log_det(ss.innovation.clone());
            }
        }
        if let Some(f) = ssf.as_mut() {
            match f.update(&y.map(T::of_f64)) {
                Some((r, nis)) => {
                    for i in 0..channels {
                        est.innovation[i].push(r[i].as_f64());
                    }
                    est.nis.push(nis.as_f64());
                    est.log_det_s.push(ss_log_det);
                }
                None => {
                    est.missing += 1;
                    push_missing(&mut est, channels);
                }
            }
        } else if y.iter().all(|v| v.is_finite()) {
            match kf.update(&y.map(T::of_f64)) {
                Ok(inn) => {
                    for i in 0..channels {
                        est.innovation[i].push(inn.residual[i].as_f64());
                    }
                    est.nis.push(inn.nis.as_f64());
                    est.log_det_s.push(log_det(inn.s.map(|v| v.as_f64())));
                }
                Err(_) => push_missing(&mut est, channels),
            }
        } else {
            est.missing += 1;
            push_missing(&mut est, channels);
        }
        let state = ssf.as_ref().map_or(kf.state(), |f| f.state());
        let x = DMatrix::from_iterator(n.value(), 1, state.iter().map(|v| v.as_f64()));
        let d = &d_rows * &x;
        for (i, out) in est.displacement.iter_mut().enumerate() {
            out.push(d[i]);
        }
        let yhat = &red.c * &x;
        for (i, out) in est.sensor.iter_mut().enumerate() {
            out.push(yhat[i] + red.offsets[i]);
        }
        let f = &f_rows * &x;
        for (i, out) in est.force.iter_mut().enumerate() {
            out.push(f[i]);
        }
        match ssf.as_mut() {
            Some(f) => f.predict(),
            None => kf.predict(),
        }
    }
    let h = kf.health();
    est.repairs = (h.covariance_resets + ssf.as_ref().map_or(0, |f| f.resets()), h.refused_updates);
    Ok(est)
}

fn push_missing(est: &mut Estimates, m: usize) {
    for i in 0..m {
        est.innovation[i].push(f64::NAN);
    }
    est.nis.push(f64::NAN);
    est.log_det_s.push(f64::NAN);
}

/// `ln det S` of a symmetric positive definite `S` through its Cholesky factor (NaN if not).
fn log_det<M: Dim>(s: OMatrix<f64, M, M>) -> f64
where
    DefaultAllocator: Allocator<M, M>,
{
    match s.cholesky() {
        Some(ch) => {
            let l = ch.l();
            2.0 * (0..l.nrows()).map(|i| l[(i, i)].ln()).sum::<f64>()
        }
        None => f64::NAN,
    }
}
