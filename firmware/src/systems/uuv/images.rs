//! The underwater vehicle's firmware image, as `cargo xtask` builds, runs and checks it.

use super::UuvImage;
use crate::hil::HilImage;
use crate::manifest::{Image, RealTime, Role};

/// Its images. Budgets: the 20-state joint UKF at 50 Hz on an 84 MHz core has 1.68 M cycles a
/// sample; the issue asks for 30 % headroom at one instruction a cycle, 1.2 M: a sample with
/// the DVL within that, an ordinary one within 1.1 M; the same with the model monitor on its
/// eleven channels (`uuv_monitored*`, the image's sample), and the sample that closes the
/// monitor's windows (with a DVL reading: the costliest).
pub const IMAGES: &[Image] = &[Image {
    bin: UuvImage::NAME,
    flag: Some("--uuv"),
    features: "qemu",
    what: "the underwater-vehicle thruster-health QEMU image",
    role: Role::Hil { env: "EDGEKF_UUV_ELF", tests: &["uuv_node"] },
    budgets: &[
        ("uuv_step", 20, 6, 1_100_000),
        ("uuv_step_dvl", 20, 6, 1_200_000),
        ("uuv_monitored", 20, 6, 1_100_000),
        ("uuv_monitored_dvl", 20, 6, 1_200_000),
        ("uuv_monitored_window", 20, 6, 1_200_000),
    ],
    real_time: Some(RealTime {
        rate_hz: 50,
        phases: &[&[("uuv_monitored", 20, 6, 1)]],
        spikes: &[("uuv_monitored_dvl", 20, 6), ("uuv_monitored_window", 20, 6)],
    }),
}];
