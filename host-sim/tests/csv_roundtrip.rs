//! Property: the CSV writer and reader are inverses. Any names, strictly increasing finite times
//! and finite-or-NaN values written by `to_csv_string` read back through `read_from` with the
//! same names and the same bits; a NaN cell reads back as NaN, written as `NaN` or left empty.

use edgekf_sim::io::data::{read_from, to_csv_string, TRUTH_PREFIX};
use proptest::num::f64::{NEGATIVE, NORMAL, POSITIVE, SUBNORMAL, ZERO};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use std::path::Path;

/// Finite values of every kind (normal, subnormal, ±0), large and small.
fn finite() -> impl Strategy<Value = f64> {
    POSITIVE | NEGATIVE | NORMAL | SUBNORMAL | ZERO
}

/// A channel value: finite, or NaN for a missing sample.
fn cell() -> impl Strategy<Value = f64> {
    prop_oneof![8 => finite(), 1 => Just(f64::NAN)]
}

/// Distinct channel names; some are `truth_` columns, which the reader keeps unasked.
fn names() -> impl Strategy<Value = Vec<String>> {
    prop::collection::btree_set(("[a-z][a-z0-9_]{0,7}", any::<bool>()), 0..6).prop_map(|set| {
        let mut names: Vec<String> = Vec::new();
        for (name, truth) in set {
            let name = if truth { format!("{TRUTH_PREFIX}{name}") } else { name };
            if name != "t" && !names.contains(&name) {
                names.push(name);
            }
        }
        names
    })
}

/// At least two strictly increasing finite times.
fn times() -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(finite(), 2..40)
        .prop_map(|mut t| {
            t.sort_by(f64::total_cmp);
            t.dedup_by(|a, b| a == b); // -0 and 0 are one time
            t
        })
        .prop_filter("two distinct times", |t| t.len() >= 2)
}

fn file() -> impl Strategy<Value = (Vec<String>, Vec<f64>, Vec<Vec<f64>>)> {
    (names(), times()).prop_flat_map(|(names, t)| {
        let columns = prop::collection::vec(prop::collection::vec(cell(), t.len()), names.len());
        (Just(names), Just(t), columns)
    })
}

/// Bits, with every NaN the same.
fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| if x.is_nan() { f64::NAN.to_bits() } else { x.to_bits() }).collect()
}

proptest! {
    #![proptest_config(Config { cases: 512, rng_seed: RngSeed::Fixed(0xC5F), failure_persistence: None, ..Config::default() })]

    #[test]
    fn written_files_read_back_bit_for_bit((names, t, columns) in file()) {
        let path = Path::new("roundtrip.csv");
        let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
        let col_refs: Vec<&[f64]> = columns.iter().map(Vec::as_slice).collect();
        let known: Vec<&str> = name_refs.iter().copied().filter(|n| !n.starts_with(TRUTH_PREFIX)).collect();
        let text = to_csv_string(path, &name_refs, &t, &col_refs).unwrap();

        // NaN written as `NaN`, and the same file with every NaN cell left empty.
        let emptied = text.replace(",NaN", ",");
        for text in [&text, &emptied] {
            let (back, report) = read_from(text.as_bytes(), path, &known).unwrap();
            prop_assert_eq!(&back.names, &names);
            prop_assert_eq!(bits(&back.t), bits(&t));
            prop_assert_eq!(back.columns.len(), columns.len());
            for (b, c) in back.columns.iter().zip(&columns) {
                prop_assert_eq!(bits(b), bits(c));
            }
            prop_assert!(report.ignored_columns.is_empty());
            let nans: usize = columns.iter().flatten().filter(|v| v.is_nan()).count();
            prop_assert_eq!(report.nan_cells.iter().map(|(_, n)| n).sum::<usize>(), nans);
        }
    }
}
