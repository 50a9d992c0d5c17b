//! The whole of `edgekf crank train` as a library call: simulate (or load) the training grid,
//! fit the fast model, fit the release laws on their own grid of short runs, and score the model
//! on an unseen test grid. The pieces are in [`super::train`] and [`super::release`]; this module
//! only orders them, so that the command line parses and prints and nothing else.

use super::model::{FastModel, FeatureVector};
use super::release::ReleaseStage;
use super::runs::{self, Run};
use super::train;
use super::trained_for::TrainedFor;
use crate::systems::crank::CrankConfig;
use anyhow::{bail, Context, Result};
use std::path::PathBuf;

/// Window length of the features, s.
const WINDOW_S: f64 = 0.25;

/// What to train on and test with (the flags of `edgekf crank train`).
#[derive(Debug, Clone, PartialEq)]
pub struct TrainPlan {
    /// Training clearances, m (each simulated at every joint).
    pub clearances: Vec<f64>,
    /// Runs per joint and clearance.
    pub variants: usize,
    /// Length of each run, s.
    pub duration: f64,
    /// Simulation threads.
    pub threads: usize,
    /// Ridge regularisation on the standardised features.
    pub ridge: f64,
    /// First noise seed of the training grid.
    pub seed_base: u64,
    /// Regress `ln c` on the squares of the features too.
    pub squares: bool,
    /// Runs per joint and clearance of the release laws' grid (0: no release stage).
    pub release_variants: usize,
    /// First noise seed of the release grid.
    pub release_seed_base: u64,
    /// Largest `|ln c|` step to a release law's clearance that is taken.
    pub max_step: f64,
    /// Runs per joint and clearance of the unseen test grid (0: none).
    pub test_variants: usize,
    /// First noise seed of the test grid.
    pub test_seed_base: u64,
    /// Test clearances, m.
    pub test_clearances: Vec<f64>,
    /// Write the runs' features here (the test grid's to `.test.csv` beside it).
    pub save_features: Option<PathBuf>,
    /// Fit to these runs and features instead of simulating.
    pub load_features: Option<PathBuf>,
    /// Score on these runs and features instead of simulating the test grid.
    pub load_test_features: Option<PathBuf>,
}

impl TrainPlan {
    /// Checks the figures before any simulation starts.
    pub fn validate(&self) -> Result<()> {
        let ok = |c: &[f64]| !c.is_empty() && c.iter().all(|v| v.is_finite() && *v > 0.0 && *v < 0.01);
        if !ok(&self.clearances) || !ok(&self.test_clearances) {
            bail!("--clearances and --test-clearances must be clearances in metres (0.1 mm = 0.1e-3)");
        }
        if self.variants == 0 || !(self.duration.is_finite() && self.duration >= 0.5) {
            bail!("--variants must be at least 1 and --duration at least 0.5 s");
        }
        if !(self.ridge.is_finite() && self.ridge >= 0.0) {
            bail!("--ridge {} must be non-negative", self.ridge);
        }
        if self.release_variants > 0 && !(self.max_step.is_finite() && self.max_step > 0.0) {
            bail!("--max-step {} must be positive", self.max_step);
        }
        Ok(())
    }
}

/// How a model does on a set of runs ([`train::score`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Score {
    /// Runs scored.
    pub runs: usize,
    /// Share of runs whose joint was named right.
    pub joint_right: f64,
    /// Largest relative clearance error of those runs.
    pub worst: f64,
    /// RMS relative clearance error of those runs.
    pub rms: f64,
}

impl Score {
    fn of(model: &FastModel, runs: &[Run], feats: &[FeatureVector]) -> Self {
        let (joint_right, worst, rms) = train::score(model, runs, feats);
        Self { runs: runs.len(), joint_right, worst, rms }
    }
}

/// The trained model and how it does on its own runs.
#[derive(Debug, Clone)]
pub struct Trained {
    /// The model, ready to write.
    pub model: FastModel,
    /// Its score on the training runs.
    pub training: Score,
}

/// The model on the unseen test grid: each run with its features, and the score.
#[derive(Debug, Clone)]
pub struct Tested {
    /// The runs and their features.
    pub runs: Vec<(Run, FeatureVector)>,
    /// The score.
    pub score: Score,
    /// Runs whose joint was named right and clearance read within ±3 %.
    pub within_3_percent: usize,
}

/// Trains the fast model of `config` by `plan`; `progress` gets one line per run simulated.
pub fn train(config: &CrankConfig, plan: &TrainPlan, progress: &(dyn Fn(String) + Sync)) -> Result<Trained> {
    plan.validate()?;
    let grid = runs::grid(&plan.clearances, plan.variants, plan.seed_base, plan.duration);
    let total = grid.len();
    let show = |k: usize, r: &Run| {
        progress(format!(
            "run {:>4}/{total}: {} {:.3} mm, release {:.1}°, radius ×{:.2}, seed {}",
            k + 1,
            r.joint,
            r.clearance * 1e3,
            r.release_deg,
            r.radius,
            r.seed
        ))
    };
    let (runs, feats) = match &plan.load_features {
        Some(path) => train::read_features(path)?,
        None => {
            let feats = train::features_of(config, &grid, WINDOW_S, plan.threads, &show)?;
            (grid, feats)
        }
    };
    if let Some(path) = &plan.save_features {
        train::write_features(path, &runs, &feats).with_context(|| format!("{}: cannot write", path.display()))?;
    }
    let desc = format!(
        "{} runs of {} s: joints A, B, C × clearances {:?} mm × {} draws (release 20–40°, journal radius × 0.8–1.2), seeds from {}, adaptive integrator, ridge {}{}",
        runs.len(),
        plan.duration,
        plan.clearances.iter().map(|c| c * 1e3).collect::<Vec<_>>(),
        plan.variants,
        plan.seed_base,
        plan.ridge,
        if plan.squares { ", with squares" } else { "" }
    );
    let mut model = train::fit(&runs, &feats, WINDOW_S, plan.ridge, plan.squares, desc);
    model.trained_for = Some(TrainedFor::new(config, runs::RELEASE_RANGE_DEG, runs::RADIUS_RANGE));
    if plan.release_variants > 0 {
        let (stage, note) = release_stage(config, plan, &model, (&runs, &feats), progress)?;
        model.trained_on += &note;
        model.release = Some(stage);
    }
    let training = Score::of(&model, &runs, &feats);
    Ok(Trained { model, training })
}

/// The release laws, fitted on their own grid of short runs, and what they were trained on; the
/// window features' own error on the training runs weighs the hypotheses.
fn release_stage(
    config: &CrankConfig,
    plan: &TrainPlan,
    model: &FastModel,
    (runs, feats): (&[Run], &[FeatureVector]),
    progress: &(dyn Fn(String) + Sync),
) -> Result<(ReleaseStage, String)> {
    let grid = train::release_grid(&plan.clearances, plan.release_variants, plan.release_seed_base);
    let total = grid.len();
    let rf = train::features_of(config, &grid, WINDOW_S, plan.threads, &|k, _| {
        if (k + 1) % 100 == 0 || k + 1 == total {
            progress(format!("release run {}/{total}", k + 1));
        }
    })?;
    let labels: Vec<usize> = rf.iter().map(|f| f.missed.unwrap_or(usize::MAX)).collect();
    let seen = |h: usize| labels.iter().filter(|&&l| l == h).count();
    progress(format!(
        "release grid: contact seen in {} of {total} runs; first contact {} , second {}, later {}",
        rf.iter().filter(|f| f.release.is_some()).count(),
        seen(0),
        seen(1),
        labels.iter().filter(|&&l| (2..usize::MAX).contains(&l)).count()
    ));
    let features: Vec<_> = rf.iter().map(|f| f.release).collect();
    let (_, _, spread) = train::score(model, runs, feats);
    let windows = feats.iter().map(|f| f.windows as f64).sum::<f64>() / feats.len().max(1) as f64;
    let stage = ReleaseStage::fit(&grid, &features, &labels, plan.max_step, (spread, windows));
    for fit in stage.residuals(&grid, &features, &labels) {
        progress(format!(
            "release law {} / contact {}: {} runs, ln c residual RMS {:.4}, largest {:.4}",
            fit.joint,
            fit.hypothesis + 1,
            fit.runs,
            fit.rms,
            fit.largest
        ));
    }
    let note = format!(
        "; release laws: {total} runs of {:.2} s, {} draws, seeds from {}",
        grid.first().map_or(0.0, |r| r.duration),
        plan.release_variants,
        plan.release_seed_base
    );
    Ok((stage, note))
}

/// Scores `model` on the plan's unseen test grid (simulated, or loaded); `None` when the plan
/// has none.
pub fn test(config: &CrankConfig, model: &FastModel, plan: &TrainPlan) -> Result<Option<Tested>> {
    if plan.test_variants == 0 && plan.load_test_features.is_none() {
        return Ok(None);
    }
    let (test, tf) = match &plan.load_test_features {
        Some(path) => train::read_features(path)?,
        None => {
            let test = runs::grid(&plan.test_clearances, plan.test_variants, plan.test_seed_base, plan.duration);
            let tf = train::features_of(config, &test, WINDOW_S, plan.threads, &|_, _| {})?;
            (test, tf)
        }
    };
    if let Some(path) = &plan.save_features {
        let path = path.with_extension("test.csv");
        train::write_features(&path, &test, &tf).with_context(|| format!("{}: cannot write", path.display()))?;
    }
    let score = Score::of(model, &test, &tf);
    let within_3_percent = test
        .iter()
        .zip(&tf)
        .filter(|(r, f)| {
            let e = model.estimate_features(**f);
            e.joint == r.joint && (e.clearance[r.joint.index()] / r.clearance - 1.0).abs() <= 0.03
        })
        .count();
    Ok(Some(Tested { runs: test.into_iter().zip(tf).collect(), score, within_3_percent }))
}
