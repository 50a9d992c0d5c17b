//! Decimal text to `f32` and `f64` with no panic path, for the node's CSV readers.
//!
//! `core`'s float parser keeps bounds checks in its slow path that no caller can remove, so an
//! image that reads numbers with it cannot be proven panic-free at link time (see the README's
//! no-panic proof). This parser takes the same syntax as `str::parse` (an optional sign, digits
//! with an optional point, an optional exponent; `inf`, `infinity` and `nan` in any case) and
//! rounds to nearest, ties to even, as `core` does:
//!
//! * the common case is Clinger's fast path: at most 2⁵³ as an integer and a power of ten up to
//!   10²² are exact in `f64`, so one multiplication or division rounds once. For `f32` that
//!   `f64` is rounded again, which is exact unless the `f64` lies on an `f32` midpoint;
//! * every other case (and that midpoint) starts from an approximation and settles the
//!   rounding by comparing the decimal exactly with the neighbouring floats and the midpoint
//!   between them, in fixed-size integers (`Big`, 1 792 bits, enough for any exponent that
//!   does not round to 0 or infinity). The text is read again for that, up to 40 digits.
//!
//! Correctly rounded for up to 40 significant digits. A longer input keeps its first 40 digits
//! and whether any later one is non-zero, which settles every rounding unless the input lies
//! within 10⁻⁴⁰ (relative) of a midpoint between two floats. The tests compare it with `core`
//! on every kind of input, bit for bit; the fuzz target `line_reader` does too.
//!
//! ```
//! use edgekf::decimal::{parse_f32, parse_f64};
//! assert_eq!(parse_f32("1.5e-3"), Some(1.5e-3));
//! assert_eq!(parse_f64("-0.1"), Some(-0.1));
//! assert_eq!(parse_f32("0.1"), "0.1".parse::<f32>().ok());
//! assert_eq!(parse_f64("1e400"), Some(f64::INFINITY));
//! assert!(parse_f32("NaN").is_some_and(f32::is_nan));
//! assert_eq!(parse_f32("1,5"), None);
//! assert_eq!(parse_f32(""), None);
//! ```

#![deny(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use core::cmp::Ordering;

/// Significant digits of the fast path's 64-bit mantissa (below 10¹⁹ < 2⁶⁴).
const FAST_DIGITS: u32 = 19;

/// Significant digits the exact comparison keeps; later ones only count as a non-zero
/// remainder. 40 digits resolve a float's rounding unless it lies within 10⁻⁴⁰ (relative) of
/// a midpoint, which no input short of an exact midpoint's 40+ digits comes near.
const EXACT_DIGITS: u32 = 40;

/// Exponents are clamped here while reading: far beyond any that does not give 0 or infinity.
const EXPONENT_CLAMP: i64 = 100_000;

/// A number as written: its sign, its digits (with at most one point) and its exponent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Written<'a> {
    negative: bool,
    digits: &'a [u8],
    exponent: i64,
}

/// The leading significant digits of a [`Written`] number, as an integer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Leading {
    /// Significant digits kept.
    kept: u32,
    /// The power of ten of the last kept digit.
    exponent: i64,
    /// Whether a digit past the kept ones is non-zero.
    sticky: bool,
}

impl Written<'_> {
    /// Feeds the first `max` significant digits to `push`, most significant first.
    fn leading(&self, max: u32, mut push: impl FnMut(u8)) -> Leading {
        let mut lead = Leading { kept: 0, exponent: 0, sticky: false };
        let mut point = false;
        let mut shift = 0i64;
        for &b in self.digits {
            if b == b'.' {
                point = true;
                continue;
            }
            let v = b.wrapping_sub(b'0');
            if lead.kept < max && (lead.kept > 0 || v != 0) {
                push(v);
                lead.kept += 1;
                if point {
                    shift -= 1;
                }
            } else if lead.kept == 0 {
                // A leading zero: only its place after the point counts.
                if point {
                    shift -= 1;
                }
            } else {
                lead.sticky |= v != 0;
                if !point {
                    shift += 1;
                }
            }
            // One a digit: clamp it on very long inputs.
            shift = shift.clamp(-EXPONENT_CLAMP, EXPONENT_CLAMP);
        }
        lead.exponent = (self.exponent + shift).clamp(-2 * EXPONENT_CLAMP, 2 * EXPONENT_CLAMP);
        lead
    }
}

/// A decimal's first 19 significant digits: `(mantissa + remainder) · 10^exponent`, with
/// `0 ≤ remainder < 1` non-zero exactly when `sticky`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Decimal {
    mantissa: u64,
    exponent: i64,
    sticky: bool,
}

impl Decimal {
    fn new(w: &Written<'_>) -> Self {
        let mut mantissa = 0u64;
        let lead = w.leading(FAST_DIGITS, |v| mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(v)));
        Self { mantissa, exponent: lead.exponent, sticky: lead.sticky }
    }
}

/// What a field reads as.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Parsed<'a> {
    Number(Written<'a>),
    Infinity { negative: bool },
    NaN,
}

/// Reads the syntax of `str::parse::<f64>`; `None` for anything else.
fn scan(text: &str) -> Option<Parsed<'_>> {
    let bytes = text.as_bytes();
    let (negative, body) = match bytes.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, bytes),
    };
    if body.eq_ignore_ascii_case(b"inf") || body.eq_ignore_ascii_case(b"infinity") {
        return Some(Parsed::Infinity { negative });
    }
    if body.eq_ignore_ascii_case(b"nan") {
        return Some(Parsed::NaN);
    }
    let mut digits = 0usize;
    let mut point = false;
    let mut len = 0usize;
    for &b in body {
        match b {
            b'0'..=b'9' => digits += 1,
            b'.' if !point => point = true,
            _ => break,
        }
        len += 1;
    }
    if digits == 0 {
        return None;
    }
    let (mantissa, rest) = body.split_at_checked(len)?;
    let mut exponent = 0i64;
    if let Some((&e, tail)) = rest.split_first() {
        if e != b'e' && e != b'E' {
            return None;
        }
        let (sign, mut tail) = match tail.split_first() {
            Some((b'-', t)) => (-1, t),
            Some((b'+', t)) => (1, t),
            _ => (1, tail),
        };
        if tail.is_empty() {
            return None;
        }
        while let Some((&b, t)) = tail.split_first() {
            if !b.is_ascii_digit() {
                return None;
            }
            exponent = (exponent * 10 + i64::from(b - b'0')).min(EXPONENT_CLAMP);
            tail = t;
        }
        exponent *= sign;
    }
    Some(Parsed::Number(Written { negative, digits: mantissa, exponent }))
}

/// Powers of ten that `f64` holds exactly.
const EXACT_POWERS: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20,
    1e21, 1e22,
];

/// `10^k` for `0 ≤ k ≤ 22`, exact.
fn exact_power(k: i64) -> f64 {
    usize::try_from(k).ok().and_then(|k| EXACT_POWERS.get(k)).copied().unwrap_or(f64::NAN)
}

/// Clinger's fast path: `mantissa · 10^exponent` rounded once, when both factors are exact.
fn fast_f64(d: &Decimal) -> Option<f64> {
    const EXACT_INTEGER: u64 = 1 << 53;
    if d.sticky || d.mantissa > EXACT_INTEGER {
        return None;
    }
    let m = d.mantissa as f64;
    match d.exponent {
        0..=22 => Some(m * exact_power(d.exponent)),
        -22..=-1 => Some(m / exact_power(-d.exponent)),
        _ => None,
    }
}

/// `mantissa · 10^exponent` within a few units in the last place (no overflow inside the
/// range that matters: the caller settles the rounding exactly).
fn approximate(d: &Decimal) -> f64 {
    let mut v = d.mantissa as f64;
    let mut k = d.exponent.clamp(-400, 400);
    while k > 22 {
        v *= 1e22;
        k -= 22;
    }
    while k < -22 {
        v /= 1e22;
        k += 22;
    }
    if k >= 0 {
        v * exact_power(k)
    } else {
        v / exact_power(-k)
    }
}

/// A binary floating-point format: `p` bits of significand, the smallest subnormal `2^emin`.
#[derive(Debug, Clone, Copy)]
struct Format {
    p: u32,
    emin: i32,
}

const F64: Format = Format { p: 53, emin: -1074 };
const F32: Format = Format { p: 24, emin: -149 };

impl Format {
    /// The bit pattern of +∞.
    fn infinity(self) -> u64 {
        // All exponent bits set: 11 bits above 52 for f64, 8 above 23 for f32.
        let exponent_bits = if self.p == 53 { 11 } else { 8 };
        ((1u64 << exponent_bits) - 1) << (self.p - 1)
    }

    /// A non-negative float's value `M · 2^E` from its bit pattern (∞ reads as `2^(emax+1)`,
    /// the value rounding towards it starts from).
    fn value(self, bits: u64) -> (u64, i32) {
        let fraction = bits & ((1u64 << (self.p - 1)) - 1);
        let field = (bits >> (self.p - 1)) as i32;
        if field == 0 {
            (fraction, self.emin)
        } else {
            (fraction | (1u64 << (self.p - 1)), self.emin + field - 1)
        }
    }
}

/// Rounds `d` (non-negative part) to `format`, starting from the candidate bit pattern
/// `guess`: walks to the pair of neighbouring floats around the decimal, then takes the nearer
/// one (ties to even), every comparison exact.
fn round_exactly(w: &Written<'_>, format: Format, guess: u64) -> u64 {
    let infinity = format.infinity();
    let Some(x) = Exact::new(w) else { return guess.min(infinity) };
    let mut k = guess.min(infinity);
    // A guess within a few units in the last place takes a few steps; the bound only keeps a
    // wrong guess from looping.
    for _ in 0..64 {
        let (m, e) = format.value(k);
        // x against value(k) = 2m · 2^(e−1).
        if x.cmp(2 * m, e - 1) == Ordering::Less {
            if k == 0 {
                return 0;
            }
            k -= 1;
            continue;
        }
        if k == infinity {
            return infinity;
        }
        // x against value(k + 1) = (2m + 2) · 2^(e−1), across a binade boundary too.
        if x.cmp(2 * m + 2, e - 1) != Ordering::Less {
            k += 1;
            continue;
        }
        // value(k) ≤ x < value(k + 1): the midpoint decides.
        return match x.cmp(2 * m + 1, e - 1) {
            Ordering::Less => k,
            Ordering::Greater => k + 1,
            Ordering::Equal => k + (k & 1),
        };
    }
    k
}

/// Parses `text` as `f64`, correctly rounded (see the module doc); `None` if it is not a
/// number in `str::parse`'s syntax.
///
/// ```
/// use edgekf::decimal::parse_f64;
/// assert_eq!(parse_f64("0.30000000000000004"), Some(0.1 + 0.2));
/// assert_eq!(parse_f64("2.2250738585072011e-308"), "2.2250738585072011e-308".parse().ok());
/// assert_eq!(parse_f64("4e-324"), Some(5e-324));
/// assert_eq!(parse_f64("1e-400"), Some(0.0));
/// ```
pub fn parse_f64(text: &str) -> Option<f64> {
    let w = match scan(text)? {
        Parsed::NaN => return Some(f64::NAN),
        Parsed::Infinity { negative } => return Some(if negative { f64::NEG_INFINITY } else { f64::INFINITY }),
        Parsed::Number(w) => w,
    };
    let d = Decimal::new(&w);
    let magnitude = if d.mantissa == 0 {
        0.0
    } else if let Some(v) = fast_f64(&d) {
        v
    } else {
        f64::from_bits(round_exactly(&w, F64, approximate(&d).to_bits()))
    };
    Some(if w.negative { -magnitude } else { magnitude })
}

/// Parses `text` as `f32`, correctly rounded (see the module doc); `None` if it is not a
/// number in `str::parse`'s syntax.
///
/// ```
/// use edgekf::decimal::parse_f32;
/// assert_eq!(parse_f32("3.4028236e38"), Some(f32::INFINITY));
/// assert_eq!(parse_f32("1.00000005960464477539062"), "1.00000005960464477539062".parse().ok());
/// assert_eq!(parse_f32("-1e-46"), Some(-0.0));
/// ```
pub fn parse_f32(text: &str) -> Option<f32> {
    let w = match scan(text)? {
        Parsed::NaN => return Some(f32::NAN),
        Parsed::Infinity { negative } => return Some(if negative { f32::NEG_INFINITY } else { f32::INFINITY }),
        Parsed::Number(w) => w,
    };
    let d = Decimal::new(&w);
    let magnitude = if d.mantissa == 0 {
        0.0
    } else {
        match fast_f64(&d).filter(|&r| !on_f32_midpoint(r)) {
            // Rounding the correctly rounded `f64` again is exact off the midpoints.
            Some(r) => r as f32,
            None => {
                let guess = (approximate(&d) as f32).to_bits();
                f32::from_bits(round_exactly(&w, F32, u64::from(guess)) as u32)
            }
        }
    };
    Some(if w.negative { -magnitude } else { magnitude })
}

/// Whether a non-negative `f64` lies exactly halfway between two neighbouring `f32` values
/// (where rounding it again may differ from rounding the decimal once).
fn on_f32_midpoint(r: f64) -> bool {
    /// Halfway between `f32::MAX` and the next power of two, `2¹²⁸ − 2¹⁰³`: where `f32`
    /// rounding overflows.
    const OVERFLOW_MIDPOINT: f64 = 340_282_356_779_733_661_637_539_395_458_142_568_448.0;
    let near = r as f32;
    if near.is_infinite() {
        return r == OVERFLOW_MIDPOINT;
    }
    let gap = r - f64::from(near);
    if gap == 0.0 {
        return false;
    }
    let bits = near.to_bits();
    let other = if gap > 0.0 { bits.wrapping_add(1) } else { bits.wrapping_sub(1) };
    let other = f64::from(f32::from_bits(other));
    other - r == -gap
}

/// Limbs of [`Big`]: 56 × 32 = 1 792 bits. The largest comparison takes about 1 400 bits
/// (an `f32` midpoint against 5⁴⁵⁰, the largest power `Exact` takes).
const LIMBS: usize = 56;

/// An unsigned integer of fixed size, little-endian 32-bit limbs; an operation that would
/// overflow it sets `overflow` instead of wrapping silently.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Big {
    limbs: [u32; LIMBS],
    overflow: bool,
}

impl Big {
    fn from_u64(v: u64) -> Self {
        let mut limbs = [0u32; LIMBS];
        let [lo, hi, ..] = &mut limbs;
        *lo = v as u32;
        *hi = (v >> 32) as u32;
        Self { limbs, overflow: false }
    }

    fn add_small(&mut self, v: u32) {
        let mut carry = u64::from(v);
        for limb in &mut self.limbs {
            if carry == 0 {
                break;
            }
            let s = u64::from(*limb) + carry;
            *limb = s as u32;
            carry = s >> 32;
        }
        self.overflow |= carry != 0;
    }

    fn mul_small(&mut self, factor: u32) {
        let mut carry = 0u64;
        for limb in &mut self.limbs {
            let v = u64::from(*limb) * u64::from(factor) + carry;
            *limb = v as u32;
            carry = v >> 32;
        }
        self.overflow |= carry != 0;
    }

    /// Multiplies by `5^n`.
    fn mul_pow5(&mut self, mut n: u32) {
        /// `5^k` for `k < 14`: 5¹³ is the largest that fits 32 bits.
        const FIVES: [u32; 14] = [
            1,
            5,
            25,
            125,
            625,
            3_125,
            15_625,
            78_125,
            390_625,
            1_953_125,
            9_765_625,
            48_828_125,
            244_140_625,
            1_220_703_125,
        ];
        while n >= 13 {
            self.mul_small(1_220_703_125);
            n -= 13;
        }
        self.mul_small(FIVES.get(n as usize).copied().unwrap_or(1));
    }

    /// Multiplies by a 64-bit `v`: two 32-bit multiplications and a shifted add.
    fn mul_u64(&mut self, v: u64) {
        let mut high = *self;
        high.mul_small((v >> 32) as u32);
        high.shl(32);
        self.mul_small(v as u32);
        let mut carry = 0u64;
        for (a, b) in self.limbs.iter_mut().zip(high.limbs.iter()) {
            let s = u64::from(*a) + u64::from(*b) + carry;
            *a = s as u32;
            carry = s >> 32;
        }
        self.overflow |= high.overflow || carry != 0;
    }

    /// Multiplies by `2^n`.
    fn shl(&mut self, n: u32) {
        let (words, bits) = ((n / 32) as usize, n % 32);
        if words >= LIMBS {
            self.overflow |= self.limbs.iter().any(|&l| l != 0);
            self.limbs = [0; LIMBS];
            return;
        }
        let mut out = [0u32; LIMBS];
        let mut carry = 0u32;
        for (i, &limb) in self.limbs.iter().enumerate() {
            let wide = (u64::from(limb) << bits) | u64::from(carry);
            carry = if bits == 0 { 0 } else { (u64::from(limb) >> (32 - bits)) as u32 };
            match out.get_mut(i + words) {
                Some(slot) => *slot = wide as u32,
                None => self.overflow |= wide as u32 != 0,
            }
        }
        self.overflow |= carry != 0;
        self.limbs = out;
    }

    fn cmp(&self, other: &Self) -> Ordering {
        self.limbs.iter().rev().cmp(other.limbs.iter().rev())
    }
}

/// A decimal held exactly as `scaled · 2^twos`, with the powers of five of a negative exponent
/// kept aside to multiply the other side of each comparison.
struct Exact {
    scaled: Big,
    twos: i64,
    /// `5^(−exponent)` for a negative exponent, else 1.
    fives: Big,
    sticky: bool,
}

impl Exact {
    /// `None` if the decimal's exponent is far outside every float format (the caller's
    /// approximation is then already 0 or infinity).
    fn new(w: &Written<'_>) -> Option<Self> {
        let mut scaled = Big::from_u64(0);
        let lead = w.leading(EXACT_DIGITS, |v| {
            scaled.mul_small(10);
            scaled.add_small(u32::from(v));
        });
        if !(-450..=450).contains(&lead.exponent) {
            return None;
        }
        let n = lead.exponent.unsigned_abs() as u32;
        let mut fives = Big::from_u64(1);
        if lead.exponent >= 0 {
            scaled.mul_pow5(n);
        } else {
            fives.mul_pow5(n);
        }
        Some(Self { scaled, twos: lead.exponent, fives, sticky: lead.sticky })
    }

    /// The decimal against `num · 2^pow2` (a remainder beyond the kept digits makes an equal
    /// one greater).
    fn cmp(&self, num: u64, pow2: i32) -> Ordering {
        let mut left = self.scaled;
        let mut right = self.fives;
        right.mul_u64(num);
        let shift = self.twos - i64::from(pow2);
        if shift >= 0 {
            left.shl(u32::try_from(shift).unwrap_or(u32::MAX));
        } else {
            right.shl(u32::try_from(-shift).unwrap_or(u32::MAX));
        }
        let order = match (left.overflow, right.overflow) {
            (false, false) => left.cmp(&right),
            // Out of range: cannot happen within the clamp of `Exact::new`; an overflowed side
            // is taken as the larger.
            (true, false) => Ordering::Greater,
            (false, true) => Ordering::Less,
            (true, true) => Ordering::Equal,
        };
        if order == Ordering::Equal && self.sticky {
            Ordering::Greater
        } else {
            order
        }
    }
}

#[cfg(test)]
mod tests;
