//! The sensor node's main loop: read a block from the accelerometer FIFO, screen the samples,
//! run the estimator, and report estimates with health counters.
//!
//! Generic over the I²C bus, so the same code runs on the board (a HAL's I²C), under QEMU (the
//! [`crate::virtual_adxl355`] device fed from a host file) and in host tests (the same virtual
//! device fed from memory, or a mock). Nothing here panics: bus errors are retried and counted,
//! bad samples are counted and bridged by prediction.
//!
//! ## Timing contract
//! [`Node::poll`] is called once per FIFO watermark period (`watermark / 3` samples at the output
//! data rate): on the board from a timer; under QEMU and in host tests right after the harness
//! advances the virtual device's clock by one period. Samples that could not be read stay in the FIFO and are
//! read late; samples the FIFO overwrote (overrun) are bridged by prediction-only steps, so the
//! estimator's clock never slips against the physical one.

use crate::adxl355::{self, Adxl355, Config, I2cInterface, RawSample};
use edgekf::systems::oscillator::ModelError;
use edgekf::systems::oscillator::{EstimatorCounters, HarmonicForceEstimator, HarmonicForceParams};
use embedded_hal::i2c::I2c;

/// Largest block one poll can read: the whole 96-entry FIFO.
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

/// Everything the node needs to start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeConfig {
    /// I²C address of the ADXL355 (0x1D with ASEL low).
    pub address: u8,
    /// Accelerometer settings.
    pub sensor: Config,
    /// Axis read by the estimator.
    pub axis: Axis,
    /// Estimator model and tuning.
    pub estimator: HarmonicForceParams,
    /// Attempts per bus operation before it is given up for this period (at least 1).
    pub attempts: u8,
}

impl Default for NodeConfig {
    /// ADXL355 at 0x1D, ±2 g, 1 kHz, 16-sample blocks, X axis, the default harmonic model.
    fn default() -> Self {
        let sensor = Config::default();
        Self {
            address: adxl355::ADDRESS_ASEL_LOW,
            sensor,
            axis: Axis::X,
            estimator: HarmonicForceParams { sample_rate_hz: sensor.odr.hz() as f64, ..HarmonicForceParams::default() },
            attempts: 4,
        }
    }
}

/// Counted events. A clean run has only `samples` and `blocks` non-zero.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Health {
    /// Polls made.
    pub blocks: u32,
    /// Samples used by the estimator.
    pub samples: u32,
    /// Bus errors seen (each failed attempt), NACKs included.
    pub bus_errors: u32,
    /// Of those, NACKs.
    pub nacks: u32,
    /// Operations that succeeded after at least one retry.
    pub recovered: u32,
    /// Polls whose FIFO could not be read within the attempt budget.
    pub failed_polls: u32,
    /// FIFO overruns reported by the sensor.
    pub fifo_overruns: u32,
    /// FIFO entries skipped to realign on the X marker.
    pub skipped_entries: u32,
    /// Samples with an axis at full scale (not used).
    pub saturated: u32,
    /// Samples identical to the previous one on all axes (frozen output, not used).
    pub stuck: u32,
    /// Samples the FIFO lost, bridged by prediction.
    pub bridged: u32,
}

/// What one poll produced: the estimate at the end of the block and block statistics.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BlockReport {
    /// Poll number, from 0.
    pub block: u32,
    /// Samples read from the FIFO in this poll.
    pub read: u16,
    /// Samples given to the estimator as missing (lost, saturated, stuck).
    pub missing: u16,
    /// Modal displacement, m.
    pub displacement: f32,
    /// Modal velocity, m/s.
    pub velocity: f32,
    /// In-phase force, N.
    pub force_cos: f32,
    /// Quadrature force, N.
    pub force_sin: f32,
    /// Force amplitude, N.
    pub force_amplitude: f32,
    /// RMS of this block's innovations, m/s² (0 if none).
    pub innovation_rms: f32,
    /// Mean NIS of this block's innovations (0 if none).
    pub nis_mean: f32,
}

/// Why the node could not start.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StartError<E> {
    /// The accelerometer did not initialise within the attempt budget (last error kept).
    Sensor(adxl355::Error<E>),
    /// The estimator's model could not be built from the parameters.
    Model(ModelError),
}

/// The main loop's state.
pub struct Node<I2C: I2c> {
    sensor: Adxl355<I2cInterface<I2C>>,
    estimator: HarmonicForceEstimator<f32>,
    config: NodeConfig,
    health: Health,
    previous: Option<RawSample>,
    /// Samples due (per the timing contract) but not yet read.
    pending: u32,
    overrun_seen: bool,
    block: [RawSample; MAX_BLOCK],
}

impl<I2C: I2c> Node<I2C> {
    /// Initialises the accelerometer (with retries) and builds the estimator from the compiled-in
    /// model ([`crate::model`]; `config.estimator` supplies its scaling). On failure the
    /// bus is handed back with the reason, so the caller can retry later.
    #[allow(clippy::type_complexity)]
    #[inline(never)] // start-up temporaries stay out of the caller's (main's) frame
    pub fn start(i2c: I2C, config: NodeConfig) -> Result<Self, (StartError<I2C::Error>, I2C)> {
        let estimator = match crate::model::compiled_estimator(&config.estimator) {
            Ok(e) => e,
            Err(e) => return Err((StartError::Model(e), i2c)),
        };
        let mut sensor = Adxl355::new_i2c(i2c, config.address);
        let mut health = Health::default();
        if let Err(e) = retry(&mut health, config.attempts, || sensor.init(config.sensor)) {
            return Err((StartError::Sensor(e), sensor.release().release()));
        }
        Ok(Self {
            sensor,
            estimator,
            config,
            health,
            previous: None,
            pending: 0,
            overrun_seen: false,
            block: [RawSample::default(); MAX_BLOCK],
        })
    }

    /// Samples per watermark period.
    pub fn samples_per_poll(&self) -> u32 {
        u32::from(self.config.sensor.fifo_watermark / 3)
    }

    /// One watermark period: read what the FIFO holds, run the estimator over it.
    pub fn poll(&mut self) -> BlockReport {
        let mut report = BlockReport { block: self.health.blocks, ..BlockReport::default() };
        self.health.blocks += 1;
        self.pending += self.samples_per_poll();
        let attempts = self.config.attempts;
        let (sensor, block, health) = (&mut self.sensor, &mut self.block, &mut self.health);
        match retry(health, attempts, || sensor.status()) {
            Ok(status) if status.fifo_overrun => {
                health.fifo_overruns += 1;
                self.overrun_seen = true;
            }
            Ok(_) => {}
            Err(_) => {
                health.failed_polls += 1;
                return self.finish(report, 0.0, 0.0);
            }
        }
        let read = match retry(health, attempts, || sensor.read_fifo(&mut block[..])) {
            Ok(r) => r,
            Err(_) => {
                health.failed_polls += 1;
                return self.finish(report, 0.0, 0.0);
            }
        };
        self.health.skipped_entries += u32::from(read.skipped_entries);
        let n = read.samples.min(MAX_BLOCK);
        report.read = n as u16;
        // Samples due but absent were overwritten if the sensor said so, or if more are due than
        // the FIFO can hold; bridge those with prediction before the newer samples.
        let due = self.pending;
        let got = n as u32;
        let lost = if due > got && (self.overrun_seen || due - got > MAX_BLOCK as u32) { due - got } else { 0 };
        self.pending = due.saturating_sub(got + lost);
        self.overrun_seen = false;
        for _ in 0..lost {
            self.estimator.step(None);
        }
        self.health.bridged += lost;
        report.missing = lost.min(u32::from(u16::MAX)) as u16;

        let (mut sum_sq, mut sum_nis, mut used) = (0.0f32, 0.0f32, 0u32);
        for k in 0..n {
            let raw = self.block[k];
            let sample = self.screen(raw);
            if sample.is_none() {
                report.missing = report.missing.saturating_add(1);
            }
            let step = self.estimator.step(sample);
            if let (Some(i), Some(nis)) = (step.innovation, step.nis) {
                sum_sq += i * i;
                sum_nis += nis;
                used += 1;
            }
        }
        self.health.samples += used;
        let (irms, nis) =
            if used > 0 { (libm::sqrtf(sum_sq / used as f32), sum_nis / used as f32) } else { (0.0, 0.0) };
        self.finish(report, irms, nis)
    }

    /// Checks one raw sample; `None` if it must not reach the estimator.
    fn screen(&mut self, raw: RawSample) -> Option<f32> {
        let frozen = self.previous == Some(raw);
        self.previous = Some(raw);
        if raw.is_saturated() {
            self.health.saturated += 1;
            return None;
        }
        if frozen {
            // A 20-bit sensor with ~100 LSB of noise repeating all three codes exactly is frozen
            // (probability ~1e-7 per sample for a live part).
            self.health.stuck += 1;
            return None;
        }
        self.sensor.to_mps2(raw).get(self.config.axis.index()).copied()
    }

    fn finish(&self, mut report: BlockReport, irms: f32, nis: f32) -> BlockReport {
        let now = self.estimator.current();
        report.displacement = now.displacement;
        report.velocity = now.velocity;
        report.force_cos = now.force_cos;
        report.force_sin = now.force_sin;
        report.force_amplitude = now.force_amplitude;
        report.innovation_rms = irms;
        report.nis_mean = nis;
        report
    }

    /// Counted events so far.
    pub fn health(&self) -> Health {
        self.health
    }

    /// The estimator's own counters (missing, gated, filter repairs).
    pub fn estimator_counters(&self) -> EstimatorCounters {
        self.estimator.counters()
    }

    /// The bus (to query a virtual device, or to recover the peripheral).
    pub fn bus(&self) -> &I2C {
        self.sensor.interface().bus()
    }

    /// The bus, mutably (a virtual device's clock is advanced through it).
    pub fn bus_mut(&mut self) -> &mut I2C {
        self.sensor.interface_mut().bus_mut()
    }

    /// The configuration in use.
    pub fn config(&self) -> &NodeConfig {
        &self.config
    }
}

/// Runs `op` up to `attempts` times (at least once), counting failures.
fn retry<T, E: embedded_hal::i2c::Error>(
    health: &mut Health,
    attempts: u8,
    mut op: impl FnMut() -> Result<T, adxl355::Error<E>>,
) -> Result<T, adxl355::Error<E>> {
    let mut tries = 0u8;
    loop {
        tries += 1;
        match op() {
            Ok(v) => {
                if tries > 1 {
                    health.recovered += 1;
                }
                return Ok(v);
            }
            Err(e) => {
                health.bus_errors += 1;
                if adxl355::is_nack(&e) {
                    health.nacks += 1;
                }
                if tries >= attempts.max(1) {
                    return Err(e);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::virtual_adxl355::{FeedSample, SliceFeed, VirtualAdxl355};
    use std::vec::Vec;

    /// Gaussian noise of the ADXL355's size (the model's σ) from a fixed-seed xorshift generator.
    fn noise(state: &mut u64) -> f64 {
        let mut uniform = || {
            *state ^= *state << 13;
            *state ^= *state >> 7;
            *state ^= *state << 17;
            (*state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (u1, u2) = (uniform().max(1e-300), uniform());
        HarmonicForceParams::default().accel_noise_std
            * libm::sqrt(-2.0 * libm::log(u1))
            * libm::cos(2.0 * core::f64::consts::PI * u2)
    }

    /// Steady forced response of the default mode to a 4 N force at the running speed, with
    /// the sensor's noise on every axis.
    fn steady_response(n: usize) -> Vec<FeedSample> {
        let p = HarmonicForceParams::default();
        let wn = 2.0 * core::f64::consts::PI * p.natural_freq_hz;
        let w = p.drive_rad_s;
        let (re, im) = (wn * wn - w * w, 2.0 * p.damping_ratio * wn * w);
        let den = re * re + im * im;
        let (xr, xi) = (4.0 * re / den, -4.0 * im / den);
        let mut seed = 0x9E37_79B9_7F4A_7C15u64;
        (0..n)
            .map(|k| {
                let t = k as f64 * 1e-3;
                let (s, c) = libm::sincos(w * t);
                let a = -w * w * (xr * c - xi * s) + noise(&mut seed);
                FeedSample::new([a as f32, noise(&mut seed) as f32, (9.80665 + noise(&mut seed)) as f32])
            })
            .collect()
    }

    fn run(samples: &[FeedSample]) -> (Vec<BlockReport>, Health) {
        let (r, h, _) = run_counted(samples);
        (r, h)
    }

    fn run_counted(samples: &[FeedSample]) -> (Vec<BlockReport>, Health, EstimatorCounters) {
        let mut node = Node::start(VirtualAdxl355::new(SliceFeed::new(samples)), NodeConfig::default())
            .map_err(|(e, _)| e)
            .unwrap();
        let mut reports = Vec::new();
        while node.bus_mut().advance_period() > 0 || !node.bus().is_exhausted() {
            reports.push(node.poll());
        }
        (reports, node.health(), node.estimator_counters())
    }

    #[test]
    fn clean_stream_estimates_the_force() {
        let (reports, health, counters) = run_counted(&steady_response(3200));
        assert_eq!(counters.filter, Default::default(), "{counters:?}");
        let last = reports.last().unwrap();
        assert!((last.force_amplitude - 4.0).abs() < 0.02, "{last:?}");
        assert_eq!(health.samples, 3200, "{health:?}");
        assert_eq!((health.bus_errors, health.stuck, health.saturated, health.bridged), (0, 0, 0, 0));
        // NIS near 1 once converged; a little below, since this force is exactly constant while
        // the model allows it to wander (S = 2.6e-5 includes that, the data's innovations don't).
        let nis: f32 = reports[100..].iter().map(|r| r.nis_mean).sum::<f32>() / (reports.len() - 100) as f32;
        assert!(nis > 0.75 && nis < 1.0, "mean NIS {nis}");
    }

    #[test]
    fn short_nack_burst_is_retried_and_counted() {
        let mut samples = steady_response(320);
        samples[40].nack = 2; // loaded in the 3rd period
        let (reports, health) = run(&samples);
        assert_eq!((health.nacks, health.recovered, health.failed_polls), (2, 1, 0), "{health:?}");
        assert_eq!(health.samples, 320);
        assert!(reports.iter().all(|r| r.read == 16));
    }

    #[test]
    fn long_nack_burst_overruns_and_is_bridged() {
        let mut samples = steady_response(640);
        samples[40].nack = 12; // three whole polls fail (4 attempts each)
        let (reports, health) = run(&samples);
        assert_eq!((health.nacks, health.failed_polls), (12, 3), "{health:?}");
        assert!(health.fifo_overruns >= 1 && health.bridged == 32, "{health:?}");
        assert_eq!(health.samples + health.bridged, 640);
        let last = reports.last().unwrap();
        assert!((last.force_amplitude - 4.0).abs() < 0.05, "{last:?}");
    }

    #[test]
    fn stuck_and_saturated_samples_are_not_used() {
        let mut samples = steady_response(640);
        for s in &mut samples[100..150] {
            s.stuck = true;
        }
        for s in &mut samples[300..310] {
            s.accel[0] = 40.0;
        }
        let (_, health) = run(&samples);
        assert_eq!(health.stuck, 50);
        assert_eq!(health.saturated, 10);
        assert_eq!(health.samples, 640 - 60);
    }
}
