//! The residual loop's table in the README: every case of `residual_loop::cases` with its noise
//! seed from the tests, closed with the default options.
//!
//! `cargo run --release -p edgekf-sim --example loop_table`

use edgekf_sim::report::text::show_value;
use edgekf_sim::residual_loop::{LoopOptions, LoopReport};
use edgekf_sim::systems::rotor::loop_system::cases::Case;
use edgekf_sim::systems::rotor::loop_system::close_loop;

/// The seeds `host-sim/tests/residual_loop.rs` uses.
fn seed(case: Case) -> u64 {
    match case {
        Case::Clean => 100,
        Case::Bias => 3,
        Case::TwoX => 5,
        Case::ThreeX => 9,
        Case::Scale => 13,
        Case::DiskMass => 17,
        Case::ShaftYoung => 19,
        Case::Two => 23,
        Case::SoftBearing => 29,
        Case::GainSwitch => 31,
        Case::Delay => 37,
        Case::OffDisk => 41,
        Case::PointMass => 43,
    }
}

fn disk_error_um(r: &LoopReport, after: bool) -> f64 {
    let s = if after { &r.after } else { &r.before };
    s.error_rms.values().copied().fold(0.0, f64::max) * 1e6
}

fn main() -> anyhow::Result<()> {
    let model = Case::declared()?;
    println!("| undeclared in the data | the loop adds | NIS before → after | disk-node error before → after (clean twin), µm |");
    println!("|---|---|---|---|");
    for case in Case::ALL {
        let s = seed(case);
        eprintln!("{} (seed {s})…", case.describe());
        let r = close_loop(&model, &case.data(s)?, &LoopOptions::default(), &Default::default())?;
        let clean = close_loop(
            &model,
            &Case::Clean.data(s)?,
            &LoopOptions { screen_parameters: false, ..LoopOptions::default() },
            &Default::default(),
        )?;
        let mut added: Vec<String> = r
            .effects_added
            .iter()
            .map(|e| {
                let what =
                    e.detail.parameter.as_ref().or(e.detail.line.as_ref()).map(|p| format!(" {p}")).unwrap_or_default();
                let order = e.detail.order.map(|o| format!(" {o}×")).unwrap_or_default();
                format!("`{}`{order} at {}{what} = {}", e.kind, e.location, show_value(e.value, &e.unit))
            })
            .collect();
        if added.is_empty() {
            added.push("nothing".into());
        }
        if case == Case::SoftBearing {
            let n = r
                .not_identifiable
                .iter()
                .filter(|n| n.location == "bearing 4" && n.parameter.as_deref() == Some("kxx"))
                .count();
            added.push(format!("(bearing 4 kxx listed as not identifiable: {})", if n > 0 { "yes" } else { "no" }));
        }
        if case == Case::GainSwitch {
            added.push(format!(
                "({} unexplained signatures, e.g. {})",
                r.unexplained.len(),
                r.unexplained
                    .iter()
                    .find(|u| u.statistic == "nis_step")
                    .map_or("-".into(), |u| format!("{}: {}", u.channel, u.description))
            ));
        }
        println!(
            "| {} | {} | {:.3} → {:.3} | {:.2} → {:.2} ({:.2}) |",
            case.describe(),
            added.join("; "),
            r.before.nis_mean,
            r.after.nis_mean,
            disk_error_um(&r, false),
            disk_error_um(&r, true),
            disk_error_um(&clean, true)
        );
    }
    Ok(())
}
