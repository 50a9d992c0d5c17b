//! Where an input the model lacks acts, read from the direction of the innovations it leaves.
//!
//! A periodic input at frequency `f` that the model lacks leaves in the innovations the phasor
//! `E = S(z) Y`: `Y` is the sensors' open-loop response to it and
//! `S(z) = I − C (zI − Φ(I − K C))⁻¹ Φ K`, at `z = e^{i2πf/fs}`, is the filter's output
//! sensitivity (what its states take up never reaches the innovations: a machine filter's
//! unbalance states absorb a 1× force at a disk). Each candidate location gives the directions
//! `S(z) Yₙ` its input can produce, and the share of the (whitened) innovation phasor they span
//! ranks the locations. That costs one small solve per location, where fitting costs a filter
//! run (or dozens) per location, so a system can search every node and fit only the few the
//! innovations point to.

use crate::residual_loop::filter::{FinalFilter, Run};
use nalgebra::{Complex, DMatrix, DVector};
use std::f64::consts::TAU;

/// A complex number (the phasors').
pub type C64 = Complex<f64>;

/// One location and the share of the innovations' energy at the lines its input explains.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement<L> {
    /// The location.
    pub location: L,
    /// Share of the whitened innovation phasors' energy the location's directions span, 0–1.
    pub explained: f64,
}

/// The stretch of `run` the phasors are read over: from where the gain froze (the filter is
/// then the steady one `S(z)` describes), or the second half of the run.
fn settled(run: &Run) -> std::ops::Range<usize> {
    let n = run.nis.len();
    run.frozen_at.filter(|&k| k < n.saturating_sub(16)).unwrap_or(n / 2)..n
}

/// The innovations' phasor at `hz` over the settled stretch, per channel (Hann window; a
/// channel's innovation is `Re(E e^{i2πft})`), each divided by the channel's innovation
/// standard deviation there (channels in different units weigh alike).
///
/// ```
/// use edgekf_sim::diagnostics::locate::phasor;
/// use edgekf_sim::residual_loop::filter::Run;
/// let fs = 1000.0;
/// let e: Vec<f64> = (0..4000).map(|k| 0.3 * (std::f64::consts::TAU * 50.0 * k as f64 / fs + 0.5).cos()).collect();
/// let run = Run { innovation: vec![e], variance: vec![vec![1.0; 4000]], nis: vec![1.0; 4000], ..Run::default() };
/// let p = phasor(&run, 50.0, fs);
/// assert!((p[0].norm() - 0.3).abs() < 1e-3 && (p[0].arg() - 0.5).abs() < 1e-3);
/// ```
pub fn phasor(run: &Run, hz: f64, sample_rate: f64) -> DVector<C64> {
    let range = settled(run);
    let sd = innovation_sd(run, &range);
    let len = range.len().max(1) as f64;
    let w = TAU * hz / sample_rate;
    DVector::from_fn(run.innovation.len(), |ch, _| {
        let (mut sum, mut weights) = (C64::new(0.0, 0.0), 0.0);
        for k in range.clone() {
            let e = run.innovation[ch][k];
            if !e.is_finite() {
                continue;
            }
            let hann = 0.5 - 0.5 * (TAU * (k - range.start) as f64 / len).cos();
            sum += C64::from_polar(hann * e, -w * k as f64);
            weights += hann;
        }
        if weights <= 0.0 || sd[ch] <= 0.0 {
            return C64::new(0.0, 0.0);
        }
        sum * (2.0 / weights) / sd[ch]
    })
}

/// Each channel's innovation standard deviation over `range`, as the filter predicted it (the
/// mean of its `S` diagonal over the samples that have one).
fn innovation_sd(run: &Run, range: &std::ops::Range<usize>) -> Vec<f64> {
    run.variance
        .iter()
        .map(|v| {
            let vals: Vec<f64> = v[range.clone()].iter().copied().filter(|x| x.is_finite()).collect();
            (vals.iter().sum::<f64>() / vals.len().max(1) as f64).sqrt()
        })
        .collect()
}

/// The filter's output sensitivity `S(z)` at `hz` (see the module's doc), or `None` when the
/// filter's error dynamics are singular at that frequency.
pub fn sensitivity(f: &FinalFilter, hz: f64, sample_rate: f64) -> Option<DMatrix<C64>> {
    let n = f.transition.nrows();
    let m = f.c.nrows();
    if n == 0 {
        return Some(DMatrix::identity(m, m));
    }
    let cplx = |a: &DMatrix<f64>| a.map(|v| C64::new(v, 0.0));
    let phi_k = &f.transition * &f.gain;
    let closed = &f.transition - &phi_k * &f.c;
    let z = C64::from_polar(1.0, TAU * hz / sample_rate);
    let lhs = DMatrix::<C64>::identity(n, n) * z - cplx(&closed);
    let x = lhs.lu().solve(&cplx(&phi_k))?;
    Some(DMatrix::<C64>::identity(m, m) - cplx(&f.c) * x)
}

/// The open-loop frequency response at `hz` of the outputs `y = C x + D u` of `ẋ = A x + B u`
/// (`m × q`). Solved a hair off the imaginary axis, so that states that run on their own at
/// `hz` (a force the filter estimates, rotating there) and are not driven by `u` stay at zero
/// instead of making the solve singular.
pub fn open_loop(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
    d: &DMatrix<f64>,
    hz: f64,
) -> Option<DMatrix<C64>> {
    let n = a.nrows();
    if n == 0 {
        return Some(d.map(|v| C64::new(v, 0.0)));
    }
    let w = TAU * hz;
    let s = C64::new(1e-6 * w.max(1.0), w);
    let lhs = DMatrix::<C64>::identity(n, n) * s - a.map(|v| C64::new(v, 0.0));
    let x = lhs.lu().solve(&b.map(|v| C64::new(v, 0.0)))?;
    Some(c.map(|v| C64::new(v, 0.0)) * x + d.map(|v| C64::new(v, 0.0)))
}

/// The share of `e`'s energy in the span of `t`'s columns (least squares, by Gram–Schmidt;
/// columns with no length of their own add nothing).
fn explained_energy(e: &DVector<C64>, t: &DMatrix<C64>) -> f64 {
    let mut basis: Vec<DVector<C64>> = Vec::new();
    let scale = t.iter().map(|v| v.norm_sqr()).fold(0.0, f64::max).max(1e-300);
    for j in 0..t.ncols() {
        let mut v = t.column(j).clone_owned();
        for q in &basis {
            let proj = q.dotc(&v);
            v -= q * proj;
        }
        let norm = v.norm();
        if norm * norm > 1e-18 * scale {
            basis.push(v / C64::new(norm, 0.0));
        }
    }
    basis.iter().map(|q| q.dotc(e).norm_sqr()).sum()
}

/// Ranks `locations` by the share of the innovations' energy at the lines `hz` (whitened,
/// summed over the lines) that the directions `S(z) Yₙ` of each location's input span, best
/// first. `response(location, f)` is the sensors' open-loop response (`m × q`: one column per
/// independent component of the input) to the input at `location` at `f` Hz, in the channels'
/// units; a location without one is left out. Without a final filter in `run`, nothing is
/// ranked.
///
/// ```
/// use edgekf_sim::diagnostics::locate::{rank, C64};
/// use edgekf_sim::residual_loop::filter::{FinalFilter, Run};
/// use nalgebra::DMatrix;
/// // Two channels, no states: the innovations are the data, and an input at "b" reads (1, 2).
/// let fs = 100.0;
/// let tone = |a: f64| (0..2000).map(|k| a * (std::f64::consts::TAU * 5.0 * k as f64 / fs).sin()).collect::<Vec<_>>();
/// let last = FinalFilter { transition: DMatrix::zeros(0, 0), gain: DMatrix::zeros(0, 2), c: DMatrix::zeros(2, 0) };
/// let run = Run {
///     innovation: vec![tone(1.0), tone(2.0)],
///     variance: vec![vec![1.0; 2000]; 2],
///     nis: vec![1.0; 2000],
///     last: Some(last),
///     ..Run::default()
/// };
/// let reads = |l: &&str, _f: f64| {
///     let col = if *l == "a" { [1.0, -1.0] } else { [1.0, 2.0] };
///     Some(DMatrix::from_fn(2, 1, |i, _| C64::new(col[i], 0.0)))
/// };
/// let ranked = rank(&run, &[5.0], fs, vec!["a", "b"], reads);
/// assert_eq!(ranked[0].location, "b");
/// assert!(ranked[0].explained > 0.999 && ranked[1].explained < 0.2);
/// ```
pub fn rank<L>(
    run: &Run,
    hz: &[f64],
    sample_rate: f64,
    locations: Vec<L>,
    response: impl Fn(&L, f64) -> Option<DMatrix<C64>>,
) -> Vec<Placement<L>> {
    let Some(last) = &run.last else { return Vec::new() };
    // The channels' innovation standard deviations, to whiten the directions as the phasors are.
    let sd = innovation_sd(run, &settled(run));
    let lines: Vec<(f64, DVector<C64>, DMatrix<C64>)> = hz
        .iter()
        .filter_map(|&f| {
            let s = sensitivity(last, f, sample_rate)?;
            Some((f, phasor(run, f, sample_rate), s))
        })
        .collect();
    let total: f64 = lines.iter().map(|(_, e, _)| e.norm_squared()).sum();
    let mut out: Vec<Placement<L>> = locations
        .into_iter()
        .filter_map(|location| {
            let mut energy = 0.0;
            for (f, e, s) in &lines {
                let y = response(&location, *f)?;
                if y.nrows() != sd.len() {
                    return None;
                }
                let mut t = s * y;
                for (i, sd) in sd.iter().enumerate() {
                    t.row_mut(i).iter_mut().for_each(|v| *v /= sd.max(1e-300));
                }
                energy += explained_energy(e, &t);
            }
            Some(Placement { location, explained: if total > 0.0 { energy / total } else { 0.0 } })
        })
        .collect();
    out.sort_by(|a, b| b.explained.total_cmp(&a.explained));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::residual_loop::filter::{run_state_space, StateSpace};

    /// A lightly damped two-mass chain read at both masses, driven by a tone at one mass the
    /// model lacks: the filter's innovations point to that mass, through the filter's own
    /// sensitivity (its states take up part of the tone).
    #[test]
    fn a_tone_at_one_mass_points_to_that_mass() {
        let (k, c, fs) = (4.0e4, 2.0, 1000.0);
        // States x1, x2, v1, v2 (unit masses).
        let a =
            DMatrix::from_row_slice(4, 4, &[0., 0., 1., 0., 0., 0., 0., 1., -2. * k, k, -c, 0., k, -2. * k, 0., -c]);
        let qc = DMatrix::from_diagonal(&nalgebra::DVector::from_row_slice(&[0., 0., 1e-2, 1e-2]));
        let cm = DMatrix::from_row_slice(2, 4, &[1., 0., 0., 0., 0., 1., 0., 0.]);
        let r = DMatrix::identity(2, 2) * 1e-12;
        let p0 = DMatrix::identity(4, 4) * 1e-6;
        // The truth: a 40 Hz force of 1 N at mass 2, simulated by the exact discretisation.
        let f = 40.0;
        let dt = 1.0 / fs;
        let mut aug = DMatrix::<f64>::zeros(6, 6);
        aug.view_mut((0, 0), (4, 4)).copy_from(&a);
        aug[(3, 4)] = 1.0;
        aug[(4, 5)] = -TAU * f;
        aug[(5, 4)] = TAU * f;
        let d = crate::residual_loop::filter::discretise(&aug, &DMatrix::zeros(6, 6), dt).unwrap();
        let mut x = DVector::from_row_slice(&[0., 0., 0., 0., 1., 0.]);
        let mut y = [Vec::new(), Vec::new()];
        for kk in 0..6000 {
            let noise = |s: u64| 1e-6 * (((kk as u64 * 2654435761 + s) % 1000) as f64 / 500.0 - 1.0);
            y[0].push(x[0] + noise(1));
            y[1].push(x[1] + noise(7));
            x = &d.a * &x;
        }
        let ss = StateSpace { a: &a, qc: &qc, c: &cm, r: &r, p0: &p0 };
        let cols: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        let run = run_state_space(&ss, dt, &cols, &DMatrix::zeros(0, 4), &[]).unwrap();
        let zero = DMatrix::zeros(2, 1);
        let input = |l: &usize, hz: f64| {
            let mut b = DMatrix::zeros(4, 1);
            b[(2 + l, 0)] = 1.0;
            open_loop(&a, &b, &cm, &zero, hz)
        };
        let ranked = rank(&run, &[f], fs, vec![0usize, 1], input);
        assert_eq!(ranked[0].location, 1, "{ranked:?}");
        assert!(ranked[0].explained > 0.95 && ranked[1].explained < 0.8 * ranked[0].explained, "{ranked:?}");
        // The innovations are what S(z) says: the measured phasor (unwhitened) is S(z) Y F for
        // the 1 N cosine, channel by channel, though far from the open-loop response Y.
        let y2 = input(&1, f).unwrap();
        let predicted = sensitivity(run.last.as_ref().unwrap(), f, fs).unwrap() * &y2;
        let e = phasor(&run, f, fs);
        for ch in 0..2 {
            let sd = (run.variance[ch][5999]).sqrt();
            let measured = e[ch] * sd;
            let err = (measured - predicted[(ch, 0)]).norm();
            assert!(err < 0.05 * predicted[(ch, 0)].norm(), "channel {ch}: {measured} vs {}", predicted[(ch, 0)]);
            assert!(predicted[(ch, 0)].norm() < 0.5 * y2[(ch, 0)].norm(), "the filter takes up little of the tone");
        }
    }
}
