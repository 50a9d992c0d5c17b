//! The vehicle image's kernels in the bench image (`edgekf-bench`). Their budgets are in
//! [`super::images`].

use crate::bench::Markers;
use crate::semihost::exit;

/// Runs and reports each kernel once.
pub fn run<M: Markers>() {
    uuv::<M>();
}

/// The underwater vehicle's 20-state joint UKF and detector (`crate::systems::uuv`)
/// at 50 Hz: a sample with the IMU, depth and heading (`uuv_step`: predict and two updates),
/// and one with a DVL reading too (`uuv_step_dvl`, one sample in ten). Steady level flight at
/// 1500 rpm, so the CUSUM stays quiet.
fn uuv<M: Markers>() {
    use super::{estimator, UuvNode, STATES};
    let Ok(mut est) = estimator() else {
        defmt::error!("bench uuv: no estimator");
        exit(1)
    };
    let mut node = UuvNode::new(&mut est);
    let row = |k: u32| {
        let dvl = if k % 10 == 0 { [1.54, 0.0, 0.0] } else { [f32::NAN; 3] };
        Some([0.0, -0.9, -9.77, 0.0, 0.0, 0.0, 10.0, 0.785, dvl[0], dvl[1], dvl[2], 1500.0, 1670.0, 0.0, 0.0])
    };
    let mut k = 0;
    while k < 21 {
        node.step(row(k));
        k += 1;
    }
    for (label, at) in [("uuv_step", 21), ("uuv_step_dvl", 30)] {
        while k < at {
            node.step(row(k));
            k += 1;
        }
        M::start();
        core::hint::black_box(node.step(core::hint::black_box(row(k))));
        M::end();
        k += 1;
        defmt::info!(
            "bench {=str} n={=usize} m={=usize} resets={=u32}",
            label,
            STATES,
            6usize,
            node.estimator().health().covariance_resets
        );
    }
}

