//! The firmware images, one row each: what `cargo xtask fw`, `bench` and `test` build, run and
//! check. A system's rows (binary, flag, HIL tests, budgets, real-time requirement) live with
//! its code, `firmware/src/systems/<name>/images.rs`, and come here through the firmware's
//! manifest ([`edgekf_firmware::systems::IMAGES`]): `xtask` is a host tool that already depends
//! on the firmware crate, so reading the rows as constants needs no file format and no
//! generator. Only the images of no system are written here. Adding a system touches nothing
//! in `xtask`.

use edgekf_firmware::manifest::{concat, count};
pub use edgekf_firmware::manifest::{Budget, Image, RealTime, Role};
use edgekf_firmware::systems;

/// The clock the real-time checks assume: an 84 MHz Cortex-M4F (the STM32F411 of the board
/// image) executing one instruction a cycle. Flash wait states and multi-cycle FPU operations
/// come on top, so the checks are a lower bound on the time a sample takes.
pub const CLOCK_HZ: f64 = 84e6;

/// Samples a sensor buffers while the node is busy: the ADXL355's FIFO holds 32 three-axis
/// samples.
pub const FIFO_SAMPLES: f64 = 32.0;

/// The images that belong to no system: the board image (it runs the oscillator's code on the
/// real part), the numerical soak's and the bench's.
const BOARD: Image = Image {
    bin: "edgekf-board",
    flag: Some("--board"),
    features: "board",
    what: "the board image (STM32F411, ADXL355 on I2C1)",
    role: Role::Board,
    budgets: &[],
    real_time: None,
};

const SOAK: Image = Image {
    bin: SOAK_IMAGE,
    flag: Some("--soak"),
    features: "qemu",
    what: "the numerical soak image",
    role: Role::Hil { env: "EDGEKF_SOAK_ELF", tests: &["soak_qemu"] },
    budgets: &[],
    real_time: None,
};

/// The bench image; its one budget is the shared core's reference kernel, the 24-state
/// Joseph-form step (the systems' budgets are in their rows).
const BENCH: Image = Image {
    bin: "edgekf-bench",
    flag: Some("--bench"),
    features: "qemu",
    what: "the instruction-count image",
    role: Role::Bench,
    budgets: &[("kalman_joseph", 24, 4, 150_000)],
    real_time: None,
};

const PARTS: &[&[Image]] = &[&[BOARD], &systems::IMAGES, &[SOAK, BENCH]];

/// Every image, in the order `cargo xtask test` builds them: the board's, every system's from
/// the firmware's manifest ([`edgekf_firmware::systems::IMAGES`]), the soak's and the bench's.
pub const IMAGES: [Image; count(PARTS)] = concat(PARTS);

/// The numerical soak's image: it reads no sensor, and runs every image's filters.
pub const SOAK_IMAGE: &str = "edgekf-soak";

/// The image `cargo xtask fw` builds without a flag (and `cargo xtask run` runs).
pub fn default_image() -> &'static Image {
    IMAGES.iter().find(|i| i.flag.is_none()).unwrap_or(&IMAGES[0])
}

/// The image selected by the first of `args` that is an image flag, or the default one.
pub fn select(args: &[String]) -> &'static Image {
    IMAGES.iter().find(|i| i.flag.is_some_and(|f| args.iter().any(|a| a == f))).unwrap_or_else(default_image)
}

/// The bench image.
pub fn bench_image() -> &'static Image {
    IMAGES.iter().find(|i| i.role == Role::Bench).unwrap_or(&IMAGES[0])
}

/// Every image's real-time requirement, with the image.
pub fn real_time() -> impl Iterator<Item = (&'static Image, &'static RealTime)> {
    IMAGES.iter().filter_map(|i| i.real_time.as_ref().map(|r| (i, r)))
}

/// Every budget of every image.
pub fn budgets() -> impl Iterator<Item = &'static Budget> {
    IMAGES.iter().flat_map(|i| i.budgets.iter())
}

/// The `fw` flags, for the usage line.
pub fn flags() -> String {
    IMAGES.iter().filter_map(|i| i.flag).collect::<Vec<_>>().join(" | ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_is_consistent() {
        assert_eq!(IMAGES.iter().filter(|i| i.flag.is_none()).count(), 1, "exactly one default image");
        assert_eq!(IMAGES.iter().filter(|i| i.role == Role::Bench).count(), 1, "exactly one bench image");
        for (k, a) in IMAGES.iter().enumerate() {
            for b in &IMAGES[k + 1..] {
                assert!(a.bin != b.bin && (a.flag.is_none() || a.flag != b.flag), "{a:?} / {b:?}");
            }
        }
        let arg = |s: &str| vec!["fw".to_string(), s.to_string()];
        assert_eq!(select(&arg("--rotor")).bin, "edgekf-rotor-qemu");
        assert_eq!(select(&arg("--rotor-accel")).bin, "edgekf-rotor-accel-qemu");
        assert_eq!(select(&arg("--crank")).bin, "edgekf-crank-qemu");
        assert_eq!(select(&arg("--board")).bin, "edgekf-board");
        assert_eq!(select(&[]).bin, "edgekf-qemu");
        // Every HIL image states how it keeps up with its sensor (the soak image reads none),
        // and every filter a HIL image runs has its numerical soak (`edgekf_firmware::soak`).
        for i in IMAGES.iter().filter(|i| matches!(i.role, Role::Hil { .. }) && i.bin != SOAK_IMAGE) {
            assert!(i.real_time.is_some(), "{} has no real-time requirement", i.bin);
            assert!(
                edgekf_firmware::soak::SOAKS.iter().any(|r| r.image == Some(i.bin)),
                "{} has no row in edgekf_firmware::soak::SOAKS: its filter is not soaked",
                i.bin
            );
        }
        assert!(IMAGES.iter().any(|i| i.bin == SOAK_IMAGE), "the soak image is in the table");
        // Every bin in the table is one the firmware crate declares.
        let manifest = include_str!("../../firmware/Cargo.toml");
        for i in &IMAGES {
            assert!(manifest.contains(&format!("name = \"{}\"", i.bin)), "{} is not a firmware binary", i.bin);
        }
    }
}
