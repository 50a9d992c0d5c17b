//! `edgekf crank simulate`: one reference simulation into a data CSV, and its summary.

use super::super::config::Method;
use super::super::integrate::Integrator;
use super::super::simulate::{CrankRecording, SimOptions};
use super::super::{Joint, Mechanism};
use super::{describe_clearances, load_config, IntegratorArg, SimulateArgs};
use crate::io::output::check;
use anyhow::Context as _;
use std::io::Write as _;
use std::time::Instant;

pub(super) fn simulate(args: SimulateArgs) -> anyhow::Result<()> {
    check(&[Some(&args.files.out)], &[args.files.config.as_deref()])?;
    let mut config = load_config(args.files.config.as_deref())?;
    if let Some(step) = args.step {
        config.integrator.step = step;
    }
    if let Some(tol) = args.tolerance {
        config.integrator.tolerance = tol;
    }
    if let Some(i) = args.integrator {
        config.integrator.method = match i {
            IntegratorArg::Symplectic => Method::Symplectic,
            IntegratorArg::Adaptive => Method::Adaptive,
        };
    }
    config.validate().context("invalid --step or --tolerance")?;
    let mut clearances = [None; 3];
    let mut named = [false; 3];
    for (joint, c) in &args.clearances {
        let j = joint.index();
        if named[j] {
            anyhow::bail!("--clearance given twice for joint {joint}");
        }
        named[j] = true;
        clearances[j] = (*c > 0.0).then_some(*c);
    }
    let mech = Mechanism::new(&config, clearances)?;
    let mut opts = SimOptions::from_config(&config, args.duration);
    opts.seed = args.files.seed;
    let started = Instant::now();
    // Progress only for runs that take a while: at most one line per second of wall time.
    let mut last_shown = 0.0;
    let mut progress = |f: f64| {
        let elapsed = started.elapsed().as_secs_f64();
        if elapsed >= last_shown + 1.0 && f < 1.0 {
            last_shown = elapsed;
            eprintln!(
                "crank simulate: {:3.0} % ({:.2} of {} s simulated, {elapsed:.1} s elapsed)",
                f * 100.0,
                f * args.duration,
                args.duration,
            );
            let _ = std::io::stderr().flush();
        }
    };
    let rec = mech.simulate_with_progress(&opts, &mut progress)?;
    let wall = started.elapsed().as_secs_f64();
    // The data error already names its cause; flatten it so the cause is printed once.
    rec.write_csv(&args.files.out).map_err(|e| anyhow::anyhow!("{e}"))?;
    println!(
        "wrote {}: {} samples at {} Hz over {} s, seed {}",
        args.files.out.display(),
        rec.len(),
        opts.sample_rate,
        args.duration,
        opts.seed
    );
    print!("{}", summary(&mech, &rec, &opts.integrator, wall));
    Ok(())
}

/// The human-readable summary of a run.
pub fn summary(mech: &Mechanism, rec: &CrankRecording, integrator: &Integrator, wall_s: f64) -> String {
    let s = &rec.stats;
    let method = match integrator {
        Integrator::SymplecticEuler { step } => format!("symplectic Euler, step {step:e} s"),
        Integrator::Adaptive { tolerance, max_step } => {
            format!("adaptive Dormand–Prince 5(4), tolerance {tolerance:e}, max step {max_step:e} s")
        }
    };
    let mut out = format!("clearances: {}\n", describe_clearances(&mech.clearances()));
    out += &format!(
        "integrator: {method}: {} steps ({} rejected), {} evaluations, steps {:.3e}–{:.3e} s, wall {:.2} s\n",
        s.steps, s.rejected, s.evaluations, s.step_range.0, s.step_range.1, wall_s
    );
    for joint in Joint::ALL {
        let kind = if mech.clearance(joint).is_some() { "contact" } else { "pin reaction" };
        out += &format!(
            "joint {joint}: {} impacts, peak {kind} force {:.1} N\n",
            s.impacts[joint.index()],
            rec.peak_force(joint)
        );
    }
    let e0 = rec.truth_energy.first().copied().unwrap_or(0.0);
    let e1 = rec.truth_energy.last().copied().unwrap_or(0.0);
    let d1 = rec.truth_dissipated.last().copied().unwrap_or(0.0);
    out += &format!(
        "energy: start {e0:.6} J, end {e1:.6} J, dissipated {d1:.3e} J, balance error max {:.3e} J, largest climb {:.3e} J\n",
        rec.energy_balance_error(),
        rec.energy_rise()
    );
    out += &format!("constraints: largest residual {:.1e} m\n", rec.max_constraint_residual);
    let rms = (rec.truth_crank_alpha.iter().map(|v| v * v).sum::<f64>() / rec.len().max(1) as f64).sqrt();
    out += &format!(
        "crank: angle {:.2}° → {:.2}°, angular acceleration RMS {rms:.1} rad/s² (truth)\n",
        rec.truth_crank_angle.first().copied().unwrap_or(0.0).to_degrees(),
        rec.truth_crank_angle.last().copied().unwrap_or(0.0).to_degrees(),
    );
    out
}
