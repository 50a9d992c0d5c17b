//! Scratch (not committed): issue #34's findings on the project's own simulators.
use edgekf_sim::residual_loop::{LoopOptions, LoopReport};
use edgekf_sim::systems::boom::estimate::{gyro_model, INCLINOMETER_NOISE};
use edgekf_sim::systems::boom::loop_system::close_loop;
use edgekf_sim::systems::boom::simulate::static_record;
use edgekf_sim::systems::boom::{simulate, BoomConfig, Scenario, SimOptions};

fn loop_on(truth: &BoomConfig, declared: &BoomConfig, duration: f64, seed: u64) -> LoopReport {
    let rec = simulate(truth, &SimOptions { scenario: Scenario::Luffing, duration, seed }, &mut |_| {}).unwrap();
    let (_, statics) = static_record(truth, 60.0, seed).unwrap();
    let ar = gyro_model(declared, &statics).unwrap();
    let options = LoopOptions { progress: true, ..LoopOptions::default() };
    close_loop(declared, &rec.to_data_file(), ar, INCLINOMETER_NOISE, &options).unwrap()
}

fn show(name: &str, r: &LoopReport) {
    let pe = |s: &edgekf_sim::residual_loop::RunSummary| s.metrics.get("peak_error_pct").copied().unwrap_or(f64::NAN);
    eprintln!("=== {name}: peak {:.2} → {:.2}", pe(&r.before), pe(&r.after));
    for e in &r.effects_added { eprintln!("  added {} at {} {:?} = {:.4}", e.kind, e.location, e.detail.parameter, e.value); }
    for e in &r.refused { eprintln!("  refused {} at {} {:?}: {}", e.kind, e.location, e.parameter, e.reason); }
    for e in &r.not_identifiable { eprintln!("  hidden {} at {} {:?}: {}", e.kind, e.location, e.parameter, e.reason); }
}

#[test]
fn boom_cases() {
    let which = std::env::var("CASE").unwrap_or_default();
    let declared = BoomConfig::default();
    if which.contains("offset") {
        let mut t = declared.clone(); t.inclinometer.offset = 0.01;
        show("incl offset 0.01", &loop_on(&t, &declared, 120.0, 1));
    }
    if which.contains("damage") {
        let mut t = declared.clone(); let n = t.section.len(); t.section[n / 2].ei *= 0.8;
        show("section EI x0.8", &loop_on(&t, &declared, 120.0, 1));
    }
    if which.contains("clean") {
        show("clean", &loop_on(&declared, &declared, 120.0, 5));
    }
}

#[test]
fn uuv_cases() {
    use edgekf_sim::systems::uuv::loop_system::close_loop as uuv_loop;
    use edgekf_sim::systems::uuv::{simulate as usim, Scenario as US, SimOptions as UO, UuvConfig};
    let which = std::env::var("CASE").unwrap_or_default();
    if !which.contains("drag") {
        return;
    }
    let model = UuvConfig::default();
    let mut sim = model.clone();
    sim.vehicle.hydro.x_uu *= 1.3;
    let rec = usim(&sim, &UO { scenario: US::Healthy, duration: 150.0, seed: 4 }, &mut |_| {}).unwrap();
    let r = uuv_loop(&model, &rec.to_data_file(), &LoopOptions::default()).unwrap();
    eprintln!("=== uuv drag x1.3: errors {:?} → {:?}", r.before.error_rms, r.after.error_rms);
    for e in &r.effects_added { eprintln!("  added {} at {} {:?} = {:.4}", e.kind, e.location, e.detail.parameter, e.value); }
    for e in &r.refused { eprintln!("  refused {} at {} {:?}: {}", e.kind, e.location, e.parameter, e.reason); }
    for e in &r.not_identifiable { eprintln!("  hidden {} at {} {:?}: {}", e.kind, e.location, e.parameter, e.reason); }
}
