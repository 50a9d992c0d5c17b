//! The mount's firmware image, as `cargo xtask` builds, runs and checks it (behind the
//! firmware's `sdof` feature, which its `features` name).

use super::SdofImage;
use crate::hil::HilImage;
use crate::manifest::{Image, RealTime, Role};

/// Its image. Budgets (`cargo xtask bench`, 2026-12-06): the 2-state filter's step
/// (`sdof_step`, 709 measured) within 1 000 instructions, about 1 % of a 1 kHz sample at
/// 84 MHz; the start-up's discretisation (`sdof_start`: the Van Loan exponential in software
/// `f64`, once, before the sensor runs; 91 777 measured) within 120 000, under 1.5 ms. Real
/// time: a sample is the step and a sixteenth of the ADXL355 poll (the oscillator's kernels:
/// the same driver), and the poll after a part's reset is the spike.
pub const IMAGES: &[Image] = &[Image {
    bin: SdofImage::NAME,
    flag: Some("--sdof"),
    features: "qemu,sdof",
    what: "the base-excited mount's QEMU image (test system)",
    role: Role::Hil { env: "EDGEKF_SDOF_ELF", tests: &["sdof_node"] },
    budgets: &[("sdof_step", 2, 1, 1_000), ("sdof_start", 2, 1, 120_000)],
    real_time: Some(RealTime {
        rate_hz: 1000,
        phases: &[&[("sdof_step", 2, 1, 1), ("adxl_poll", 16, 1, 16)]],
        spikes: &[("adxl_poll_reset", 16, 1)],
    }),
}];
