//! `cargo xtask cwru --dir D`: issue #35's benchmark on the Case Western Reserve University
//! bearing records the user has converted (`tools/cwru_to_csv.py`; none is in the repository,
//! their licence being unstated). It learns the 0 hp baseline from `097a.csv` with `edgekf
//! baseline rotor`, runs `edgekf loop rotor --baseline` on every 12 kHz drive-end fault
//! record found in D (N at a time), and writes the table record → expected → what the loop
//! named → right or wrong → Smith & Randall's grade, with the counts ([`table`]).
//!
//! It drives the `edgekf` binary, exactly as a user would run it (the README's commands), so
//! the table measures the shipped command line, not a test harness. The records 3001–3008
//! hold only the drive-end channel: they run with `rotor_cwru_de.toml` (the same rig, its
//! drive-end sensor only) and a baseline learnt from the same half of 097 with it. No record
//! carries its speed: the loop reads it from the data within ±10 % of the configuration's
//! 1797 rpm, which holds every load's nominal speed (1730–1797 rpm).

pub mod catalogue;
pub mod table;

use anyhow::{bail, Context, Result};
use catalogue::Record;
use clap::Parser;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;
use table::{Outcome, Row, RunResult};

/// The flags of `cargo xtask cwru`.
#[derive(Debug, Parser)]
#[command(
    name = "cargo xtask cwru",
    about = "Run the residual loop on the CWRU 12 kHz drive-end fault records and score it"
)]
pub struct Args {
    /// Folder of converted records: `<record>.csv` or `12k_Drive_End_<fault>_<load>_<record>.csv`,
    /// and `097a.csv` (the first half of the healthy 097, at 12 kHz) for the baseline.
    #[arg(long, value_name = "D")]
    pub dir: PathBuf,
    /// Runs at a time (default: the cores).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub jobs: Option<u32>,
    /// Only the records at these loads, hp.
    #[arg(long, value_name = "LIST", value_delimiter = ',', default_value = "0,1,2,3",
          value_parser = clap::value_parser!(u8).range(0..=3))]
    pub loads: Vec<u8>,
    /// Also write the table (Markdown) to this file, whole or not at all; an existing file is
    /// refused (before any run) unless --force.
    #[arg(long, value_name = "FILE.md")]
    pub out: Option<PathBuf>,
    /// Keep the baselines, each run's report folder and log in DIR, a new or empty folder
    /// unless --force (default: a temporary folder, removed at the end).
    #[arg(long, value_name = "DIR")]
    pub keep: Option<PathBuf>,
    /// Replace an existing --out, write into a --keep folder that holds files.
    #[arg(long)]
    pub force: bool,
    /// The `edgekf` binary to run (default: build it, release).
    #[arg(long, value_name = "PATH")]
    pub edgekf: Option<PathBuf>,
}

/// What is in the data folder.
#[derive(Debug)]
pub struct Plan {
    /// The records to run, with their files, in catalogue order.
    pub records: Vec<(Record, PathBuf)>,
    /// The healthy half the baselines are learnt from.
    pub healthy: PathBuf,
}

/// The healthy record the baselines come from (0 hp): the README's first half of 097.
const HEALTHY: &str = "097a.csv";

/// Finds the records of `loads` in `dir` and the healthy half, or says clearly why it cannot.
pub fn plan(dir: &Path, loads: &[u8]) -> Result<Plan> {
    if !dir.is_dir() {
        bail!("--dir {}: no such folder", dir.display());
    }
    let mut found: Vec<(Record, PathBuf)> = Vec::new();
    let entries = std::fs::read_dir(dir).with_context(|| format!("--dir {}: cannot list it", dir.display()))?;
    for entry in entries {
        let path = entry?.path();
        let Some(name) = path.file_name().and_then(|n| n.to_str()) else { continue };
        let record = catalogue::from_file_name(name).map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?;
        let Some(record) = record else { continue };
        if let Some((_, other)) = found.iter().find(|(r, _)| r.number == record.number) {
            bail!(
                "record {} is in {} twice ({} and {}): keep one",
                record.number,
                dir.display(),
                other.display(),
                path.display()
            );
        }
        found.push((record, path));
    }
    if found.is_empty() {
        bail!(
            "{} holds none of the 60 12 kHz drive-end fault records (`105.csv`, … or the mirror's \
             `12k_Drive_End_IR007_0_105.csv`, …): convert the mirror with tools/cwru_convert_all.sh, or a record with \
             tools/cwru_to_csv.py (README, \"The CWRU bearing data\")",
            dir.display()
        );
    }
    let all = found.len();
    found.retain(|(r, _)| loads.contains(&r.load_hp));
    if found.is_empty() {
        bail!("{}: {all} record(s), none at the loads asked for ({loads:?} hp)", dir.display());
    }
    let order: Vec<u32> = catalogue::records().iter().map(|r| r.number).collect();
    found.sort_by_key(|(r, _)| order.iter().position(|n| *n == r.number));
    let healthy = dir.join(HEALTHY);
    if !healthy.is_file() {
        bail!(
            "{}: missing; the baseline is learnt from it (the first 2.541 s of the healthy 097, decimated to 12 kHz: \
             tools/cwru_to_csv.py normal_0_97.mat --decimate 4 --start 0 --duration 2.541 --out 097a.csv …, see the README)",
            healthy.display()
        );
    }
    Ok(Plan { records: found, healthy })
}

/// The configurations: the two-housing rig and its drive-end-only variant.
#[derive(Debug, Clone)]
pub struct Configs {
    /// `rotor_cwru.toml`.
    pub both: PathBuf,
    /// `rotor_cwru_de.toml`.
    pub drive_end: PathBuf,
}

impl Configs {
    /// The shipped ones under `root`.
    pub fn shipped(root: &Path) -> Self {
        let dir = root.join("host-sim/configs");
        Self { both: dir.join("rotor_cwru.toml"), drive_end: dir.join("rotor_cwru_de.toml") }
    }

    fn for_record(&self, r: &Record) -> &Path {
        if r.drive_end_only() {
            &self.drive_end
        } else {
            &self.both
        }
    }
}

/// Runs the edgekf binary on a plan, `jobs` at a time, its files in `work`.
#[derive(Debug, Clone)]
pub struct Runner {
    /// The `edgekf` binary.
    pub edgekf: PathBuf,
    /// The configurations.
    pub configs: Configs,
    /// Where the baselines, reports and logs go.
    pub work: PathBuf,
    /// Runs at a time.
    pub jobs: usize,
}

/// The load of the healthy record (097 is at 0 hp).
const BASELINE_HP: u8 = 0;

impl Runner {
    /// The baseline file learnt with `config`.
    fn baseline_path(&self, config: &Path) -> PathBuf {
        let stem = config.file_stem().and_then(|s| s.to_str()).unwrap_or("rotor");
        self.work.join(format!("baseline-097a-{stem}.toml"))
    }

    /// `edgekf baseline rotor` on the healthy half with each configuration the plan needs.
    fn learn_baselines(&self, plan: &Plan) -> Result<()> {
        let mut configs: Vec<&Path> = plan.records.iter().map(|(r, _)| self.configs.for_record(r)).collect();
        configs.sort();
        configs.dedup();
        for config in configs {
            let out = self.baseline_path(config);
            eprintln!("cwru: learning the 0 hp baseline from {} with {}", plan.healthy.display(), config.display());
            let start = Instant::now();
            let mut cmd = Command::new(&self.edgekf);
            cmd.args(["baseline", "rotor", "--config"]).arg(config).arg("--data").arg(&plan.healthy);
            cmd.arg("--out").arg(&out).args(["--condition", "0 hp", "--quiet"]);
            let log = self.work.join(format!("{}.log", out.file_stem().and_then(|s| s.to_str()).unwrap_or("baseline")));
            if let Err(why) = run_logged(cmd, &log) {
                bail!("learning the baseline with {} failed: {why} (log: {})", config.display(), log.display());
            }
            eprintln!("cwru: baseline {} in {:.0} s", out.display(), start.elapsed().as_secs_f64());
        }
        Ok(())
    }

    /// One record's loop; a failure is the row's, not the runner's.
    fn run_one(&self, record: &Record, data: &Path) -> Row {
        let start = Instant::now();
        let config = self.configs.for_record(record);
        let report = self.work.join(record.number.to_string());
        let mut cmd = Command::new(&self.edgekf);
        cmd.args(["loop", "rotor", "--config"]).arg(config).arg("--baseline").arg(self.baseline_path(config));
        cmd.arg("--data").arg(data).arg("--report").arg(&report).arg("--quiet");
        let log = self.work.join(format!("{}.log", record.number));
        let result = match run_logged(cmd, &log).and_then(|()| read_outcome(&report.join("report.json"))) {
            Ok(outcome) => RunResult::Done(outcome),
            Err(why) => RunResult::Failed(why),
        };
        Row { record: *record, baseline_hp: BASELINE_HP, result, seconds: start.elapsed().as_secs_f64() }
    }

    /// Every record of the plan, `jobs` at a time, with a line on stderr as each ends.
    pub fn run(&self, plan: &Plan) -> Result<Vec<Row>> {
        std::fs::create_dir_all(&self.work).with_context(|| format!("{}: cannot make it", self.work.display()))?;
        self.learn_baselines(plan)?;
        let n = plan.records.len();
        eprintln!("cwru: {n} record(s), {} at a time; reports in {}", self.jobs, self.work.display());
        let (next, finished) = (AtomicUsize::new(0), AtomicUsize::new(0));
        let rows: Mutex<Vec<Option<Row>>> = Mutex::new(vec![None; n]);
        std::thread::scope(|s| {
            for _ in 0..self.jobs.clamp(1, n) {
                s.spawn(|| loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    let Some((record, data)) = plan.records.get(i) else { break };
                    let row = self.run_one(record, data);
                    let k = finished.fetch_add(1, Ordering::SeqCst) + 1;
                    eprintln!("cwru: [{k}/{n}] {}", progress_line(&row));
                    rows.lock().expect("a run panicked")[i] = Some(row);
                });
            }
        });
        let rows = rows.into_inner().expect("a run panicked");
        Ok(rows.into_iter().map(|r| r.expect("every record ran")).collect())
    }
}

/// `105 (IR007, 0 hp): BPFI at bearing 1 — right, 74 s`.
fn progress_line(row: &Row) -> String {
    let what = match &row.result {
        RunResult::Done(o) => o.named(),
        RunResult::Failed(why) => format!("failed: {why}"),
    };
    format!(
        "{} ({}, {} hp): {what} — {}, {:.0} s",
        row.record.number,
        row.record.label(),
        row.record.load_hp,
        row.verdict().word(),
        row.seconds
    )
}

/// Runs `cmd` with its output into `log`; on failure, the reason: the command's `error:` line
/// (the edgekf binary's one-line error) or its last line, else its exit status.
fn run_logged(mut cmd: Command, log: &Path) -> Result<(), String> {
    let out = cmd.output().map_err(|e| format!("cannot start {}: {e}", cmd.get_program().to_string_lossy()))?;
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    // The log is for reading afterwards; failing to write it must not lose the run.
    let _ = std::fs::write(log, format!("$ {cmd:?}\n{stdout}\n--- stderr ---\n{stderr}"));
    if out.status.success() {
        return Ok(());
    }
    let lines: Vec<&str> = stderr.lines().map(str::trim).filter(|l| !l.is_empty()).collect();
    let reason = lines
        .iter()
        .rev()
        .find_map(|l| l.strip_prefix("error: "))
        .or(lines.last().copied())
        .map(str::to_string)
        .unwrap_or_else(|| format!("{}", out.status));
    Err(reason)
}

/// The outcome in a run's `report.json`.
fn read_outcome(path: &Path) -> Result<Outcome, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let json: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    Outcome::from_report(&json).map_err(|e| format!("{}: {e}", path.display()))
}

/// `cargo xtask cwru …` (`argv`: the arguments after `cwru`), from the workspace `root`.
pub fn main(root: &Path, argv: &[String]) -> Result<()> {
    let args = Args::try_parse_from(std::iter::once("cargo xtask cwru".to_string()).chain(argv.iter().cloned()))
        .unwrap_or_else(|e| e.exit());
    let plan = plan(&args.dir, &args.loads)?;
    let configs = Configs::shipped(root);
    let mut inputs: Vec<&Path> = plan.records.iter().map(|(_, p)| p.as_path()).collect();
    inputs.extend([plan.healthy.as_path(), configs.both.as_path(), configs.drive_end.as_path()]);
    let inputs: Vec<Option<&Path>> = inputs.into_iter().map(Some).collect();
    check_outputs(&args, &inputs)?;
    let scratch;
    let work = match &args.keep {
        Some(dir) => dir.clone(),
        None => {
            scratch = tempfile::tempdir().context("making a temporary folder")?;
            scratch.path().to_path_buf()
        }
    };
    let edgekf = match &args.edgekf {
        Some(path) => path.clone(),
        None => build_edgekf(root)?,
    };
    let jobs =
        args.jobs.map(|j| j as usize).unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    // The commit and date of the start: the tree may change while the runs go on.
    let heading = format!(
        "CWRU 12 kHz drive-end fault records, `edgekf loop rotor` against the 0 hp baseline (097a); {} hp; {}",
        args.loads.iter().map(u8::to_string).collect::<Vec<_>>().join(", "),
        provenance(root)
    );
    let runner = Runner { edgekf, configs, work, jobs };
    let rows = runner.run(&plan)?;
    let text = table::markdown(&rows, &heading);
    print!("{text}");
    if let Some(out) = &args.out {
        write_table(out, &text, args.force)?;
        eprintln!("cwru: wrote {}", out.display());
    }
    Ok(())
}

/// Before any run: `--out` can be written (its folder exists, it is no input, and it is new
/// unless `--force`), `--keep` is a folder that can be made or is empty (unless `--force`).
/// An hour of runs must not end in a refusal, nor mix its reports with an older run's.
fn check_outputs(args: &Args, inputs: &[Option<&Path>]) -> Result<()> {
    use edgekf_sim::io::output::{check, check_folder};
    check(&[args.out.as_deref()], inputs)?;
    if let Some(out) = args.out.as_deref().filter(|o| o.exists() && !args.force) {
        bail!("{}: exists; choose another name or add --force to replace it", out.display());
    }
    if let Some(dir) = &args.keep {
        check_folder(dir, &[], inputs)?;
        let used = dir.is_dir() && std::fs::read_dir(dir)?.next().is_some();
        if used && !args.force {
            bail!(
                "--keep {}: holds files already; choose a new folder or add --force to write among them",
                dir.display()
            );
        }
    }
    Ok(())
}

/// Writes the table to `out` through a temporary file renamed onto it when complete; without
/// `force` an `out` that appeared meanwhile is kept (the rename refuses to replace it).
fn write_table(out: &Path, text: &str, force: bool) -> Result<()> {
    use std::io::Write as _;
    if force {
        return edgekf_sim::io::output::write_atomic(out, text)
            .with_context(|| format!("{}: cannot write", out.display()));
    }
    let folder = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let mut builder = tempfile::Builder::new();
    builder.prefix(".cwru-table.").suffix(".partial");
    // An ordinary file, readable as the umask allows (a temporary file is private).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder.tempfile_in(folder)?;
    tmp.write_all(text.as_bytes())?;
    tmp.as_file().sync_all()?;
    tmp.persist_noclobber(out).map_err(|e| anyhow::anyhow!("{}: cannot write: {}", out.display(), e.error))?;
    Ok(())
}

/// Builds the release `edgekf` and returns its path.
fn build_edgekf(root: &Path) -> Result<PathBuf> {
    eprintln!("cwru: building edgekf (release)");
    let mut cargo = crate::cargo_here();
    cargo.current_dir(root).args(["build", "--release", "-p", "edgekf-sim", "--bin", "edgekf"]);
    crate::status(cargo, "building edgekf")?;
    let target = std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| root.join("target"));
    Ok(target.join("release").join("edgekf"))
}

/// `commit abc1234 (uncommitted changes), 2026-12-07 UTC` from git and the clock.
fn provenance(root: &Path) -> String {
    let git = |args: &[&str]| {
        Command::new("git")
            .current_dir(root)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let commit = git(&["rev-parse", "--short", "HEAD"]).unwrap_or_else(|| "unknown commit".into());
    let dirty = git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
    let date = Command::new("date").args(["-u", "+%Y-%m-%d %H:%M UTC"]).output().ok();
    let date = date.map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string()).unwrap_or_default();
    format!("commit {commit}{}, {date}", if dirty { " (with uncommitted changes)" } else { "" })
}

#[cfg(test)]
mod tests;
