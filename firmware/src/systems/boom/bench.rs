//! The boom image's kernels in the bench image (`edgekf-bench`). Their budgets are in
//! [`super::images`].

use crate::bench::Markers;
use crate::semihost::exit;

/// Runs and reports each kernel once.
pub fn run<M: Markers>() {
    boom::<M>();
    monitored::<M>();
}

/// The sample as the image runs it, with the model monitor on both channels
/// (`crate::monitor`): an ordinary sample (`boom_monitored`) and one that closes a monitor
/// window (`boom_monitored_window`). Its settling time is left out so that the monitor runs
/// from the first sample.
fn monitored<M: Markers>() {
    use super::{estimators, monitor_settings, BoomNode};
    use crate::monitor::Monitored;
    use crate::node::NodeEstimator;
    use edgekf::systems::boom::STATES;
    let Ok((mut model, mut paper)) = estimators() else {
        defmt::error!("bench boom_monitored: no estimator");
        exit(1)
    };
    let settings = edgekf::residual::MonitorSettings { settle_s: 0.0, ..monitor_settings() };
    let window = settings.window;
    let mut node = Monitored::new(BoomNode::new(&mut model, &mut paper), &settings);
    let row = Some([0.002, 0.5, 30.0, 0.0]);
    for k in 1..=window {
        let label = match k {
            20 => Some("boom_monitored"),
            k if k == window => Some("boom_monitored_window"),
            _ => None,
        };
        if label.is_some() {
            M::start();
        }
        core::hint::black_box(node.step(core::hint::black_box(row)));
        if let Some(label) = label {
            M::end();
            defmt::info!("bench {=str} n={=usize} m={=usize} resets={=u32}", label, STATES, 2usize, 0u32);
        }
    }
}

/// The boom's model-based filter and the paper's method side by side
/// (`crate::systems::boom`) at 100 Hz: a sample at a fixed length and angle
/// (`boom_step`), and one that re-reduces the boom (`boom_rereduce`: three Rayleigh–Ritz
/// reductions in `f64`, once per 0.5 m of telescoping or 0.1 rad of luffing).
fn boom<M: Markers>() {
    use edgekf::systems::boom::STATES;
    use super::{estimators, BoomNode};
    let Ok((mut model, mut paper)) = estimators() else {
        defmt::error!("bench boom: no estimator");
        exit(1)
    };
    let mut node = BoomNode::new(&mut model, &mut paper);
    // At rest at 30 m, then a sample telescoped 0.6 m further in.
    let row = |length: f32| Some([0.002, 0.5, length, 0.0]);
    for _ in 0..20 {
        node.step(row(30.0));
    }
    for (label, length) in [("boom_step", 30.0), ("boom_rereduce", 29.4)] {
        M::start();
        core::hint::black_box(node.step(core::hint::black_box(row(length))));
        M::end();
        defmt::info!(
            "bench {=str} n={=usize} m={=usize} resets={=u32}",
            label,
            STATES,
            2usize,
            node.model().health().covariance_resets
        );
    }
}

