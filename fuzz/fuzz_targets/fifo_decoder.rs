//! The ADXL355 FIFO burst decoder on arbitrary bytes: whole samples in range, every entry either
//! delivered or counted as skipped, never a panic.
#![no_main]

use edgekf_firmware::adxl355::{decode_fifo, decode_xyz, RawSample, RAW_MAX, RAW_MIN};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    // First byte: the room in the output (0..=63 samples); the rest is the burst.
    let (&room, burst) = bytes.split_first().unwrap_or((&0, &[]));
    let mut out = vec![RawSample::default(); usize::from(room % 64)];
    let read = decode_fifo(burst, &mut out);
    assert!(read.samples <= out.len());
    let in_range = |s: &RawSample| [s.x, s.y, s.z].iter().all(|c| (RAW_MIN..=RAW_MAX).contains(c));
    assert!(out[..read.samples].iter().all(in_range));
    let entries = burst.len() / 3;
    let accounted = 3 * read.samples + usize::from(read.skipped_entries);
    if usize::from(read.skipped_entries) < usize::from(u8::MAX) {
        assert_eq!(accounted, entries, "every entry is delivered or counted");
    } else {
        assert!(3 * read.samples + 255 <= entries);
    }
    if let Some(xyz) = burst.first_chunk::<9>() {
        assert!(in_range(&decode_xyz(xyz)));
    }
});
