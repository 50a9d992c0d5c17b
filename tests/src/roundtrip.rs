//! The oscillator's round trip (issue #36), end to end, as `cargo xtask roundtrip oscillator`
//! and `tests/roundtrip.rs` run it: the QEMU image on a recording whose accelerometer offset
//! starts mid-run (the scenario's `offset` fault) → its `mismatch` frame → the window it hands
//! over → `edgekf capture` → `edgekf loop oscillator --corrected-config` → `edgekf oscillator
//! export` → the image rebuilt with the corrected constants (`EDGEKF_OSCILLATOR_MODEL`, files
//! under `target/roundtrip/`, never the committed one) → a fresh recording (another seed, the
//! offset there from the start) on which it must raise no `mismatch` and track the truth within
//! 1.5× a node built with the true configuration. Every `edgekf` step is the CLI's own code
//! ([`edgekf_sim::cli::run_with`]), on files, as a user would run it.

use crate::qemu;
use crate::report::{frame, RunReport};
use anyhow::{anyhow, bail, Context, Result};
use edgekf_firmware::frame::Frame;
use edgekf_firmware::monitor::MismatchFrame;
use edgekf_firmware::systems::oscillator::BlockReport;
use edgekf_sim::systems::oscillator::scenario::Scenario;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Samples a poll reads (the ADXL355's 16-sample watermark).
const BLOCK: usize = 16;
/// Seconds at the start of a run left out of the errors (the node starts from rest).
const SETTLE_S: f64 = 1.0;
/// How much worse than the true-configuration node the corrected one may track.
pub const ERROR_RATIO_LIMIT: f64 = 1.5;

/// What the round trip runs: the offset, when it starts, the recordings' lengths and seeds.
#[derive(Debug, Clone, PartialEq)]
pub struct Setup {
    /// Where every file goes (emptied first).
    pub dir: PathBuf,
    /// The accelerometer's offset, m/s².
    pub offset_m_s2: f64,
    /// When it starts in the first recording, s.
    pub onset_s: f64,
    /// The first recording's length, s: the alarm, then the window (about 4.4 s after the
    /// change's date) and its hand-over (about 1 s) must fit.
    pub duration_s: f64,
    /// The first recording's seed.
    pub seed: u64,
    /// The fresh recording's length, s, and seed.
    pub fresh: (f64, u64),
}

impl Setup {
    /// 0.05 m/s² (ten noise standard deviations) from 4 s of an 11 s run, seed 11; the fresh
    /// run 8 s at seed 12; files in `dir`.
    pub fn oscillator(dir: PathBuf) -> Self {
        Self { dir, offset_m_s2: 0.05, onset_s: 4.0, duration_s: 11.0, seed: 11, fresh: (8.0, 12) }
    }

    /// A scenario file: the demo's oscillator with its force held at 5 N (the model's), `run`
    /// seconds at `seed`, an offset fault from `fault` s if given, and the filter's declared
    /// offset if given.
    fn scenario(&self, (run, seed): (f64, u64), fault: Option<f64>, declared: Option<f64>) -> String {
        let mut s = format!(
            "# The round trip's oscillator: the demo's mode and drive, the force held at 5 N.\n\
             duration_s = {run:?}\nseed = {seed}\n\n[force]\namplitude_n = 5.0\n"
        );
        if let Some(offset) = declared {
            s.push_str(&format!("\n[filter]\naccel_offset_m_s2 = {offset:?}\n"));
        }
        if let Some(t) = fault {
            s.push_str(&format!("\n[[faults]]\nkind = \"offset\"\nt = {t:?}\naccel = {:?}\n", self.offset_m_s2));
        }
        s
    }
}

/// What the round trip measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Figures {
    /// The offset's start, s.
    pub onset_s: f64,
    /// The end of the poll whose `mismatch` frame came first, s.
    pub alarm_s: f64,
    /// That frame.
    pub mismatch: MismatchFrame,
    /// The captured window's first and last sample times, s.
    pub window_s: (f64, f64),
    /// The effects the loop added on the window, `kind at location = value unit`.
    pub effects: Vec<String>,
    /// The corrected configuration's `[filter] accel_offset_m_s2`, m/s².
    pub corrected_offset: f64,
    /// On the fresh recording, each node's displacement RMS error against `truth_x` after
    /// 1 s (m) and its `mismatch` frames: the shipped node, the corrected one, the true one.
    pub fresh: [(f64, usize); 3],
    /// Effects the loop adds with the corrected configuration on the window, and on the fresh
    /// recording.
    pub rerun_adds: (Vec<String>, Vec<String>),
    /// Wall-clock seconds of the whole round trip.
    pub seconds: f64,
}

impl Figures {
    /// Whether the round trip did what it must: an alarm after the onset, one effect named (a
    /// sensor bias on `ax` within 20 % of the truth), no `mismatch` from the corrected node and
    /// an error within [`ERROR_RATIO_LIMIT`] of the true node's (and below the shipped node's),
    /// and the corrected configuration adding nothing on either recording.
    pub fn check(&self, offset: f64) -> Result<()> {
        let [(before, _), (after, after_alarms), (truth, _)] = self.fresh;
        let rel = (self.corrected_offset - offset).abs() / offset;
        if self.alarm_s < self.onset_s {
            bail!("the alarm at {:.3} s came before the offset at {} s", self.alarm_s, self.onset_s);
        }
        if self.effects.len() != 1 || !self.effects[0].starts_with("sensor_bias at ax") || rel > 0.2 {
            bail!(
                "the loop named {:?} (offset {}), not one sensor bias near {offset}",
                self.effects,
                self.corrected_offset
            );
        }
        if after_alarms != 0 {
            bail!("the corrected node raised {after_alarms} mismatch frame(s) on the fresh recording");
        }
        if after > ERROR_RATIO_LIMIT * truth || after >= before {
            bail!("corrected node's error {after:.3e} m against the true node's {truth:.3e} m and the shipped {before:.3e} m");
        }
        if !self.rerun_adds.0.is_empty() || !self.rerun_adds.1.is_empty() {
            bail!(
                "the corrected configuration still adds {:?} on the window, {:?} on the fresh run",
                self.rerun_adds.0,
                self.rerun_adds.1
            );
        }
        Ok(())
    }
}

impl std::fmt::Display for Figures {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let m = &self.mismatch;
        let statistic = m.statistic().map_or("unknown", |s| s.name());
        let [(before, b), (after, a), (truth, t)] = self.fresh;
        writeln!(f, "offset from t = {} s; the node's first alarm at {:.3} s ({:.3} s later): {statistic} on channel {}, since sample {}",
            self.onset_s, self.alarm_s, self.alarm_s - self.onset_s, m.channel, m.since)?;
        writeln!(f, "window handed over: t = {:.3} … {:.3} s", self.window_s.0, self.window_s.1)?;
        writeln!(
            f,
            "the loop on the window: {}; corrected [filter] accel_offset_m_s2 = {:.5} m/s²",
            self.effects.join(", "),
            self.corrected_offset
        )?;
        writeln!(f, "fresh recording, displacement RMS error after {SETTLE_S} s (mismatch frames): shipped node {:.3} µm ({b}), corrected node {:.3} µm ({a}), true-config node {:.3} µm ({t}); corrected/true = {:.3}",
            before * 1e6, after * 1e6, truth * 1e6, after / truth)?;
        writeln!(
            f,
            "the loop with the corrected configuration adds: on the window {:?}, on the fresh recording {:?}",
            self.rerun_adds.0, self.rerun_adds.1
        )?;
        write!(f, "round trip: {:.0} s", self.seconds)
    }
}

/// Runs `edgekf` with `args` (the CLI's own dispatcher, in this process).
pub(crate) fn edgekf(args: &[&str]) -> Result<()> {
    let line = std::iter::once("edgekf").chain(args.iter().copied());
    edgekf_sim::cli::run_with(edgekf_sim::systems::REGISTRY, line).with_context(|| format!("edgekf {}", args.join(" ")))
}

/// The path as an argument.
pub(crate) fn arg(p: &Path) -> &str {
    p.to_str().unwrap_or_default()
}

/// Runs `elf` on `csv` in QEMU; its decoded lines.
fn node(elf: &Path, csv: &Path) -> Result<Vec<String>> {
    let input = std::fs::read(csv).with_context(|| format!("reading {}", csv.display()))?;
    let run = qemu::run(elf, &input, Duration::from_secs(600))?;
    if let Some(msg) = run.failure() {
        bail!(msg);
    }
    Ok(run.lines)
}

/// The first `mismatch` frame of a run and the end of the poll it followed, s.
fn first_alarm(lines: &[String], rate: f64) -> Result<Option<(f64, MismatchFrame)>> {
    let mut block = None;
    for line in lines {
        if let Some(b) = frame::<BlockReport>(line)? {
            block = Some(b.block);
        } else if let Some(m) = frame::<MismatchFrame>(line)? {
            let polls = block.map_or(0, |b| b + 1);
            return Ok(Some((f64::from(polls) * BLOCK as f64 / rate, m)));
        }
    }
    Ok(None)
}

/// The RMS of a run's block displacements against `truth_x` at each block's last sample, after
/// [`SETTLE_S`].
fn displacement_error(run: &RunReport, scenario: &Scenario) -> Result<f64> {
    let rec = scenario.simulate();
    let (mut sum, mut n) = (0.0, 0usize);
    for b in &run.blocks {
        let last = (b.block as usize + 1) * BLOCK - 1;
        let (Some(&t), Some(&x)) = (rec.t.get(last), rec.truth_x.get(last)) else { continue };
        if t >= SETTLE_S {
            sum += (f64::from(b.displacement) - x).powi(2);
            n += 1;
        }
    }
    if n == 0 {
        bail!("no block after {SETTLE_S} s");
    }
    Ok((sum / n as f64).sqrt())
}

/// The effects a loop report (`dir/report.json`) added, as `kind at location = value unit`.
fn effects_added(dir: &Path) -> Result<Vec<String>> {
    let path = dir.join("report.json");
    let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let json: serde_json::Value = serde_json::from_str(&text)?;
    let added = json["effects_added"].as_array().ok_or_else(|| anyhow!("{}: no effects_added", path.display()))?;
    Ok(added
        .iter()
        .map(|e| {
            format!(
                "{} at {} = {:.5} {}",
                e["kind"].as_str().unwrap_or("?"),
                e["location"].as_str().unwrap_or("?"),
                e["value"].as_f64().unwrap_or(f64::NAN),
                e["unit"].as_str().unwrap_or("")
            )
        })
        .collect())
}

/// `edgekf loop` with `args` (the system, its configuration and data), `--quiet`, its report
/// in `dir/name/` and the corrected configuration written to `corrected` if given; the effects
/// it added.
pub(crate) fn close_loop(dir: &Path, name: &str, args: &[&str], corrected: Option<&Path>) -> Result<Vec<String>> {
    let report = dir.join(name);
    std::fs::create_dir_all(&report)?;
    let mut all = vec!["loop"];
    all.extend_from_slice(args);
    all.extend(["--quiet", "--report", arg(&report)]);
    if let Some(c) = corrected {
        all.extend(["--corrected-config", arg(c)]);
    }
    edgekf(&all)?;
    effects_added(&report)
}

/// One node's run on a recording: its RMS error against the recording's truth after a
/// settling time (in the unit of the estimate it was taken on), and its `mismatch` frames with
/// the sample each followed.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeRun {
    /// RMS of the estimate against its truth column.
    pub error: f64,
    /// `(sample, frame)` of each `mismatch`.
    pub mismatches: Vec<(u32, MismatchFrame)>,
}

impl NodeRun {
    /// Its mismatch frames on `channel`.
    pub fn on(&self, channel: u8) -> usize {
        self.mismatches.iter().filter(|(_, m)| m.channel == channel).count()
    }

    /// Its first mismatch on `channel` as `statistic at s (since sample n)`, or `none`.
    pub fn first_on(&self, channel: u8, rate: f64) -> String {
        self.mismatches.iter().find(|(_, m)| m.channel == channel).map_or("none".to_string(), |(s, m)| {
            let statistic = m.statistic().map_or("unknown", |s| s.name());
            format!("{statistic} at {:.2} s (since sample {})", f64::from(*s) / rate, m.since)
        })
    }
}

/// The part of a round trip's figures every system with a model monitor shares: the three
/// nodes on the fresh recording, what the loop adds with the corrected configuration, the time.
#[derive(Debug, Clone, PartialEq)]
pub struct Fresh {
    /// On the fresh recording: the shipped node, the corrected one, the true one.
    pub nodes: [NodeRun; 3],
    /// Effects the loop adds with the corrected configuration on the first recording and on
    /// the fresh one.
    pub rerun_adds: (Vec<String>, Vec<String>),
    /// Wall-clock seconds of the whole round trip.
    pub seconds: f64,
}

impl Fresh {
    /// The corrected node tracks within [`ERROR_RATIO_LIMIT`] of the true node (and better than
    /// the shipped one), raises no `mismatch` on the `watched` channels (the effect's) nor any
    /// (channel, statistic) the true node does not, and the corrected configuration adds
    /// nothing on either recording.
    pub fn check(&self, watched: &[u8]) -> Result<()> {
        let [before, after, truth] = &self.nodes;
        if after.error > ERROR_RATIO_LIMIT * truth.error || after.error >= before.error {
            bail!(
                "corrected node's error {:.4e} against the true node's {:.4e} and the shipped {:.4e}",
                after.error,
                truth.error,
                before.error
            );
        }
        let raised = |r: &NodeRun| r.mismatches.iter().map(|(_, m)| (m.channel, m.statistic)).collect::<Vec<_>>();
        let on_watched = watched.iter().any(|&c| after.on(c) != 0);
        if on_watched || raised(after).iter().any(|m| !raised(truth).contains(m)) {
            bail!("the corrected node raised {:?}, the true node {:?}", after.mismatches, truth.mismatches);
        }
        if !self.rerun_adds.0.is_empty() || !self.rerun_adds.1.is_empty() {
            bail!("the corrected configuration still adds {:?} / {:?}", self.rerun_adds.0, self.rerun_adds.1);
        }
        Ok(())
    }

    /// The figures' last lines: `what` says which error, `run` shows one node's run.
    pub fn write(
        &self,
        f: &mut std::fmt::Formatter<'_>,
        what: &str,
        run: impl Fn(&NodeRun) -> String,
    ) -> std::fmt::Result {
        let [b, c, t] = &self.nodes;
        writeln!(
            f,
            "fresh recording, {what}: shipped node {}, corrected {}, true-config {}; corrected/true = {:.3}",
            run(b),
            run(c),
            run(t),
            c.error / t.error
        )?;
        writeln!(
            f,
            "the loop with the corrected configuration adds: on the first recording {:?}, on the fresh one {:?}",
            self.rerun_adds.0, self.rerun_adds.1
        )?;
        write!(f, "round trip: {:.0} s", self.seconds)
    }
}

/// Runs `elf` on `csv` in QEMU: each per-sample frame `F` gives `(sample, estimate)` through
/// `estimate`, compared with the recording's column `truth` from `settle_s` on (a NaN
/// estimate counts as missed, not as zero error: the run fails if any is); the `mismatch`
/// frames are kept with the sample they followed.
pub(crate) fn node_run<F: Frame>(
    elf: &Path,
    csv: &Path,
    (truth, settle_s): (&str, f64),
    estimate: impl Fn(&F) -> (u32, f64),
) -> Result<NodeRun> {
    let input = std::fs::read(csv).with_context(|| format!("reading {}", csv.display()))?;
    let run = qemu::run(elf, &input, Duration::from_secs(900))?;
    if let Some(msg) = run.failure() {
        bail!(msg);
    }
    let data = edgekf_sim::io::data::read(csv, &[truth]).map_err(|e| anyhow!("{}: {e}", csv.display()))?.0;
    let truth = data.column(truth).ok_or_else(|| anyhow!("{}: no {truth}", csv.display()))?;
    let (mut sum, mut n, mut sample, mut mismatches) = (0.0, 0usize, 0u32, Vec::new());
    for line in &run.lines {
        if let Some(f) = frame::<F>(line)? {
            let (k, x) = estimate(&f);
            sample = k;
            let i = (k as usize).saturating_sub(1);
            if let (Some(&t), Some(&want)) = (data.t.get(i), truth.get(i)) {
                if t >= settle_s {
                    if !x.is_finite() {
                        bail!("{}: no estimate at sample {k}", csv.display());
                    }
                    sum += (x - want).powi(2);
                    n += 1;
                }
            }
        } else if let Some(m) = frame::<MismatchFrame>(line)? {
            mismatches.push((sample, m));
        }
    }
    if n == 0 {
        bail!("{}: no sample after {settle_s} s", csv.display());
    }
    Ok(NodeRun { error: (sum / n as f64).sqrt(), mismatches })
}

/// Where a round trip's files go and how it rebuilds the image: `build` cross-builds the
/// system's image with a constants file and returns its ELF, which is copied into `dir` (the
/// next build lands on the same path).
pub(crate) struct Rebuilds<'a> {
    /// The round trip's folder.
    pub dir: &'a Path,
    /// The system's name in `edgekf <system> export`.
    pub system: &'a str,
    /// The image's build with a constants file.
    pub build: &'a dyn Fn(&Path) -> Result<PathBuf>,
}

impl Rebuilds<'_> {
    /// `elf` copied to `dir/name`.
    pub fn copy(&self, elf: &Path, name: &str) -> Result<PathBuf> {
        let to = self.dir.join(name);
        std::fs::copy(elf, &to).with_context(|| format!("copying {} to {}", elf.display(), to.display()))?;
        Ok(to)
    }

    /// `edgekf <system> export` of `config` into `dir/<name>_<system>.rs`, the image built
    /// with it, copied to `dir/<name>.elf`.
    pub fn image(&self, config: &Path, name: &str) -> Result<PathBuf> {
        let rs = self.dir.join(format!("{name}_{}.rs", self.system));
        edgekf(&[self.system, "export", "--config", arg(config), "--out", arg(&rs)])?;
        self.copy(&(self.build)(&rs)?, &format!("{name}.elf"))
    }
}

/// `dir`, emptied (made if missing).
pub(crate) fn empty(dir: &Path) -> Result<()> {
    if dir.exists() {
        std::fs::remove_dir_all(dir).with_context(|| format!("emptying {}", dir.display()))?;
    }
    Ok(std::fs::create_dir_all(dir)?)
}

/// The round trip of [`Setup`] from the `shipped` image (the committed model's, copied first);
/// `build` cross-builds the oscillator's image with a model file and returns its ELF (copied
/// here, as the next build lands on the same path). The workspace's image is then the last
/// one built (the corrected model's) until the next `cargo xtask` build, which rebuilds it
/// (`EDGEKF_OSCILLATOR_MODEL` changed): run nothing else on it in between.
pub fn oscillator(setup: &Setup, shipped: &Path, build: &dyn Fn(&Path) -> Result<PathBuf>) -> Result<Figures> {
    let started = Instant::now();
    let dir = &setup.dir;
    empty(dir)?;
    let file = |name: &str| dir.join(name);
    let write = |name: &str, text: String| std::fs::write(file(name), text).map(|_| file(name));
    let run = (setup.duration_s, setup.seed);
    let declared = write("scenario.toml", setup.scenario(run, None, None))?;
    let alarm_toml = write("alarm.toml", setup.scenario(run, Some(setup.onset_s), None))?;
    let fresh_toml = write("fresh.toml", setup.scenario(setup.fresh, Some(0.0), None))?;
    let true_toml = write("true.toml", setup.scenario(run, None, Some(setup.offset_m_s2)))?;
    let (alarm_csv, fresh_csv) = (file("alarm.csv"), file("fresh.csv"));
    edgekf(&["oscillator", "simulate", "--config", arg(&alarm_toml), "--out", arg(&alarm_csv)])?;
    edgekf(&["oscillator", "simulate", "--config", arg(&fresh_toml), "--out", arg(&fresh_csv)])?;
    let images = Rebuilds { dir, system: "oscillator", build };
    let shipped = images.copy(shipped, "shipped.elf")?;

    // The true configuration's node (its offset declared).
    let true_elf = images.image(&true_toml, "true")?;

    // The alarm, the window, the loop, the corrected configuration and its constants.
    let lines = node(&shipped, &alarm_csv)?;
    let log = file("node.log");
    std::fs::write(&log, lines.join("\n") + "\n")?;
    let rate = Scenario::load(&alarm_toml)?.sensor.odr_hz;
    let (alarm_s, mismatch) =
        first_alarm(&lines, rate)?.ok_or_else(|| anyhow!("the shipped node raised no mismatch"))?;
    let window = file("window.csv");
    edgekf(&["capture", "--log", arg(&log), "--out", arg(&window)])?;
    let data = edgekf_sim::io::data::read(&window, &["ax"]).map_err(|e| anyhow!("{}: {e}", window.display()))?.0;
    let window_s = (data.t[0], data.t[data.t.len() - 1]);
    let fixed = file("fixed.toml");
    let effects =
        close_loop(dir, "report", &["oscillator", "--config", arg(&declared), "--data", arg(&window)], Some(&fixed))?;
    let corrected_offset = Scenario::load(&fixed)?.filter.accel_offset_m_s2;
    let corrected = images.image(&fixed, "corrected")?;

    // The three nodes on the fresh recording, and the loop's checks.
    let fresh_scenario = Scenario::load(&fresh_toml)?;
    let mut fresh = [(0.0, 0); 3];
    for (slot, elf) in fresh.iter_mut().zip([&shipped, &corrected, &true_elf]) {
        let report = RunReport::parse(node(elf, &fresh_csv)?.iter().map(String::as_str))?;
        *slot = (displacement_error(&report, &fresh_scenario)?, report.mismatches.len());
    }
    let on_window =
        close_loop(dir, "rerun_window", &["oscillator", "--config", arg(&fixed), "--data", arg(&window)], None)?;
    let on_fresh =
        close_loop(dir, "rerun_fresh", &["oscillator", "--config", arg(&fixed), "--data", arg(&fresh_csv)], None)?;
    let seconds = started.elapsed().as_secs_f64();
    let (onset_s, rerun_adds) = (setup.onset_s, (on_window, on_fresh));
    Ok(Figures { onset_s, alarm_s, mismatch, window_s, effects, corrected_offset, fresh, rerun_adds, seconds })
}
