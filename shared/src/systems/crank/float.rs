//! The scalar of the clearance estimator.

use crate::Real;
use core::ops::{BitAnd, BitOr, Shl, Shr};

/// `f32` (the chip) or `f64` (the host) as the clearance estimator needs it: the bit pattern
/// of non-negative values, which orders like the values (IEEE 754: sign bit clear, then
/// exponent, then mantissa), for the in-place median ([`super::select_nth`]); and `ln`/`exp`
/// from the `libm` crate on every target.
///
/// Why not `Real`'s own `ln`/`exp`: with `std` in the build (the host), nalgebra's scalar
/// functions are the platform's (glibc), which round differently from `libm` in the last bit
/// now and then; calling `libm` explicitly makes the host's `f32` run of the node's code
/// bit-identical to the chip's.
///
/// ```
/// use edgekf::systems::crank::ClearanceFloat;
/// assert!(1.5f32.key() < 2.0f32.key());
/// assert_eq!(f64::of_key(0.25f64.key()), 0.25);
/// assert_eq!(ClearanceFloat::ln_m(1.0f32), 0.0);
/// ```
pub trait ClearanceFloat: Real {
    /// The bit pattern's integer (`u32` for `f32`: the chip does no 64-bit arithmetic here).
    type Key: Copy
        + Eq
        + BitAnd<Output = Self::Key>
        + BitOr<Output = Self::Key>
        + Shl<u32, Output = Self::Key>
        + Shr<u32, Output = Self::Key>
        + From<u8>
        + Into<u64>;
    /// Bytes in the pattern (4 for `f32`, 8 for `f64`).
    const KEY_BYTES: u32;
    /// The bit pattern.
    fn key(self) -> Self::Key;
    /// The value of a pattern [`ClearanceFloat::key`] returned.
    fn of_key(key: Self::Key) -> Self;
    /// Natural logarithm (`libm`).
    fn ln_m(self) -> Self;
    /// Exponential (`libm`).
    fn exp_m(self) -> Self;
}

impl ClearanceFloat for f32 {
    type Key = u32;
    const KEY_BYTES: u32 = 4;
    #[inline]
    fn key(self) -> u32 {
        self.to_bits()
    }
    #[inline]
    fn of_key(key: u32) -> Self {
        f32::from_bits(key)
    }
    #[inline]
    fn ln_m(self) -> Self {
        libm::logf(self)
    }
    #[inline]
    fn exp_m(self) -> Self {
        libm::expf(self)
    }
}

impl ClearanceFloat for f64 {
    type Key = u64;
    const KEY_BYTES: u32 = 8;
    #[inline]
    fn key(self) -> u64 {
        self.to_bits()
    }
    #[inline]
    fn of_key(key: u64) -> Self {
        f64::from_bits(key)
    }
    #[inline]
    fn ln_m(self) -> Self {
        libm::log(self)
    }
    #[inline]
    fn exp_m(self) -> Self {
        libm::exp(self)
    }
}
