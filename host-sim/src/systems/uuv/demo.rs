//! The vehicle's part of `edgekf demo`: a minute of healthy flight whose IMU has a 0.05 m/s²
//! accelerometer offset on z that the declared estimator does not carry (`sensor_biases =
//! false`). The vertical thruster's health factor takes the offset up as a loss of thrust until
//! the loop names it, so the part shows both the finding and the health error it removes.

use super::{simulate, Scenario, SimOptions, UuvConfig};
use crate::cli::demo_loop::{check, close, say, ErrorOf, LoopInputs};
use crate::cli::request::DemoArgs;
use anyhow::Result;

/// The undeclared accelerometer offset on z, m/s².
pub const OFFSET: f64 = 0.05;
/// Length of the flight, s.
pub const DURATION: f64 = 60.0;
/// Noise seed.
pub const SEED: u64 = 5;

/// The configuration the part writes: the shipped REMUS 100 whose simulated IMU has no random
/// biases but the [`OFFSET`] on z (`[sensors]`, which only the simulator reads), and whose
/// estimator has no bias states, so that `edgekf uuv simulate` on it makes the same recording.
pub fn config() -> UuvConfig {
    let mut c = UuvConfig::default();
    (c.sensors.acc_bias, c.sensors.gyro_bias) = (0.0, 0.0);
    c.sensors.acc_offset[2] = OFFSET;
    c.estimator.sensor_biases = false;
    c
}

/// One line saying what was simulated.
pub fn describe() -> String {
    format!(
        "underwater vehicle (REMUS 100), {DURATION} s of healthy flight at 50 Hz, seed {SEED}; undeclared: \
         a {OFFSET} m/s² offset of the accelerometer's z axis (the estimator has no bias states)"
    )
}

/// Runs the part: simulate, close the loop, print the finding and the vertical thruster's
/// health error (k_v RMS) before and after; `--out DIR` writes `uuv/` with the inputs and
/// the report.
pub fn demo(args: &DemoArgs) -> Result<()> {
    check(args, "uuv", &[])?;
    println!("vehicle — {}", describe());
    let config = config();
    let options = SimOptions { scenario: Scenario::Healthy, duration: DURATION, seed: SEED };
    let rec = simulate(&config, &options, &mut |_| {})?;
    let inputs = LoopInputs {
        system: "uuv",
        run: super::cli::close_loop,
        args: |c| c,
        config: config.to_toml(),
        data: rec.to_csv(std::path::Path::new("data.csv"))?,
        extra: Vec::new(),
    };
    let report = close(args, &inputs)?;
    say(args, &report, &ErrorOf { label: "k_v RMS error", unit: "", of: |s| s.error_rms.get("k_v").copied() });
    Ok(())
}
