//! Each system the node runs, one folder per system, and the manifest that registers them.
//!
//! A system's chip code lives in `systems/<name>/`:
//! * `mod.rs`: its [`crate::node::NodeEstimator`], report frames and [`crate::hil::HilImage`]
//!   (further files of the folder as it needs them, e.g. [`rotor::accel`]);
//! * `soak.rs`: its filters' numerical soak rows, `SOAKS` (the engine is [`crate::soak::engine`]);
//! * `bench.rs`: its kernels in the bench image (`edgekf-bench`, QEMU only), whose counts its
//!   image rows' budgets bound;
//! * `images.rs`: its firmware images as `cargo xtask` builds, runs and checks them, `IMAGES`
//!   (binary, flag, HIL tests, instruction budgets, real-time requirement: [`crate::manifest`]);
//! * `generated/`: the constants the host exports for it (`edgekf <name> export`), if any,
//!   which `mod.rs` `include!`s.
//!
//! The manifest below (`systems!`) is the one list of systems: it declares each module and
//! assembles from the systems' own rows [`SOAKS`] (which [`crate::soak::SOAKS`] runs),
//! [`IMAGES`] (which `xtask`'s image table reads) and `bench` (the bench image's kernels), so
//! that no other list in the firmware or `xtask` has to name a new system.
//!
//! Adding a system `<name>` with a QEMU image, outside its own folders (here,
//! `shared/src/systems/<name>/` for what the host runs too, `host-sim/src/systems/<name>/`):
//! 1. its name in the `systems!` list at the end of this file (and its line in the list
//!    below);
//! 2. its image's binary: a `[[bin]]` in `firmware/Cargo.toml` and a new one-line
//!    `firmware/src/bin/<image>/main.rs`, `edgekf_firmware::qemu_image!(…)` (Cargo cannot
//!    generate bin targets);
//! 3. `pub mod <name>;` in `shared/src/systems/mod.rs`, if it has shared code;
//! 4. one row in `host-sim/src/systems/mod.rs` (`REGISTRY`), which gives its command line.
//!
//! A test system (one that a user's build must not carry) sits behind a cargo feature of the
//! firmware named like it: `#[cfg(feature = "<name>")] <name>` in the list, the feature in
//! `firmware/Cargo.toml` (turning on the shared crate's), `required-features` on its binary.
//! The manifest gathers its rows only when the feature is on, lists it in [`OFF`] when it is
//! off (so the folder check still finds it declared), and names the features on in
//! [`FEATURES`], which `xtask` adds to the soak and bench images it builds: they then run the
//! same systems as the table `xtask` was built with. The tests crate turns the
//! features on, so `cargo xtask test` builds and tests them.
//!
//! Nothing in `xtask`: its rows come from `images.rs`. Its HIL tests are a new file in
//! `tests/tests/`, named by its image row, that finds its ELF with
//! `edgekf_tests::qemu::image_elf`; its soak rows run in `tests/tests/soak.rs` and the soak
//! image without an edit. The build checks that every system has `soak::SOAKS`,
//! `images::IMAGES` and (on the chip) `bench::run`; the tests check the rest: every folder here
//! is in the manifest, every system has a soak row, every HIL image has a soak row and a
//! real-time requirement, every image's binary is declared in `firmware/Cargo.toml`, and
//! `cargo xtask bench` fails on a budget that no kernel measures.
//!
//! * [`oscillator`]: the harmonic force driving a structural mode, from one ADXL355 axis;
//! * [`rotor`]: rotor virtual sensing (disk motion and unbalance forces from four probes, or
//!   from four accelerometer axes: [`rotor::accel`]);
//! * [`crank`]: slider-crank joint clearance from the crank angular acceleration;
//! * [`uuv`]: an underwater vehicle's thruster health from its IMU, depth, compass and DVL;
//! * [`boom`]: a telescoping boom's tip vibration from a tip gyro and a root inclinometer;
//! * `sdof` (feature `sdof`, a test system): a base-excited mount's relative motion from one
//!   ADXL355 axis on its mass.

use crate::manifest::{concat, count, Image};
use crate::soak::engine::SoakRow;

/// The manifest: declares each system's module and gathers its rows, in the order given (the
/// order of the soak rows and of `cargo xtask test`'s builds). A system written
/// `#[cfg(feature = "<name>")] <name>` is there only when the firmware's feature is on.
macro_rules! systems {
    ($($(#[cfg(feature = $feature:literal)])? $name:ident),+ $(,)?) => {
        $($(#[cfg(feature = $feature)])? pub mod $name;)+

        /// Every system's module name in this build, in the manifest's order.
        pub const NAMES: &[&str] = &[$($(#[cfg(feature = $feature)])? stringify!($name)),+];

        /// The systems behind a feature that is off in this build.
        pub const OFF: &[&str] = &[$($(#[cfg(not(feature = $feature))] stringify!($name),)?)+];

        /// The features of the systems behind one that are on in this build: `xtask` builds
        /// every image with them.
        pub const FEATURES: &[&str] = &[$($(#[cfg(feature = $feature)] $feature,)?)+];

        const SOAK_PARTS: &[&[SoakRow]] = &[$($(#[cfg(feature = $feature)])? $name::soak::SOAKS),+];

        /// Every system's soak rows, in the manifest's order.
        pub const SOAKS: [SoakRow; count(SOAK_PARTS)] = concat(SOAK_PARTS);

        const IMAGE_PARTS: &[&[Image]] = &[$($(#[cfg(feature = $feature)])? $name::images::IMAGES),+];

        /// Every system's firmware images, in the manifest's order.
        pub const IMAGES: [Image; count(IMAGE_PARTS)] = concat(IMAGE_PARTS);

        /// Every system's kernels in the bench image (`<name>/bench.rs`), in the manifest's
        /// order.
        #[cfg(all(target_os = "none", feature = "qemu"))]
        pub fn bench<M: crate::bench::Markers>() {
            $($(#[cfg(feature = $feature)])? $name::bench::run::<M>();)+
        }
    };
}

systems!(
    oscillator,
    rotor,
    crank,
    uuv,
    boom,
    #[cfg(feature = "sdof")]
    sdof
);
