//! The window hand-over: the node keeps its last `N` raw samples in a ring ([`Captured`]) and,
//! after its model monitor's first `mismatch`, hands them to the host once, with the
//! estimator's state, as frames on the same sink as every report (defmt over semihosting under
//! QEMU, over RTT on the board). `edgekf capture --log node.log --out window.csv` turns those
//! frames back into a recording the host's loop reads.
//!
//! Why a ring on the node: the monitor says *when* the model stopped explaining the data; the
//! loop needs the samples themselves to say *what* it lacks, and a node on a radio link cannot
//! stream them all the time. Why wait after the alarm: the mismatch's `since` dates the change,
//! and the loop names an effect best on a window that holds it throughout; so the node keeps
//! recording until the ring's oldest sample is [`GUARD`] samples past `since` (the monitor's
//! bias window: the change may begin anywhere in the window that dated it), then freezes the
//! ring and drains it [`CHUNK`] frames a poll, so no poll stalls for the whole window.
//!
//! Frames, in order: one [`WindowStart`], the estimator's [`WindowState`] frame, `N`
//! [`WindowSample`]s (oldest first; a missing sample as NaN), one [`WindowEnd`].

use crate::frame::{Frame, FrameSink};
use crate::monitor::MismatchFrame;
use crate::node::{Innovation, NodeEstimator, Poll};
use core::ops::{Deref, DerefMut};

/// Samples past the mismatch's `since` that the window's first sample must be: the model
/// monitor's window (`MonitorSettings::new`'s 256), within which a bias alarm dates a change.
pub const GUARD: u32 = 256;

/// Window frames emitted per poll while the ring drains: 64 frames per 16-sample poll drain a
/// 4096-sample ring in 64 polls (about 1 s at 1 kHz) without one poll carrying them all.
pub const CHUNK: usize = 64;

crate::frame! {
    /// The window's header: the mismatch that started it, where it begins, how long it is and
    /// the sample rate (a sample `k` is at `(k − 1) / rate` seconds from the node's start).
    #[derive(Eq)]
    pub struct WindowStart = "window_start channel={=u8} statistic={=u8} since={=u32} first={=u32} samples={=u32} rate={=u32}" {
        /// The mismatch's channel.
        pub channel: u8,
        /// The mismatch's statistic (see [`MismatchFrame`]).
        pub statistic: u8,
        /// The mismatch's `since`, a sample number from 1.
        pub since: u32,
        /// The window's first sample number (from 1 at start-up).
        pub first: u32,
        /// Samples in the window.
        pub samples: u32,
        /// Samples a second.
        pub rate: u32,
    }
}

crate::frame! {
    /// One raw sample of the window, as the source delivered it (before any declared offset).
    pub struct WindowSample = "window k={=u32} a={=f32}" {
        /// Its sample number, from 1 at start-up.
        pub k: u32,
        /// The reading, in the channel's SI unit (NaN: missing).
        pub a: f32,
    }
}

crate::frame! {
    /// The window is complete.
    #[derive(Eq)]
    pub struct WindowEnd = "window_end samples={=u32}" {
        /// Samples sent (the header's `samples`).
        pub samples: u32,
    }
}

/// An estimator whose state goes with a captured window (its frame: the state when the ring
/// froze, at the window's last sample, and the constants the host needs to read the window as
/// the node did).
pub trait WindowState {
    /// The state's frame.
    type State: Frame;
    /// The state now.
    fn window_state(&self) -> Self::State;
}

/// Where the hand-over stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Recording; no mismatch yet.
    Watching,
    /// Recording until the window holds only samples from `since + GUARD` on.
    Waiting(MismatchFrame),
    /// The ring is frozen at sample `last`; `sent` samples of it are out.
    Draining { last: u32, sent: u32 },
    /// The window went out (once per run).
    Done,
}

/// Estimator `E` (one `f32` input a sample) with a ring of its last `N` raw inputs in
/// borrowed storage (a buffer of 16 KB must not be moved or copied), handed over once after
/// the first mismatch (see the module docs). Dereferences to `E`.
pub struct Captured<'s, E, const N: usize> {
    estimator: E,
    ring: &'s mut [f32; N],
    /// Where the next sample goes.
    head: usize,
    /// Samples stepped so far (the last one's number).
    samples: u32,
    rate_hz: u32,
    phase: Phase,
}

impl<'s, E, const N: usize> Captured<'s, E, N> {
    /// `estimator` at `rate_hz` samples a second, recording into `ring`.
    pub fn new(estimator: E, ring: &'s mut [f32; N], rate_hz: u32) -> Self {
        Self { estimator, ring, head: 0, samples: 0, rate_hz, phase: Phase::Watching }
    }

    /// Asks for the window as after mismatch `m` (what the first mismatch does by itself; a
    /// node may also be asked from outside, e.g. by a command): ignored once a hand-over has
    /// begun.
    pub fn request(&mut self, m: MismatchFrame) {
        if self.phase == Phase::Watching {
            self.phase = Phase::Waiting(m);
        }
    }

    /// Whether the window has gone out.
    pub fn handed_over(&self) -> bool {
        self.phase == Phase::Done
    }

    /// The `j`-th oldest sample of the full ring (the oldest is where the next would go).
    fn oldest(&self, j: u32) -> f32 {
        let at = (self.head as u32).wrapping_add(j).checked_rem(N as u32).unwrap_or(0);
        self.ring.get(at as usize).copied().unwrap_or(f32::NAN)
    }
}

impl<E: NodeEstimator<Input = f32> + WindowState, const N: usize> NodeEstimator for Captured<'_, E, N> {
    type Input = f32;
    type Frame = E::Frame;

    /// Records the raw input (NaN when missing), unless the ring is frozen, then steps `E`.
    fn step(&mut self, input: Option<f32>) -> Innovation {
        if !matches!(self.phase, Phase::Draining { .. }) {
            if let Some(cell) = self.ring.get_mut(self.head) {
                *cell = input.unwrap_or(f32::NAN);
            }
            self.head = if self.head + 1 >= N { 0 } else { self.head + 1 };
        }
        self.samples = self.samples.saturating_add(1);
        self.estimator.step(input)
    }

    fn report(&mut self, poll: &Poll) -> Option<E::Frame> {
        self.estimator.report(poll)
    }

    /// `E`'s mismatches, passed on; the first one starts the hand-over.
    fn take_mismatch(&mut self) -> Option<MismatchFrame> {
        let m = self.estimator.take_mismatch()?;
        if self.phase == Phase::Watching {
            self.phase = Phase::Waiting(m);
        }
        Some(m)
    }

    /// Freezes the ring once its oldest sample is [`GUARD`] past the mismatch's `since` and
    /// sends the header and state, then up to [`CHUNK`] samples a call, then the end.
    fn hand_over<S: FrameSink>(&mut self, sink: &mut S) {
        let n = N as u32;
        let span = n.saturating_sub(1);
        match self.phase {
            Phase::Waiting(m) if n > 0 && self.samples >= m.since.saturating_add(GUARD).saturating_add(span).max(n) => {
                let first = self.samples.saturating_sub(span);
                let (channel, statistic, since, rate) = (m.channel, m.statistic, m.since, self.rate_hz);
                sink.frame(&WindowStart { channel, statistic, since, first, samples: n, rate });
                sink.frame(&self.estimator.window_state());
                self.phase = Phase::Draining { last: self.samples, sent: 0 };
            }
            Phase::Draining { last, sent } => {
                let upto = sent.saturating_add(CHUNK as u32).min(n);
                for j in sent..upto {
                    sink.frame(&WindowSample { k: last.saturating_sub(span).saturating_add(j), a: self.oldest(j) });
                }
                self.phase = Phase::Draining { last, sent: upto };
                if upto == n {
                    sink.frame(&WindowEnd { samples: n });
                    self.phase = Phase::Done;
                }
            }
            _ => {}
        }
    }
}

impl<E, const N: usize> Deref for Captured<'_, E, N> {
    type Target = E;
    fn deref(&self) -> &E {
        &self.estimator
    }
}

impl<E, const N: usize> DerefMut for Captured<'_, E, N> {
    fn deref_mut(&mut self) -> &mut E {
        &mut self.estimator
    }
}

#[cfg(test)]
mod tests;
