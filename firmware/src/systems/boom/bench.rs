//! The boom image's kernels in the bench image (`edgekf-bench`). Their budgets are in
//! [`super::images`].

use crate::bench::Markers;
use crate::semihost::exit;

/// Runs and reports each kernel once.
pub fn run<M: Markers>() {
    boom::<M>();
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

