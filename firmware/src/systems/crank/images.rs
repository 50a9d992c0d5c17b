//! The slider-crank's firmware image, as `cargo xtask` builds, runs and checks it.

use super::CrankImage;
use crate::hil::HilImage;
use crate::manifest::{Image, RealTime, Role};

/// Its images. Budgets: the estimator samples at 10 kHz (8 400 cycles a sample at 84 MHz): an
/// ordinary sample within 200 instructions, a whole 0.25 s window (2 500 samples, the median
/// and the model at its end included) within 300 per sample on average, under 4 % of the core,
/// and a sample while the release detector looks for the first contact within 600.
pub const IMAGES: &[Image] = &[Image {
    bin: CrankImage::NAME,
    flag: Some("--crank"),
    features: "qemu",
    what: "the slider-crank clearance QEMU image",
    role: Role::Hil { env: "EDGEKF_CRANK_ELF", tests: &["crank_node"] },
    budgets: &[
        ("crank_sample", 2500, 1, 200),
        ("crank_window", 2500, 1, 750_000),
        ("crank_release_sample", 2500, 1, 600),
    ],
    real_time: Some(RealTime {
        rate_hz: 10_000,
        phases: &[
            &[("crank_release_sample", 2500, 1, 1)],
            &[("crank_sample", 2500, 1, 1)],
            &[("crank_window", 2500, 1, 2500)],
        ],
        spikes: &[("crank_window_end", 2500, 1)],
    }),
}];
