//! The synthetic machine history the trend is checked on (`host-sim/tests/trend.rs`) and the
//! README's trend figure is drawn from (`cargo run --release -p edgekf-sim --example
//! trend_figure`): 30 recordings of the oscillator's reference simulator (4 s each, ADXL355
//! noise at a seed of its own, the load and its phase varying from one recording to the next),
//! with a second harmonic of the force growing by 0.02 N per recording and an accelerometer
//! offset that appears at recording 20. One generator, so the figure shows what the test checks.

use crate::systems::oscillator::scenario::Scenario;
use crate::systems::oscillator::sim::ExtraHarmonic;
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// Recordings in the history.
pub const RECORDINGS: usize = 30;
/// The recording (numbered from 1) where the offset appears.
pub const OFFSET_FROM: usize = 20;
/// The accelerometer offset from then on, m/s².
pub const OFFSET: f64 = 0.05;
/// The second harmonic's amplitude on recording 1, N, and its growth per recording.
pub const HARMONIC: (f64, f64) = (0.2, 0.02);
/// The declared scenario (the demo's mode, drive and sensor, 4 s): the loop's model.
pub const DECLARED: &str = "duration_s = 4.0\n";

/// Recording `k` (from 1) of the history: its own noise seed, load and phase; the harmonic at
/// its size for `k`; the offset from [`OFFSET_FROM`] on.
pub fn recording(k: usize) -> Scenario {
    let mut s = Scenario { duration_s: 4.0, seed: 1000 + k as u64, ..Scenario::default() };
    // The running conditions: the load between 4 and 6 N, its phase anywhere (golden-ratio
    // steps spread them without a trend of their own).
    let u = (k as f64 * 0.618_034).fract();
    s.force.amplitude_n = 4.0 + 2.0 * u;
    s.force.phase_deg = 360.0 * (k as f64 * 0.381_966).fract();
    let amplitude = HARMONIC.0 + HARMONIC.1 * k.saturating_sub(1) as f64;
    s.force.extra.push(ExtraHarmonic::new(2.0, amplitude, 45.0));
    if k >= OFFSET_FROM {
        s.sensor.bias_m_s2[0] = OFFSET;
    }
    s
}

/// Writes recordings `1..=n` into `root/data/` as `day01.csv`, … and the declared scenario as
/// `root/declared.toml`; returns the data folder and the configuration.
pub fn write_history(root: &Path, n: usize) -> Result<(PathBuf, PathBuf)> {
    let data = root.join("data");
    std::fs::create_dir_all(&data).with_context(|| format!("{}: cannot make the folder", data.display()))?;
    for k in 1..=n {
        let path = data.join(format!("day{k:02}.csv"));
        std::fs::write(&path, recording(k).simulate().to_csv_string())
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    let config = root.join("declared.toml");
    std::fs::write(&config, DECLARED).with_context(|| format!("cannot write {}", config.display()))?;
    Ok((data, config))
}
