//! `edgekf crank estimate`: a recording's clearance by the paper's UKF or the fast model.
//!
//! One step per estimator: each prints its own summary and returns the rows; the estimate file
//! is written in one place, whichever estimator made them.

use super::super::config::CrankConfig;
use super::super::error::CrankError;
use super::super::estimate::fast::FeatureMap;
use super::super::estimate::model::FastModel;
use super::super::estimate::{self, release, ukf, EstimateRow, Recording};
use super::super::Joint;
use super::{describe_clearances, load_config, EstimateArgs, MethodArg};
use crate::io::output::check;
use crate::report::summary::{EstimateSummary, Prose, Quantity};
use std::path::Path;
use std::time::Instant;

pub(super) fn estimate(args: EstimateArgs) -> anyhow::Result<()> {
    check(&[Some(&args.files.out)], &[Some(&args.files.data), args.files.config.as_deref(), args.model.as_deref()])?;
    let config = load_config(args.files.config.as_deref())?;
    let (rec, notes) = Recording::read(&args.files.data, &config.timeline)?;
    for line in notes {
        eprintln!("{line}");
    }
    let truth = rec.truth_clearance.map(|c| describe_clearances(&c.map(|v| (v > 0.0).then_some(v))));
    let truth = truth.map_or(String::new(), |t| format!("; truth: {t}"));
    let started = Instant::now();
    let prose = args.files.prose();
    let rows = match args.method {
        MethodArg::Ukf => by_ukf(prose, &args, &config, &rec, &truth, started)?,
        MethodArg::Fast => match fast_model(args.model.as_deref())? {
            Fast::Model(model) => by_model(prose, &args.files.data, &config, &rec, &model, &truth, started)?,
            Fast::Legacy(map) => by_legacy_map(prose, &args.files.data, &rec, &map, &truth)?,
        },
    };
    estimate::write_estimates(&args.files.out, &rows).map_err(|e| anyhow::anyhow!("{e}"))?;
    prose.say(format_args!("wrote {}: {} rows", args.files.out.display(), rows.len()));
    if args.files.json {
        json_summary(&args, &rec, &rows).print()?;
    }
    Ok(())
}

/// The JSON object: per joint the clearance over the windows, `final` the last row's (the
/// estimate for the whole recording), and against the truth the final estimate's error in m
/// and, at a loose joint, in per cent.
fn json_summary(args: &EstimateArgs, rec: &Recording, rows: &[EstimateRow]) -> EstimateSummary {
    let mut j = args.files.summary("crank", &rec.t);
    for joint in Joint::ALL {
        let values: Vec<f64> = rows.iter().map(|r| r.clearance[joint.index()]).collect();
        let mut q = Quantity::of("m", &values);
        if let (Some(truth), Some(last)) = (rec.truth_clearance.map(|c| c[joint.index()]), values.last()) {
            let pct = if truth > 0.0 { (last - truth) / truth * 100.0 } else { f64::NAN };
            q = q.map(|q| q.with_error("truth", truth).with_error("final", last - truth).with_error("final_pct", pct));
        }
        j.quantity(format!("clearance_{joint}"), q);
    }
    j.detail("method", format!("{:?}", args.method).to_lowercase());
    j.detail("windows", rows.len().saturating_sub(1));
    j
}

/// An error about the recording, named by its file.
fn on_data(data: &Path) -> impl Fn(anyhow::Error) -> anyhow::Error + '_ {
    move |e| e.context(data.display().to_string())
}

/// The paper's UKF, a progress line per window on stderr.
fn by_ukf(
    prose: Prose,
    args: &EstimateArgs,
    config: &CrankConfig,
    rec: &Recording,
    truth: &str,
    started: Instant,
) -> anyhow::Result<Vec<EstimateRow>> {
    let opts = ukf_options(args)?;
    let mut progress = |k: usize, s: &ukf::UkfStep| {
        eprintln!(
            "window {k:>3} (t {:.2} s): a measured {:>8} predicted {:7.1}, sigma {:.4}/{:.4}/{:.4} mm → A {:.4} ± {:.4} mm",
            s.t,
            s.measured.map_or("—".to_string(), |a| format!("{a:.1}")),
            s.predicted,
            s.sigma[0] * 1e3,
            s.sigma[1] * 1e3,
            s.sigma[2] * 1e3,
            s.clearance * 1e3,
            s.std * 1e3
        );
    };
    let run = ukf::run(config, rec, &opts, &mut progress).map_err(|e| match e {
        CrankError::Data(_) => on_data(&args.files.data)(e.into()),
        e => e.into(),
    })?;
    prose.say(format_args!(
        "ukf: {} windows of {} s, R std {:.1} rad/s², {} simulations, {} integration steps, wall {:.2} s",
        run.steps.len(),
        args.window,
        run.measurement_std,
        run.simulations,
        run.integration_steps,
        started.elapsed().as_secs_f64()
    ));
    prose.say(format_args!(
        "estimate: A {:.4} ± {:.4} mm (last window {:.4} mm){truth}",
        run.estimate * 1e3,
        run.estimate_std * 1e3,
        run.steps.last().map_or(f64::NAN, |s| s.clearance) * 1e3,
    ));
    Ok(run.rows())
}

/// The UKF's options from the command line (`--paper` keeps the paper's ensemble size).
fn ukf_options(args: &EstimateArgs) -> anyhow::Result<ukf::UkfOptions> {
    if !(args.initial.is_finite() && args.initial > 0.0 && args.initial < 0.01) {
        anyhow::bail!("--initial {} m must be a clearance in metres (0.1 mm = 0.1e-3)", args.initial);
    }
    let base = if args.paper { ukf::UkfOptions::paper() } else { ukf::UkfOptions::default() };
    if args.members == 0 {
        anyhow::bail!("--members must be at least 1");
    }
    Ok(ukf::UkfOptions {
        initial: args.initial,
        window: args.window,
        measurement_std: args.measurement_std,
        members: if args.paper { base.members } else { args.members },
        ..base
    })
}

/// What `--model` holds: a learned model (boxed: it is ten times the map's size), or an old
/// impact-rate map.
enum Fast {
    Model(Box<FastModel>),
    Legacy(FeatureMap),
}

/// The built-in model, or `--model`'s file read as a learned model and failing that as a legacy
/// map (the learned model's error is the one reported when neither reads).
fn fast_model(path: Option<&Path>) -> anyhow::Result<Fast> {
    let Some(path) = path else { return Ok(Fast::Model(Box::new(FastModel::builtin()))) };
    match FastModel::load(path) {
        Ok(model) => Ok(Fast::Model(Box::new(model))),
        Err(e) => FeatureMap::load(path).map(Fast::Legacy).map_err(|_| e),
    }
}

/// A legacy impact-rate map (joint A only).
fn by_legacy_map(
    prose: Prose,
    data: &Path,
    rec: &Recording,
    map: &FeatureMap,
    truth: &str,
) -> anyhow::Result<Vec<EstimateRow>> {
    let est = map.estimate(rec).map_err(on_data(data))?;
    prose.say(format_args!(
        "fast (legacy impact-rate map, joint A): {} windows, {} feature operations",
        est.windows, est.operations
    ));
    prose.say(format_args!("estimate: {}{truth}", describe_clearances(&est.clearance.map(|v| (v > 0.0).then_some(v)))));
    Ok(est.rows(rec))
}

/// The learned model: warnings where the configuration is outside what it was trained for, then
/// its scores, where the clearance came from (the release stage or the window features) and the
/// estimate.
fn by_model(
    prose: Prose,
    data: &Path,
    config: &CrankConfig,
    rec: &Recording,
    model: &FastModel,
    truth: &str,
    started: Instant,
) -> anyhow::Result<Vec<EstimateRow>> {
    if let Some(t) = &model.trained_for {
        for w in t.check(config).map_err(anyhow::Error::msg)? {
            eprintln!("warning: {w}");
        }
    }
    let est = model.estimate(rec).map_err(on_data(data))?;
    prose.say(format_args!(
        "fast: {} windows, {} operations, wall {:.3} s; joint scores A {:.2}, B {:.2}, C {:.2}{}",
        est.features.windows,
        est.operations,
        started.elapsed().as_secs_f64(),
        est.scores[0],
        est.scores[1],
        est.scores[2],
        match rec.missing() {
            0 => String::new(),
            m => format!("; {m} missing sample(s) skipped, their time counted by the release stage"),
        }
    ));
    let features_only = est.per_joint[est.joint.index()] * 1e3;
    match (est.features.release, est.release) {
        (Some(r), Some(h)) => prose.say(format_args!(
            "release: first contact seen at {:.1} ms, crank acceleration before it {:.1} rad/s²; taken as contact {} after release: {} {:.4} mm (window features alone {features_only:.4} mm)",
            r.contact * 1e3,
            r.release_alpha,
            h + 1,
            est.joint,
            est.clearance[est.joint.index()] * 1e3
        )),
        (Some(r), None) => prose.say(format_args!(
            "release: first contact seen at {:.1} ms, crank acceleration before it {:.1} rad/s²; no release law fits it, so the window features give the clearance ({features_only:.4} mm)",
            r.contact * 1e3,
            r.release_alpha
        )),
        (None, _) => prose.say(format_args!(
            "release: no contact seen in the first {} s; the window features give the clearance ({features_only:.4} mm)",
            release::RELEASE_SPAN
        )),
    }
    prose.say(format_args!(
        "estimate: joint {}: {}{truth}",
        est.joint,
        describe_clearances(&est.clearance.map(|v| (v > 0.0).then_some(v))),
    ));
    model.rows(rec, &est)
}
