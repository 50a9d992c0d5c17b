//! Two virtual ADXL355s fed from one CSV stream: each line's four channels split between the
//! parts (the first two the first part's x and y, the last two the second's), read back
//! through the real driver and [`PairSource`]. What the HIL images of a two-part node run.
//!
//! Each watermark period the source reads a period's lines and queues every line's halves in
//! the two parts' [`HalfFeed`]s, then lets the period pass on both parts. A line that does not
//! parse is a sample at which both parts repeat their last output (`stuck`): the source's
//! screening refuses it as frozen, so the node steps it as missing at its place and its clock
//! does not slip (counted in `Health::stuck`, once per part). A dropped sample would do the
//! same for the clock, but the FIFO has no time stamps and the source bridges a drop at the
//! end of its period, shifting the samples between by one. Before the first good line there is
//! no output to repeat: a bad line there is dropped (bridged at its period's end). The parts' `z` axes (along the shaft) read 0. The file's lines are the
//! samples in order: there are no time stamps to bridge missing lines by, as with a real part.
#![deny(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use crate::adxl355::{self, Adxl355, I2cInterface};
use crate::line_feed::{ByteSource, ChannelReader};
use crate::node::{Health, Recorded, SampleSource};
use crate::pair_source::PairSource;
use crate::source::{Adxl355Settings, Adxl355Source, AxisPair, MAX_BLOCK};
use crate::virtual_adxl355::{FeedSample, SampleFeed, VirtualAdxl355};
use heapless::Deque;

/// One part's share of the lines read so far this period.
#[derive(Debug, Default)]
pub struct HalfFeed(Deque<FeedSample, MAX_BLOCK>);

impl SampleFeed for HalfFeed {
    fn next_sample(&mut self) -> Option<FeedSample> {
        self.0.pop_front()
    }
}

/// One of the two parts.
pub type VirtualPart = Adxl355Source<I2cInterface<VirtualAdxl355<HalfFeed>>, AxisPair>;

/// Two virtual parts on the lines of `B` (see the module's docs).
pub struct VirtualPairSource<B: ByteSource> {
    reader: ChannelReader<B, 4>,
    pair: PairSource<VirtualPart, VirtualPart>,
    lines: u32,
    good_lines: u32,
}

/// Why a [`VirtualPairSource`] could not start: a part's initialisation failed (the virtual
/// parts only fail this way if their settings are invalid).
pub type PairStartError = adxl355::Error<crate::virtual_adxl355::VirtualBusError>;

impl<B: ByteSource> VirtualPairSource<B> {
    /// Starts both parts (at I²C address `0x1D`, each on its own bus) with `settings`; the
    /// lines come from `reader`, whose four channels are the first part's axes then the
    /// second's.
    pub fn start(
        reader: ChannelReader<B, 4>,
        settings: Adxl355Settings<AxisPair>,
        health: &mut Health,
    ) -> Result<Self, PairStartError> {
        let part = |health: &mut Health| {
            let sensor = Adxl355::new_i2c(VirtualAdxl355::new(HalfFeed::default()), 0x1D);
            VirtualPart::start(sensor, settings, health).map_err(|(e, _)| e)
        };
        let first = part(health)?;
        let second = part(health)?;
        Ok(Self { reader, pair: PairSource::new(first, second), lines: 0, good_lines: 0 })
    }

    /// The reader (its counters: bad lines, ignored columns).
    pub fn reader(&self) -> &ChannelReader<B, 4> {
        &self.reader
    }

    /// Lines read so far (good and bad).
    pub fn lines(&self) -> u32 {
        self.lines
    }

    /// The two parts.
    pub fn pair(&self) -> &PairSource<VirtualPart, VirtualPart> {
        &self.pair
    }

    /// Queues `a` for the first part and `b` for the second.
    fn queue(&mut self, a: FeedSample, b: FeedSample) {
        // A period is at most MAX_BLOCK samples and the parts take every queued sample each
        // period, so the queues have room; a sample that found none would be lost to its
        // part, which the FIFO timing then bridges.
        let _ = feed(self.pair.first_mut()).0.push_back(a);
        let _ = feed(self.pair.second_mut()).0.push_back(b);
    }
}

/// A part's feed.
fn feed(part: &mut VirtualPart) -> &mut HalfFeed {
    part.sensor_mut().interface_mut().bus_mut().feed_mut()
}

impl<B: ByteSource> SampleSource for VirtualPairSource<B> {
    type Sample = [f32; 4];

    fn read(&mut self, health: &mut Health, each: impl FnMut(Option<[f32; 4]>)) -> u16 {
        self.pair.read(health, each)
    }
}

impl<B: ByteSource> Recorded for VirtualPairSource<B> {
    /// Reads one period's lines into the parts' feeds, then lets the period pass on both.
    fn advance(&mut self) -> bool {
        let period = self.pair.first().sensor().interface().bus().period_samples();
        for _ in 0..period {
            let Some(line) = self.reader.next_values() else { break };
            self.lines = self.lines.saturating_add(1);
            match line {
                Ok([ax, ay, bx, by]) => {
                    self.good_lines = self.good_lines.saturating_add(1);
                    self.queue(FeedSample::new([ax, ay, 0.0]), FeedSample::new([bx, by, 0.0]));
                }
                Err(_) => {
                    let first = self.good_lines == 0;
                    let bad = FeedSample { stuck: !first, dropped: first, ..FeedSample::default() };
                    self.queue(bad, bad);
                }
            }
        }
        self.pair.advance()
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use super::*;
    use crate::source::Axis;
    use std::string::String;
    use std::vec::Vec;

    /// 40 lines (two and a half periods), line 20 garbage: 40 samples, each the four channels
    /// of its line quantised to the part's LSB, the garbage line's missing at its place,
    /// counted as frozen by both parts; the short last period is not due.
    #[test]
    fn one_line_feeds_both_parts() {
        let value = |k: usize, i: usize| 0.01 * k as f32 * (i as f32 + 1.0) - 0.1 * i as f32;
        let mut csv = String::from("t,truth,p_x,p_y,q_x,q_y\n");
        for k in 0..40 {
            if k == 20 {
                csv.push_str("0.020,0,oops,0,0,0\n");
            } else {
                let v: Vec<String> = (0..4).map(|i| std::format!("{}", value(k, i))).collect();
                csv.push_str(&std::format!("{},1,{}\n", k as f64 * 1e-3, v.join(",")));
            }
        }
        let reader = ChannelReader::new(csv.as_bytes(), ["p_x", "p_y", "q_x", "q_y"]).unwrap();
        let mut health = Health::default();
        let settings = Adxl355Settings::default().with_axes(AxisPair(Axis::X, Axis::Y));
        let mut source = VirtualPairSource::start(reader, settings, &mut health).unwrap();
        let mut got = Vec::new();
        while source.advance() {
            source.read(&mut health, |s| got.push(s));
        }
        assert_eq!((got.len(), source.lines(), source.reader().bad_lines()), (40, 40, 1));
        let lsb = 9.80665f32 / 256_000.0;
        for (k, s) in got.iter().enumerate() {
            if k == 20 {
                assert_eq!(*s, None);
                continue;
            }
            let s = s.unwrap();
            for i in 0..4 {
                assert!((s[i] - value(k, i)).abs() <= 0.5 * lsb * 1.001, "sample {k} channel {i}: {s:?}");
            }
        }
        assert_eq!((health.stuck, health.dropped, health.bus_errors), (2, 0, 0), "one sample of each part");
        assert_eq!(source.pair().waiting(), [0, 0]);
    }
}
