//! The `edgekf demo`: simulate a scenario, run the harmonic-force estimator over it in `f64`
//! (the host reference) and in `f32` (as the sensor node runs it), and summarise.
//!
//! ```
//! use edgekf_sim::systems::oscillator::demo::Demo;
//! use edgekf_sim::systems::oscillator::scenario::Scenario;
//! let demo = Demo::run(&Scenario { duration_s: 3.0, ..Default::default() }).unwrap();
//! assert!((demo.f64.mean_force_amplitude(1.5, 3.0).unwrap() - 5.0).abs() < 0.01);
//! assert!(demo.summary().to_string().contains("force amplitude, mean 1.5–3 s [N]"));
//! ```

use crate::io::data::DataFile;
use crate::systems::oscillator::estimate::{self, EstimateOptions, Estimates};
use crate::systems::oscillator::report::{steady_windows, Summary};
use crate::systems::oscillator::scenario::{Gain, Recording, Scenario};
use anyhow::Context as _;
use std::path::Path;

/// A finished demo run.
#[derive(Debug, Clone)]
pub struct Demo {
    /// The scenario.
    pub scenario: Scenario,
    /// What the simulator produced.
    pub recording: Recording,
    /// The recording as a data file (what `data.csv` holds).
    pub data: DataFile,
    /// The estimator in `f64`.
    pub f64: Estimates,
    /// The estimator in `f32`.
    pub f32: Estimates,
}

impl Demo {
    /// Simulates `scenario` and runs both precisions. Readings at the sensor's full scale count
    /// as missing (clipped).
    pub fn run(scenario: &Scenario) -> anyhow::Result<Self> {
        scenario.validate()?;
        let recording = scenario.simulate();
        let data = recording.to_data_file();
        let params = scenario.estimator_params();
        let opts = EstimateOptions { clip_level: Some(scenario.sensor.range_m_s2()), ..Default::default() };
        let f64 = estimate::run::<f64>(&data, &params, &opts)?;
        let f32 = estimate::run::<f32>(&data, &params, &opts)?;
        Ok(Self { scenario: scenario.clone(), recording, data, f64, f32 })
    }

    /// The summary table, titled with the scenario.
    pub fn summary(&self) -> Summary<'_> {
        let s = &self.scenario;
        let t_end = self.data.t.last().copied().unwrap_or(0.0) + 1.0 / s.sensor.odr_hz;
        Summary {
            title: format!("{}\n{}", describe(s), describe_run(s)),
            data: &self.data,
            runs: vec![("f64", &self.f64), ("f32", &self.f32)],
            windows: steady_windows(&s.force, 0.0, t_end),
            noise_std: Some(s.sensor.noise_std()),
        }
    }

    /// Writes `data.csv` (the recording), `est.csv` (the `f64` estimates) and `est_f32.csv` into
    /// `dir`, creating it if needed.
    pub fn write(&self, dir: &Path) -> anyhow::Result<()> {
        std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create directory", dir.display()))?;
        self.recording.write_csv(&dir.join("data.csv"))?;
        self.f64.write_csv(&dir.join("est.csv"))?;
        self.f32.write_csv(&dir.join("est_f32.csv"))?;
        Ok(())
    }
}

/// Three heading lines describing a scenario's model: the mode and force, the sensor, the filter.
pub fn describe(s: &Scenario) -> String {
    let f = &s.force;
    let mut force = format!("{} N at {}°", f.amplitude_n, f.phase_deg);
    for c in &f.changes {
        let what: Vec<String> = [c.amplitude_n.map(|a| format!("{a} N")), c.phase_deg.map(|p| format!("{p}°"))]
            .into_iter()
            .flatten()
            .collect();
        force.push_str(&format!(" → {} at {} s", what.join(" "), c.t));
    }
    if !f.extra.is_empty() {
        force.push_str(&format!(" + {} extra harmonic(s)", f.extra.len()));
    }
    let t = &s.filter;
    let gain = match t.gain {
        Gain::SteadyState => "steady-state gain".to_string(),
        Gain::TimeVarying => format!("time-varying gain (prior force std {} m/s²)", t.initial_force_std),
    };
    let gate = if t.gate_nis > 0.0 { format!("NIS gate {}", t.gate_nis) } else { "no gate".into() };
    format!(
        "mode {} Hz, ζ = {}, {} kg; force {force} ({} s transitions) at {} rad/s ({:.2} Hz)\n\
         ADXL355 at {} Hz, ±{} g: noise σ = {:.3} mm/s² per sample\n\
         filter: {gain}, force_psd {:e}, motion_psd {:e} (m/s²)²/s, {gate}",
        s.mode.natural_freq_hz,
        s.mode.damping_ratio,
        s.mode.modal_mass_kg,
        f.transition_s,
        f.drive_rad_s,
        f.drive_rad_s / (2.0 * std::f64::consts::PI),
        s.sensor.odr_hz,
        s.sensor.range_g,
        s.sensor.noise_std() * 1e3,
        t.force_psd,
        t.motion_psd,
    )
}

/// One line describing a scenario's run: duration, samples, seed and faults.
pub fn describe_run(s: &Scenario) -> String {
    format!("{} s, {} samples, seed {}, {} fault(s)", s.duration_s, s.samples(), s.seed, s.faults.len())
}
