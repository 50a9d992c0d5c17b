//! The vehicle image's kernels in the bench image (`edgekf-bench`). Their budgets are in
//! [`super::images`].

use crate::bench::Markers;
use crate::semihost::exit;

/// Runs and reports each kernel once.
pub fn run<M: Markers>() {
    uuv::<M>();
    monitored::<M>();
}

/// Steady level flight at 1500 rpm (so the CUSUM stays quiet), a DVL reading on the samples
/// `k` with `k % 10 == dvl_at`.
fn row(k: u32, dvl_at: u32) -> Option<[f32; 15]> {
    let dvl = if k % 10 == dvl_at { [1.54, 0.0, 0.0] } else { [f32::NAN; 3] };
    Some([0.0, -0.9, -9.77, 0.0, 0.0, 0.0, 10.0, 0.785, dvl[0], dvl[1], dvl[2], 1500.0, 1670.0, 0.0, 0.0])
}

/// The underwater vehicle's 20-state joint UKF and detector (`crate::systems::uuv`)
/// at 50 Hz: a sample with the IMU, depth and heading (`uuv_step`: predict and two updates),
/// and one with a DVL reading too (`uuv_step_dvl`, one sample in ten).
fn uuv<M: Markers>() {
    use super::{estimator, UuvNode, STATES};
    let Ok(mut est) = estimator() else {
        defmt::error!("bench uuv: no estimator");
        exit(1)
    };
    let mut node = UuvNode::new(&mut est);
    let mut k = 0;
    while k < 21 {
        node.step(row(k, 0));
        k += 1;
    }
    for (label, at) in [("uuv_step", 21), ("uuv_step_dvl", 30)] {
        while k < at {
            node.step(row(k, 0));
            k += 1;
        }
        M::start();
        core::hint::black_box(node.step(core::hint::black_box(row(k, 0))));
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

/// The sample as the image runs it, with the model monitor on its eleven channels
/// (`crate::monitor`): an ordinary sample (`uuv_monitored`), one with a DVL reading
/// (`uuv_monitored_dvl`), and the costliest, a DVL reading on the sample that closes the
/// windows of the eight channels updated every sample (`uuv_monitored_window`). Its settling
/// time is left out so that the monitor runs from the first update.
fn monitored<M: Markers>() {
    use super::{estimator, monitor_settings, UuvNode, MONITORED, STATES};
    use crate::monitor::Monitored;
    use crate::node::NodeEstimator;
    let Ok(mut est) = estimator() else {
        defmt::error!("bench uuv_monitored: no estimator");
        exit(1)
    };
    let settings = edgekf::residual::MonitorSettings { settle_s: 0.0, ..monitor_settings() };
    // The first sample starts the filter without an update: the eight channels' windows close
    // on the update of sample `window + 1`, counted from 1 (`k = window` from 0).
    let window = settings.window;
    let dvl_at = window % 10;
    let mut node = Monitored::<_, MONITORED>::new(UuvNode::new(&mut est), &settings);
    for k in 0..=window {
        let label = match k {
            k if k == window => Some("uuv_monitored_window"),
            k if k == 20 + (dvl_at + 5) % 10 => Some("uuv_monitored"),
            k if k == 30 + dvl_at => Some("uuv_monitored_dvl"),
            _ => None,
        };
        if label.is_some() {
            M::start();
        }
        core::hint::black_box(node.step(core::hint::black_box(row(k, dvl_at))));
        if let Some(label) = label {
            M::end();
            let resets = node.estimator().health().covariance_resets;
            defmt::info!("bench {=str} n={=usize} m={=usize} resets={=u32}", label, STATES, 6usize, resets);
        }
    }
}
