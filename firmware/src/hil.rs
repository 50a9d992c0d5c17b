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

    /// Fresh storage, as a constant: the caller's frame holds it from the start.
    const STORAGE: Self::Storage;

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

crate::frame! {
    /// What an image that reads its channels from a file met in that file, emitted before the
    /// image's own end frame: one set of counts, read the same way for every system.
    #[derive(Eq)]
    pub struct FileEnd = "file bad_lines={=u32} untimed_lines={=u32} missing_lines={=u32} time_jumps={=u32}" {
        /// Lines that did not parse (stepped as missing if their `t` did).
        pub bad_lines: u32,
        /// Lines without a usable `t` (not stepped).
        pub untimed_lines: u32,
        /// Lines missing from the file (by their `t`), stepped as missing samples.
        pub missing_lines: u32,
        /// Lines whose `t` was off the sample grid (not bridged; see [`ChannelSource`]).
        pub time_jumps: u32,
    }
}

impl FileEnd {
    /// The counts of `source` so far.
    ///
    /// ```
    /// use edgekf_firmware::hil::{clocked_source, FileEnd};
    /// use edgekf_firmware::line_feed::ChannelReader;
    /// use edgekf_firmware::node::{Health, Recorded, SampleSource};
    /// // At 10 Hz: the line at t = 0.1 is missing, "x" does not parse.
    /// let text = b"t,a\n0,1\n0.2,x\n0.3,2\n";
    /// let mut src = clocked_source(ChannelReader::new(&text[..], ["a"]).unwrap(), 10);
    /// while src.advance() {
    ///     src.read(&mut Health::default(), |_| {});
    /// }
    /// let end = FileEnd::of(&src);
    /// assert_eq!((end.bad_lines, end.missing_lines, end.untimed_lines, end.time_jumps), (1, 1, 0, 0));
    /// ```
    pub fn of<B: ByteSource, const M: usize>(source: &ChannelSource<B, M>) -> Self {
        Self {
            bad_lines: source.reader().bad_lines(),
            untimed_lines: source.untimed_lines(),
            missing_lines: source.missing_lines(),
            time_jumps: source.time_jumps(),
        }
    }
}

/// The node of an image that reads the channels of a file sampled `rate_hz` a second (the
/// source of [`clocked_source`]): `reader` is the header's outcome, `estimator` is started only
/// on a usable header. One start-up for every such image.
///
/// ```
/// use edgekf_firmware::hil::{clocked_node, HilError};
/// use edgekf_firmware::line_feed::ChannelReader;
/// use edgekf_firmware::node::{Innovation, NodeEstimator, Poll};
/// # struct Sum(f32);
/// # impl NodeEstimator for Sum {
/// #     type Input = [f32; 1];
/// #     type Frame = edgekf_firmware::frame::Done;
/// #     fn step(&mut self, x: Option<[f32; 1]>) -> Innovation { self.0 += x.map_or(0.0, |[a]| a); Innovation::default() }
/// #     fn report(&mut self, _: &Poll) -> Option<Self::Frame> { None }
/// # }
/// let text = b"t,a\n0,1\n0.1,2\n";
/// let mut node = clocked_node(ChannelReader::new(&text[..], ["a"]), 10, || Ok::<_, ()>(Sum(0.0))).unwrap();
/// node.run(|_| {});
/// assert_eq!(node.estimator().0, 3.0);
/// // A header without the channel is the header's error; the estimator is not started.
/// let bad = clocked_node(ChannelReader::new(&b"t,b\n"[..], ["a"]), 10, || -> Result<Sum, ()> { unreachable!() });
/// assert!(matches!(bad, Err(HilError::Header(_))));
/// ```
pub fn clocked_node<B: ByteSource, E: NodeEstimator<Input = [f32; M]>, X, const M: usize>(
    reader: Result<ChannelReader<B, M>, FeedError>,
    rate_hz: u32,
    estimator: impl FnOnce() -> Result<E, X>,
) -> Result<Node<ChannelSource<B, M>, E>, HilError<X>> {
    let source = clocked_source(reader.map_err(HilError::Header)?, rate_hz);
    Ok(Node::new(source, estimator().map_err(HilError::Start)?, Default::default()))
}

/// [`clocked_node`] on a file whose empty cells are missing readings of their channel alone
/// ([`ChannelReader::with_empty_cells`]): the images of systems whose sensors come at several
/// rates in one file (the boom's, the vehicle's).
///
/// ```
/// use edgekf_firmware::hil::sensors_node;
/// use edgekf_firmware::node::{Innovation, NodeEstimator, Poll};
/// # struct Seen(u32);
/// # impl NodeEstimator for Seen {
/// #     type Input = [f32; 2];
/// #     type Frame = edgekf_firmware::frame::Done;
/// #     fn step(&mut self, x: Option<[f32; 2]>) -> Innovation { self.0 += x.map_or(0, |[_, b]| u32::from(b.is_nan())); Innovation::default() }
/// #     fn report(&mut self, _: &Poll) -> Option<Self::Frame> { None }
/// # }
/// // The second line has no `b`: a missing reading of `b` alone, not a bad line.
/// let text = b"t,a,b\n0,1,2\n0.1,3,\n";
/// let mut node = sensors_node(&text[..], ["a", "b"], 10, || Ok::<_, ()>(Seen(0))).unwrap();
/// node.run(|_| {});
/// assert_eq!(node.estimator().0, 1);
/// ```
pub fn sensors_node<B: ByteSource, E: NodeEstimator<Input = [f32; M]>, X, const M: usize>(
    input: B,
    channels: [&'static str; M],
    rate_hz: u32,
    estimator: impl FnOnce() -> Result<E, X>,
) -> Result<Node<ChannelSource<B, M>, E>, HilError<X>> {
    clocked_node(ChannelReader::new(input, channels).map(ChannelReader::with_empty_cells), rate_hz, estimator)
}

/// Polls `node` until its input has run out, every report to `sink` followed by the model
/// mismatches found in that poll ([`crate::monitor::MismatchFrame`]) and the captured window's
/// frames due ([`crate::capture`]), then the image's end-of-run frames.
pub fn run<I: HilImage, B: ByteSource>(node: &mut HilNode<'_, I, B>, sink: &mut impl FrameSink) {
    while node.source_mut().advance() {
        if let Some(frame) = node.poll() {
            sink.frame(&frame);
        }
        while let Some(mismatch) = node.estimator_mut().take_mismatch() {
            sink.frame(&mismatch);
        }
        node.estimator_mut().hand_over(sink);
    }
    I::finish(node, sink);
}
