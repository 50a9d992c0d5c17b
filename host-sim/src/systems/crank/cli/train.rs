//! `edgekf crank train`: the fast estimator's model learned from simulated runs.

use super::{load_config, TrainArgs};
use crate::io::output::check;
use anyhow::Context as _;
use std::time::Instant;

pub(super) fn train(args: TrainArgs) -> anyhow::Result<()> {
    use super::super::estimate::training::{self, TrainPlan};
    let test_features = args.save_features.as_ref().map(|p| p.with_extension("test.csv"));
    let inputs = [args.config.as_deref(), args.load_features.as_deref(), args.load_test_features.as_deref()];
    check(&[Some(&args.out), args.save_features.as_deref(), test_features.as_deref()], &inputs)?;
    let config = load_config(args.config.as_deref())?;
    let plan = TrainPlan {
        clearances: args.clearances,
        variants: args.variants,
        duration: args.duration,
        threads: args.threads,
        ridge: args.ridge,
        seed_base: args.seed_base,
        squares: !args.linear,
        release_variants: args.release_variants,
        release_seed_base: args.release_seed_base,
        max_step: args.max_step,
        test_variants: args.test_variants,
        test_seed_base: args.test_seed_base,
        test_clearances: args.test_clearances,
        save_features: args.save_features,
        load_features: args.load_features,
        load_test_features: args.load_test_features,
    };
    plan.validate()?;
    let started = Instant::now();
    let progress = |line: String| eprintln!("crank train: {line} ({:.0} s elapsed)", started.elapsed().as_secs_f64());
    let trained = training::train(&config, &plan, &progress)?;
    let s = trained.training;
    println!(
        "training set: joint right in {:.1} % of {} runs; clearance error RMS {:.1} %, worst {:.1} %",
        s.joint_right * 100.0,
        s.runs,
        s.rms * 100.0,
        s.worst * 100.0
    );
    let model = trained.model;
    crate::io::output::write_atomic(&args.out, model.to_toml())
        .with_context(|| format!("{}: cannot write", args.out.display()))?;
    println!("wrote {}", args.out.display());
    if let Some(tested) = training::test(&config, &model, &plan)? {
        for (r, f) in &tested.runs {
            let e = model.estimate_features(*f);
            println!(
                "test {r}: named {} {:.4} mm ({:+.1} %; first stage {:+.1} %{})",
                e.joint,
                e.clearance[e.joint.index()] * 1e3,
                (e.clearance[e.joint.index()] / r.clearance - 1.0) * 100.0,
                (e.per_joint[r.joint.index()] / r.clearance - 1.0) * 100.0,
                match e.release {
                    Some(h) => format!(
                        ", release law {}",
                        ["first contact", "second contact", "third contact", "fourth contact"][h.min(3)]
                    ),
                    None => String::new(),
                }
            );
        }
        let s = tested.score;
        println!(
            "test set (unseen seeds and draws): joint right in {:.1} % of {} runs; clearance error RMS {:.1} %, worst {:.1} %, within ±3 % in {}",
            s.joint_right * 100.0,
            s.runs,
            s.rms * 100.0,
            s.worst * 100.0,
            tested.within_3_percent
        );
    }
    println!("wall {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}
