//! Discretisation of the reduced rotor and the filter run over a data file.

use super::reduce::ReducedRotor;
use crate::io::data::DataFile;
use anyhow::{anyhow, bail, Result};
use edgekf::filter::{KalmanFilter, LinearModel};
use edgekf::linalg::van_loan;
use edgekf::Real;
use nalgebra::{DMatrix, SMatrix, SVector};

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
    /// `innovation[channel][k]`, in the channel's unit (NaN where the sample was missing).
    pub innovation: Vec<Vec<f64>>,
    /// NIS per sample (NaN where missing).
    pub nis: Vec<f64>,
    /// Samples whose measurement was missing (NaN in the file) and were bridged by prediction.
    pub missing: usize,
    /// Covariance resets and refused updates of the filter (both 0 in a healthy run).
    pub repairs: (u32, u32),
}

fn fixed<const R: usize, const C: usize>(m: &DMatrix<f64>) -> Result<SMatrix<f64, R, C>> {
    if m.nrows() != R || m.ncols() != C {
        bail!("matrix is {}×{}, expected {R}×{C}", m.nrows(), m.ncols());
    }
    Ok(SMatrix::from_fn(|i, j| m[(i, j)]))
}

/// The discrete model of `red` at its sample rate (exact discretisation, Van Loan).
pub fn discrete<const N: usize, const M: usize, const N2: usize>(red: &ReducedRotor) -> Result<LinearModel<f64, N, M>> {
    let dt = 1.0 / red.sample_rate;
    let (a, q) = van_loan::<f64, N, N2>(&fixed(&red.a)?, &fixed(&red.qc)?, dt)
        .map_err(|e| anyhow!("cannot discretise the reduced model: {e}"))?;
    Ok(LinearModel { a, c: fixed(&red.c)?, q, r: fixed(&red.r)? })
}

/// Runs the filter of `red` over `data` (channels named as the sensors).
///
/// Sizes are compile-time on the chip, so the host supports the sizes the firmware can run:
/// 20 states × 4 sensors (8 modes, 2 unbalance nodes, 4 sensors: the paper's rotor).
pub fn run(red: &ReducedRotor, data: &DataFile, precision: FilterPrecision) -> Result<Estimates> {
    match (red.states(), red.c.nrows(), precision) {
        (20, 4, FilterPrecision::F64) => run_sized::<f64, 20, 4, 40>(red, data),
        (20, 4, FilterPrecision::F32) => run_sized::<f32, 20, 4, 40>(red, data),
        (n, m, _) => bail!("no filter build for {n} states × {m} sensors (supported: 20 × 4, i.e. 8 modes, 2 unbalance nodes, 4 sensors)"),
    }
}

fn run_sized<T: Real, const N: usize, const M: usize, const N2: usize>(
    red: &ReducedRotor,
    data: &DataFile,
) -> Result<Estimates> {
    let model = discrete::<N, M, N2>(red)?;
    let columns: Vec<&[f64]> = red
        .channels
        .iter()
        .map(|name| data.column(name).ok_or_else(|| anyhow!("the data file has no channel {name}")))
        .collect::<Result<_>>()?;
    let p0: SMatrix<f64, N, N> = fixed(&red.p0)?;
    let mut kf = KalmanFilter::<T, N, M>::new(model.cast(), SVector::zeros(), p0.map(T::of_f64));
    let d_rows: DMatrix<f64> = red.displacement.clone();
    let f_rows: DMatrix<f64> = red.force.clone();
    let nodes = d_rows.nrows() / 2;
    let mut est = Estimates {
        t: data.t.clone(),
        displacement_names: (0..nodes).flat_map(|n| [format!("n{n}_x"), format!("n{n}_y")]).collect(),
        displacement: vec![Vec::with_capacity(data.t.len()); d_rows.nrows()],
        force_names: red.force_nodes.iter().flat_map(|n| [format!("f{n}_x"), format!("f{n}_y")]).collect(),
        force: vec![Vec::with_capacity(data.t.len()); f_rows.nrows()],
        innovation: vec![Vec::with_capacity(data.t.len()); M],
        nis: Vec::with_capacity(data.t.len()),
        ..Estimates::default()
    };
    for k in 0..data.t.len() {
        let y = SVector::<f64, M>::from_fn(|i, _| columns[i].get(k).copied().unwrap_or(f64::NAN));
        if y.iter().all(|v| v.is_finite()) {
            match kf.update(&y.map(T::of_f64)) {
                Ok(inn) => {
                    for i in 0..M {
                        est.innovation[i].push(inn.residual[i].as_f64());
                    }
                    est.nis.push(inn.nis.as_f64());
                }
                Err(_) => push_missing(&mut est, M),
            }
        } else {
            est.missing += 1;
            push_missing(&mut est, M);
        }
        let x = DMatrix::from_iterator(N, 1, kf.state().iter().map(|v| v.as_f64()));
        let d = &d_rows * &x;
        for (i, out) in est.displacement.iter_mut().enumerate() {
            out.push(d[i]);
        }
        let f = &f_rows * &x;
        for (i, out) in est.force.iter_mut().enumerate() {
            out.push(f[i]);
        }
        kf.predict();
    }
    let h = kf.health();
    est.repairs = (h.covariance_resets, h.refused_updates);
    Ok(est)
}

fn push_missing(est: &mut Estimates, m: usize) {
    for i in 0..m {
        est.innovation[i].push(f64::NAN);
    }
    est.nis.push(f64::NAN);
}
