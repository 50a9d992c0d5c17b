//! Exact order statistics of non-negative floats without reordering them: a most-significant-
//! byte-first radix select over the bit patterns.
//!
//! Why not quickselect: the window's `|Δα|` must stay in time order for the impact pass that
//! follows the median (the threshold is 6 × the median), and a second buffer for a copy would
//! double the chip's largest allocation (10 KB in `f32` at 10 kHz). Counting 8-bit digits of the
//! bit pattern, one digit per pass, finds the same element in place with a 256-entry histogram
//! on the stack: 4 passes in `f32`, 8 in `f64`.

use super::ClearanceFloat;

/// The `rank`-th smallest (from 0) of `values`, which must be non-negative and not NaN (the
/// absolute differences of finite samples are); `values` is not reordered. `None` if `rank` is
/// out of range.
///
/// ```
/// use edgekf::systems::crank::select_nth;
/// let v = [3.0f32, 0.5, 7.0, 0.5, 2.0];
/// assert_eq!(select_nth(&v, 2), Some(2.0)); // the median
/// assert_eq!(select_nth(&v, 1), Some(0.5));
/// assert_eq!(v, [3.0, 0.5, 7.0, 0.5, 2.0]); // untouched
/// assert_eq!(select_nth(&v, 5), None);
/// ```
pub fn select_nth<T: ClearanceFloat>(values: &[T], rank: usize) -> Option<T> {
    if rank >= values.len() {
        return None;
    }
    let mut rank = rank;
    let zero = T::Key::from(0u8);
    let byte_mask = T::Key::from(0xffu8);
    let (mut prefix, mut mask) = (zero, zero);
    for byte in (0..T::KEY_BYTES).rev() {
        let shift = 8 * byte;
        let mut hist = [0usize; 256];
        for v in values {
            let key = v.key();
            if key & mask == prefix {
                let d = ((key >> shift) & byte_mask).into() as usize & 0xff;
                hist[d] = hist[d].wrapping_add(1);
            }
        }
        // The digit whose bucket holds the rank-th of the candidates left.
        let mut digit = 0u8;
        for &count in &hist {
            if rank < count {
                break;
            }
            rank -= count;
            digit = digit.wrapping_add(1);
        }
        prefix = prefix | (T::Key::from(digit) << shift);
        mask = mask | (byte_mask << shift);
    }
    Some(T::of_key(prefix))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against sorting, on values with many ties and a wide range of exponents.
    #[test]
    fn agrees_with_sorting() {
        let mut s = 12345u64;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for len in [1usize, 2, 3, 17, 256, 999] {
            let mut v = [0.0f64; 999];
            for x in v.iter_mut().take(len) {
                let u = next();
                // Ties: a quarter of the values from a set of 8.
                *x = if u < 0.25 { (u * 32.0).floor() } else { (u * 40.0 - 20.0).exp() };
            }
            let v = &v[..len];
            let mut sorted = [0.0f64; 999];
            sorted[..len].copy_from_slice(v);
            sorted[..len].sort_by(f64::total_cmp);
            let v32: [f32; 999] = core::array::from_fn(|i| v.get(i).copied().unwrap_or(0.0) as f32);
            let mut s32 = v32;
            s32[..len].sort_by(f32::total_cmp);
            for rank in 0..len {
                assert_eq!(select_nth(v, rank), Some(sorted[rank]), "len {len} rank {rank}");
                assert_eq!(select_nth(&v32[..len], rank), Some(s32[rank]), "f32 len {len} rank {rank}");
            }
        }
    }
}
