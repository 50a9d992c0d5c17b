//! Figures of the README for the slider-crank clearance estimators:
//!
//! ```text
//! cargo run --release -p edgekf-sim --example crank_plots -- convergence [DURATION_S] [OUTDIR]
//! ```
//!
//! * `convergence`: the paper's UKF ([`edgekf_sim::crank::estimate::ukf`], default options) on
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
//! A wrong argument prints the usage and exits with status 2; a failed run exits with 1.

use anyhow::Context;
use edgekf_sim::crank::config::Method;
use edgekf_sim::crank::estimate::ukf::{self, UkfOptions, UkfRun};
use edgekf_sim::crank::estimate::Recording;
use edgekf_sim::crank::{CrankConfig, Mechanism, SimOptions};
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
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
/// Font family of the figure's text (rendered by the viewer, as in the HTML report).
const FONT: &str = "sans-serif";
/// Colours of the three starts (colour-blind safe: blue, orange, green).
const COLOURS: [RGBColor; 3] = [RGBColor(31, 100, 180), RGBColor(228, 108, 10), RGBColor(44, 160, 44)];
/// Colour of the truth and of the final-estimate legend entry.
const TRUTH_COLOUR: RGBColor = RGBColor(40, 40, 40);
/// Colour of the ±5 % band.
const BAND_COLOUR: RGBColor = RGBColor(120, 120, 120);

/// The usage line.
const USAGE: &str = "usage: crank_plots convergence [DURATION_S] [OUTDIR]\n  \
    DURATION_S  recording length, s (default 4; 0.5 to 60)\n  \
    OUTDIR      where the SVG goes (default: the workspace's docs/)";

/// What the command line asks for.
#[derive(Debug, Clone, PartialEq)]
enum Command {
    /// The UKF convergence figure for a recording of `duration` s, written into `outdir`.
    Convergence { duration: f64, outdir: PathBuf },
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

/// An axis tick label: at most three decimals, without trailing zeros.
fn tick(v: &f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// How far right of the recording's end the final estimates are drawn, s (at least half a
/// window, or 3 % of the recording): they come from the release window's update, made after
/// the last window.
fn final_offset(duration: f64) -> f64 {
    (0.03 * duration).max(0.125)
}

/// Draws the convergence figure for a recording of `duration` s as an SVG document.
fn convergence_svg(runs: &[Convergence], duration: f64) -> anyhow::Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        // Room right of the end for the final estimates' markers.
        let x_end = duration + 2.0 * final_offset(duration);
        let truth_mm = TRUTH * 1e3;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "Paper's UKF, slider-crank, clearance at A: {duration} s recording, truth {truth_mm} mm, three starts"
                ),
                (FONT, 17),
            )
            .margin(10)
            .margin_right(18)
            .x_label_area_size(44)
            .y_label_area_size(62)
            .build_cartesian_2d(0.0..x_end, 0.0..y_max(runs))
            .map_err(plot_error)?;
        chart
            .configure_mesh()
            .x_desc("time: end of the 0.25 s window (s)")
            .y_desc("clearance estimate at A (mm)")
            .x_labels(10)
            .y_labels(8)
            .max_light_lines(1)
            .x_label_formatter(&tick)
            .y_label_formatter(&tick)
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 14))
            .bold_line_style(RGBColor(225, 225, 225))
            .light_line_style(RGBColor(244, 244, 244))
            .draw()
            .map_err(plot_error)?;

        // The band and the truth, under the estimates.
        let band = BAND_COLOUR.stroke_width(1);
        for (k, f) in [1.0 + BAND, 1.0 - BAND].into_iter().enumerate() {
            let y = truth_mm * f;
            let drawn =
                chart.draw_series(DashedLineSeries::new([(0.0, y), (x_end, y)], 6, 4, band)).map_err(plot_error)?;
            if k == 0 {
                drawn
                    .label(format!("±{:.0} % ({:.4} / {:.4} mm)", BAND * 100.0, truth_mm * (1.0 - BAND), y))
                    .legend(move |(x, y)| DashedPathElement::new([(x, y), (x + 20, y)], 6, 4, band));
            }
        }
        let truth = TRUTH_COLOUR.stroke_width(2);
        chart
            .draw_series(LineSeries::new([(0.0, truth_mm), (x_end, truth_mm)], truth))
            .map_err(plot_error)?
            .label(format!("truth {truth_mm} mm"))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], truth));

        for (c, colour) in runs.iter().zip(COLOURS) {
            // The start, then the estimate after each window (the release window, measured
            // last, only predicts in its turn).
            let path: Vec<(f64, f64)> = [(0.0, c.initial * 1e3)]
                .into_iter()
                .chain(c.run.steps.iter().map(|s| (s.t, s.clearance * 1e3)))
                .collect();
            let line = colour.stroke_width(2);
            chart
                .draw_series(LineSeries::new(path.iter().copied(), line))
                .map_err(plot_error)?
                .label(format!(
                    "from {:.2} mm → {:.4} mm ({:+.1} %)",
                    c.initial * 1e3,
                    c.run.estimate * 1e3,
                    (c.run.estimate / TRUTH - 1.0) * 100.0
                ))
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], line));
            chart.draw_series(path.iter().map(|&p| Circle::new(p, 2, colour.filled()))).map_err(plot_error)?;
            // The release-window update, made after the last window: from the last window's
            // estimate to the final one, drawn a little right of the end.
            let last = *path.last().unwrap_or(&(0.0, c.initial * 1e3));
            let end = (duration + final_offset(duration), c.run.estimate * 1e3);
            chart.draw_series(DashedLineSeries::new([last, end], 4, 3, colour.stroke_width(1))).map_err(plot_error)?;
            chart
                .draw_series([Circle::new(end, 5, colour.filled()), Circle::new(end, 5, TRUTH_COLOUR.stroke_width(1))])
                .map_err(plot_error)?;
        }
        // A legend entry for the final markers (drawn off the plot: only its legend shows).
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(plot_error)?
            .label("final estimate (release window, measured last)")
            .legend(|(x, y)| {
                EmptyElement::at((x + 10, y))
                    + Circle::new((0, 0), 5, BAND_COLOUR.filled())
                    + Circle::new((0, 0), 5, TRUTH_COLOUR.stroke_width(1))
            });

        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .margin(12)
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(190, 190, 190))
            .draw()
            .map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    let label = format!("UKF clearance estimates against time from three starts, {duration} s recording");
    Ok(svg.replacen("<svg ", &format!("<svg role=\"img\" aria-label=\"{label}\" "), 1))
}

/// A plotters error as an `anyhow` error (the backend's error type is not `Send + Sync`).
fn plot_error<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow::anyhow!("drawing the figure: {e}")
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
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("crank_plots: {e:#}");
            ExitCode::FAILURE
        }
    }
}
