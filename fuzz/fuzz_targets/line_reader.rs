//! The firmware's CSV line readers (`ChannelReader` for named channels, `LineFeed` for the
//! virtual ADXL355) on arbitrary bytes, delivered in chunks of arbitrary sizes as semihosting
//! does: lines are values or counted bad lines, never a panic. Every field also goes through
//! the node's number parser (`edgekf::decimal`) beside `core`'s, which must agree bit for bit.
#![no_main]

use edgekf_firmware::line_feed::{ByteSource, ChannelReader, LineFeed};
use edgekf_firmware::virtual_adxl355::SampleFeed;
use libfuzzer_sys::fuzz_target;

/// The node's parser and `core`'s read `field` alike: both refuse it, or give the same bits
/// (any NaN for a NaN).
fn same_number(field: &str) {
    let same64 = match (edgekf::decimal::parse_f64(field), field.parse::<f64>().ok()) {
        (Some(a), Some(b)) => a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
        (a, b) => a.is_none() && b.is_none(),
    };
    let same32 = match (edgekf::decimal::parse_f32(field), field.parse::<f32>().ok()) {
        (Some(a), Some(b)) => a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
        (a, b) => a.is_none() && b.is_none(),
    };
    assert!(same64 && same32, "{field:?}");
}

/// Bytes in chunks whose sizes cycle through `sizes` (0 = as many as asked for).
struct Chunked<'a> {
    data: &'a [u8],
    sizes: &'a [u8],
    k: usize,
}

impl ByteSource for Chunked<'_> {
    fn read_bytes(&mut self, buf: &mut [u8]) -> usize {
        let size = match self.sizes.get(self.k % self.sizes.len().max(1)) {
            Some(&s) if s > 0 => usize::from(s),
            _ => buf.len(),
        };
        self.k += 1;
        let n = size.min(buf.len()).min(self.data.len());
        buf[..n].copy_from_slice(&self.data[..n]);
        self.data = &self.data[n..];
        n
    }
}

fuzz_target!(|bytes: &[u8]| {
    // First byte: how many chunk sizes follow; then the sizes; the rest is the file.
    let (&n, rest) = bytes.split_first().unwrap_or((&0, &[]));
    let (sizes, data) = rest.split_at(usize::from(n % 8).min(rest.len()));
    let source = || Chunked { data, sizes, k: 0 };
    if let Ok(text) = core::str::from_utf8(data) {
        text.split(['\n', ',']).for_each(same_number);
    }

    if let Ok(mut r) = ChannelReader::new(source(), ["t", "n5_x"]) {
        let mut lines = 0u32;
        while let Some(line) = r.next_values() {
            if let Ok(values) = line {
                assert!(values.iter().all(|v| v.is_finite()));
            }
            lines += 1;
        }
        assert!(r.bad_lines() <= lines);
    }
    if let Ok(mut r) = ChannelReader::new(source(), ["ax"]) {
        while r.next_values().is_some() {}
    }
    if let Ok(mut feed) = LineFeed::new(source()) {
        while feed.next_sample().is_some() {}
        assert!(feed.bad_lines() <= feed.lines());
    }
});
