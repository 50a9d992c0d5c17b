//! Two two-axis sources in lockstep: one sample of four channels (the first part's two axes,
//! then the second's) per sample period, e.g. two ADXL355s at two bearing housings, or x and y
//! of one housing from two parts.
//!
//! Each part keeps its own timing contract ([`crate::source::Adxl355Source`]): over time it
//! hands out exactly one sample (or `None`) per period due, but a poll can deliver a different
//! number from each (one part's poll failed and its samples come at the next). The pair pairs
//! the `k`-th sample of one with the `k`-th of the other and holds the part that is ahead in a
//! queue of [`PAIR_QUEUE`] samples; a pair is missing (`None`) if either half is. When a queue
//! is full (the other part has delivered nothing for that long) its oldest sample leaves as a
//! missing pair, and the other part's sample for that period, when it comes, is skipped: the
//! clock never slips. Both parts count their events in the node's one [`Health`].
#![deny(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use crate::node::{Health, Recorded, SampleSource};

/// Samples one part may be ahead of the other: four 16-sample periods.
pub const PAIR_QUEUE: usize = 64;

/// One part's samples waiting for the other's, and the samples it owes (skipped on arrival).
struct Lane {
    queue: [Option<[f32; 2]>; PAIR_QUEUE],
    head: usize,
    len: usize,
    /// Samples of this part whose period has already left as a missing pair.
    owed: u32,
}

impl Lane {
    const fn new() -> Self {
        Self { queue: [None; PAIR_QUEUE], head: 0, len: 0, owed: 0 }
    }

    fn pop(&mut self) -> Option<Option<[f32; 2]>> {
        if self.len == 0 {
            return None;
        }
        let s = self.queue.get(self.head).copied().flatten();
        self.head = (self.head + 1) % PAIR_QUEUE;
        self.len -= 1;
        Some(s)
    }

    /// Queues `s` if there is room; `false` if the queue is full.
    fn push(&mut self, s: Option<[f32; 2]>) -> bool {
        if self.len >= PAIR_QUEUE {
            return false;
        }
        if let Some(slot) = self.queue.get_mut((self.head + self.len) % PAIR_QUEUE) {
            *slot = s;
        }
        self.len += 1;
        true
    }
}

/// The four channels of `a`'s and `b`'s halves, missing if either is.
fn join(a: Option<[f32; 2]>, b: Option<[f32; 2]>) -> Option<[f32; 4]> {
    let ([a0, a1], [b0, b1]) = (a?, b?);
    Some([a0, a1, b0, b1])
}

/// One sample `s` of the part whose lane is `own`: paired with the other part's oldest waiting
/// sample, else queued (the oldest queued leaving as a missing pair if the queue is full).
fn arrive(
    own: &mut Lane,
    other: &mut Lane,
    s: Option<[f32; 2]>,
    own_first: bool,
    each: &mut impl FnMut(Option<[f32; 4]>),
) {
    if own.owed > 0 {
        own.owed -= 1;
        return;
    }
    if let Some(o) = other.pop() {
        each(if own_first { join(s, o) } else { join(o, s) });
        return;
    }
    if !own.push(s) {
        let _ = own.pop();
        let _ = own.push(s);
        other.owed = other.owed.saturating_add(1);
        each(None);
    }
}

/// Two sources of two axes each, read in lockstep as one source of four channels (see the
/// module's docs).
///
/// ```
/// use edgekf_firmware::node::{Health, SampleSource};
/// use edgekf_firmware::pair_source::PairSource;
/// /// Hands out `n` samples of `[v, v]` a read.
/// struct Fake(u16, f32);
/// impl SampleSource for Fake {
///     type Sample = [f32; 2];
///     fn read(&mut self, _: &mut Health, mut each: impl FnMut(Option<[f32; 2]>)) -> u16 {
///         (0..self.0).for_each(|_| each(Some([self.1; 2])));
///         self.0
///     }
/// }
/// let mut pair = PairSource::new(Fake(2, 1.0), Fake(2, 2.0));
/// let mut got = Vec::new();
/// pair.read(&mut Health::default(), |s| got.push(s));
/// assert_eq!(got, [Some([1.0, 1.0, 2.0, 2.0]); 2]);
/// ```
pub struct PairSource<S1, S2> {
    first: S1,
    second: S2,
    lanes: [Lane; 2],
}

impl<S1, S2> PairSource<S1, S2> {
    /// The pair of `first` (channels 0, 1) and `second` (channels 2, 3).
    pub fn new(first: S1, second: S2) -> Self {
        Self { first, second, lanes: [Lane::new(), Lane::new()] }
    }

    /// The first part's source.
    pub fn first(&self) -> &S1 {
        &self.first
    }

    /// The second part's source.
    pub fn second(&self) -> &S2 {
        &self.second
    }

    /// The first part's source, mutably.
    pub fn first_mut(&mut self) -> &mut S1 {
        &mut self.first
    }

    /// The second part's source, mutably.
    pub fn second_mut(&mut self) -> &mut S2 {
        &mut self.second
    }

    /// Samples waiting for the other part: the first's, the second's.
    pub fn waiting(&self) -> [usize; 2] {
        let [a, b] = &self.lanes;
        [a.len, b.len]
    }
}

impl<S1, S2> SampleSource for PairSource<S1, S2>
where
    S1: SampleSource<Sample = [f32; 2]>,
    S2: SampleSource<Sample = [f32; 2]>,
{
    type Sample = [f32; 4];

    /// Reads the first part, then the second; returns the larger of their counts read.
    fn read(&mut self, health: &mut Health, mut each: impl FnMut(Option<[f32; 4]>)) -> u16 {
        let [a, b] = &mut self.lanes;
        let n1 = self.first.read(health, |s| arrive(a, b, s, true, &mut each));
        let n2 = self.second.read(health, |s| arrive(b, a, s, false, &mut each));
        n1.max(n2)
    }
}

impl<S1: Recorded, S2: Recorded> Recorded for PairSource<S1, S2> {
    /// Both parts' periods pass; the pair has run out when both have.
    fn advance(&mut self) -> bool {
        let a = self.first.advance();
        let b = self.second.advance();
        a || b
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use super::*;
    use std::vec::Vec;

    /// Hands out the scripted counts of samples, one script entry per read, numbered on.
    struct Script {
        counts: Vec<u16>,
        next: f32,
        tag: f32,
    }

    impl SampleSource for Script {
        type Sample = [f32; 2];
        fn read(&mut self, _: &mut Health, mut each: impl FnMut(Option<[f32; 2]>)) -> u16 {
            let n = if self.counts.is_empty() { 0 } else { self.counts.remove(0) };
            for _ in 0..n {
                each(Some([self.next, self.tag]));
                self.next += 1.0;
            }
            n
        }
    }

    fn run(a: &[u16], b: &[u16]) -> Vec<Option<[f32; 4]>> {
        let mut pair = PairSource::new(
            Script { counts: a.to_vec(), next: 0.0, tag: 1.0 },
            Script { counts: b.to_vec(), next: 0.0, tag: 2.0 },
        );
        let mut got = Vec::new();
        for _ in 0..a.len().max(b.len()) {
            pair.read(&mut Health::default(), |s| got.push(s));
        }
        got
    }

    /// Two ADXL355s through the real driver, x and y of each: the second part's first poll
    /// is NACKed on every attempt, so its samples come a period late, and pair with the
    /// first part's samples of the same periods. Every bus transaction is checked.
    #[test]
    fn two_adxl355s_through_the_driver_in_lockstep() {
        use crate::adxl355::{encode_axis, Adxl355};
        use crate::source::tests::{init_traffic, ADDR};
        use crate::source::{Adxl355Settings, Adxl355Source, Axis, AxisPair};
        use embedded_hal::i2c::{ErrorKind, NoAcknowledgeSource};
        use embedded_hal_mock::eh1::i2c::{Mock, Transaction};
        use std::vec;

        // Part `p`'s sample `k`: x = (p + 1)·1000·k codes, y = 7·p − k, z = 1 g.
        let code = |p: i32, k: i32| [((p + 1) * 1000 * k, 1), (7 * p - k, 0), (256_000, 0)];
        let fifo = |p: i32, ks: core::ops::Range<i32>| -> Vec<u8> {
            ks.flat_map(|k| code(p, k)).flat_map(|(c, f)| encode_axis(c, f)).collect()
        };
        let status =
            |entries: u8| Transaction::write_read(ADDR, vec![0x00], vec![0xAD, 0x1D, 0xED, 0x01, 0b11, entries]);
        let mut first = init_traffic();
        first.extend([status(48), Transaction::write_read(ADDR, vec![0x11], fifo(0, 0..16))]);
        first.extend([status(48), Transaction::write_read(ADDR, vec![0x11], fifo(0, 16..32))]);
        let nack = ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address);
        let mut second = init_traffic();
        second.extend((0..4).map(|_| Transaction::write_read(ADDR, vec![0x00], vec![0; 6]).with_error(nack)));
        second.extend([status(96), Transaction::write_read(ADDR, vec![0x11], fifo(1, 0..32))]);

        let mut health = Health::default();
        let settings = Adxl355Settings::default().with_axes(AxisPair(Axis::X, Axis::Y));
        let start = |traffic: &[Transaction], health: &mut Health| {
            Adxl355Source::start(Adxl355::new_i2c(Mock::new(traffic), ADDR), settings, health)
                .map_err(|(e, _)| e)
                .unwrap()
        };
        let (a, b) = (start(&first, &mut health), start(&second, &mut health));
        let mut pair = PairSource::new(a, b);
        let mut got = Vec::new();
        assert_eq!(pair.read(&mut health, |s| got.push(s)), 16);
        assert_eq!((got.len(), pair.waiting()), (0, [16, 0]), "the first part's samples wait");
        assert_eq!(pair.read(&mut health, |s| got.push(s)), 32);
        assert_eq!((got.len(), pair.waiting()), (32, [0, 0]));
        let lsb = 9.80665f32 / 256_000.0;
        for (k, s) in got.iter().enumerate() {
            let (k, s) = (k as i32, s.unwrap());
            let codes = s.map(|v| (v / lsb).round() as i32);
            assert_eq!(codes, [1000 * k, -k, 2000 * k, 7 - k], "sample {k}");
        }
        assert_eq!(health, Health { bus_errors: 4, nacks: 4, failed_polls: 1, ..Health::default() });
        pair.first_mut().sensor_mut().interface_mut().bus_mut().done();
        pair.second_mut().sensor_mut().interface_mut().bus_mut().done();
    }

    /// Two virtual ADXL355s (x and y of a bearing housing, or two housings) through the
    /// driver, the second dropping its third period: the pairs carry both parts' quantised
    /// samples of the same period, the dropped period's pairs are missing, and the run ends
    /// when both recordings have.
    #[test]
    fn two_virtual_adxl355s_in_lockstep() {
        use crate::adxl355::Adxl355;
        use crate::source::{Adxl355Settings, Adxl355Source, Axis, AxisPair};
        use crate::virtual_adxl355::{FeedSample, SliceFeed, VirtualAdxl355};

        let part = |p: f32| -> Vec<FeedSample> {
            (0..64).map(|k| FeedSample::new([0.01 * k as f32 + p, p - 0.02 * k as f32, 9.8])).collect()
        };
        let (a, mut b) = (part(1.0), part(-3.0));
        b[32..48].iter_mut().for_each(|s| s.dropped = true);
        let mut health = Health::default();
        let settings = Adxl355Settings::default().with_axes(AxisPair(Axis::X, Axis::Y));
        type Part<'a> = Adxl355Source<crate::adxl355::I2cInterface<VirtualAdxl355<SliceFeed<'a>>>, AxisPair>;
        fn start<'a>(feed: &'a [FeedSample], settings: Adxl355Settings<AxisPair>, health: &mut Health) -> Part<'a> {
            let sensor = Adxl355::new_i2c(VirtualAdxl355::new(SliceFeed::new(feed)), 0x1D);
            Adxl355Source::start(sensor, settings, health).map_err(|(e, _)| e).unwrap()
        }
        let (sa, sb) = (start(&a, settings, &mut health), start(&b, settings, &mut health));
        let mut pair = PairSource::new(sa, sb);
        let mut got = Vec::new();
        while pair.advance() {
            pair.read(&mut health, |s| got.push(s));
        }
        assert_eq!(got.len(), 64);
        let lsb = 9.80665f32 / 256_000.0;
        let q = |v: f32| (v / lsb).round() * lsb;
        for (k, s) in got.iter().enumerate() {
            if (32..48).contains(&k) {
                assert_eq!(*s, None, "sample {k}: dropped by the second part");
                continue;
            }
            let s = s.unwrap();
            let want = [a[k].accel[0], a[k].accel[1], b[k].accel[0], b[k].accel[1]];
            for i in 0..4 {
                assert!((s[i] - q(want[i])).abs() <= 1.5 * lsb, "sample {k} channel {i}: {s:?} {want:?}");
            }
        }
        assert_eq!((health.dropped, health.bridged), (16, 16));
    }

    /// A part that delivers nothing for two polls and catches up at the third: its samples
    /// pair with the other's of the same periods.
    #[test]
    fn a_late_part_pairs_with_the_same_periods() {
        let got = run(&[16, 16, 16], &[0, 0, 48]);
        assert_eq!(got.len(), 48);
        for (k, s) in got.iter().enumerate() {
            assert_eq!(*s, Some([k as f32, 1.0, k as f32, 2.0]), "sample {k}");
        }
    }

    /// A part silent for longer than the queue: the other's oldest samples leave as missing
    /// pairs, and the silent part's samples of those periods are skipped when they come.
    #[test]
    fn an_overflowing_queue_keeps_the_clock() {
        let got = run(&[32, 32, 32, 0], &[0, 0, 0, 96]);
        assert_eq!(got.len(), 96);
        assert!(got[..32].iter().all(Option::is_none));
        for (k, s) in got.iter().enumerate().skip(32) {
            assert_eq!(*s, Some([k as f32, 1.0, k as f32, 2.0]), "sample {k}");
        }
    }
}
