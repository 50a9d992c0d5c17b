//! Tuning the phasor AKF of the paper rotor from data: the paper's compromise objective under
//! differential evolution against the innovations' maximum likelihood, compared on held-out
//! reference simulations.

use edgekf_sim::systems::rotor::estimate::tune::{held_out, tune, Objective, Optimiser};
use edgekf_sim::systems::rotor::estimate::Tuning;
use edgekf_sim::systems::rotor::{RotorConfig, RotorModel, SimOptions};

#[test]
fn likelihood_tuning_is_at_least_as_good_as_the_papers_objective() {
    let cfg = RotorConfig::from_toml_str(include_str!("../configs/rotor_paper.toml")).unwrap();
    let model = RotorModel::from_config(&cfg).unwrap();
    let speed = cfg.operation.speed;
    let train =
        model.simulate(&SimOptions { duration: 2.0, seed: 11, ..SimOptions::default() }).unwrap().to_data_file();
    let base = Tuning::default();
    let de = tune(
        &model,
        speed,
        &base,
        &train,
        Objective::Compromise,
        Optimiser::DifferentialEvolution { population: 12, generations: 8 },
        1,
    );
    let ml = tune(&model, speed, &base, &train, Objective::Likelihood, Optimiser::NelderMead { max_evals: 60 }, 1);
    // The same optimiser on the likelihood, to separate the objective from the optimiser.
    let ml_de = tune(
        &model,
        speed,
        &base,
        &train,
        Objective::Likelihood,
        Optimiser::DifferentialEvolution { population: 12, generations: 8 },
        1,
    );
    let seeds = [21, 22];
    let de_h = held_out(&model, &model, speed, &de.tuning, &seeds, 4.0).unwrap();
    let ml_h = held_out(&model, &model, speed, &ml.tuning, &seeds, 4.0).unwrap();
    let ml_de_h = held_out(&model, &model, speed, &ml_de.tuning, &seeds, 4.0).unwrap();
    for (name, r, h) in
        [("DE, compromise", &de, de_h), ("Nelder–Mead, likelihood", &ml, ml_h), ("DE, likelihood", &ml_de, ml_de_h)]
    {
        eprintln!(
            "{name}: θ = [{:.2}, {:.2}, {:.2}] (log10 force psd, modal psd, R scale), {} evaluations, objective {:.4e}; held out: disk RMS {:.3} µm, NIS mean {:.2}",
            r.theta[0], r.theta[1], r.theta[2], r.evaluations, r.value, h.disk_rms * 1e6, h.nis_mean
        );
    }
    assert!(ml_h.disk_rms <= de_h.disk_rms * 1.2, "ML {} vs DE {}", ml_h.disk_rms, de_h.disk_rms);
    assert!(ml_de_h.disk_rms <= de_h.disk_rms * 1.2, "ML (DE) {} vs DE {}", ml_de_h.disk_rms, de_h.disk_rms);
    // The likelihood is consistent by construction: NIS near the 4 channels.
    assert!((ml_h.nis_mean - 4.0).abs() < 0.5, "NIS {}", ml_h.nis_mean);
}

#[test]
fn the_tune_command_reports_the_tuning_and_held_out_figures() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_edgekf"))
        .args(["rotor", "tune", "--config", concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml")])
        .args(["--method", "ml", "--seed", "5", "--duration", "1", "--budget", "20"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    assert!(text.contains("maximum likelihood") && text.contains("held out (seeds [6, 7, 8], 4 s)"), "{text}");
    assert!(text.contains("force_psd") && text.contains("NIS mean"), "{text}");
}
