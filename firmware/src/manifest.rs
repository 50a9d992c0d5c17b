//! The firmware images as data: what `cargo xtask` builds, runs and checks for each image. A
//! system's images are rows in its own folder (`systems/<name>/images.rs`), gathered by the
//! manifest in [`crate::systems`]; `xtask` adds the images that belong to no system (the board,
//! the soak and the bench images) and reads the rest from here, so a system's budgets and
//! real-time requirement live with its code. Plain `&'static` data, so the no_std firmware
//! can hold it and the host tools read it as constants.

/// An instruction budget: kernel label, `n`, `m` (as the bench image prints them) and the most
/// instructions one step may take on the Cortex-M4F.
pub type Budget = (&'static str, usize, usize, u64);

/// A share of a sample's cost: a bench label (with its `n`, `m`) and how many sensor samples
/// one measured step serves (an ADXL355 poll serves 16; a whole crank window 2 500).
pub type Share = (&'static str, usize, usize, u32);

/// How an image keeps up with its sensor, "real time per FIFO block": at `xtask`'s clock
/// (84 MHz, one instruction a cycle), every ordinary sample of every phase fits its sample
/// period, and every occasional costly sample, with the rest of a FIFO block of the costliest
/// ordinary samples, fits the time the sensor takes to fill its FIFO, so that the backlog never
/// exceeds the FIFO. `cargo xtask bench` checks it from the measured counts, from the first
/// sample on.
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
    /// The binary's name (for a system's HIL image, its [`crate::hil::HilImage::NAME`]).
    pub bin: &'static str,
    /// The `cargo xtask fw` flag that selects it; `None` for the default image.
    pub flag: Option<&'static str>,
    /// Cargo features of `edgekf-firmware` it needs.
    pub features: &'static str,
    /// What it is, for the step messages.
    pub what: &'static str,
    /// What it is for.
    pub role: Role,
    /// Its instruction budgets, measured by the bench image (each row says why its figures).
    pub budgets: &'static [Budget],
    /// How it keeps up with its sensor (`None`: not checked here).
    pub real_time: Option<RealTime>,
}

/// The number of items in `parts` together: the length of [`concat()`]'s array.
pub const fn count<T>(parts: &[&[T]]) -> usize {
    let mut n = 0;
    let mut i = 0;
    while i < parts.len() {
        n += parts[i].len();
        i += 1;
    }
    n
}

/// `parts` one after the other, at compile time: how the per-system rows become one table.
/// `N` must be [`count`]`(parts)` and at least one part non-empty, else the build fails.
pub const fn concat<T: Copy, const N: usize>(parts: &[&[T]]) -> [T; N] {
    let mut i = 0;
    while parts[i].is_empty() {
        i += 1;
    }
    // Filled with the first item until every place is overwritten.
    let mut out = [parts[i][0]; N];
    let mut k = 0;
    i = 0;
    while i < parts.len() {
        let mut j = 0;
        while j < parts[i].len() {
            out[k] = parts[i][j];
            k += 1;
            j += 1;
        }
        i += 1;
    }
    assert!(k == N, "concat: N is not the number of items");
    out
}
