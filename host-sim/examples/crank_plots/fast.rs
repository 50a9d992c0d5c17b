//! The `fast` figure: the chip's streaming clearance estimator on unseen runs.

use super::{band, BAND_COLOUR, COLOURS, TRUTH_COLOUR};
use anyhow::Context;
use edgekf::systems::crank::{window_samples, ClearanceEstimate, ClearanceEstimator, ClearanceModel};
use edgekf_sim::report::plot::{
    tick, Axis, Entry, Figure, Key, LegendColumn, Line, Marker, Markers, Mesh, Panel, RGBColor, Shape, Stroke,
};
use edgekf_sim::systems::crank::estimate::model::{FastModel, ModelEstimate};
use edgekf_sim::systems::crank::estimate::runs::{grid, Run};
use edgekf_sim::systems::crank::{CrankConfig, Joint};
use rayon::prelude::*;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

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
    let done = AtomicUsize::new(0);
    let started = Instant::now();
    let simulate = || {
        runs.par_iter()
            .map(|&run| {
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
                r
            })
            .collect::<Vec<_>>()
    };
    // Every run's result in the order of `runs`: the first failure is the one reported.
    rayon::ThreadPoolBuilder::new().num_threads(FAST_THREADS).build()?.install(simulate).into_iter().collect()
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
pub(super) fn fast(outdir: &Path) -> anyhow::Result<()> {
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
