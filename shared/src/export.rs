//! Export of discrete models as Rust source: the host computes a model (discretisation,
//! Riccati solution) once in `f64`, writes it as constants, and the firmware compiles them in
//! with `include!`, so the chip does no start-up work and carries no solver code.
//!
//! Values are written in Rust's shortest round-trip form, so the constants are bit-identical to
//! what the host computed.

use crate::filter::{LinearModel, SteadyState};
use core::fmt::{self, Write};
use nalgebra::SMatrix;

/// Writes one matrix as `pub const {prefix}_{suffix}: [[f64; C]; R]` with a doc line.
pub fn write_matrix<const R: usize, const C: usize>(
    out: &mut impl Write,
    prefix: &str,
    suffix: &str,
    doc: &str,
    m: &SMatrix<f64, R, C>,
) -> fmt::Result {
    if m.iter().any(|v| !v.is_finite()) {
        return Err(fmt::Error);
    }
    writeln!(out, "/// {doc}")?;
    writeln!(out, "pub const {prefix}_{suffix}: [[f64; {C}]; {R}] = [")?;
    for r in 0..R {
        write!(out, "    [")?;
        for c in 0..C {
            if c > 0 {
                write!(out, ", ")?;
            }
            write!(out, "{:?}", m[(r, c)])?;
        }
        writeln!(out, "],")?;
    }
    writeln!(out, "];")
}

/// Writes `model` as constants `{prefix}_A`, `_C`, `_Q`, `_R` (row-major `[[f64; cols]; rows]`).
/// Fails (`fmt::Error`) on a non-finite value rather than writing code that does not compile.
///
/// ```
/// use edgekf::export::write_model;
/// use edgekf::filter::LinearModel;
/// use nalgebra::Matrix1;
/// let m = LinearModel { a: Matrix1::new(0.5), c: Matrix1::new(1.0), q: Matrix1::new(1e-5), r: Matrix1::new(2.0) };
/// let mut s = String::new();
/// write_model(&mut s, "DEMO", &m).unwrap();
/// assert!(s.contains("pub const DEMO_A: [[f64; 1]; 1] = [\n    [0.5],\n];"));
/// assert!(s.contains("[1e-5]"));
/// ```
pub fn write_model<const N: usize, const M: usize>(
    out: &mut impl Write,
    prefix: &str,
    model: &LinearModel<f64, N, M>,
) -> fmt::Result {
    write_matrix(out, prefix, "A", "State transition.", &model.a)?;
    write_matrix(out, prefix, "C", "Measurement matrix.", &model.c)?;
    write_matrix(out, prefix, "Q", "Process-noise covariance.", &model.q)?;
    write_matrix(out, prefix, "R", "Measurement-noise covariance.", &model.r)
}

/// Writes a steady state as `{prefix}_GAIN` and `{prefix}_S` (innovation covariance).
pub fn write_steady_state<const N: usize, const M: usize>(
    out: &mut impl Write,
    prefix: &str,
    ss: &SteadyState<N, M>,
) -> fmt::Result {
    write_matrix(out, prefix, "GAIN", "Steady-state Kalman gain.", &ss.gain)?;
    write_matrix(out, prefix, "S", "Steady-state innovation covariance.", &ss.innovation)
}

/// Rebuilds a matrix from exported rows.
///
/// ```
/// use edgekf::export::matrix;
/// let m = matrix(&[[1.0, 2.0], [3.0, 4.0]]);
/// assert_eq!(m[(1, 0)], 3.0);
/// ```
pub fn matrix<const R: usize, const C: usize>(rows: &[[f64; C]; R]) -> SMatrix<f64, R, C> {
    SMatrix::from_fn(|r, c| rows[r][c])
}

/// Rebuilds a model from exported constants.
pub fn model<const N: usize, const M: usize>(
    a: &[[f64; N]; N],
    c: &[[f64; N]; M],
    q: &[[f64; N]; N],
    r: &[[f64; M]; M],
) -> LinearModel<f64, N, M> {
    LinearModel { a: matrix(a), c: matrix(c), q: matrix(q), r: matrix(r) }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::filter::solve_riccati;
    use crate::systems::oscillator::HarmonicForceParams;
    use std::string::String;

    /// Every exported number reads back to the same bits (the firmware's golden test,
    /// `firmware/src/model.rs`, checks a committed file against the live computation).
    #[test]
    fn exported_constants_round_trip_bit_for_bit() {
        let model = HarmonicForceParams::default().discrete_model().unwrap();
        let ss = solve_riccati(&model, 1e-12, 100_000).unwrap();
        let mut text = String::new();
        write_model(&mut text, "HARMONIC", &model).unwrap();
        write_steady_state(&mut text, "HARMONIC", &ss).unwrap();
        let numbers: std::vec::Vec<f64> = text
            .lines()
            .filter(|l| l.trim_start().starts_with('['))
            .flat_map(|l| {
                l.trim()
                    .trim_start_matches('[')
                    .trim_end_matches("],")
                    .split(", ")
                    .map(|v| v.parse::<f64>().unwrap())
                    .collect::<std::vec::Vec<_>>()
            })
            .collect();
        let expected: std::vec::Vec<f64> = [
            model.a.transpose().as_slice(),
            model.c.transpose().as_slice(),
            model.q.transpose().as_slice(),
            model.r.as_slice(),
            ss.gain.transpose().as_slice(),
            ss.innovation.as_slice(),
        ]
        .concat();
        assert_eq!(numbers.len(), expected.len());
        for (a, b) in numbers.iter().zip(&expected) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
    }

    #[test]
    fn non_finite_values_are_refused() {
        let mut m = HarmonicForceParams::default().discrete_model().unwrap();
        m.q[(0, 0)] = f64::NAN;
        assert!(write_model(&mut String::new(), "X", &m).is_err());
    }
}
