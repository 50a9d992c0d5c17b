//! The firmware images, one row each: what `cargo xtask fw`, `bench` and `test` build, run and
//! check. Adding a system adds its row here and nothing else in `xtask`.

/// An instruction budget: kernel label, `n`, `m` (as the bench image prints them) and the most
/// instructions one step may take on the Cortex-M4F.
pub type Budget = (&'static str, usize, usize, u64);

/// The clock the real-time checks assume: an 84 MHz Cortex-M4F (the STM32F411 of the board
/// image) executing one instruction a cycle. Flash wait states and multi-cycle FPU operations
/// come on top, so the checks are a lower bound on the time a sample takes.
pub const CLOCK_HZ: f64 = 84e6;

/// Samples a sensor buffers while the node is busy: the ADXL355's FIFO holds 32 three-axis
/// samples.
pub const FIFO_SAMPLES: f64 = 32.0;

/// A share of a sample's cost: a bench label (with its `n`, `m`) and how many sensor samples
/// one measured step serves (an ADXL355 poll serves 16; a whole crank window 2 500).
pub type Share = (&'static str, usize, usize, u32);

/// How an image keeps up with its sensor, "real time per FIFO block": at [`CLOCK_HZ`], every
/// ordinary sample of every phase fits its sample period, and every occasional costly sample,
/// with the rest of a FIFO block of the costliest ordinary samples, fits the time the sensor
/// takes to fill [`FIFO_SAMPLES`] samples, so that the backlog never exceeds the FIFO.
/// `cargo xtask bench` checks it from the measured counts, from the first sample on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RealTime {
    /// The sensor's sample rate, Hz.
    pub rate_hz: u32,
    /// Each phase's ordinary sample (start-up, steady, ...), as the sum of its shares.
    pub phases: &'static [&'static [Share]],
    /// Occasional samples (their whole cost: a window's end, a re-reduction, a reading of a slow
    /// sensor).
    pub spikes: &'static [(&'static str, usize, usize)],
}

/// What an image is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// A board image: cross-built and sized, not run here.
    Board,
    /// A HIL image: the test targets of `edgekf-tests` that run it (with `--features hil`)
    /// find its ELF in the environment variable `env`.
    Hil {
        /// The environment variable with the ELF's path.
        env: &'static str,
        /// The `--test` targets that run it.
        tests: &'static [&'static str],
    },
    /// The instruction-count image of `cargo xtask bench`.
    Bench,
}

/// One firmware image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Image {
    /// The binary's name.
    pub bin: &'static str,
    /// The `cargo xtask fw` flag that selects it; `None` for the default image.
    pub flag: Option<&'static str>,
    /// Cargo features of `edgekf-firmware` it needs.
    pub features: &'static str,
    /// What it is, for the step messages.
    pub what: &'static str,
    /// What it is for.
    pub role: Role,
    /// Its instruction budgets, measured by the bench image. Why these figures: the oscillator
    /// step must leave most of a 1 kHz sample free; the rotor node's steady-state step must fit
    /// a 1 kHz sample at 84 MHz with room for the I/O and the loop (8 000 instructions, under a
    /// tenth of the 84 000 cycles, where it measures 4 700); the slider-crank estimator samples at 10 kHz (8 400
    /// cycles a sample): an ordinary sample within 200 instructions, a whole 0.25 s window (2 500
    /// samples, the median and the model at its end included) within 300 per sample on average,
    /// under 4 % of the core, and a sample while the release detector looks for the first
    /// contact within 600; the 24-state Joseph-form step is the shared core's reference kernel.
    /// The oscillator node's ADXL355 poll (16 samples, the virtual part's register emulation
    /// included) within 10 000 instructions, under 1 % of its 16 ms period at 84 MHz; a poll
    /// that finds the FIFO empty (the configuration read back) within 1 000, and the one that
    /// re-initialises a part that reset within 2 000: fault handling must not cost a period.
    /// The vehicle's 20-state joint UKF at 50 Hz on an 84 MHz core has 1.68 M cycles a sample;
    /// the issue asks for 30 % headroom at one instruction a cycle, 1.2 M: a sample with the
    /// DVL within that, an ordinary one within 1.1 M. The rotor node's start-up step (its
    /// filter with the start-up term) within 40 000, under half of a 1 kHz sample. The
    /// accelerometer rotor node's (28 states: the probes' 20 and the sensors' low-pass) measures
    /// about 53 500, 64 % of a 1 kHz sample at 84 MHz: within 60 000, which leaves its two
    /// ADXL355 polls and the loop room in the sample (the 40 000 of the issue is the 20-state
    /// probe node's); its steady step (about 6 600) within the probes' 8 000.
    pub budgets: &'static [Budget],
    /// How it keeps up with its sensor (`None`: not checked here; the board image runs the
    /// default image's code).
    pub real_time: Option<RealTime>,
}

/// Every image, in the order `cargo xtask test` builds them.
pub const IMAGES: [Image; 9] = [
    Image {
        bin: "edgekf-board",
        flag: Some("--board"),
        features: "board",
        what: "the board image (STM32F411, ADXL355 on I2C1)",
        role: Role::Board,
        budgets: &[],
        real_time: None,
    },
    Image {
        bin: "edgekf-qemu",
        flag: None,
        features: "qemu",
        what: "the QEMU image (harmonic force on a virtual ADXL355)",
        role: Role::Hil { env: "EDGEKF_FW_ELF", tests: &["hil"] },
        budgets: &[
            ("harmonic_step", 4, 1, 5_000),
            ("adxl_poll", 16, 1, 10_000),
            ("adxl_poll_stall", 16, 1, 1_000),
            ("adxl_poll_reset", 16, 1, 2_000),
        ],
        real_time: Some(RealTime {
            rate_hz: 1000,
            phases: &[&[("harmonic_step", 4, 1, 1), ("adxl_poll", 16, 1, 16)]],
            spikes: &[("adxl_poll_reset", 16, 1)],
        }),
    },
    Image {
        bin: "edgekf-rotor-qemu",
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
        bin: "edgekf-rotor-accel-qemu",
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
    Image {
        bin: "edgekf-crank-qemu",
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
    },
    Image {
        bin: "edgekf-uuv-qemu",
        flag: Some("--uuv"),
        features: "qemu",
        what: "the underwater-vehicle thruster-health QEMU image",
        role: Role::Hil { env: "EDGEKF_UUV_ELF", tests: &["uuv_node"] },
        budgets: &[("uuv_step", 20, 6, 1_100_000), ("uuv_step_dvl", 20, 6, 1_200_000)],
        real_time: Some(RealTime {
            rate_hz: 50,
            phases: &[&[("uuv_step", 20, 6, 1)]],
            spikes: &[("uuv_step_dvl", 20, 6)],
        }),
    },
    Image {
        bin: "edgekf-boom-qemu",
        flag: Some("--boom"),
        features: "qemu",
        what: "the boom tip-vibration QEMU image",
        role: Role::Hil { env: "EDGEKF_BOOM_ELF", tests: &["boom_node"] },
        budgets: &[("boom_step", 14, 2, 65_000), ("boom_rereduce", 14, 2, 18_000_000)],
        real_time: Some(RealTime {
            rate_hz: 100,
            phases: &[&[("boom_step", 14, 2, 1)]],
            spikes: &[("boom_rereduce", 14, 2)],
        }),
    },
    Image {
        bin: "edgekf-soak",
        flag: Some("--soak"),
        features: "qemu",
        what: "the numerical soak image",
        role: Role::Hil { env: "EDGEKF_SOAK_ELF", tests: &["soak_qemu"] },
        budgets: &[],
        real_time: None,
    },
    Image {
        bin: "edgekf-bench",
        flag: Some("--bench"),
        features: "qemu",
        what: "the instruction-count image",
        role: Role::Bench,
        budgets: &[("kalman_joseph", 24, 4, 150_000)],
        real_time: None,
    },
];

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
