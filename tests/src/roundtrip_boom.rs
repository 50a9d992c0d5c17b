//! The boom's round trip (issue #36), as `cargo xtask roundtrip boom` runs it: the QEMU image
//! on a luffing recording whose platform is heavier than the shipped configuration's → its
//! `mismatch` frames → `edgekf loop boom --corrected-config` → `edgekf boom export` → the
//! image rebuilt with the corrected constants (`EDGEKF_BOOM_MODEL`, files under
//! `target/roundtrip/boom/`, never the committed one) → a fresh recording (another seed, the
//! same platform) on which its error must come within 1.5× a node built with the true
//! configuration's.
//!
//! The loop runs on the recording the node uploads, not on a window the node keeps: the boom's
//! loop needs the whole luffing run (its stops and free decays) and the static record taken at
//! rest, which 100 Hz of four channels for minutes would not fit in the node's RAM beside
//! its filter. Every `edgekf` step is the CLI's own code, on files.

use crate::roundtrip::{arg, edgekf, node_run, Fresh, NodeRun, Rebuilds};
use anyhow::{anyhow, bail, Result};
use edgekf_firmware::systems::boom::{BoomFrame, SAMPLE_RATE_HZ};
use edgekf_sim::io::config_edit::{corrected, ConfigEdit, Op};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Seconds at the start of a run left out of the errors (the filter starts from rest).
const SETTLE_S: f64 = 2.0;

/// What the round trip runs.
#[derive(Debug, Clone, PartialEq)]
pub struct BoomSetup {
    /// Where every file goes (emptied first).
    pub dir: PathBuf,
    /// The platform's mass and rotary inertia, as a factor on the shipped configuration's.
    pub factor: f64,
    /// The recordings' length, s.
    pub duration_s: f64,
    /// The first recording's seed and the fresh one's.
    pub seeds: (u64, u64),
}

impl BoomSetup {
    /// A platform 1.3 times the shipped one (390 kg), 120 s of luffing at seed 2, fresh at 3.
    pub fn new(dir: PathBuf) -> Self {
        Self { dir, factor: 1.3, duration_s: 120.0, seeds: (2, 3) }
    }
}

/// What the boom's round trip measured.
#[derive(Debug, Clone, PartialEq)]
pub struct BoomFigures {
    /// The true platform mass, kg.
    pub true_mass: f64,
    /// The shipped node on the first recording.
    pub alarm: NodeRun,
    /// The effects the loop added on it.
    pub effects: Vec<String>,
    /// The corrected configuration's `[tip] mass`, kg.
    pub corrected_mass: f64,
    /// The fresh recording, the reruns and the time.
    pub fresh: Fresh,
}

impl BoomFigures {
    /// Whether the round trip did what it must: the shipped node flags the inclinometer's
    /// channel, the loop names the platform's mass within 5 %, and [`Fresh::check`]: the
    /// corrected node tracks within 1.5× the true node (and better than the shipped one) and
    /// raises no `mismatch` the true node does not (none on the inclinometer's channel; the gyro's CUSUM
    /// alarms on every run, healthy ones too: see `firmware/src/systems/boom/mod.rs`), and the
    /// corrected configuration adds nothing on either recording.
    pub fn check(&self) -> Result<()> {
        if self.alarm.on(1) == 0 {
            bail!("the shipped node raised no mismatch on the inclinometer's channel: {:?}", self.alarm.mismatches);
        }
        let rel = (self.corrected_mass - self.true_mass).abs() / self.true_mass;
        if self.effects.len() != 1 || !self.effects[0].starts_with("parameter at tip") || rel > 0.05 {
            bail!(
                "the loop named {:?} (mass {} kg), not the platform near {} kg",
                self.effects,
                self.corrected_mass,
                self.true_mass
            );
        }
        // The gyro's channel (0) is not watched: its CUSUM alarms on healthy runs too.
        self.fresh.check(&[1])?;
        Ok(())
    }
}

impl std::fmt::Display for BoomFigures {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let rate = f64::from(SAMPLE_RATE_HZ);
        let a = &self.alarm;
        writeln!(
            f,
            "platform {} kg; the shipped node's first mismatch: gyro (channel 0) {}, inclinometer (channel 1) {}",
            self.true_mass,
            a.first_on(0, rate),
            a.first_on(1, rate)
        )?;
        writeln!(
            f,
            "the loop on the uploaded recording: {}; corrected [tip] mass = {:.1} kg",
            self.effects.join(", "),
            self.corrected_mass
        )?;
        let run = |r: &NodeRun| format!("{:.3} mm ({}/{})", r.error * 1e3, r.on(0), r.on(1));
        let what = format!("tip-vibration RMS error after {SETTLE_S} s (mismatch frames gyro/inclinometer)");
        self.fresh.write(f, &what, run)
    }
}

/// Runs `elf` on `csv` in QEMU; its tip-vibration error (m) against the recording's truth.
fn node(elf: &Path, csv: &Path) -> Result<NodeRun> {
    node_run::<BoomFrame>(elf, csv, ("truth_tip_vibration", SETTLE_S), |b| (b.sample, f64::from(b.vibration)))
}

/// `edgekf loop boom` with `config` on `data` (the run and its static record), its report in
/// `dir/name/`; the effects.
fn close_loop(
    dir: &Path,
    name: &str,
    config: &Path,
    data: (&Path, &Path),
    corrected: Option<&Path>,
) -> Result<Vec<String>> {
    let args = ["boom", "--config", arg(config), "--data", arg(data.0), "--static", arg(data.1)];
    crate::roundtrip::close_loop(dir, name, &args, corrected)
}

/// The round trip of `setup` from the `shipped` image; `build` cross-builds the boom's image
/// with a constants file and returns its ELF (copied here: the next build lands on the same
/// path). The workspace's boom image is then the last one built until the next `cargo xtask`
/// build rebuilds it (`EDGEKF_BOOM_MODEL` changed).
pub fn boom(setup: &BoomSetup, shipped: &Path, build: &dyn Fn(&Path) -> Result<PathBuf>) -> Result<BoomFigures> {
    let started = Instant::now();
    let dir = &setup.dir;
    crate::roundtrip::empty(dir)?;
    let file = |name: &str| dir.join(name);
    let text = std::fs::read_to_string(crate::cross::workspace_root().join("host-sim/configs/boom_ladder30.toml"))?;
    let declared = file("shipped.toml");
    std::fs::write(&declared, &text)?;
    let heavier = ["tip.mass", "tip.rotary_inertia"]
        .map(|k| ("heavier platform".to_string(), ConfigEdit::new(k, Op::Scale(setup.factor))));
    let true_toml = file("true.toml");
    std::fs::write(&true_toml, corrected(&text, &heavier).map_err(|e| anyhow!("{e}"))?)?;
    let true_mass = edgekf_sim::systems::boom::BoomConfig::load(&true_toml)?.tip.mass;
    let mut recordings = Vec::new();
    for (name, seed) in [("alarm", setup.seeds.0), ("fresh", setup.seeds.1)] {
        let (csv, statics) = (file(&format!("{name}.csv")), file(&format!("{name}_static.csv")));
        let (duration, seed) = (format!("{}", setup.duration_s), seed.to_string());
        edgekf(&[
            "boom",
            "simulate",
            "--config",
            arg(&true_toml),
            "--scenario",
            "luffing",
            "--duration",
            &duration,
            "--seed",
            &seed,
            "--out",
            arg(&csv),
            "--static",
            arg(&statics),
        ])?;
        recordings.push((csv, statics));
    }
    let [(alarm_csv, alarm_static), (fresh_csv, fresh_static)] =
        <[_; 2]>::try_from(recordings).map_err(|_| anyhow!("two recordings"))?;
    let images = Rebuilds { dir, system: "boom", build };
    let shipped = images.copy(shipped, "shipped.elf")?;
    let true_elf = images.image(&true_toml, "true")?;

    // The alarm, the loop on the uploaded recording, the corrected constants.
    let alarm = node(&shipped, &alarm_csv)?;
    let fixed = file("fixed.toml");
    let effects = close_loop(dir, "report", &declared, (&alarm_csv, &alarm_static), Some(&fixed))?;
    let corrected_mass = edgekf_sim::systems::boom::BoomConfig::load(&fixed)?.tip.mass;
    let corrected_elf = images.image(&fixed, "corrected")?;

    let nodes = [node(&shipped, &fresh_csv)?, node(&corrected_elf, &fresh_csv)?, node(&true_elf, &fresh_csv)?];
    let on_first = close_loop(dir, "rerun_first", &fixed, (&alarm_csv, &alarm_static), None)?;
    let on_fresh = close_loop(dir, "rerun_fresh", &fixed, (&fresh_csv, &fresh_static), None)?;
    let fresh = Fresh { nodes, rerun_adds: (on_first, on_fresh), seconds: started.elapsed().as_secs_f64() };
    Ok(BoomFigures { true_mass, alarm, effects, corrected_mass, fresh })
}
