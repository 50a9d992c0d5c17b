//! The paper's method on a boom and a seed it was not developed on (issue #34).
//!
//! The fix (`edgekf::systems::boom::paper`: the AR filter's state with the rate in it, the
//! boom's own rate as a least-squares slope, the inclinometer's declared lag taken out) was
//! developed on `boom_ladder30.toml` with seeds 1 and 3 (both runs) and on a 24 m variant of it
//! with a 450 kg platform, telescoping from 15 m, seed 5. Checked here on neither: the ladder at
//! 27 m with a 200 kg platform, luffing at 0.04 rad/s from 0.7 rad, telescoping from 21 m, seed
//! 11. Before the fix the method gave 126–253 % mean peak error on the development runs.

use edgekf_sim::systems::boom::estimate::{estimate, gyro_model, Method};
use edgekf_sim::systems::boom::peaks::peak_errors;
use edgekf_sim::systems::boom::simulate::static_record;
use edgekf_sim::systems::boom::{simulate, BoomConfig, Scenario, SimOptions};

/// The held-out boom: the shipped ladder with another platform, length, luffing and extension.
fn held_out() -> BoomConfig {
    let shipped = include_str!("../configs/boom_ladder30.toml");
    let text = [
        ("mass = 300.0", "mass = 200.0"),
        ("rotary_inertia = 75.0", "rotary_inertia = 50.0"),
        ("length = 30.0", "length = 27.0"),
        ("extension_from = 18.0", "extension_from = 21.0"),
        ("luff_rate = 0.05", "luff_rate = 0.04"),
        ("start_angle = 0.5", "start_angle = 0.7"),
    ]
    .iter()
    .fold(shipped.to_string(), |text, (from, to)| {
        assert_eq!(text.matches(from).count(), 1, "`{from}` once in the shipped configuration");
        text.replace(from, to)
    });
    BoomConfig::from_toml_str(&text).unwrap()
}

/// Mean peak error within the 40 % on both runs of the held-out boom, over at least the
/// paper's 27 peaks each; the model-based filter beside it for scale.
#[test]
fn the_papers_method_within_40_percent_on_a_boom_it_was_not_developed_on() {
    const SEED: u64 = 11;
    let c = held_out();
    let (_, statics) = static_record(&c, 60.0, SEED).unwrap();
    let ar = gyro_model(&c, &statics).unwrap();
    for scenario in [Scenario::Luffing, Scenario::Extension] {
        let rec = simulate(&c, &SimOptions { scenario, duration: 120.0, seed: SEED }, &mut |_| {}).unwrap();
        let data = rec.to_data_file();
        let (truth, rate) = (rec.column("truth_tip_vibration").unwrap(), rec.column("truth_root_rate").unwrap());
        let errors = |method| {
            let est = estimate(&c, &data, ar, method).unwrap();
            peak_errors(&rec.t, est.column("tip_vibration").unwrap(), truth, rate)
        };
        let (paper, model) = (errors(Method::Paper), errors(Method::Model));
        println!(
            "held-out boom, {} run, seed {SEED}: paper {} peaks, mean {:.1} %, median {:.1} %; model mean {:.2} %",
            scenario.name(),
            paper.peaks,
            paper.mean_pct,
            paper.median_pct,
            model.mean_pct
        );
        assert!(paper.peaks >= 27, "{paper:?}");
        assert!(paper.mean_pct <= 40.0, "paper's method, {} run: {paper:?}", scenario.name());
        assert!(model.mean_pct < paper.mean_pct, "the model-based filter {model:?}");
    }
}
