//! The node's sample sources: the ADXL355 over any bus interface, and named channels of a CSV
//! stream (the HIL files of sensors that are not an ADXL355).
//!
//! Each source owns what is specific to its input: the ADXL355 source the FIFO timing (what is
//! due, what the FIFO overwrote), bus retries and the screening of saturated and frozen
//! samples; the channel source the line parsing. The node sees only samples or `None`.

use crate::adxl355::{self, Adxl355, Config, I2cInterface, Interface, RawSample};
use crate::line_feed::{BadLine, ByteSource, ChannelReader, LineFeed};
use crate::node::{Health, Recorded, SampleSource};
use crate::virtual_adxl355::VirtualAdxl355;

/// Largest block one poll can read.
pub const MAX_BLOCK: usize = 32;

/// Accelerometer axis that carries the mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Axis {
    /// X axis.
    X,
    /// Y axis.
    Y,
    /// Z axis.
    Z,
}

impl Axis {
    fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// How the node drives the ADXL355.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adxl355Settings {
    /// Accelerometer settings.
    pub sensor: Config,
    /// Axis handed to the estimator.
    pub axis: Axis,
    /// Attempts per bus operation before it is given up for this period (at least 1).
    pub attempts: u8,
}

impl Default for Adxl355Settings {
    /// ±2 g, 1 kHz, 16-sample blocks, X axis, 4 attempts.
    fn default() -> Self {
        Self { sensor: Config::default(), axis: Axis::X, attempts: 4 }
    }
}

/// The ADXL355 read in FIFO blocks, one block per watermark period.
pub struct Adxl355Source<IF> {
    sensor: Adxl355<IF>,
    settings: Adxl355Settings,
    previous: Option<RawSample>,
    /// Samples due (per the timing contract) but not yet read.
    pending: u32,
    overrun_seen: bool,
    block: [RawSample; MAX_BLOCK],
}

impl<IF: Interface> Adxl355Source<IF> {
    /// Initialises the part (with retries, counted in `health`). On failure the driver is
    /// handed back with the last error, so the caller can retry later.
    #[allow(clippy::type_complexity)]
    pub fn start(
        mut sensor: Adxl355<IF>,
        settings: Adxl355Settings,
        health: &mut Health,
    ) -> Result<Self, (adxl355::Error<IF::Error>, Adxl355<IF>)> {
        match retry::<_, IF>(health, settings.attempts, || sensor.init(settings.sensor)) {
            Ok(()) => Ok(Self {
                sensor,
                settings,
                previous: None,
                pending: 0,
                overrun_seen: false,
                block: [RawSample::default(); MAX_BLOCK],
            }),
            Err(e) => Err((e, sensor)),
        }
    }

    /// Samples per watermark period.
    pub fn samples_per_poll(&self) -> u32 {
        u32::from(self.settings.sensor.fifo_watermark / 3)
    }

    /// The settings in use.
    pub fn settings(&self) -> &Adxl355Settings {
        &self.settings
    }

    /// The driver (to reach the bus: a virtual device's clock and counters).
    pub fn sensor(&self) -> &Adxl355<IF> {
        &self.sensor
    }

    /// The driver, mutably.
    pub fn sensor_mut(&mut self) -> &mut Adxl355<IF> {
        &mut self.sensor
    }

    /// Checks one raw sample; `None` if it must not reach the estimator.
    fn screen(&mut self, raw: RawSample, health: &mut Health) -> Option<f32> {
        let frozen = self.previous == Some(raw);
        self.previous = Some(raw);
        if raw.is_saturated() {
            health.saturated = health.saturated.saturating_add(1);
            return None;
        }
        if frozen {
            // A 20-bit sensor with ~100 LSB of noise repeating all three codes exactly is frozen
            // (probability ~1e-7 per sample for a live part).
            health.stuck = health.stuck.saturating_add(1);
            return None;
        }
        self.sensor.to_mps2(raw).get(self.settings.axis.index()).copied()
    }
}

impl<IF: Interface> SampleSource for Adxl355Source<IF> {
    type Sample = f32;

    fn read(&mut self, health: &mut Health, mut each: impl FnMut(Option<f32>)) -> u16 {
        self.pending += self.samples_per_poll();
        let attempts = self.settings.attempts;
        let (sensor, block) = (&mut self.sensor, &mut self.block);
        match retry::<_, IF>(health, attempts, || sensor.status()) {
            Ok(status) if status.fifo_overrun => {
                health.fifo_overruns = health.fifo_overruns.saturating_add(1);
                self.overrun_seen = true;
            }
            Ok(_) => {}
            Err(_) => {
                health.failed_polls = health.failed_polls.saturating_add(1);
                return 0;
            }
        }
        let read = match retry::<_, IF>(health, attempts, || sensor.read_fifo(&mut block[..])) {
            Ok(r) => r,
            Err(_) => {
                health.failed_polls = health.failed_polls.saturating_add(1);
                return 0;
            }
        };
        health.skipped_entries += u32::from(read.skipped_entries);
        let n = read.samples.min(MAX_BLOCK);
        // Samples due but absent were overwritten if the sensor said so, or if more are due than
        // the FIFO can hold; bridge those with prediction before the newer samples.
        let due = self.pending;
        let got = n as u32;
        let lost = if due > got && (self.overrun_seen || due - got > MAX_BLOCK as u32) { due - got } else { 0 };
        self.pending = due.saturating_sub(got + lost);
        self.overrun_seen = false;
        for _ in 0..lost {
            each(None);
        }
        health.bridged += lost;
        for k in 0..n {
            let raw = self.block[k];
            each(self.screen(raw, health));
        }
        n as u16
    }
}

impl<F: crate::virtual_adxl355::SampleFeed> Recorded for Adxl355Source<I2cInterface<VirtualAdxl355<F>>> {
    /// One watermark period of the virtual device's clock; `false` once the data has run out
    /// and the FIFO is drained.
    fn advance(&mut self) -> bool {
        let bus = self.sensor.interface_mut().bus_mut();
        bus.advance_period() > 0 || !bus.is_exhausted()
    }
}

/// The virtual ADXL355 source of a HIL file.
pub type VirtualSource<B> = Adxl355Source<I2cInterface<VirtualAdxl355<LineFeed<B>>>>;

impl<B: ByteSource> VirtualSource<B> {
    /// The virtual device behind the driver.
    pub fn device(&self) -> &VirtualAdxl355<LineFeed<B>> {
        self.sensor.interface().bus()
    }
}

/// Runs `op` up to `attempts` times (at least once), counting failures.
fn retry<T, IF: Interface>(
    health: &mut Health,
    attempts: u8,
    mut op: impl FnMut() -> Result<T, adxl355::Error<IF::Error>>,
) -> Result<T, adxl355::Error<IF::Error>> {
    let mut tries = 0u8;
    loop {
        tries += 1;
        match op() {
            Ok(v) => {
                if tries > 1 {
                    health.recovered = health.recovered.saturating_add(1);
                }
                return Ok(v);
            }
            Err(e) => {
                health.bus_errors = health.bus_errors.saturating_add(1);
                if matches!(&e, adxl355::Error::Comm(c) if IF::is_nack(c)) {
                    health.nacks = health.nacks.saturating_add(1);
                }
                if tries >= attempts.max(1) {
                    return Err(e);
                }
            }
        }
    }
}

/// Named channels of a CSV stream, one line per period.
///
/// ```
/// use edgekf_firmware::line_feed::ChannelReader;
/// use edgekf_firmware::node::{Health, Recorded, SampleSource};
/// use edgekf_firmware::source::ChannelSource;
/// let text = b"t,a\n0,1.5\n0.1,x\n";
/// let mut src = ChannelSource::new(ChannelReader::new(&text[..], ["a"]).unwrap());
/// let mut got = Vec::new();
/// while src.advance() {
///     src.read(&mut Health::default(), |s| got.push(s));
/// }
/// assert_eq!(got, [Some([1.5]), None]);
/// assert_eq!(src.reader().bad_lines(), 1);
/// ```
pub struct ChannelSource<B: ByteSource, const M: usize> {
    reader: ChannelReader<B, M>,
    line: Option<Result<[f32; M], BadLine>>,
}

impl<B: ByteSource, const M: usize> ChannelSource<B, M> {
    /// Lines of `reader`, its header already read.
    pub fn new(reader: ChannelReader<B, M>) -> Self {
        Self { reader, line: None }
    }

    /// The reader (its counters).
    pub fn reader(&self) -> &ChannelReader<B, M> {
        &self.reader
    }
}

impl<B: ByteSource, const M: usize> SampleSource for ChannelSource<B, M> {
    type Sample = [f32; M];

    fn read(&mut self, _health: &mut Health, mut each: impl FnMut(Option<[f32; M]>)) -> u16 {
        match self.line.take() {
            Some(line) => {
                each(line.ok());
                1
            }
            None => 0,
        }
    }
}

impl<B: ByteSource, const M: usize> Recorded for ChannelSource<B, M> {
    fn advance(&mut self) -> bool {
        self.line = self.reader.next_values();
        self.line.is_some()
    }
}
