//! The `convergence` figure: the paper's UKF from three starts on one recording.

use super::{band, BAND_COLOUR, COLOURS, DEFAULT_DURATION, TRUTH_COLOUR};
use anyhow::Context;
use edgekf_sim::report::plot::{Axis, Figure, Key, Line, Marker, Markers, Mesh, Panel, Shape};
use edgekf_sim::systems::crank::config::Method;
use edgekf_sim::systems::crank::estimate::ukf::{self, UkfOptions, UkfRun};
use edgekf_sim::systems::crank::estimate::Recording;
use edgekf_sim::systems::crank::{CrankConfig, Mechanism, SimOptions};
use std::path::Path;
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
/// Size of the figure, px.
const SIZE: (u32, u32) = (820, 500);

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

/// The `convergence` figure: simulate, run the UKF from the three starts, print the table,
/// write the SVG.
pub(super) fn convergence(duration: f64, outdir: &Path) -> anyhow::Result<()> {
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
