//! The oscillator's firmware image, as `cargo xtask` builds, runs and checks it (the default
//! image: `cargo xtask fw` without a flag).

use super::OscillatorImage;
use crate::hil::HilImage;
use crate::manifest::{Image, RealTime, Role};

/// Its images. Budgets: the harmonic-force step must leave most of a 1 kHz sample free; the
/// ADXL355 poll (16 samples, the virtual part's register emulation included) within 10 000
/// instructions, under 1 % of its 16 ms period at 84 MHz; a poll that finds the FIFO empty (the
/// configuration read back) within 1 000, and the one that re-initialises a part that reset
/// within 2 000: fault handling must not cost a period. The window hand-over's ring adds a
/// store a sample (`harmonic_captured`, the step the image runs); a poll's share of the
/// hand-over (64 frames through defmt) is a spike within 100 000, 1.2 ms at 84 MHz.
pub const IMAGES: &[Image] = &[Image {
    bin: OscillatorImage::NAME,
    flag: None,
    features: "qemu",
    what: "the QEMU image (harmonic force on a virtual ADXL355)",
    role: Role::Hil { env: "EDGEKF_FW_ELF", tests: &["hil"] },
    budgets: &[
        ("harmonic_step", 4, 1, 5_000),
        ("harmonic_monitored", 4, 1, 5_000),
        ("harmonic_captured", 4, 1, 5_000),
        ("window_chunk", 4, 1, 100_000),
        ("adxl_poll", 16, 1, 10_000),
        ("adxl_poll_stall", 16, 1, 1_000),
        ("adxl_poll_reset", 16, 1, 2_000),
    ],
    real_time: Some(RealTime {
        rate_hz: 1000,
        phases: &[&[("harmonic_captured", 4, 1, 1), ("adxl_poll", 16, 1, 16)]],
        spikes: &[("adxl_poll_reset", 16, 1), ("harmonic_monitored_window", 4, 1), ("window_chunk", 4, 1)],
    }),
}];
