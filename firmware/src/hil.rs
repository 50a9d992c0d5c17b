//! The HIL images' wiring, once for every system: how an image builds its node from the
//! recorded input, and the run from the first poll to the last frame. The QEMU entry point
//! ([`crate::semihost::run_image`]) and the host-side reference runs of the tests both go
//! through [`run`], so a HIL run and its host run are the same code on the same bytes.

use crate::frame::FrameSink;
use crate::line_feed::{ByteSource, FeedError};
use crate::node::{Node, NodeEstimator, Recorded, SampleSource};

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

/// Polls `node` until its input has run out, every report to `sink`, then the image's
/// end-of-run frames.
pub fn run<I: HilImage, B: ByteSource>(node: &mut HilNode<'_, I, B>, sink: &mut impl FrameSink) {
    node.run(|frame| sink.frame(frame));
    I::finish(node, sink);
}
