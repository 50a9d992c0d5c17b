//! Sine and cosine with `+ − ×` and one rounding only: the chip's `f32` filters need them in
//! every sigma point, and `libm`'s `sinf`/`cosf` reduce their argument in `f64`, which the
//! Cortex-M4F emulates in software (about a thousand instructions a call). Written once for
//! any [`Real`], so the chip and a host run in the same precision compute the same bits.
//!
//! The argument is reduced to `|r| ≤ π/4` by a multiple `k` of π/2 (π/2 split in two parts,
//! Cody–Waite), then both are Taylor series to `r¹⁷` and `r¹⁸` (truncation below 2·10⁻¹⁹ at
//! π/4, so the series is as good as `f64` allows and better than `f32` needs). Meant for the
//! angles of a vehicle's attitude: the reduction loses accuracy beyond `|x| ≈ 10⁵` rad.

use crate::Real;

/// `(sin x, cos x)`.
///
/// ```
/// use edgekf::trig::sin_cos;
/// for x in [-7.0f64, -3.0, -0.5, 0.0, 0.1, 0.785, 1.6, 3.14159, 100.0] {
///     let (s, c) = sin_cos(x);
///     assert!((s - x.sin()).abs() < 4e-16 && (c - x.cos()).abs() < 4e-16, "{x}");
/// }
/// let (s, c) = sin_cos(0.3f32);
/// assert!((s - 0.3f32.sin()).abs() < 1.2e-7 && (c - 0.3f32.cos()).abs() < 1.2e-7);
/// ```
pub fn sin_cos<T: Real>(x: T) -> (T, T) {
    let t = T::of_f64;
    let k = (x * t(core::f64::consts::FRAC_2_PI)).round();
    // π/2 = HI + LO, HI with few significant bits so that k·HI is exact for |k| < 2¹⁷.
    const HI: f64 = 1.570_796_251_296_997;
    const LO: f64 = 7.549_789_954_891_882e-8;
    let r = (x - k * t(HI)) - k * t(LO);
    let r2 = r * r;
    // Horner from the highest term: sin r = r (1 − r²/(2·3) (1 − r²/(4·5) (1 − …))) to r¹⁷,
    // cos r = 1 − r²/(1·2) (1 − r²/(3·4) (1 − …)) to r¹⁶ (the next terms are below 3·10⁻¹⁸).
    let mut s = T::one();
    let mut c = T::one();
    for (sin_step, cos_step) in STEPS.iter().rev() {
        s = T::one() - r2 * s * t(*sin_step);
        c = T::one() - r2 * c * t(*cos_step);
    }
    quadrant(k, r * s, c)
}

/// `1/((2n)(2n+1))` and `1/((2n−1)(2n))` for n = 1…8.
const STEPS: [(f64, f64); 8] = {
    let mut steps = [(0.0, 0.0); 8];
    let mut n = 1;
    while n <= 8 {
        let (a, b, c) = ((2 * n - 1) as f64, (2 * n) as f64, (2 * n + 1) as f64);
        steps[n - 1] = (1.0 / (b * c), 1.0 / (a * b));
        n += 1;
    }
    steps
};

fn quadrant<T: Real>(k: T, s: T, c: T) -> (T, T) {
    // k mod 4, from its value (|k| is small for a vehicle's angles).
    let four = T::of_f64(4.0);
    let q = k - four * (k / four).floor();
    let half = T::of_f64(0.5);
    if q < half {
        (s, c)
    } else if q < half * T::of_f64(3.0) {
        (c, -s)
    } else if q < half * T::of_f64(5.0) {
        (-s, -c)
    } else {
        (-c, s)
    }
}
