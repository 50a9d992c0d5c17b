//! Figures of the README for the slider-crank clearance estimators:
//!
//! ```text
//! cargo run --release -p edgekf-sim --example crank_plots -- convergence [DURATION_S] [OUTDIR]
//! cargo run --release -p edgekf-sim --example crank_plots -- fast [OUTDIR]
//! ```
//!
//! * `convergence`: the paper's UKF ([`edgekf_sim::systems::crank::estimate::ukf`], default options) on
//!   one recording of 0.25 mm at joint A, started from 0.01, 0.1 and 0.2 mm. The recording is
//!   the one of the CI test `ukf_approaches_the_clearance_from_three_starts`
//!   (`host-sim/tests/crank_estimate.rs`): the paper's mechanism
//!   (`host-sim/configs/crank_paper.toml`, the built-in default), released at 30°, noise seed
//!   7, simulated by the adaptive integrator at a tolerance of 1e-9 (the filter's sigma points
//!   use 1e-8, so none of them replays the recording). Writes
//!   `OUTDIR/crank_ukf_convergence.svg` (4 s, the default) or
//!   `OUTDIR/crank_ukf_convergence_<DURATION>s.svg` (any other duration): the estimate after
//!   each 0.25 s window for the three starts (the first window, the release window, only
//!   predicts in its turn: the filter measures it last), the final estimate after that
//!   release-window update (drawn a little right of the end), the truth and a ±5 % band.
//!   Prints a table of the results to stdout and the progress to stderr. `DURATION_S` defaults
//!   to 4 (at least 0.5, at most 60), `OUTDIR` to the workspace's `docs/`.
//!
//!   Measured (two threads): 4 s, −3.0 / +3.1 / +1.4 % from 0.01 / 0.1 / 0.2 mm, 13.5 M
//!   integration steps, ~25 s; 10 s (`convergence 10`), −0.1 / +3.5 / +5.3 %, 24 M steps,
//!   ~40–55 s.
//!
//! * `fast`: the fast clearance estimator ([`edgekf_sim::systems::crank::estimate::model::FastModel`],
//!   the built-in model) as the chip runs it: the shared crate's streaming
//!   `edgekf::systems::crank::ClearanceEstimator` in `f64`, which reports a running estimate after
//!   every 0.25 s window. Nine unseen runs of 10 s
//!   (`train::grid(&[0.1e-3, 0.3e-3, 0.5e-3], 1, 720_000, 10.0)`: joints A, B, C × three
//!   clearances, random release angle and journal radius, noise seeds 720 000–720 008; the
//!   built-in model was trained on seeds from 1 000 and, its release laws, from 500 000), simulated by the adaptive integrator on two threads. Writes
//!   `OUTDIR/crank_fast_convergence.svg`: the relative clearance error of the running
//!   estimate against the window's end (top panel; a ring marks the windows no release law
//!   refined, which fall back to the window features) and, below, of the window features alone
//!   (the true joint's regression, `per_joint`, before the release stage), with ±3 % and the
//!   axis clipped at ±30 %. Prints a table (final estimate, error, the features-only error,
//!   the time from which it stays within ±3 %, the release law) to stdout, checks the last
//!   running estimate against `FastModel::estimate` on the whole recording, and reports the
//!   progress on stderr. `OUTDIR` defaults to the workspace's `docs/`.
//!
//!   Measured: 9 of 9 within ±3 % at the end (RMS 0.64 %, worst −1.05 %), 8 of them from the
//!   first window on and the ninth from 0.75 s; the window features alone 2 of 9 (RMS 10.4 %,
//!   worst −20.4 %); the last running estimate equals the whole-recording one; ~3–7 s.
//!
//! A wrong argument prints the usage and exits with status 2; a failed run exits with 1.
//!
//! The figures are drawn with the plot kit of the HTML report ([`edgekf_sim::report::plot`]);
//! this file only says what each figure shows.

use anyhow::Context;
use edgekf::systems::crank::{window_samples, ClearanceEstimate, ClearanceEstimator, ClearanceModel};
use edgekf_sim::report::plot::{
    tick, Axis, Band, Entry, Figure, Key, LegendColumn, Line, Marker, Markers, Mesh, Panel, RGBColor, Shape, Stroke,
};
use edgekf_sim::systems::crank::config::Method;
use edgekf_sim::systems::crank::estimate::model::{FastModel, ModelEstimate};
use edgekf_sim::systems::crank::estimate::train::{grid, Run};
use edgekf_sim::systems::crank::estimate::ukf::{self, UkfOptions, UkfRun};
use edgekf_sim::systems::crank::estimate::Recording;
use edgekf_sim::systems::crank::{CrankConfig, Joint, Mechanism, SimOptions};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// The true clearance at A, m.
const TRUTH: f64 = 0.25e-3;
/// The UKF's initial guesses, m.
const STARTS: [f64; 3] = [0.01e-3, 0.1e-3, 0.2e-3];
/// Noise seed of the recording (as in the CI test).
const SEED: u64 = 7;
/// Tolerance of the adaptive integrator that simulates the recording (as in the CI test).
const RECORDING_TOLERANCE: f64 = 1e-9;
/// Half-width of the band drawn about the truth, as a fraction of it.
const BAND: f64 = 0.05;
/// Default recording length, s (the CI test's).
const DEFAULT_DURATION: f64 = 4.0;
/// Accepted recording lengths, s: at least two windows, at most a few minutes of run time.
const DURATIONS: std::ops::RangeInclusive<f64> = 0.5..=60.0;

/// Size of the figure, px.
const SIZE: (u32, u32) = (820, 500);
/// Colours of the three starts (colour-blind safe: blue, orange, green).
const COLOURS: [RGBColor; 3] = [RGBColor(31, 100, 180), RGBColor(228, 108, 10), RGBColor(44, 160, 44)];
/// Colour of the truth and of the final-estimate legend entry.
const TRUTH_COLOUR: RGBColor = RGBColor(40, 40, 40);
/// Colour of the ±5 % band.
const BAND_COLOUR: RGBColor = RGBColor(120, 120, 120);
/// Fill of the bands about the truth.
const BAND_FILL: RGBColor = RGBColor(236, 236, 236);

/// The usage line.
const USAGE: &str = "usage: crank_plots convergence [DURATION_S] [OUTDIR]\n       \
    crank_plots fast [OUTDIR]\n  \
    DURATION_S  recording length, s (default 4; 0.5 to 60)\n  \
    OUTDIR      where the SVG goes (default: the workspace's docs/)";

/// What the command line asks for.
#[derive(Debug, Clone, PartialEq)]
enum Command {
    /// The UKF convergence figure for a recording of `duration` s, written into `outdir`.
    Convergence { duration: f64, outdir: PathBuf },
    /// The fast estimator's convergence figure, written into `outdir`.
    Fast { outdir: PathBuf },
}

/// Parses the arguments after the program name; `Err` names what is wrong.
fn parse(args: &[String]) -> Result<Command, String> {
    match args.first().map(String::as_str) {
        Some("convergence") => {
            if args.len() > 3 {
                return Err(format!("unexpected argument `{}`", args[3]));
            }
            let duration = match args.get(1) {
                None => DEFAULT_DURATION,
                Some(s) => match s.parse::<f64>() {
                    Ok(d) if DURATIONS.contains(&d) => d,
                    _ => return Err(format!("DURATION_S must be a number of seconds from 0.5 to 60, not `{s}`")),
                },
            };
            let outdir = args.get(2).map_or_else(default_outdir, PathBuf::from);
            Ok(Command::Convergence { duration, outdir })
        }
        Some("fast") => {
            if args.len() > 2 {
                return Err(format!("unexpected argument `{}`", args[2]));
            }
            Ok(Command::Fast { outdir: args.get(1).map_or_else(default_outdir, PathBuf::from) })
        }
        Some(other) => Err(format!("unknown figure `{other}`")),
        None => Err("which figure?".into()),
    }
}

/// The workspace's `docs/` (wherever the example is run from).
fn default_outdir() -> PathBuf {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().unwrap_or(manifest).join("docs")
}

/// The figure's file name: `crank_ukf_convergence.svg` for the default 4 s,
/// `crank_ukf_convergence_<DURATION>s.svg` otherwise.
fn file_name(duration: f64) -> String {
    if duration == DEFAULT_DURATION {
        "crank_ukf_convergence.svg".into()
    } else {
        format!("crank_ukf_convergence_{duration}s.svg")
    }
}

/// The recording of the CI test: [`TRUTH`] at A, `duration` s, released at the configured 30°,
/// seed [`SEED`], adaptive integrator at [`RECORDING_TOLERANCE`].
fn recording(cfg: &CrankConfig, duration: f64) -> anyhow::Result<Recording> {
    let mut rc = *cfg;
    rc.integrator.method = Method::Adaptive;
    rc.integrator.tolerance = RECORDING_TOLERANCE;
    let mech = Mechanism::new(&rc, [Some(TRUTH), None, None])?;
    let sim = mech.simulate(&SimOptions { seed: SEED, ..SimOptions::from_config(&rc, duration) })?;
    Ok(Recording::from_simulation(&sim, rc.sensor.sample_rate))
}

/// One UKF run from one start.
struct Convergence {
    /// Initial guess, m.
    initial: f64,
    /// What the filter did.
    run: UkfRun,
    /// Wall-clock time of the run, s.
    seconds: f64,
}

/// Runs the UKF (default options but the start) on `rec` from each of [`STARTS`], reporting
/// every window and release-window iteration on stderr.
fn run_starts(cfg: &CrankConfig, rec: &Recording) -> anyhow::Result<Vec<Convergence>> {
    let windows = rec.crank_alpha.len() / rec.window_len(UkfOptions::default().window).max(1);
    let mut out = Vec::with_capacity(STARTS.len());
    for (i, &initial) in STARTS.iter().enumerate() {
        let started = Instant::now();
        let opts = UkfOptions { initial, ..UkfOptions::default() };
        let mut iteration = 0;
        let mut progress = |k: usize, s: &ukf::UkfStep| {
            let what = if k < windows {
                format!("window {:2}/{windows} (t = {:5.2} s)", k + 1, s.t)
            } else {
                iteration += 1;
                format!("release window, iteration {iteration}")
            };
            eprintln!(
                "  start {}/{} ({:.2} mm): {what}: {:.4} ± {:.4} mm  [{:.1} s]",
                i + 1,
                STARTS.len(),
                initial * 1e3,
                s.clearance * 1e3,
                s.std * 1e3,
                started.elapsed().as_secs_f64()
            );
        };
        let run =
            ukf::run(cfg, rec, &opts, &mut progress).with_context(|| format!("UKF from {:.2} mm", initial * 1e3))?;
        out.push(Convergence { initial, run, seconds: started.elapsed().as_secs_f64() });
    }
    Ok(out)
}

/// The results as a text table (clearances in mm).
fn table(runs: &[Convergence]) -> String {
    let mut s = format!(
        "{:>10}  {:>18}  {:>19}  {:>9}  {:>17}  {:>11}  {:>8}\n",
        "start (mm)",
        "after windows (mm)",
        "final ± std (mm)",
        "error (%)",
        "integration steps",
        "simulations",
        "time (s)"
    );
    for c in runs {
        let before = c.run.steps.last().map_or(f64::NAN, |s| s.clearance);
        s.push_str(&format!(
            "{:>10.2}  {:>18.4}  {:>10.4} ± {:.4}  {:>+9.1}  {:>17}  {:>11}  {:>8.1}\n",
            c.initial * 1e3,
            before * 1e3,
            c.run.estimate * 1e3,
            c.run.estimate_std * 1e3,
            (c.run.estimate / TRUTH - 1.0) * 100.0,
            c.run.integration_steps,
            c.run.simulations,
            c.seconds
        ));
    }
    s
}

/// The upper end of the clearance axis, mm: above every estimate and the band, rounded up to
/// 0.05 mm.
fn y_max(runs: &[Convergence]) -> f64 {
    let top = runs
        .iter()
        .flat_map(|c| c.run.steps.iter().map(|s| s.clearance).chain([c.run.estimate, c.initial]))
        .fold(TRUTH * (1.0 + BAND), f64::max)
        * 1e3;
    ((top * 1.12) / 0.05).ceil() * 0.05
}

/// How far right of the recording's end the final estimates are drawn, s (at least half a
/// window, or 3 % of the recording): they come from the release window's update, made after
/// the last window.
fn final_offset(duration: f64) -> f64 {
    (0.03 * duration).max(0.125)
}

/// A band of ±`half` about `centre`, lightly filled with dashed edges.
fn band(name: String, centre: f64, half: f64) -> Band {
    let edge = Stroke::dashed(BAND_COLOUR, 1, 6, 4);
    Band { name, lo: centre - half, hi: centre + half, fill: BAND_FILL, edge }
}

/// Draws the convergence figure for a recording of `duration` s as an SVG document.
fn convergence_svg(runs: &[Convergence], duration: f64) -> anyhow::Result<String> {
    let truth_mm = TRUTH * 1e3;
    let mut p = Panel::new("", "time: end of the 0.25 s window (s)", "clearance estimate at A (mm)");
    // Room right of the end for the final estimates' markers.
    p.x = Axis::Linear(0.0, duration + 2.0 * final_offset(duration));
    p.y = Axis::Linear(0.0, y_max(runs));
    p.mesh = Mesh { x_labels: 10, y_labels: 8, light_lines: 1, signed_y: false };

    // The band and the truth, under the estimates.
    let (lo, hi) = (truth_mm * (1.0 - BAND), truth_mm * (1.0 + BAND));
    p.bands.push(band(format!("±{:.0} % ({lo:.4} / {hi:.4} mm)", BAND * 100.0), truth_mm, truth_mm * BAND));
    p.lines.push(Line::horizontal(&format!("truth {truth_mm} mm"), TRUTH_COLOUR, p.x, truth_mm).width(2));

    for (c, colour) in runs.iter().zip(COLOURS) {
        // The start, then the estimate after each window (the release window, measured
        // last, only predicts in its turn).
        let path: Vec<(f64, f64)> =
            [(0.0, c.initial * 1e3)].into_iter().chain(c.run.steps.iter().map(|s| (s.t, s.clearance * 1e3))).collect();
        let name = format!(
            "from {:.2} mm → {:.4} mm ({:+.1} %)",
            c.initial * 1e3,
            c.run.estimate * 1e3,
            (c.run.estimate / TRUTH - 1.0) * 100.0
        );
        // The release-window update, made after the last window: from the last window's
        // estimate to the final one, drawn a little right of the end.
        let last = *path.last().unwrap_or(&(0.0, c.initial * 1e3));
        let end = (duration + final_offset(duration), c.run.estimate * 1e3);
        p.lines.push(Line::new(&name, colour, path.clone()).width(2));
        p.lines.push(Line::new("", colour, vec![last, end]).dashed(4, 3));
        p.markers.push(Markers::new("", Marker::new(Shape::Circle, 2, colour), path));
        p.markers.push(Markers::new("", Marker::new(Shape::Circle, 5, colour).outlined(TRUTH_COLOUR), vec![end]));
    }
    // One legend entry for the three final markers.
    let final_marker = Marker::new(Shape::Circle, 5, BAND_COLOUR).outlined(TRUTH_COLOUR);
    p.legend_extra.push((Key::Marker(final_marker), "final estimate (release window, measured last)".into()));

    let title =
        format!("Paper's UKF, slider-crank, clearance at A: {duration} s recording, truth {truth_mm} mm, three starts");
    let label = format!("UKF clearance estimates against time from three starts, {duration} s recording");
    Figure::new(&label, SIZE, vec![p]).titled(&title).svg()
}

// ---------------------------------------------------------------------------------------------
// The `fast` figure: the chip's streaming clearance estimator on unseen runs.
// ---------------------------------------------------------------------------------------------

/// Clearances of the `fast` figure's runs, m.
const FAST_CLEARANCES: [f64; 3] = [0.1e-3, 0.3e-3, 0.5e-3];
/// Seed base of the `fast` figure's grid (draws and noise seeds; no training run shares one).
const FAST_SEED_BASE: u64 = 720_000;
/// Length of each run, s.
const FAST_DURATION: f64 = 10.0;
/// The tolerance drawn about zero error, as a fraction.
const FAST_BAND: f64 = 0.03;
/// Half-height of the error axis, %: errors beyond are clipped at the frame.
const FAST_CLIP: f64 = 30.0;
/// Size of the `fast` figure, px.
const FAST_SIZE: (u32, u32) = (1000, 900);
/// Width of the legend column right of the panels, px.
const FAST_LEGEND_WIDTH: u32 = 190;
/// File name of the `fast` figure.
const FAST_FILE: &str = "crank_fast_convergence.svg";
/// Simulation threads of the `fast` figure.
const FAST_THREADS: usize = 2;

/// The running estimate after one window.
struct FastWindow {
    /// End of the window, s after release.
    t: f64,
    /// What the streaming estimator says for everything so far.
    estimate: ClearanceEstimate<f64>,
}

/// One run of the `fast` figure.
struct FastRun {
    /// The simulated run.
    run: Run,
    /// The streaming estimator's running estimate after each window.
    windows: Vec<FastWindow>,
    /// The whole-recording estimate ([`FastModel::estimate`]).
    whole: ModelEstimate,
    /// Wall-clock time of the simulation, s.
    seconds: f64,
}

impl FastRun {
    /// The true joint's index.
    fn joint(&self) -> usize {
        self.run.joint.index()
    }

    /// The index of its clearance in [`FAST_CLEARANCES`] (its marker's shape).
    fn clearance_index(&self) -> usize {
        FAST_CLEARANCES.iter().position(|&c| c == self.run.clearance).unwrap_or(0)
    }

    /// The run's name, e.g. `A 0.1 mm`.
    fn name(&self) -> String {
        format!("{} {} mm", self.run.joint, tick(self.run.clearance * 1e3))
    }

    /// The last running estimate (the chip's report at the end of the recording).
    fn last(&self) -> Option<&ClearanceEstimate<f64>> {
        self.windows.last().map(|w| &w.estimate)
    }

    /// Error of a running estimate at the true joint, %; `None` if it names another joint
    /// (it then says the true joint has no clearance).
    fn error(&self, e: &ClearanceEstimate<f64>) -> Option<f64> {
        (e.joint == self.joint()).then(|| (e.clearance / self.run.clearance - 1.0) * 100.0)
    }

    /// Error of the window features' regression of the true joint (before the release
    /// stage, whichever joint is named), %.
    fn features_error(&self, e: &ClearanceEstimate<f64>) -> f64 {
        (e.per_joint[self.joint()] / self.run.clearance - 1.0) * 100.0
    }

    /// The first window end from which every running estimate names the true joint within
    /// ±[`FAST_BAND`]; `None` if the last one does not.
    fn settled(&self, error: impl Fn(&ClearanceEstimate<f64>) -> Option<f64>) -> Option<f64> {
        let inside = |w: &FastWindow| error(&w.estimate).is_some_and(|e| e.abs() <= FAST_BAND * 100.0);
        let outside_after = self.windows.iter().rposition(|w| !inside(w));
        match outside_after {
            None => self.windows.first().map(|w| w.t),
            Some(k) => self.windows.get(k + 1).map(|w| w.t),
        }
    }
}

/// The release law of a running estimate, as words.
fn law_name(release: Option<usize>) -> String {
    match release {
        Some(0) => "1st contact".into(),
        Some(1) => "2nd contact".into(),
        Some(2) => "3rd contact".into(),
        Some(h) => format!("{}th contact", h + 1),
        None => "none (features)".into(),
    }
}

/// Simulates `run` and runs the streaming estimator and the whole-recording one on it.
fn fast_run(cfg: &CrankConfig, model: &FastModel, shared: &ClearanceModel<f64>, run: Run) -> anyhow::Result<FastRun> {
    let started = Instant::now();
    let rec = run.simulate(cfg).with_context(|| format!("simulating {} {:.1} mm", run.joint, run.clearance * 1e3))?;
    let seconds = started.elapsed().as_secs_f64();
    let n = window_samples(shared.window, rec.sample_rate);
    let mut est = ClearanceEstimator::new(shared, vec![0.0; n.saturating_sub(1)], rec.sample_rate)
        .map_err(|e| anyhow::anyhow!("the streaming estimator: {e:?}"))?;
    let t0 = rec.t.first().copied().unwrap_or(0.0);
    let mut windows = Vec::new();
    for (k, &x) in rec.crank_alpha.iter().enumerate() {
        if let Some(estimate) = est.push(x) {
            windows.push(FastWindow { t: t0 + (k + 1) as f64 / rec.sample_rate, estimate });
        }
    }
    let whole = model.estimate(&rec)?;
    Ok(FastRun { run, windows, whole, seconds })
}

/// Every run of `runs`, on [`FAST_THREADS`] threads, in the order of `runs`; progress on
/// stderr.
fn fast_runs(cfg: &CrankConfig, runs: &[Run]) -> anyhow::Result<Vec<FastRun>> {
    let model = FastModel::builtin();
    let shared = model.to_shared();
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let started = Instant::now();
    let results: Mutex<Vec<Option<anyhow::Result<FastRun>>>> = Mutex::new((0..runs.len()).map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..FAST_THREADS.min(runs.len()).max(1) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(&run) = runs.get(i) else { break };
                let r = fast_run(cfg, &model, &shared, run);
                let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                match &r {
                    Ok(f) => {
                        let last = f.last();
                        eprintln!(
                            "  [{d}/{}] {} (release {:.1}°, radius × {:.3}, seed {}): simulated in {:.1} s, {} windows, \
                             final {:.4} mm at {}  [{:.1} s]",
                            runs.len(),
                            f.name(),
                            run.release_deg,
                            run.radius,
                            run.seed,
                            f.seconds,
                            f.windows.len(),
                            last.map_or(f64::NAN, |e| e.clearance * 1e3),
                            last.map_or("?", |e| Joint::ALL[e.joint].name()),
                            started.elapsed().as_secs_f64()
                        )
                    }
                    Err(e) => eprintln!("  [{d}/{}] {} {:.1} mm failed: {e:#}", runs.len(), run.joint, run.clearance * 1e3),
                }
                if let Ok(mut v) = results.lock() {
                    v[i] = Some(r);
                }
            });
        }
    });
    let results = results.into_inner().map_err(|_| anyhow::anyhow!("a simulation thread panicked"))?;
    results.into_iter().map(|r| r.unwrap_or_else(|| Err(anyhow::anyhow!("a run was not simulated")))).collect()
}

/// The `fast` figure's results as a text table.
fn fast_table(runs: &[FastRun]) -> String {
    let mut s = format!(
        "{:<9}  {:>7}  {:>7}  {:>5}  {:>10}  {:>9}  {:>13}  {:>16}  {:>11}  {:>15}  {:>11}\n",
        "run",
        "release",
        "radius",
        "joint",
        "final (mm)",
        "error (%)",
        "features (mm)",
        "features err (%)",
        "settled (s)",
        "release law",
        "law windows"
    );
    for f in runs {
        let Some(e) = f.last() else {
            s.push_str(&format!("{:<9}  (no window)\n", f.name()));
            continue;
        };
        let settled = f.settled(|e| f.error(e)).map_or("never".into(), |t| format!("{t:.2}"));
        s.push_str(&format!(
            "{:<9}  {:>6.1}°  {:>7.3}  {:>5}  {:>10.4}  {:>+9.2}  {:>13.4}  {:>+16.2}  {:>11}  {:>15}  {:>11}\n",
            f.name(),
            f.run.release_deg,
            f.run.radius,
            Joint::ALL[e.joint].name(),
            e.clearance * 1e3,
            f.error(e).unwrap_or(-100.0),
            e.per_joint[f.joint()] * 1e3,
            f.features_error(e),
            settled,
            law_name(e.release),
            format!("{}/{}", f.windows.iter().filter(|w| w.estimate.release.is_some()).count(), f.windows.len())
        ));
    }
    s
}

/// A colour moved a fraction `f` of the way toward `to`.
fn mix(c: RGBColor, to: RGBColor, f: f64) -> RGBColor {
    let m = |a: u8, b: u8| (a as f64 + (b as f64 - a as f64) * f).round() as u8;
    RGBColor(m(c.0, to.0), m(c.1, to.1), m(c.2, to.2))
}

/// The colour of a run: the hue of its joint, darker for small clearances, lighter for large.
fn fast_colour(joint: usize, clearance: usize) -> RGBColor {
    let base = COLOURS[joint % COLOURS.len()];
    match clearance {
        0 => mix(base, RGBColor(0, 0, 0), 0.35),
        1 => base,
        _ => mix(base, RGBColor(255, 255, 255), 0.35),
    }
}

/// The marker of the `k`-th clearance: circle, triangle, square.
fn fast_marker(k: usize, colour: RGBColor) -> Marker {
    let shape = [Shape::Circle, Shape::Triangle, Shape::Square][k.min(2)];
    Marker::new(shape, 3, colour)
}

/// The grey ring around the windows no release law refined.
fn ring() -> Marker {
    Marker::new(Shape::Circle, 7, BAND_COLOUR).hollow()
}

/// One panel of the `fast` figure: `error(run, estimate)` (%; `None`: the estimate names
/// another joint, drawn as a cross on the bottom edge) after each window, for every run; with
/// `rings`, a grey ring around the windows no release law refined (the window features' value).
fn fast_panel(
    caption: &str,
    runs: &[FastRun],
    error: impl Fn(&FastRun, &ClearanceEstimate<f64>) -> Option<f64>,
    rings: bool,
) -> Panel {
    let mut p = Panel::new(caption, "time: end of the 0.25 s window (s)", "clearance error (%)");
    p.x = Axis::Linear(0.0, FAST_DURATION);
    p.y = Axis::Linear(-FAST_CLIP, FAST_CLIP);
    p.mesh = Mesh { x_labels: 11, y_labels: 13, light_lines: 1, signed_y: true };
    // The ±3 % band and zero, under the runs.
    p.bands.push(band(String::new(), 0.0, FAST_BAND * 100.0));
    p.lines.push(Line::horizontal("", TRUTH_COLOUR, p.x, 0.0));
    for f in runs {
        let (j, k) = (f.joint(), f.clearance_index());
        let colour = fast_colour(j, k);
        // NaN where the estimate names another joint: the line breaks there.
        let points: Vec<(f64, f64)> =
            f.windows.iter().map(|w| (w.t, error(f, &w.estimate).unwrap_or(f64::NAN))).collect();
        let elsewhere = points.iter().filter(|p| p.1.is_nan()).map(|p| (p.0, -FAST_CLIP)).collect();
        let unrefined = points.iter().zip(&f.windows).filter(|(_, w)| rings && w.estimate.release.is_none());
        p.lines.push(Line::new("", colour, points.clone()).width(2));
        p.markers.push(Markers::new("", ring(), unrefined.map(|(p, _)| *p).collect()).at_edge());
        p.markers.push(Markers::new("", Marker::new(Shape::Cross, 5, colour), elsewhere));
        // Filled inside the axis, hollow at its edge beyond.
        p.markers.push(Markers::new("", fast_marker(k, colour), points).at_edge());
    }
    p
}

/// Draws the `fast` figure: the running estimate (top) and the window features' alone
/// (bottom), with a legend column right of them.
fn fast_svg(runs: &[FastRun]) -> anyhow::Result<String> {
    let title = format!(
        "Fast estimator on the chip's streaming code: {} unseen {} s runs (joints A, B, C × {} clearances)",
        runs.len(),
        FAST_DURATION,
        FAST_CLEARANCES.len()
    );
    let running = fast_panel(
        "Running estimate after each window, with the release stage (what the chip reports)",
        runs,
        |f, e| f.error(e),
        true,
    );
    let features = fast_panel(
        "Window features only (the true joint's regression, before the release stage)",
        runs,
        |f, e| Some(f.features_error(e)),
        false,
    );
    let label = format!(
        "Relative clearance error against time of the fast estimator's running estimate on {} runs, with and without its release stage",
        runs.len()
    );
    Figure::new(&label, FAST_SIZE, vec![running, features]).titled(&title).with_legend(fast_legend(runs)).svg()
}

/// The legend column of the `fast` figure: one entry per run with its final error, then the
/// band and the marker conventions.
fn fast_legend(runs: &[FastRun]) -> LegendColumn {
    let mut entries = vec![Entry::heading(&["run: final error", "(features only)"])];
    for f in runs {
        let (j, k) = (f.joint(), f.clearance_index());
        let colour = fast_colour(j, k);
        let (err, feat) =
            f.last().map_or((f64::NAN, f64::NAN), |e| (f.error(e).unwrap_or(-100.0), f.features_error(e)));
        let key = Key::LineMarker(Stroke::solid(colour, 2), fast_marker(k, colour));
        entries.push(Entry::new(key, &[&format!("{}: {err:+.1} %", f.name()), &format!("({feat:+.1} %)")]));
    }
    let b = band(String::new(), 0.0, FAST_BAND * 100.0);
    entries.push(Entry::new(Key::Band(b.fill, b.edge), &[&format!("±{:.0} %", FAST_BAND * 100.0)]));
    let beyond = fast_marker(0, BAND_COLOUR).hollow();
    entries.push(Entry::new(Key::Marker(beyond), &[&format!("beyond ±{FAST_CLIP:.0} %:"), "drawn hollow at the edge"]));
    entries.push(Entry::new(Key::Marker(ring()), &["no release law:", "window features' value"]));
    if runs.iter().any(|f| f.windows.iter().any(|w| w.estimate.joint != f.joint())) {
        entries.push(Entry::new(Key::Marker(Marker::new(Shape::Cross, 5, BAND_COLOUR)), &["another joint named"]));
    }
    for (k, c) in FAST_CLEARANCES.iter().enumerate() {
        entries.push(Entry::new(Key::Marker(fast_marker(k, BAND_COLOUR)), &[&format!("{} mm", tick(c * 1e3))]));
    }
    LegendColumn { width: FAST_LEGEND_WIDTH, entries }
}

/// The `fast` figure: simulate the runs, run the streaming and whole-recording estimators,
/// print the table, write the SVG.
fn fast(outdir: &Path) -> anyhow::Result<()> {
    let started = Instant::now();
    let cfg = CrankConfig::default();
    let runs = grid(&FAST_CLEARANCES, 1, FAST_SEED_BASE, FAST_DURATION);
    eprintln!(
        "simulating {} runs of {FAST_DURATION} s (grid seed base {FAST_SEED_BASE}, adaptive integrator) on {FAST_THREADS} threads",
        runs.len()
    );
    let runs = fast_runs(&cfg, &runs)?;

    let windows = runs.first().map_or(0, |f| f.windows.len());
    println!(
        "Fast estimator (built-in model), streaming as on the chip (f64), {} unseen runs of {FAST_DURATION} s \
         (grid seed base {FAST_SEED_BASE}; {windows} windows of 0.25 s each):",
        runs.len()
    );
    print!("{}", fast_table(&runs));
    let finals: Vec<f64> = runs.iter().filter_map(|f| f.last().and_then(|e| f.error(e))).collect();
    let features: Vec<f64> = runs.iter().filter_map(|f| f.last().map(|e| f.features_error(e))).collect();
    let within = |v: &[f64]| v.iter().filter(|e| e.abs() <= FAST_BAND * 100.0).count();
    let rms = |v: &[f64]| (v.iter().map(|e| e * e).sum::<f64>() / v.len().max(1) as f64).sqrt();
    let named = runs.iter().filter(|f| f.last().is_some_and(|e| e.joint == f.joint())).count();
    // The chip's last running estimate against the host's whole-recording one.
    let agree = runs
        .iter()
        .filter_map(|f| {
            let e = f.last()?;
            let whole = f.whole.clearance[f.whole.joint.index()];
            Some(if f.whole.joint.index() == e.joint { (e.clearance / whole - 1.0).abs() } else { f64::INFINITY })
        })
        .fold(0.0, f64::max);
    println!(
        "true joint named in {named} of {}; with the release stage {} of {} within ±{:.0} % (RMS {:.2} %), \
         window features only {} of {} (RMS {:.2} %)",
        runs.len(),
        within(&finals),
        runs.len(),
        FAST_BAND * 100.0,
        rms(&finals),
        within(&features),
        runs.len(),
        rms(&features)
    );
    println!(
        "last running estimate vs FastModel::estimate on the whole recording: largest relative difference {agree:.1e}; \
         total time {:.1} s",
        started.elapsed().as_secs_f64()
    );

    let svg = fast_svg(&runs)?;
    std::fs::create_dir_all(outdir).with_context(|| format!("creating {}", outdir.display()))?;
    let path = outdir.join(FAST_FILE);
    std::fs::write(&path, svg).with_context(|| format!("writing {}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

/// The `convergence` figure: simulate, run the UKF from the three starts, print the table,
/// write the SVG.
fn convergence(duration: f64, outdir: &Path) -> anyhow::Result<()> {
    let started = Instant::now();
    let cfg = CrankConfig::default();
    eprintln!(
        "simulating the recording: {duration} s, {:.2} mm at A, seed {SEED}, adaptive integrator at {RECORDING_TOLERANCE:e}",
        TRUTH * 1e3
    );
    let rec = recording(&cfg, duration)?;
    eprintln!("  done [{:.1} s]; running the UKF from {} starts", started.elapsed().as_secs_f64(), STARTS.len());
    let runs = run_starts(&cfg, &rec)?;

    let windows = runs.first().map_or(0, |c| c.run.steps.len());
    println!(
        "UKF (default options) on a {duration} s recording of {:.2} mm at A ({windows} windows of 0.25 s; adaptive integrator at {RECORDING_TOLERANCE:e}, seed {SEED}):",
        TRUTH * 1e3
    );
    print!("{}", table(&runs));
    let steps: u64 = runs.iter().map(|c| c.run.integration_steps).sum();
    let sims: u64 = runs.iter().map(|c| c.run.simulations).sum();
    let within = runs.iter().filter(|c| (c.run.estimate / TRUTH - 1.0).abs() <= BAND).count();
    println!(
        "{within} of {} within ±{:.0} %; the UKF spent {steps} integration steps in {sims} window simulations; total time {:.1} s",
        runs.len(),
        BAND * 100.0,
        started.elapsed().as_secs_f64()
    );

    let svg = convergence_svg(&runs, duration)?;
    std::fs::create_dir_all(outdir).with_context(|| format!("creating {}", outdir.display()))?;
    let path = outdir.join(file_name(duration));
    std::fs::write(&path, svg).with_context(|| format!("writing {}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let command = match parse(&args) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("crank_plots: {e}\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    let result = match &command {
        Command::Convergence { duration, outdir } => convergence(*duration, outdir),
        Command::Fast { outdir } => fast(outdir),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("crank_plots: {e:#}");
            ExitCode::FAILURE
        }
    }
}
