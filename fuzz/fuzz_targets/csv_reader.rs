//! The host's CSV data reader on arbitrary bytes: it refuses or accepts, never panics; what it
//! accepts keeps the contract (one value per row and channel, strictly increasing finite `t`),
//! its report formats, its gaps bridge within bounds, and the writer gives back a file that
//! reads to the same bits.
#![no_main]

use edgekf_sim::io::data::{read_from, to_csv_string};
use edgekf_sim::io::timeline::{bridge, TimelineOptions, MAX_FILL};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

/// Channels a caller might know; anything else in a header is ignored or `truth_`.
const KNOWN: [&str; 4] = ["ax", "ay", "az", "n5_x"];

fuzz_target!(|bytes: &[u8]| {
    let path = Path::new("fuzz.csv");
    let Ok((data, report)) = read_from(bytes, path, &KNOWN) else { return };
    assert!(data.t.len() >= 2);
    assert!(data.t.iter().all(|t| t.is_finite()));
    assert!(data.t.windows(2).all(|w| w[0] < w[1]));
    assert_eq!(data.names.len(), data.columns.len());
    assert!(data.columns.iter().all(|c| c.len() == data.t.len()));
    let _ = report.to_string();
    // The timeline every estimator reads: gaps filled with empty rows or marked as restarts,
    // never more rows than the file and `MAX_FILL` allow per gap.
    let (bridged, what) = bridge(&data, &report.timing, &TimelineOptions::default());
    assert_eq!(bridged.t.len(), data.t.len() + what.inserted);
    assert!(what.inserted <= report.timing.gaps.len() * data.t.len().max(MAX_FILL));

    let names: Vec<&str> = data.names.iter().map(String::as_str).collect();
    let columns: Vec<&[f64]> = data.columns.iter().map(Vec::as_slice).collect();
    let text = to_csv_string(path, &names, &data.t, &columns).expect("lengths match");
    let (back, _) = read_from(text.as_bytes(), path, &KNOWN).expect("the writer's output reads back");
    assert_eq!(back.names, data.names);
    let bits = |v: &[f64]| v.iter().map(|x| if x.is_nan() { u64::MAX } else { x.to_bits() }).collect::<Vec<_>>();
    assert_eq!(bits(&back.t), bits(&data.t));
    for (b, d) in back.columns.iter().zip(&data.columns) {
        assert_eq!(bits(b), bits(d));
    }
});
