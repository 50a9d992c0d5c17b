//! The numerical soak, once for the host and the chip: every filter the node runs, in `f32`,
//! for many steps on data whose parameters drift slowly, with its soundness figures
//! ([`SoakFrame`]). `tests/tests/soak.rs` runs it on the host (10⁶–10⁷ steps), the image
//! `edgekf-soak` runs the same code under QEMU, and the HIL test compares the two bit for bit.
//!
//! One row per filter in [`SOAKS`], each naming its system (a module of [`crate::systems`])
//! and its HIL image: a test checks that every system module has a row, and `xtask`'s image
//! table test that every HIL image has one, so a new system cannot come without its soak.
//! This module is the registry; [`engine`] is the engine (the frame, the drifts, the block
//! statistics and covariance checks) and names no system: each system's rows and soak code live
//! in its folder, `systems/<name>/soak.rs`, built on the engine alone, and [`joint_ukf`] soaks
//! the shared core's joint UKF, which no system runs as such.
//!
//! The truth comes from each filter's own model with the drift added, in `f32` like the
//! filter: `f64` is soft-float on the Cortex-M4F (~100 instructions an operation) and would
//! make the truth cost many times the filter, leaving the chip far fewer steps in its
//! instruction budget. The truth's rounding (~1e-7 relative a step, on stable models or with
//! the drifting sizes re-imposed every step) is far below its process noise, so what is tested
//! is the filter's `f32` arithmetic over a long run, not a model error. Block statistics and
//! the covariance checks are taken in `f64`.
//!
//! No allocation and no panic path: the image is proven panic-free at link time.

pub mod engine;
pub mod joint_ukf;

pub use engine::{SoakFrame, SoakRow};

use crate::manifest::{concat, count};
use crate::systems;

/// The rows in [`SOAKS`]' order: every system's, in the manifest's order
/// ([`crate::systems::SOAKS`]), then the shared core's.
const PARTS: &[&[SoakRow]] = &[&systems::SOAKS, joint_ukf::SOAKS];

/// Every soak, one row per filter; the index is the frame's `filter`.
pub static SOAKS: [SoakRow; count(PARTS)] = concat(PARTS);

/// Runs soak `index` of [`SOAKS`] for `steps` steps (`None` for an index out of range).
pub fn run(index: usize, steps: u32) -> Option<SoakFrame> {
    let row = SOAKS.get(index)?;
    let mut frame = (row.run)(steps);
    frame.filter = u8::try_from(index).unwrap_or(u8::MAX);
    Some(frame)
}

/// The soak image's input: one line per soak to run, `name steps` (or `name,steps`); lines
/// that do not parse, and names not in [`SOAKS`], are skipped. Calls `each(index, steps)`.
pub fn parse_plan(text: &[u8], mut each: impl FnMut(usize, u32)) {
    for line in text.split(|b| *b == b'\n') {
        let mut fields =
            line.split(|b| *b == b' ' || *b == b',' || *b == b'\r' || *b == b'\t').filter(|f| !f.is_empty());
        let (Some(name), Some(steps)) = (fields.next(), fields.next()) else { continue };
        let Some(index) = SOAKS.iter().position(|r| r.name.as_bytes() == name) else { continue };
        let mut n: u32 = 0;
        let mut ok = true;
        for d in steps {
            match (d.checked_sub(b'0'), n.checked_mul(10)) {
                (Some(v @ 0..=9), Some(m)) => match m.checked_add(u32::from(v)) {
                    Some(s) => n = s,
                    None => ok = false,
                },
                _ => ok = false,
            }
        }
        if ok {
            each(index, n);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every folder of `src/systems` (a system the node runs) is in the manifest, and every
    /// system there has a soak row of its own: a new system cannot come without its soak.
    #[test]
    fn every_system_has_a_soak() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/systems");
        let mut folders = std::vec::Vec::new();
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(std::string::String::from(path.file_name().unwrap().to_str().unwrap()));
            }
        }
        folders.sort();
        // A system behind a feature that is off is declared all the same (`systems::OFF`).
        let declared = systems::NAMES.iter().chain(systems::OFF);
        let mut names: std::vec::Vec<_> = declared.map(|n| std::string::String::from(*n)).collect();
        names.sort();
        assert_eq!(folders, names, "the folders of {} and the manifest (systems!) differ", dir.display());
        assert!(names.len() >= 5, "found only {} systems in {}", names.len(), dir.display());
        for name in systems::NAMES {
            assert!(SOAKS.iter().any(|r| r.system == *name), "system `{name}` has no soak row in SOAKS");
        }
        for (i, r) in SOAKS.iter().enumerate() {
            assert!(SOAKS[..i].iter().all(|o| o.name != r.name), "two rows named {}", r.name);
            assert!(r.system == "core" || systems::NAMES.contains(&r.system), "row {} names no system", r.name);
        }
    }

    #[test]
    fn the_plan_names_soaks_and_their_steps() {
        let mut got = std::vec::Vec::new();
        parse_plan(b"crank 2500\nboom,100\r\nnone 5\nuuv 99999999999\nrotor_node x1\n\n", |i, n| got.push((i, n)));
        let index = |name: &str| SOAKS.iter().position(|r| r.name == name).unwrap();
        assert_eq!(got, [(index("crank"), 2500), (index("boom"), 100)]);
    }
}
