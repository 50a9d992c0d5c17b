//! Dense linear algebra that the filters need beyond nalgebra: the matrix exponential and
//! exact discretisation of continuous-time models.
//!
//! These routines use only `+ − × ÷` and comparisons (no `exp`, `log` or `pow` from a maths
//! library), so they produce identical bits on the Cortex-M4F and on x86-64. That is what lets a
//! firmware run under QEMU be compared with a host run bit for bit.
//!
//! [`expm`], [`solve`], [`zoh_with`] and [`van_loan_with`] are generic over nalgebra's
//! dimensions: fixed sizes on the chip, and with the `alloc` feature `DMatrix` on the host, so
//! that every reduced model, of a size compiled in or not, is discretised by this one code.
//! [`zoh`] and [`van_loan`] are their const-generic forms.

mod discretize;
mod expm;

pub use discretize::{van_loan, van_loan_with, zoh, zoh_with};
pub use expm::expm;

/// Why a linear-algebra routine could not produce a result.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinalgError {
    /// A matrix that had to be inverted was singular to working precision.
    Singular,
    /// An input held a NaN or an infinity.
    NonFinite,
    /// The sizes do not fit: a block size that does not match the blocks (for example
    /// `NM != N + M` in [`zoh`]) or, for dynamic sizes, shapes that disagree.
    SizeMismatch,
}

impl core::fmt::Display for LinalgError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            LinalgError::Singular => f.write_str("matrix is singular to working precision"),
            LinalgError::NonFinite => f.write_str("matrix holds NaN or infinity"),
            LinalgError::SizeMismatch => f.write_str("block sizes do not add up"),
        }
    }
}

mod cholesky;
mod solve;
pub use cholesky::{cholesky, cholesky_scaled_into, solve_lower, solve_lower_transposed};
pub use solve::solve;

mod jacobi;
pub use jacobi::symmetric_eigen;

mod dot;
pub use dot::{column, dot, mul_tr, mul_tr_add};
