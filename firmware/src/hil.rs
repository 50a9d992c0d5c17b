//! The HIL images' wiring, once for every system: how an image builds its node from the
//! recorded input, and the run from the first poll to the last frame. The QEMU entry point
//! ([`crate::semihost::run_image`]) and the host-side reference runs of the tests both go
//! through [`run`], so a HIL run and its host run are the same code on the same bytes.

use crate::frame::FrameSink;
use crate::line_feed::{ByteSource, ChannelReader, FeedError};
use crate::node::{Node, NodeEstimator, Recorded, SampleSource};
use crate::source::{ChannelSource, MAX_GAP_S};

/// Why a HIL image could not start (exit codes 3 and 4 under QEMU).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HilError<E> {
    /// The input has no usable header (exit code 3).
    Header(FeedError),
    /// The sensor or the estimator did not start (exit code 4).
    Start(E),
}

/// The node an image runs on input `B`, its estimator borrowing storage for `'s`.
pub type HilNode<'s, I, B> = Node<<I as HilImage>::Source<B>, <I as HilImage>::Estimator<'s>>;

/// One system's HIL image: its input, its node, and its end-of-run frames. One implementation
/// per system, in [`crate::systems`]; the QEMU binary is then one line.
pub trait HilImage {
    /// The binary's name, for messages.
    const NAME: &'static str;
    /// The input columns the image needs (for the message on a bad header).
    const COLUMNS: &'static [&'static str];
    /// One sample as the estimator takes it.
    type Input: Copy;
    /// Memory the estimator borrows, owned by the caller's frame (so that a large buffer is
    /// never moved).
    type Storage;
    /// The sample source on input `B`.
    type Source<B: ByteSource>: SampleSource<Sample = Self::Input> + Recorded;
    /// The estimator.
    type Estimator<'s>: NodeEstimator<Input = Self::Input>;
    /// Why the sensor or the estimator may not start.
    type StartError: core::fmt::Debug;

    /// Fresh storage.
    fn storage() -> Self::Storage;

    /// Reads the input's header and starts the node.
    #[allow(clippy::type_complexity)]
    fn start<B: ByteSource>(
        input: B,
        storage: &mut Self::Storage,
    ) -> Result<HilNode<'_, Self, B>, HilError<Self::StartError>>;

    /// Frames right after start-up (none by default).
    fn started<B: ByteSource>(node: &HilNode<'_, Self, B>, sink: &mut impl FrameSink) {
        let _ = (node, sink);
    }

    /// Frames after the last poll: counters and final estimates.
    fn finish<B: ByteSource>(node: &HilNode<'_, Self, B>, sink: &mut impl FrameSink);
}

/// The channel source of an image whose samples come `rate_hz` a second: lines missing from the
/// file are bridged for up to [`MAX_GAP_S`] (see [`ChannelSource::with_clock`]), as the host
/// bridges them. One start-up for every image that reads a system's channels from its file.
///
/// ```
/// use edgekf_firmware::hil::clocked_source;
/// use edgekf_firmware::line_feed::ChannelReader;
/// use edgekf_firmware::node::{Health, Recorded, SampleSource};
/// // At 10 Hz the line at t = 0.1 is missing: it is stepped as a missing sample.
/// let text = b"t,a\n0,1\n0.2,2\n";
/// let mut src = clocked_source(ChannelReader::new(&text[..], ["a"]).unwrap(), 10);
/// let mut got = Vec::new();
/// while src.advance() {
///     src.read(&mut Health::default(), |s| got.push(s));
/// }
/// assert_eq!(got, [Some([1.0]), None, Some([2.0])]);
/// ```
pub fn clocked_source<B: ByteSource, const M: usize>(reader: ChannelReader<B, M>, rate_hz: u32) -> ChannelSource<B, M> {
    let max_gap = MAX_GAP_S * f64::from(rate_hz);
    ChannelSource::new(reader).with_clock(1.0 / f64::from(rate_hz), max_gap as u32)
}

/// Polls `node` until its input has run out, every report to `sink`, then the image's
/// end-of-run frames.
pub fn run<I: HilImage, B: ByteSource>(node: &mut HilNode<'_, I, B>, sink: &mut impl FrameSink) {
    node.run(|frame| sink.frame(frame));
    I::finish(node, sink);
}
