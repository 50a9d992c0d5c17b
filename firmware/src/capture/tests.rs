use super::*;
use crate::frame::Done;
use std::string::String;
use std::vec::Vec;

/// Frames as decoded lines.
#[derive(Default)]
struct Lines(Vec<String>);

impl FrameSink for Lines {
    fn frame<F: Frame>(&mut self, frame: &F) {
        let mut line = String::new();
        frame.write_line(&mut line).unwrap();
        self.0.push(line);
    }
}

/// Raises a mismatch dated `since` once it has seen `at` samples.
struct Scripted {
    seen: u32,
    at: u32,
    since: u32,
    raised: bool,
}

impl NodeEstimator for Scripted {
    type Input = f32;
    type Frame = Done;
    fn step(&mut self, _: Option<f32>) -> Innovation {
        self.seen += 1;
        Innovation::default()
    }
    fn report(&mut self, _: &Poll) -> Option<Done> {
        None
    }
    fn take_mismatch(&mut self) -> Option<MismatchFrame> {
        if self.seen >= self.at && !self.raised {
            self.raised = true;
            return Some(MismatchFrame { channel: 0, statistic: 1, since: self.since });
        }
        None
    }
}

impl WindowState for Scripted {
    type State = Done;
    fn window_state(&self) -> Done {
        Done {}
    }
}

/// Steps `total` samples (sample `k` reads `k`, every 7th missing) in polls of 16, handing
/// over after each; returns the lines.
fn run<const N: usize>(total: u32, at: u32, since: u32) -> Vec<String> {
    let mut ring = [0.0; N];
    let mut c = Captured::new(Scripted { seen: 0, at, since, raised: false }, &mut ring, 1000);
    let mut sink = Lines::default();
    for k in 1..=total {
        c.step((k % 7 != 0).then_some(k as f32));
        if k % 16 == 0 {
            while let Some(m) = c.take_mismatch() {
                sink.frame(&m);
            }
            c.hand_over(&mut sink);
        }
    }
    sink.0
}

#[test]
fn the_window_goes_out_once_after_the_guard_oldest_first() {
    // Mismatch found at sample 320, dated 300: the window's first sample must be ≥ 556, so the
    // ring freezes at the first poll end ≥ 556 + 63 = 619, i.e. 624 (first sample 561).
    let lines = run::<64>(2000, 320, 300);
    let start = lines.iter().position(|l| l.starts_with("window_start")).expect("a window");
    assert_eq!(lines[start], "window_start channel=0 statistic=1 since=300 first=561 samples=64 rate=1000");
    assert_eq!(lines[start + 1], "done");
    let samples: Vec<WindowSample> =
        lines.iter().filter_map(|l| WindowSample::parse(l)).collect::<Result<_, _>>().unwrap();
    assert_eq!(samples.len(), 64);
    for (j, s) in samples.iter().enumerate() {
        let k = 561 + j as u32;
        assert_eq!(s.k, k);
        if k % 7 == 0 {
            assert!(s.a.is_nan(), "{s:?}");
        } else {
            assert_eq!(s.a, k as f32);
        }
    }
    assert_eq!(lines.iter().filter(|l| l.starts_with("window_end samples=64")).count(), 1);
    assert_eq!(lines.iter().filter(|l| l.starts_with("window_start")).count(), 1);
}

#[test]
fn a_long_window_drains_a_chunk_a_poll_while_the_ring_is_frozen() {
    // 256 samples in chunks of 64: four polls; samples stepped meanwhile do not enter it.
    let lines = run::<256>(3000, 100, 90);
    let start = lines.iter().position(|l| l.starts_with("window_start")).unwrap();
    let first = WindowStart::parse(&lines[start]).unwrap().unwrap().first;
    let samples: Vec<WindowSample> =
        lines.iter().filter_map(|l| WindowSample::parse(l)).collect::<Result<_, _>>().unwrap();
    assert_eq!(samples.len(), 256);
    assert!(samples.iter().enumerate().all(|(j, s)| s.k == first + j as u32));
    assert!(samples.iter().filter(|s| s.k % 7 != 0).all(|s| s.a == s.k as f32));
    assert!(first >= 90 + GUARD);
}

#[test]
fn no_mismatch_or_too_short_a_run_sends_nothing() {
    assert!(!run::<64>(2000, u32::MAX, 0).iter().any(|l| l.starts_with("window")));
    // Found at 320, dated 300: the ring would freeze at 624, after the run's end.
    assert!(!run::<64>(600, 320, 300).iter().any(|l| l.starts_with("window")));
}
