//! The HIL images run on the host over the same input a firmware run gets, through the same
//! [`edgekf_firmware::hil::run`]: the reference a QEMU run is compared with, bit for bit. The
//! host run's frames are written as lines and parsed like the decoded defmt log, so both runs
//! go through the same parser.

use crate::report::RunReport;
use anyhow::{anyhow, Result};
use edgekf_firmware::frame::{Done, Frame, FrameSink};
use edgekf_firmware::hil::{self, FileEnd, HilImage, HilNode};
use edgekf_firmware::systems::oscillator::OscillatorImage;

/// Frames collected as the lines a decoded defmt log would hold.
#[derive(Debug, Default, Clone)]
pub struct Lines(pub Vec<String>);

impl FrameSink for Lines {
    fn frame<F: Frame>(&mut self, frame: &F) {
        let mut line = String::new();
        // Writing to a String cannot fail.
        let _ = frame.write_line(&mut line);
        self.0.push(line);
    }
}

/// Runs image `I` over CSV text exactly as its QEMU binary does (without the `stack` frame);
/// returns the frames as lines.
pub fn lines<I: HilImage>(csv: &[u8]) -> Result<Vec<String>> {
    let mut storage = I::STORAGE;
    let mut node = I::start(csv, &mut storage).map_err(|e| anyhow!("{} did not start: {e:?}", I::NAME))?;
    let mut sink = Lines::default();
    I::started(&node, &mut sink);
    finish::<I>(&mut node, sink)
}

/// Runs an already started `node` of image `I` to its end and returns the frames as lines.
pub fn run_node<I: HilImage>(node: &mut HilNode<'_, I, &[u8]>) -> Result<Vec<String>> {
    finish::<I>(node, Lines::default())
}

fn finish<I: HilImage>(node: &mut HilNode<'_, I, &[u8]>, mut sink: Lines) -> Result<Vec<String>> {
    hil::run::<I, _>(node, &mut sink);
    sink.frame(&Done {});
    Ok(sink.0)
}

/// The `file` frame of a run's lines: what the image met in its input file.
pub fn file_end(lines: &[String]) -> Result<FileEnd> {
    crate::report::frames::<FileEnd>(lines)?.pop().ok_or_else(|| anyhow!("no `file` line: the run did not finish"))
}

/// Runs the oscillator image (`NodeConfig::default()`) over CSV text exactly as `edgekf-qemu`
/// does.
pub fn run(csv: &[u8]) -> Result<RunReport> {
    RunReport::parse(lines::<OscillatorImage>(csv)?.iter().map(String::as_str))
}
