//! `edgekf rotor estimate` and `edgekf rotor export`: the work behind the commands (the
//! argument parsing lives with the other rotor commands).

use super::estimate::{discrete, run, Estimates, FilterPrecision};
use super::reduce::{reduce, ForceModel, ReducedRotor, Tuning};
use crate::io::data::{self, DataFile};
use crate::rotor::{RotorConfig, RotorModel};
use anyhow::{bail, Context, Result};
use edgekf::export::{write_model, write_steady_state};
use edgekf::filter::solve_riccati;
use std::path::Path;

fn load(config: &Path, modes: usize, random_walk: bool) -> Result<(RotorModel, ReducedRotor)> {
    let cfg = RotorConfig::load(config).with_context(|| format!("{}: cannot load the rotor", config.display()))?;
    let model = RotorModel::from_config(&cfg)?;
    let force_model = if random_walk { ForceModel::RandomWalk } else { ForceModel::Phasor };
    let tuning = Tuning { modes, force_model, ..Tuning::default() };
    let red = reduce(&model, cfg.operation.speed, &tuning)?;
    Ok((model, red))
}

/// RMS of `est − truth` over samples with `t ≥ t0` (NaN if none).
fn rms_error(t: &[f64], est: &[f64], truth: &[f64], t0: f64) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for k in 0..t.len().min(est.len()).min(truth.len()) {
        if t[k] >= t0 && truth[k].is_finite() {
            s += (est[k] - truth[k]).powi(2);
            n += 1;
        }
    }
    if n == 0 {
        f64::NAN
    } else {
        (s / n as f64).sqrt()
    }
}

/// Runs the virtual-sensing filter over a data file; prints notices and a summary, writes the
/// estimates if asked.
pub fn estimate(
    config: &Path,
    data_path: &Path,
    out: Option<&Path>,
    f32: bool,
    modes: usize,
    random_walk: bool,
) -> Result<()> {
    let (model, red) = load(config, modes, random_walk)?;
    let known: Vec<String> = red.channels.clone();
    let known_refs: Vec<&str> = known.iter().map(String::as_str).collect();
    let (file, report) = data::read(data_path, &known_refs)?;
    eprintln!("{}: {report}", data_path.display());
    let expected = red.sample_rate;
    if (report.timing.sample_rate - expected).abs() > 0.01 * expected {
        bail!(
            "{}: sampled at {:.3} Hz, the configuration says {expected} Hz ([operation] sample_rate)",
            data_path.display(),
            report.timing.sample_rate
        );
    }
    let precision = if f32 { FilterPrecision::F32 } else { FilterPrecision::F64 };
    let est = run(&red, &file, precision)?;
    print_summary(&model, &red, &file, &est, precision);
    if let Some(out) = out {
        write_estimates(out, &est)?;
        println!("wrote {}", out.display());
    }
    Ok(())
}

fn print_summary(model: &RotorModel, red: &ReducedRotor, file: &DataFile, est: &Estimates, precision: FilterPrecision) {
    println!(
        "rotor virtual sensing ({:?}): {} modes ({:.1}–{:.1} Hz), {} states, forces at nodes {:?}, speed {} rad/s",
        precision,
        red.frequencies_hz.len(),
        red.frequencies_hz.first().copied().unwrap_or(0.0),
        red.frequencies_hz.last().copied().unwrap_or(0.0),
        red.states(),
        red.force_nodes,
        red.speed
    );
    println!("samples {}, missing {}, filter repairs {:?}", est.t.len(), est.missing, est.repairs);
    for (i, name) in red.channels.iter().enumerate() {
        let v: Vec<f64> = est.innovation[i].iter().copied().filter(|x| x.is_finite()).collect();
        let rms = (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
        println!("innovation RMS {name}: {rms:.3e}");
    }
    let nis: Vec<f64> = est.nis.iter().copied().filter(|x| x.is_finite()).collect();
    println!("NIS mean {:.3} (consistent: {})", nis.iter().sum::<f64>() / nis.len().max(1) as f64, red.channels.len());
    let nodes = model.n_nodes();
    let mut any_truth = false;
    for node in 0..nodes {
        for (d, dir) in ["x", "y"].iter().enumerate() {
            let Some(truth) = file.column(&format!("truth_n{node}_{dir}")) else { continue };
            any_truth = true;
            let e = &est.displacement[2 * node + d];
            if red.force_nodes.contains(&node) || red.channels.iter().any(|c| c == &format!("n{node}_{dir}")) {
                println!(
                    "n{node}_{dir}: RMS error {:.3} µm for t ≥ 1 s ({:.3} µm over the whole run)",
                    rms_error(&est.t, e, truth, 1.0) * 1e6,
                    rms_error(&est.t, e, truth, f64::NEG_INFINITY) * 1e6
                );
            }
        }
    }
    if !any_truth {
        println!("(no truth_ columns: errors not computed)");
    }
}

fn write_estimates(out: &Path, est: &Estimates) -> Result<()> {
    let mut names: Vec<&str> = est.displacement_names.iter().map(String::as_str).collect();
    names.extend(est.force_names.iter().map(String::as_str));
    let mut cols: Vec<&[f64]> = est.displacement.iter().map(Vec::as_slice).collect();
    cols.extend(est.force.iter().map(Vec::as_slice));
    data::write(out, &names, &est.t, &cols)?;
    Ok(())
}

/// Writes the discrete reduced model and its steady-state gain as Rust constants
/// (`ROTOR_A`, `_C`, `_Q`, `_R`, `_GAIN`, `_S`, and `ROTOR_DISK_*` output rows) for the firmware.
pub fn export(config: &Path, out: &Path, modes: usize) -> Result<()> {
    let (_, red) = load(config, modes, false)?;
    if (red.states(), red.c.nrows()) != (20, 4) {
        bail!(
            "the firmware build supports 20 states × 4 sensors; this configuration gives {} × {}",
            red.states(),
            red.c.nrows()
        );
    }
    let model = discrete::<20, 4, 40>(&red)?;
    let ss = solve_riccati(&model, 1e-12, 200_000).map_err(|e| anyhow::anyhow!("no steady-state gain: {e:?}"))?;
    let mut text = format!(
        "// Generated by `edgekf rotor export --config {}`: {} modes, forces at nodes {:?}, {} rad/s, {} Hz.\n\
         // Steady-state gain after {} Riccati iterations. Do not edit.\n",
        config.display(),
        modes,
        red.force_nodes,
        red.speed,
        red.sample_rate,
        ss.iterations
    );
    let err = |_| anyhow::anyhow!("a model value is not finite");
    write_model(&mut text, "ROTOR", &model).map_err(err)?;
    write_steady_state(&mut text, "ROTOR", &ss).map_err(err)?;
    std::fs::write(out, text).with_context(|| format!("writing {}", out.display()))?;
    println!("wrote {}: discrete model (20 states, 4 sensors) and steady-state gain", out.display());
    Ok(())
}
