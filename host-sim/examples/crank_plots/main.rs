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
//!   (`runs::grid(&[0.1e-3, 0.3e-3, 0.5e-3], 1, 720_000, 10.0)`: joints A, B, C × three
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
//! these files only say what each figure shows (`convergence.rs`, `fast.rs`).

mod convergence;
mod fast;

use edgekf_sim::report::plot::{Band, RGBColor, Stroke};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Default recording length, s (the CI test's).
const DEFAULT_DURATION: f64 = 4.0;
/// Accepted recording lengths, s: at least two windows, at most a few minutes of run time.
const DURATIONS: std::ops::RangeInclusive<f64> = 0.5..=60.0;

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

/// A band of ±`half` about `centre`, lightly filled with dashed edges.
fn band(name: String, centre: f64, half: f64) -> Band {
    let edge = Stroke::dashed(BAND_COLOUR, 1, 6, 4);
    Band { name, lo: centre - half, hi: centre + half, fill: BAND_FILL, edge }
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
        Command::Convergence { duration, outdir } => convergence::convergence(*duration, outdir),
        Command::Fast { outdir } => fast::fast(outdir),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("crank_plots: {e:#}");
            ExitCode::FAILURE
        }
    }
}
