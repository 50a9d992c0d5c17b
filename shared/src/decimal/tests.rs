//! The parser against `core`'s (the oracle): every kind of input, bit for bit.

extern crate std;
use super::*;
use proptest::prelude::*;
use std::format;
use std::string::String;

/// `same_f64` and `same_f32`: the parser and `core` both refuse `s`, or give the same bits.
macro_rules! same_as_core {
    ($name:ident, $parse:ident, $ty:ty) => {
        fn $name(s: &str) {
            match ($parse(s), s.parse::<$ty>().ok()) {
                (Some(a), Some(b)) => {
                    assert!(a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()), "{s}: {a:e} vs {b:e}")
                }
                (a, b) => assert_eq!(a.is_some(), b.is_some(), "{s}: {a:?} vs {b:?}"),
            }
        }
    };
}
same_as_core!(same_f64, parse_f64, f64);
same_as_core!(same_f32, parse_f32, f32);

/// A deterministic 64-bit generator (SplitMix64).
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

#[test]
fn syntax_is_cores() {
    for s in [
        "",
        ".",
        "+",
        "-",
        "1.",
        ".5",
        "+.5",
        "-.5e-3",
        "1e",
        "1e+",
        "1e-",
        "e1",
        "E1",
        "1.2.3",
        "1..2",
        "inf",
        "-Infinity",
        "+INF",
        "infinit",
        "nan",
        "NaN",
        "-nan",
        "+nan",
        "nana",
        "0x10",
        "1_0",
        " 1",
        "1 ",
        "1,5",
        "1e5.0",
        "1e+05",
        "1E-0",
        "00001",
        "-0",
        "+0.000",
        "0e999999999999",
        "1e99999999999",
        "1e-99999999999",
        "١",
        "1e٣",
        "--1",
        "+-1",
        "1f",
        "12345678901234567890123456789",
        "0.000000000000000000000000000001234",
    ] {
        same_f64(s);
        same_f32(s);
    }
}

#[test]
fn every_shortest_and_scientific_form_of_random_floats_reads_back_as_core_does() {
    let mut rng = SplitMix(7);
    for _ in 0..100_000 {
        let bits = rng.next();
        let f = f32::from_bits(bits as u32);
        let d = f64::from_bits(bits);
        for s in [format!("{f}"), format!("{f:e}"), format!("{f:.3e}"), format!("{:.9}", f), format!("{:.12e}", f)] {
            same_f32(&s);
            same_f64(&s);
        }
        for s in [format!("{d}"), format!("{d:e}"), format!("{d:.5e}"), format!("{d:.16e}")] {
            same_f64(&s);
            same_f32(&s);
        }
    }
}

#[test]
fn random_decimals_of_up_to_19_digits_at_every_exponent_agree_with_core() {
    let mut rng = SplitMix(11);
    for _ in 0..200_000 {
        let digits = 1 + rng.next() % 19;
        let mantissa = rng.next() % 10u64.pow(digits as u32);
        let exponent = (rng.next() % 760) as i64 - 380;
        let s = format!("{mantissa}e{exponent}");
        same_f64(&s);
        let small = format!("{mantissa}e{}", exponent / 8);
        same_f32(&small);
    }
}

#[test]
fn midpoints_tie_to_even_and_a_digit_beyond_breaks_the_tie() {
    // Between 2^53 and 2^53 + 2, between 2^24 and 2^24 + 2: the tie goes to the even one.
    for (s, want) in [
        ("9007199254740993", 9007199254740992.0),
        ("9007199254740995", 9007199254740996.0),
        ("9007199254740993.0000001", 9007199254740994.0),
        ("9007199254740992.9999999", 9007199254740992.0),
    ] {
        assert_eq!(parse_f64(s), Some(want), "{s}");
        same_f64(s);
    }
    for (s, want) in [("16777217", 16777216.0f32), ("16777219", 16777220.0), ("16777217.00001", 16777218.0)] {
        assert_eq!(parse_f32(s), Some(want), "{s}");
        same_f32(s);
    }
    // Every f32 midpoint between odd integers' neighbours in [2^24, 2^31), and just off it.
    let mut rng = SplitMix(3);
    for _ in 0..50_000 {
        let f = (16_777_216 + rng.next() % 2_130_706_432) as f32;
        let next = f32::from_bits(f.to_bits() + 1);
        let mid = (f64::from(f) + f64::from(next)) / 2.0;
        for s in [format!("{mid}"), format!("{mid}.000000001"), format!("{}.999999999", mid - 1.0)] {
            same_f32(&s);
        }
    }
}

#[test]
fn the_f64_fast_path_landing_on_an_f32_midpoint_is_settled_exactly() {
    // 1 + 2^-24 is an f32 midpoint; a decimal a hair above it rounds (once) to the f64 midpoint.
    let above = "1.0000000596046448";
    assert_eq!(parse_f64(above), Some(1.0 + 2f64.powi(-24)));
    same_f32(above);
    assert_eq!(parse_f32(above), Some(1.0 + f32::EPSILON));
    let below = "1.0000000596046447";
    same_f32(below);
    // The overflow threshold of f32 and the smallest subnormals.
    for s in [
        "3.4028235677973366e38",
        "3.40282356779733661637e38",
        "3.4028235e38",
        "1.401298464324817e-45",
        "7e-46",
        "7.1e-46",
    ] {
        same_f32(s);
    }
    for s in [
        "4.9406564584124654e-324",
        "2.4703282292062327e-324",
        "2.4703282292062328e-324",
        "1.7976931348623157e308",
        "1.7976931348623158e308",
        "1.797693134862315807e308",
    ] {
        same_f64(s);
    }
}

#[test]
fn inputs_of_20_to_40_digits_agree_with_core() {
    let mut rng = SplitMix(5);
    let mut differ = 0;
    for _ in 0..50_000 {
        let mut s = String::new();
        for _ in 0..(20 + rng.next() % 21) {
            s.push(char::from(b'0' + (rng.next() % 10) as u8));
        }
        s.insert(1 + (rng.next() % 10) as usize, '.');
        let s = format!("{s}e{}", (rng.next() % 80) as i64 - 40);
        let (a, b) = (parse_f64(&s), s.parse::<f64>().ok());
        if a.map(f64::to_bits) != b.map(f64::to_bits) {
            differ += 1;
        }
        same_f32(&s);
    }
    assert_eq!(differ, 0);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(20_000))]

    #[test]
    fn anything_in_the_syntax_agrees_with_core(s in "[-+]?[0-9]{0,20}(\\.[0-9]{0,20})?([eE][-+]?[0-9]{1,3})?") {
        same_f64(&s);
        same_f32(&s);
    }

    #[test]
    fn arbitrary_text_never_panics_and_is_refused_when_core_refuses(s in "\\PC{0,30}") {
        prop_assert_eq!(parse_f64(&s).is_some(), s.parse::<f64>().is_ok());
        prop_assert_eq!(parse_f32(&s).is_some(), s.parse::<f32>().is_ok());
    }
}
