//! The scalar trait that lets one filter implementation run in `f32` on the chip and `f64` on
//! the host.

use nalgebra::RealField;

/// A floating-point scalar usable by every filter and model in this crate (`f32` or `f64`).
///
/// Model constants are always computed in `f64` (once, at construction) and converted with
/// [`Real::of_f64`], so an `f32` filter on the chip and an `f32` filter on the host start from
/// the same bits.
///
/// ```
/// use edgekf::Real;
/// assert_eq!(<f32 as Real>::of_f64(0.1), 0.1f32);
/// assert_eq!(Real::as_f64(0.5f32), 0.5f64);
/// let (s, c) = Real::libm_sin_cos(0.5f64);
/// assert!((s * s + c * c - 1.0).abs() < 1e-15);
/// ```
pub trait Real: RealField + Copy {
    /// Converts (rounding to nearest) from an `f64`.
    fn of_f64(v: f64) -> Self;
    /// Widens (or copies) to an `f64`.
    fn as_f64(self) -> f64;
    /// `(sin x, cos x)` from `libm` explicitly, so the chip and a host run in the same precision
    /// compute the same bits (the standard library's `sin` may differ in the last bit).
    fn libm_sin_cos(self) -> (Self, Self);
}

impl Real for f32 {
    #[inline]
    fn of_f64(v: f64) -> Self {
        v as f32
    }
    #[inline]
    fn as_f64(self) -> f64 {
        self as f64
    }
    #[inline]
    fn libm_sin_cos(self) -> (Self, Self) {
        libm::sincosf(self)
    }
}

impl Real for f64 {
    #[inline]
    fn of_f64(v: f64) -> Self {
        v
    }
    #[inline]
    fn as_f64(self) -> f64 {
        self
    }
    #[inline]
    fn libm_sin_cos(self) -> (Self, Self) {
        libm::sincos(self)
    }
}
