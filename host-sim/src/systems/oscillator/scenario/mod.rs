//! A complete synthetic test case for the harmonic-force estimator: a mode, its force, the
//! sensor that reads it, faults to inject, and the filter tuning to use.
//!
//! The same scenario drives the CLI demo, the `oscillator` commands and the cross-crate
//! hardware-in-the-loop tests, so a result can be reproduced from its TOML file and seed alone.
//! The defaults are the demo: a 20 Hz mode (ζ = 0.02, 1 kg) driven at 87.96 rad/s by 5 N at 30°,
//! stepping to 3 N at 6 s over 0.2 s, for 12 s, read by an ADXL355 at 1 kHz, ±2 g.
//!
//! ```
//! use edgekf_sim::systems::oscillator::scenario::Scenario;
//! let s = Scenario::from_toml_str("duration_s = 2.0\n[force]\namplitude_n = 2.0\n").unwrap();
//! let rec = s.simulate();
//! assert_eq!(rec.len(), 2000);
//! assert_eq!(rec.truth_force_amplitude[1500], 2.0);
//! assert!((s.estimator_params().accel_noise_std - 4.857e-3).abs() < 1e-6);
//! ```

mod fault;
mod recording;

pub use crate::systems::oscillator::sensor::Adxl355Config as SensorConfig;
pub use crate::systems::oscillator::sim::{ExtraHarmonic, ForceChange, ForceConfig, ModeConfig};
pub use fault::{Fault, TIME_TOLERANCE};
pub use recording::Recording;

use crate::systems::oscillator::sensor::Adxl355;
use crate::systems::oscillator::sim::{Oscillator, DEFAULT_SUBSTEPS};
use anyhow::Context as _;
use edgekf::systems::oscillator::{GainMode, HarmonicForceParams};
use serde::Deserialize;
use std::path::Path;

/// Tuning of the harmonic-force filter: the fields of [`HarmonicForceParams`] that are choices
/// rather than physics, and what the filter assumes of its sensor. Defaults are those of
/// `HarmonicForceParams::default()`, and no offset.
///
/// `[sensor]` describes the simulated sensor (what `simulate` produces); `[filter]` what the
/// filter (the host's and, through `edgekf oscillator export`, the node's) assumes. They differ
/// on purpose: a recording from a real part has no `[sensor]` to read, and a calibration found by
/// `edgekf loop oscillator` is declared here (`--corrected-config` writes it).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FilterTuning {
    /// Spectral density of the force phasor's random walk, (m/s²)²/s.
    pub force_psd: f64,
    /// Spectral density of unmodelled acceleration, (m/s²)²/s.
    pub motion_psd: f64,
    /// Prior standard deviation of each phasor component, m/s².
    pub initial_force_std: f64,
    /// NIS gate (0 disables it).
    pub gate_nis: f64,
    /// Gated samples in a row after which the gate is bypassed once.
    pub gate_max_consecutive: u32,
    /// How the Kalman gain is computed.
    pub gain: Gain,
    /// The accelerometer's x-axis offset the filter subtracts from each sample before it
    /// steps, m/s² (the node does the same with the exported `HARMONIC_ACCEL_OFFSET`).
    pub accel_offset_m_s2: f64,
}

/// How the Kalman gain is computed (TOML: `gain = "steady_state"` or `"time_varying"`); mirrors
/// [`GainMode`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Gain {
    /// The converged gain, solved once at construction: what the chip runs.
    SteadyState,
    /// The full covariance recursion every sample.
    TimeVarying,
}

impl From<GainMode> for Gain {
    fn from(g: GainMode) -> Self {
        match g {
            GainMode::SteadyState => Gain::SteadyState,
            GainMode::TimeVarying => Gain::TimeVarying,
        }
    }
}

impl From<Gain> for GainMode {
    fn from(g: Gain) -> Self {
        match g {
            Gain::SteadyState => GainMode::SteadyState,
            Gain::TimeVarying => GainMode::TimeVarying,
        }
    }
}

impl Default for FilterTuning {
    fn default() -> Self {
        let p = HarmonicForceParams::default();
        Self {
            force_psd: p.force_psd,
            motion_psd: p.motion_psd,
            initial_force_std: p.initial_force_std,
            gate_nis: p.gate_nis,
            gate_max_consecutive: p.gate_max_consecutive,
            gain: p.gain.into(),
            accel_offset_m_s2: 0.0,
        }
    }
}

/// A synthetic test case. Deserialised from TOML (every table and field optional, defaulting to
/// the demo; lists such as `faults` and `force.changes` default to empty when a table is given).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Scenario {
    /// The structural mode.
    pub mode: ModeConfig,
    /// The force on it.
    pub force: ForceConfig,
    /// The accelerometer.
    pub sensor: SensorConfig,
    /// Length of the run, s.
    pub duration_s: f64,
    /// Seed of the sensor noise.
    pub seed: u64,
    /// Faults to inject.
    #[serde(default)]
    pub faults: Vec<Fault>,
    /// Filter tuning (`[filter]` table).
    pub filter: FilterTuning,
    /// RK4 sub-steps per output sample of the reference simulation.
    pub substeps: u32,
    /// How gaps in a recording's time column are bridged (`[timeline]`).
    pub timeline: crate::io::timeline::TimelineOptions,
}

impl Default for Scenario {
    fn default() -> Self {
        Self {
            mode: ModeConfig::default(),
            force: ForceConfig::default(),
            sensor: SensorConfig::default(),
            duration_s: 12.0,
            seed: 1,
            faults: vec![],
            filter: FilterTuning::default(),
            substeps: DEFAULT_SUBSTEPS,
            timeline: Default::default(),
        }
    }
}

impl Scenario {
    /// Parses and validates a scenario from TOML text.
    pub fn from_toml_str(text: &str) -> anyhow::Result<Self> {
        let s: Scenario = crate::io::config::parse_toml(text)?;
        s.validate()?;
        s.timeline.validate().map_err(anyhow::Error::msg)?;
        Ok(s)
    }

    /// Reads, parses and validates a scenario file.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
        Self::from_toml_str(&text).with_context(|| format!("{}: invalid scenario", path.display()))
    }

    /// Checks every figure; the message names the offending field.
    pub fn validate(&self) -> anyhow::Result<()> {
        self.mode.validate().map_err(anyhow::Error::msg)?;
        self.force.validate().map_err(anyhow::Error::msg)?;
        self.sensor.validate().map_err(anyhow::Error::msg)?;
        if !(self.duration_s.is_finite() && self.duration_s > 0.0) {
            anyhow::bail!("duration_s = {} must be positive", self.duration_s);
        }
        if self.samples() < 2 {
            anyhow::bail!("duration_s = {} s gives fewer than 2 samples at {} Hz", self.duration_s, self.sensor.odr_hz);
        }
        if self.substeps == 0 {
            anyhow::bail!("substeps must be at least 1");
        }
        for (i, f) in self.faults.iter().enumerate() {
            f.validate().map_err(|e| anyhow::anyhow!("faults[{i}]: {e}"))?;
        }
        let f = &self.filter;
        let tuning = [f.force_psd, f.motion_psd, f.initial_force_std, f.gate_nis];
        if tuning.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            anyhow::bail!("filter: force_psd, motion_psd, initial_force_std and gate_nis must be non-negative numbers");
        }
        if !(f.accel_offset_m_s2.is_finite() && f.accel_offset_m_s2.abs() < self.sensor.range_m_s2()) {
            anyhow::bail!(
                "filter: accel_offset_m_s2 = {} must be a number within the sensor's range",
                f.accel_offset_m_s2
            );
        }
        edgekf::systems::oscillator::HarmonicForceEstimator::<f64>::new(&self.estimator_params())
            .map_err(|e| anyhow::anyhow!("the filter cannot be built from this scenario: {e:?}"))?;
        Ok(())
    }

    /// Number of output samples: `round(duration · ODR)`.
    pub fn samples(&self) -> usize {
        let n = (self.duration_s * self.sensor.odr_hz).round();
        if n.is_finite() && n > 0.0 {
            n as usize
        } else {
            0
        }
    }

    /// Runs the reference simulation and the sensor model.
    ///
    /// The x axis reads the mode's acceleration (replaced during a [`Fault::Saturation`], plus
    /// the [`Fault::Offset`]s begun by then) plus noise and bias, clipped; y and z read noise and bias only. The `fault_*` columns carry
    /// the virtual-device faults; they do not alter `ax`.
    pub fn simulate(&self) -> Recording {
        let n = self.samples();
        let osc = Oscillator::new(self.mode, self.force.clone());
        let truth = osc.simulate(0.0, 0.0, self.sensor.odr_hz, n, self.substeps);
        let mut sensor = Adxl355::new(self.sensor, self.seed);
        let mut rec = Recording {
            t: Vec::with_capacity(n),
            ax: Vec::with_capacity(n),
            ay: Vec::with_capacity(n),
            az: Vec::with_capacity(n),
            fault_nack: vec![0; n],
            fault_timeout: vec![0; n],
            fault_garbage: vec![0; n],
            fault_stuck: vec![false; n],
            fault_drop: vec![false; n],
            fault_reset: vec![false; n],
            truth_x: Vec::with_capacity(n),
            truth_v: Vec::with_capacity(n),
            truth_force: Vec::with_capacity(n),
            truth_force_amplitude: Vec::with_capacity(n),
            truth_accel: Vec::with_capacity(n),
        };
        for s in &truth {
            let saturated = self.faults.iter().find_map(|f| match *f {
                Fault::Saturation { accel, .. } if f.covers(s.t) => Some(accel),
                _ => None,
            });
            let offset: f64 = self
                .faults
                .iter()
                .filter_map(|f| match *f {
                    Fault::Offset { t, accel } if s.t >= t - TIME_TOLERANCE => Some(accel),
                    _ => None,
                })
                .sum();
            let [ax, ay, az] = sensor.measure([saturated.unwrap_or(s.a) + offset, 0.0, 0.0]);
            rec.t.push(s.t);
            rec.ax.push(ax);
            rec.ay.push(ay);
            rec.az.push(az);
            rec.truth_x.push(s.x);
            rec.truth_v.push(s.v);
            rec.truth_force.push(s.force);
            rec.truth_force_amplitude.push(self.force.amplitude_phase(s.t).0);
            rec.truth_accel.push(s.a);
        }
        for f in &self.faults {
            let at = f.first_sample(&rec.t);
            match *f {
                Fault::NackBurst { transactions, .. }
                | Fault::Timeout { transactions, .. }
                | Fault::Garbage { transactions, .. } => {
                    let column = match f {
                        Fault::NackBurst { .. } => &mut rec.fault_nack,
                        Fault::Timeout { .. } => &mut rec.fault_timeout,
                        _ => &mut rec.fault_garbage,
                    };
                    if let Some(cell) = at.and_then(|k| column.get_mut(k)) {
                        *cell = cell.saturating_add(transactions);
                    }
                }
                Fault::Reset { .. } => {
                    if let Some(cell) = at.and_then(|k| rec.fault_reset.get_mut(k)) {
                        *cell = true;
                    }
                }
                Fault::Stuck { .. } | Fault::Dropout { .. } => {
                    let column =
                        if matches!(f, Fault::Stuck { .. }) { &mut rec.fault_stuck } else { &mut rec.fault_drop };
                    for (cell, &tk) in column.iter_mut().zip(&rec.t) {
                        if f.covers(tk) {
                            *cell = true;
                        }
                    }
                }
                Fault::Saturation { .. } | Fault::Offset { .. } => {}
            }
        }
        rec
    }

    /// The estimator's parameters: the mode, the drive frequency, the sensor's sample rate and
    /// noise from the sensor model, and the tuning of the `[filter]` table.
    // The struct update is a no-op today; it keeps this compiling with edgekf's defaults when
    // edgekf adds a parameter.
    #[allow(clippy::needless_update)]
    pub fn estimator_params(&self) -> HarmonicForceParams {
        HarmonicForceParams {
            natural_freq_hz: self.mode.natural_freq_hz,
            damping_ratio: self.mode.damping_ratio,
            modal_mass_kg: self.mode.modal_mass_kg,
            drive_rad_s: self.force.drive_rad_s,
            sample_rate_hz: self.sensor.odr_hz,
            accel_noise_std: self.sensor.noise_std(),
            force_psd: self.filter.force_psd,
            motion_psd: self.filter.motion_psd,
            initial_force_std: self.filter.initial_force_std,
            gate_nis: self.filter.gate_nis,
            gate_max_consecutive: self.filter.gate_max_consecutive,
            gain: self.filter.gain.into(),
            // Anything else (e.g. fields added to edgekf later) keeps edgekf's default.
            ..HarmonicForceParams::default()
        }
    }
}

#[cfg(test)]
mod tests;
