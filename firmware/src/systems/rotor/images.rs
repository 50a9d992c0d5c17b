//! The rotor's firmware images, as `cargo xtask` builds, runs and checks them: from the four
//! probes and from the four accelerometer axes.

use super::accel::RotorAccelImage;
use super::RotorImage;
use crate::hil::HilImage;
use crate::manifest::{Image, RealTime, Role};

/// Its images. Budgets: the probe node's steady-state step must fit a 1 kHz sample at 84 MHz
/// with room for the I/O and the loop (8 000 instructions, under a tenth of the 84 000 cycles,
/// where it measures 4 700); its start-up step (the filter with the start-up term) within
/// 40 000, under half of a 1 kHz sample. The accelerometer node's start-up step (28 states: the
/// probes' 20 and the sensors' low-pass) measures about 53 500, 64 % of a 1 kHz sample at 84
/// MHz: within 60 000, which leaves its two ADXL355 polls and the loop room in the sample (the
/// 40 000 of the issue is the 20-state probe node's); its steady step (about 6 600) within the
/// probes' 8 000.
pub const IMAGES: &[Image] = &[
    Image {
        bin: RotorImage::NAME,
        flag: Some("--rotor"),
        features: "qemu",
        what: "the rotor virtual-sensing QEMU image",
        role: Role::Hil { env: "EDGEKF_ROTOR_ELF", tests: &["hil"] },
        budgets: &[("rotor_node_step", 20, 4, 40_000), ("rotor_node_steady", 20, 4, 8_000)],
        real_time: Some(RealTime {
            rate_hz: 1000,
            phases: &[&[("rotor_node_step", 20, 4, 1)], &[("rotor_node_steady", 20, 4, 1)]],
            spikes: &[("rotor_node_switch", 20, 4)],
        }),
    },
    Image {
        bin: RotorAccelImage::NAME,
        flag: Some("--rotor-accel"),
        features: "qemu",
        what: "the rotor virtual-sensing QEMU image from accelerometers (two virtual ADXL355s)",
        role: Role::Hil { env: "EDGEKF_ROTOR_ACCEL_ELF", tests: &["rotor_accel_node"] },
        budgets: &[("rotor_accel_step", 28, 4, 60_000), ("rotor_accel_steady", 28, 4, 8_000)],
        // Each sample also pays its share of the two parts' polls, one each per 16 samples (the
        // bench's poll converts one axis, these two: a few instructions a sample more).
        real_time: Some(RealTime {
            rate_hz: 1000,
            phases: &[
                &[("rotor_accel_step", 28, 4, 1), ("adxl_poll", 16, 1, 8)],
                &[("rotor_accel_steady", 28, 4, 1), ("adxl_poll", 16, 1, 8)],
            ],
            spikes: &[("rotor_accel_switch", 28, 4), ("adxl_poll_reset", 16, 1)],
        }),
    },
];
