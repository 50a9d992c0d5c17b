//! Van der Merwe's scaled sigma points and their weights, as the unscented filter uses them,
//! and [`UkfError`], which their weights and the filter's constructor share: it lives here, below
//! the filter, so that this module needs nothing of `ukf.rs`.

use crate::Real;

/// Why an unscented filter could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum UkfError {
    /// `α`, `β` or `κ` not finite, `α ≤ 0`, `n + κ ≤ 0` (no real spread), or a centre weight
    /// `|Wm₀|` so large that the means would keep fewer than four significant digits in the
    /// precision in use (see [`MerweSigmaPoints`]).
    SigmaPoints,
    /// The initial state or covariance is not finite, or `(n + λ) P₀` has no Cholesky factor:
    /// `P₀` is also the value the covariance guard resets to, so it must be positive definite.
    InitialCovariance,
}

/// Van der Merwe's scaled sigma points (filterpy's `MerweScaledSigmaPoints`).
///
/// With `λ = α² (n + κ) − n` the `2n + 1` points are `x`, `x + √((n+λ)P)` column `i` and
/// `x − √((n+λ)P)` column `i` (`i = 1…n`, lower Cholesky factor), weighted by
/// `Wm₀ = λ/(n+λ)`, `Wc₀ = Wm₀ + 1 − α² + β` and `Wmᵢ = Wcᵢ = 1/(2(n+λ))`.
///
/// `α` sets the spread (small, e.g. 1e-3 … 1, keeps the points local), `β = 2` is optimal for a
/// Gaussian prior, `κ` is usually `0` or `3 − n`.
///
/// Precision: the unscented mean is in effect a second difference of `f` over a step of
/// `α √(n+κ) σ`, so the rounding of `f`'s outputs (`ε |f|`) reaches the mean amplified by about
/// `|Wm₀| ≈ 1/α²`. At α = 1e-3 that costs 6 of `f64`'s 16 digits (filterpy loses the same) and
/// more than all of `f32`'s 7. [`MerweSigmaPoints::weights`] therefore refuses parameters with
/// `|Wm₀| · ε > 1e-4` for the precision in use (fewer than four significant digits left): in
/// `f32` that means `|Wm₀| ≤ 838`, e.g. `α ≳ 0.035` for `κ = 0`; `α ≈ 0.1 … 0.5` is a good
/// choice there.
///
/// ```
/// use edgekf::filter::MerweSigmaPoints;
/// let w = MerweSigmaPoints { alpha: 0.5f64, beta: 2.0, kappa: 1.0 }.weights::<2>().unwrap();
/// // λ = 0.25·3 − 2 = −1.25, n + λ = 0.75
/// assert!((w.mean_center - (-1.25 / 0.75)).abs() < 1e-15);
/// assert!((w.mean_center + 4.0 * w.side - 1.0).abs() < 1e-15); // the mean weights sum to one
/// // α = 1e-3 is fine in f64 but would leave no significant digit in f32.
/// assert!(MerweSigmaPoints { alpha: 1e-3f64, beta: 2.0, kappa: 0.0 }.weights::<4>().is_ok());
/// assert!(MerweSigmaPoints { alpha: 1e-3f32, beta: 2.0, kappa: 0.0 }.weights::<4>().is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MerweSigmaPoints<T: Real> {
    /// Spread `α > 0`.
    pub alpha: T,
    /// Prior-knowledge term `β` (2 for Gaussian).
    pub beta: T,
    /// Secondary scaling `κ`; `n + κ` must be positive.
    pub kappa: T,
}

/// The weights and scale of a set of sigma points for `n` states.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SigmaWeights<T: Real> {
    /// `Wm₀`: mean weight of the centre point.
    pub mean_center: T,
    /// `Wc₀`: covariance weight of the centre point.
    pub cov_center: T,
    /// `Wmᵢ = Wcᵢ = 1/(2(n+λ))` of each of the other `2n` points.
    pub side: T,
    /// `n + λ`: the sigma points use the Cholesky factor of `(n + λ) P`.
    pub spread: T,
    /// `β − α² = Wc₀ + 2n·Wᵢ − 2`: the weight of `m mᵀ` when the covariance is summed about the
    /// centre image (`m` = mean minus centre image), as this filter does.
    pub cov_shift: T,
}

impl<T: Real> MerweSigmaPoints<T> {
    /// The weights for `N` states, computed in `f64` with filterpy's expressions and converted to
    /// `T` once, so an `f32` filter on the chip and on the host start from the same bits.
    ///
    /// Fails with [`UkfError::SigmaPoints`] for parameters without a real spread or too fine for
    /// the precision `T` (see the type's documentation).
    pub fn weights<const N: usize>(&self) -> Result<SigmaWeights<T>, UkfError> {
        let (alpha, beta, kappa) = (self.alpha.as_f64(), self.beta.as_f64(), self.kappa.as_f64());
        let n = N as f64;
        let finite = alpha.is_finite() && beta.is_finite() && kappa.is_finite();
        // `n + λ = α² (n + κ)`; the comparisons are false for NaN.
        let positive = alpha > 0.0 && n + kappa > 0.0;
        if !(finite && positive) {
            return Err(UkfError::SigmaPoints);
        }
        let a2 = alpha * alpha;
        let lambda = a2 * (n + kappa) - n;
        let spread = n + lambda;
        let spread_ok = spread > 0.0 && spread.is_finite();
        if !spread_ok {
            return Err(UkfError::SigmaPoints);
        }
        let side = 0.5 / spread;
        let mean_center = lambda / spread;
        let cov_center = mean_center + (1.0 - a2 + beta);
        // Digits lost to the spread: the means carry about |Wm₀|·ε of relative rounding error.
        let too_fine = mean_center.abs() * T::default_epsilon().as_f64() > 1e-4;
        if !(side.is_finite() && mean_center.is_finite() && cov_center.is_finite()) || too_fine {
            return Err(UkfError::SigmaPoints);
        }
        Ok(SigmaWeights {
            mean_center: T::of_f64(mean_center),
            cov_center: T::of_f64(cov_center),
            side: T::of_f64(side),
            spread: T::of_f64(spread),
            cov_shift: T::of_f64(beta - a2),
        })
    }
}
