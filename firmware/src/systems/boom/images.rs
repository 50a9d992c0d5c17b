//! The boom's firmware image, as `cargo xtask` builds, runs and checks it.

use super::BoomImage;
use crate::hil::HilImage;
use crate::manifest::{Image, RealTime, Role};

/// Its images. Budgets: an ordinary 100 Hz sample of both estimators (`boom_step`), and the
/// sample that re-reduces the boom (`boom_rereduce`: three Rayleigh–Ritz reductions in `f64`).
pub const IMAGES: &[Image] = &[Image {
    bin: BoomImage::NAME,
    flag: Some("--boom"),
    features: "qemu",
    what: "the boom tip-vibration QEMU image",
    role: Role::Hil { env: "EDGEKF_BOOM_ELF", tests: &["boom_node"] },
    budgets: &[("boom_step", 14, 2, 65_000), ("boom_monitored", 14, 2, 65_000), ("boom_rereduce", 14, 2, 18_000_000)],
    real_time: Some(RealTime {
        rate_hz: 100,
        phases: &[&[("boom_monitored", 14, 2, 1)]],
        spikes: &[("boom_rereduce", 14, 2), ("boom_monitored_window", 14, 2)],
    }),
}];
