//! `edgekf rotor estimate` and `edgekf rotor export`: the work behind the commands (the
//! argument parsing lives with the other rotor commands).

use crate::io::data::{self, DataFile};
use crate::io::timeline::bridge;
use crate::report::summary::{truth, EstimateSummary, Prose, Quantity, Stats};
use crate::systems::rotor::estimate::filter::{discrete, run_with, Estimates, FilterPrecision, RunOptions};
use crate::systems::rotor::estimate::reduce::{reduce, ForceModel, ReducedRotor, Tuning};
use crate::systems::rotor::{RotorConfig, RotorModel};
use anyhow::{bail, Context, Result};
use edgekf::export::{write_matrix, write_model, write_steady_state};
use edgekf::filter::solve_riccati;
use std::path::Path;

/// Options of `edgekf rotor estimate`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EstimateOptions {
    /// The chip's arithmetic.
    pub f32: bool,
    /// Modes kept.
    pub modes: usize,
    /// The paper's random-walk forces.
    pub random_walk: bool,
    /// [`Tuning::robust`] instead of the default tuning.
    pub robust: bool,
    /// Switch to the steady-state gain at this time, s.
    pub steady_after: Option<f64>,
    /// One JSON object on stdout, the text on stderr.
    pub json: bool,
}

fn load_tuned(config: &Path, modes: usize, random_walk: bool, robust: bool) -> Result<(RotorModel, ReducedRotor)> {
    let cfg = RotorConfig::load(config).with_context(|| format!("{}: cannot load the rotor", config.display()))?;
    let model = RotorModel::from_config(&cfg)?;
    let force_model = if random_walk { ForceModel::RandomWalk } else { ForceModel::Phasor };
    let base = if robust { Tuning::robust() } else { Tuning::default() };
    let tuning = Tuning { modes, force_model, ..base };
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
pub fn estimate(config: &Path, data_path: &Path, out: Option<&Path>, options: &EstimateOptions) -> Result<()> {
    crate::io::output::check(&[out], &[Some(data_path), Some(config)])?;
    let (model, red) = load_tuned(config, options.modes, options.random_walk, options.robust)?;
    let channels: Vec<&str> = red.channels.iter().map(String::as_str).collect();
    let prose = Prose { json: options.json };
    let (file, report) = data::read_required(data_path, &channels, &[])?;
    eprintln!("{}: {report}", data_path.display());
    let expected = red.sample_rate;
    if (report.timing.sample_rate - expected).abs() > 0.01 * expected {
        bail!(
            "{}: sampled at {:.3} Hz, the configuration says {expected} Hz ([operation] sample_rate)",
            data_path.display(),
            report.timing.sample_rate
        );
    }
    let (file, timeline) = bridge(&file, &report.timing, &model.config().timeline);
    for n in timeline.notices() {
        eprintln!("notice: {n}");
    }
    let precision = if options.f32 { FilterPrecision::F32 } else { FilterPrecision::F64 };
    let run_options = RunOptions { steady_after: options.steady_after };
    let est = run_stretches(&red, &file, &timeline.stretches(file.len()), precision, &run_options)?;
    print_summary(prose, &model, &red, &file, &est, precision);
    if let Some(out) = out {
        write_estimates(out, &est)?;
        prose.say(format_args!("wrote {}", out.display()));
    }
    if options.json {
        let mut j = EstimateSummary::new("rotor", data_path, Some(config), &est.t);
        json_quantities(&mut j, &model, &red, &file, &est);
        j.detail("precision", format!("{precision:?}").to_lowercase());
        j.out = out.map(Path::to_path_buf);
        j.print()?;
    }
    Ok(())
}

/// The nodes whose displacement the text reports (the unbalance nodes and the sensors'), as
/// (node, direction index, direction).
fn reported_nodes(model: &RotorModel, red: &ReducedRotor) -> Vec<(usize, usize, &'static str)> {
    let mut nodes = Vec::new();
    for node in 0..model.n_nodes() {
        for (d, dir) in ["x", "y"].into_iter().enumerate() {
            if red.force_nodes.contains(&node) || red.channels.iter().any(|c| c == &format!("n{node}_{dir}")) {
                nodes.push((node, d, dir));
            }
        }
    }
    nodes
}

/// The JSON object's quantities: the reported nodes' displacements (with the text's RMS
/// errors, whole run and `t ≥ 1 s`), each unbalance force's components and its magnitude
/// (whose `final` is the force the run ends with) against `truth_f<k>_*` where present.
fn json_quantities(j: &mut EstimateSummary, model: &RotorModel, red: &ReducedRotor, file: &DataFile, est: &Estimates) {
    for (node, d, dir) in reported_nodes(model, red) {
        let e = &est.displacement[2 * node + d];
        let mut q = Quantity::of("m", e).map(Quantity::without_final);
        if let Some(truth) = truth(file.column(&format!("truth_n{node}_{dir}"))) {
            let whole = rms_error(&est.t, e, truth, f64::NEG_INFINITY);
            let settled = rms_error(&est.t, e, truth, 1.0);
            q = q.map(|q| q.with_error("rms", whole).with_error("rms_after_1s", settled));
        }
        j.quantity(format!("n{node}_{dir}"), q);
    }
    for pair in est.force_names.chunks(2).zip(est.force.chunks(2)) {
        let (names, forces) = pair;
        for (name, f) in names.iter().zip(forces) {
            let q = Quantity::of("N", f)
                .map(|q| q.without_final().against(f, truth(file.column(&format!("truth_{name}")))));
            j.quantity(name.clone(), q);
        }
        if let ([x, y], [fx, fy]) = (names, forces) {
            let node = x.trim_end_matches("_x");
            let magnitude = |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(a, b)| a.hypot(*b)).collect() };
            let m = magnitude(fx, fy);
            let truth_m = match (truth(file.column(&format!("truth_{x}"))), truth(file.column(&format!("truth_{y}")))) {
                (Some(tx), Some(ty)) => Some(magnitude(tx, ty)),
                _ => None,
            };
            j.quantity(format!("{node}_magnitude"), Quantity::of("N", &m).map(|q| q.against(&m, truth_m.as_deref())));
        }
    }
    j.detail("nis_mean", Stats::of(&est.nis).map(|s| s.mean));
    j.detail("missing_samples", est.missing);
    j.detail("force_nodes", &red.force_nodes);
}

/// The filter over each stretch between restarts (a fresh filter each), the estimates
/// concatenated; the steady-state switch counts from each stretch's start.
fn run_stretches(
    red: &ReducedRotor,
    file: &DataFile,
    stretches: &[std::ops::Range<usize>],
    precision: FilterPrecision,
    options: &RunOptions,
) -> Result<Estimates> {
    let mut all: Option<Estimates> = None;
    for r in stretches {
        let part = DataFile {
            sha256: None,
            names: file.names.clone(),
            t: file.t[r.clone()].to_vec(),
            columns: file.columns.iter().map(|c| c[r.clone()].to_vec()).collect(),
        };
        let t0 = part.t.first().copied().unwrap_or(0.0) - file.t.first().copied().unwrap_or(0.0);
        let shifted = RunOptions { steady_after: options.steady_after.map(|s| s + t0) };
        let est = run_with(red, &part, precision, &shifted)?;
        match all.as_mut() {
            None => all = Some(est),
            Some(a) => a.append(est),
        }
    }
    all.ok_or_else(|| anyhow::anyhow!("no samples to estimate"))
}

/// The run in words: the model, the innovations, the NIS and the errors against truth.
fn print_summary(
    prose: Prose,
    model: &RotorModel,
    red: &ReducedRotor,
    file: &DataFile,
    est: &Estimates,
    precision: FilterPrecision,
) {
    prose.say(format_args!(
        "rotor virtual sensing ({:?}): {} modes ({:.1}–{:.1} Hz), {} states, forces at nodes {:?}, speed {} rad/s",
        precision,
        red.frequencies_hz.len(),
        red.frequencies_hz.first().copied().unwrap_or(0.0),
        red.frequencies_hz.last().copied().unwrap_or(0.0),
        red.states(),
        red.force_nodes,
        red.speed
    ));
    prose.say(format_args!("samples {}, missing {}, filter repairs {:?}", est.t.len(), est.missing, est.repairs));
    for (i, name) in red.channels.iter().enumerate() {
        let v: Vec<f64> = est.innovation[i].iter().copied().filter(|x| x.is_finite()).collect();
        let rms = (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
        prose.say(format_args!("innovation RMS {name}: {rms:.3e}"));
    }
    let nis_mean = Stats::of(&est.nis).map_or(0.0, |s| s.mean);
    prose.say(format_args!("NIS mean {nis_mean:.3} (consistent: {})", red.channels.len()));
    for (node, d, dir) in reported_nodes(model, red) {
        let Some(truth) = file.column(&format!("truth_n{node}_{dir}")) else { continue };
        let e = &est.displacement[2 * node + d];
        let whole = rms_error(&est.t, e, truth, f64::NEG_INFINITY) * 1e6;
        let settled = rms_error(&est.t, e, truth, 1.0) * 1e6;
        if settled.is_finite() {
            prose.say(format_args!(
                "n{node}_{dir}: RMS error {settled:.3} µm for t ≥ 1 s ({whole:.3} µm over the whole run)"
            ));
        } else {
            prose.say(format_args!("n{node}_{dir}: RMS error {whole:.3} µm over the whole run (none after 1 s)"));
        }
    }
    let truth_at = |node: usize, dir: &str| file.column(&format!("truth_n{node}_{dir}")).is_some();
    if !(0..model.n_nodes()).any(|node| truth_at(node, "x") || truth_at(node, "y")) {
        prose.say("(no truth_ columns: errors not computed)");
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
/// `robust`: [`Tuning::robust`] instead of the default tuning.
pub fn export(config: &Path, out: &Path, modes: usize, robust: bool) -> Result<()> {
    crate::io::output::check(&[Some(out)], &[Some(config)])?;
    let (text, states) = export_sized_text(config, modes, robust)?;
    crate::io::output::write_atomic(out, text).with_context(|| format!("writing {}", out.display()))?;
    println!(
        "wrote {}: discrete model ({states} states, 4 sensors), steady-state gain, P0 and its start-up filter, disk and force rows",
        out.display()
    );
    Ok(())
}

/// Rank of the node's start-up deviation from the steady state for the 20-state model
/// (displacement probes): the four unbalance-force states, whose prior is wide
/// (`initial_force_std`), against a modal prior at the noise level.
pub const START_RANK: usize = 12;

/// Rank of the start-up deviation for the 28-state model (accelerometers with their
/// 2nd-order low-passes as states): as for the probes, the four force directions and eight
/// modal directions whose prior is below the steady state; the largest left out is the same
/// (a relative eigenvalue of −1.0, the header of `generated/rotor_accel.rs`).
pub const ACCEL_START_RANK: usize = 12;

/// The Rust source [`export`] writes with the default tuning (the firmware's
/// `firmware/src/systems/rotor/generated/rotor.rs` is this text for `host-sim/configs/rotor_paper.toml`, which a
/// cross-crate test checks).
pub fn export_text(config: &Path, modes: usize) -> Result<String> {
    Ok(export_sized_text(config, modes, false)?.0)
}

/// The Rust source [`export`] writes, and the model's state count: 20 states (displacement
/// probes) or 28 (accelerometers with 2nd-order low-passes, `firmware/src/systems/rotor/generated/rotor_accel.rs` for
/// `rotor_paper_accel.toml` with `robust`), 4 sensors and 2 unbalance nodes.
pub fn export_sized_text(config: &Path, modes: usize, robust: bool) -> Result<(String, usize)> {
    let (_, red) = load_tuned(config, modes, false, robust)?;
    let text = match (red.states(), red.c.nrows()) {
        (20, 4) => export_model::<20, 40, START_RANK>(config, modes, robust, &red)?,
        (28, 4) => export_model::<28, 56, ACCEL_START_RANK>(config, modes, robust, &red)?,
        (n, m) => bail!("the firmware build supports 20 or 28 states × 4 sensors; this configuration gives {n} × {m}"),
    };
    Ok((text, red.states()))
}

/// [`export_sized_text`] at `N` states (`N2 = 2 N` for the discretisation), start-up rank `R`.
fn export_model<const N: usize, const N2: usize, const R: usize>(
    config: &Path,
    modes: usize,
    robust: bool,
    red: &ReducedRotor,
) -> Result<String> {
    let model = discrete::<N, 4, N2>(red)?;
    let ss = solve_riccati(&model, 1e-12, 200_000).map_err(|e| anyhow::anyhow!("no steady-state gain: {e:?}"))?;
    let mut text = format!(
        "// Generated by `edgekf rotor export --config {}{}`: {} modes, forces at nodes {:?}, {} rad/s, {} Hz.\n\
         // Sensors: {}. Steady-state gain after {} Riccati iterations. Do not edit.\n",
        config.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default(),
        if robust { " --robust" } else { "" },
        modes,
        red.force_nodes,
        red.speed,
        red.sample_rate,
        red.channels.join(", "),
        ss.iterations
    );
    let err = |_| anyhow::anyhow!("a model value is not finite");
    write_model(&mut text, "ROTOR", &model).map_err(err)?;
    write_steady_state(&mut text, "ROTOR", &ss).map_err(err)?;
    // What the node reports: the disk nodes' x/y displacement (virtual sensors) and the forces.
    let disks: Vec<usize> = red.force_nodes.clone();
    if disks.len() != 2 {
        bail!("the firmware build expects 2 unbalance nodes, found {:?}", disks);
    }
    let rows = |m: &nalgebra::DMatrix<f64>, idx: &[usize]| -> nalgebra::SMatrix<f64, 4, N> {
        nalgebra::SMatrix::from_fn(|i, j| m[(idx[i], j)])
    };
    let disk_rows = [2 * disks[0], 2 * disks[0] + 1, 2 * disks[1], 2 * disks[1] + 1];
    let p0: nalgebra::SMatrix<f64, N, N> = nalgebra::SMatrix::from_fn(|i, j| red.p0[(i, j)]);
    write_matrix(&mut text, "ROTOR", "P0", "Initial state covariance.", &p0).map_err(err)?;
    // The node's start-up filter: the steady state plus the prior's deviation from it, of
    // rank R (the unbalance forces' wide prior).
    let (start, fit) = edgekf::filter::LowRankDesign::<f64, N, 4, R>::from_prior(&model, &ss, &p0)
        .ok_or_else(|| anyhow::anyhow!("the steady innovation covariance is not positive definite"))?;
    write_matrix(&mut text, "ROTOR", "CLOSED", "Steady closed loop A (I − K C).", &start.closed).map_err(err)?;
    write_matrix(&mut text, "ROTOR", "PCT", "Steady predicted covariance times Cᵀ.", &start.pct).map_err(err)?;
    write_matrix(&mut text, "ROTOR", "S_INV", "Inverse of the steady innovation covariance.", &start.s_inv)
        .map_err(err)?;
    let doc = format!(
        "Start-up deviation U0 (P0 ≈ P + U0 diag(SIGNS) U0ᵀ): eigenvalues relative to P {:?} kept, largest left out {:e}.",
        fit.kept.as_slice(),
        fit.dropped
    );
    write_matrix(&mut text, "ROTOR", "U0", &doc, &start.u0).map_err(err)?;
    write_matrix(&mut text, "ROTOR", "SIGNS", "Signs of the start-up deviation's columns.", &start.signs)
        .map_err(err)?;
    let doc = format!("Displacement rows of the unbalance (disk) nodes {:?}: x, y of each, m.", disks);
    write_matrix(&mut text, "ROTOR", "DISK", &doc, &rows(&red.displacement, &disk_rows)).map_err(err)?;
    write_matrix(
        &mut text,
        "ROTOR",
        "FORCE",
        "Force rows: F_x, F_y of each disk node, N.",
        &rows(&red.force, &[0, 1, 2, 3]),
    )
    .map_err(err)?;
    Ok(text)
}

/// Tunes the filter on a simulated training record and reports it on held-out seeds
/// (`edgekf rotor tune`).
pub fn tune(config: &Path, likelihood: bool, seed: u64, duration: f64, budget: usize, modes: usize) -> Result<()> {
    use crate::systems::rotor::estimate::tune::{held_out, tune, Objective, Optimiser};
    let cfg = RotorConfig::load(config).with_context(|| format!("{}: cannot load the rotor", config.display()))?;
    let model = RotorModel::from_config(&cfg)?;
    let speed = cfg.operation.speed;
    if !(duration.is_finite() && duration >= 0.5) {
        bail!("--duration must be at least 0.5 s");
    }
    if budget < 16 {
        bail!("--budget must be at least 16 evaluations");
    }
    let base = Tuning { modes, ..Tuning::default() };
    let train = model
        .simulate(&crate::systems::rotor::SimOptions { duration, seed, ..Default::default() })
        .with_context(|| format!("{}: cannot simulate the training record", config.display()))?
        .to_data_file();
    let (objective, optimiser, label) = if likelihood {
        (Objective::Likelihood, Optimiser::NelderMead { max_evals: budget }, "maximum likelihood (Nelder–Mead)")
    } else {
        let population = 12;
        (
            Objective::Compromise,
            Optimiser::DifferentialEvolution { population, generations: budget / population - 1 },
            "compromise Σ(1 − |R²|) (differential evolution)",
        )
    };
    let start = std::time::Instant::now();
    let r = tune(&model, speed, &base, &train, objective, optimiser, seed);
    let seconds = start.elapsed().as_secs_f64();
    println!(
        "{}: {label} on seed {seed} ({duration} s): {} evaluations in {seconds:.1} s, objective {:.6e}",
        config.display(),
        r.evaluations,
        r.value
    );
    println!(
        "force_psd {:.3e} N²/s, modal_psd {:.3e}, measurement scale {:.3} (log10: {:.2}, {:.2}, {:.2})",
        r.tuning.force_psd, r.tuning.modal_psd, r.tuning.measurement_scale, r.theta[0], r.theta[1], r.theta[2]
    );
    let seeds = [seed + 1, seed + 2, seed + 3];
    let h = held_out(&model, &model, speed, &r.tuning, &seeds, 4.0)?;
    println!(
        "held out (seeds {seeds:?}, 4 s): disk-node RMS error {:.3} µm for t ≥ 1 s, NIS mean {:.2} (consistent: {})",
        h.disk_rms * 1e6,
        h.nis_mean,
        cfg.sensors.len()
    );
    Ok(())
}
