//! The rotor images' kernels in the bench image (`edgekf-bench`). Their budgets are in
//! [`super::images`].

use crate::bench::Markers;
use crate::semihost::exit;

/// Runs and reports each kernel once.
pub fn run<M: Markers>() {
    rotor::<M>();
}

/// The rotor node's per-sample step with its disk and force outputs, in both phases: the
/// filter with its start-up term of rank 12 (`rotor_node_step`), the sample that drops the
/// term (`rotor_node_switch`), and the steady-state step the node runs from 0.5 s on
/// (`rotor_node_steady`); the same for the accelerometer node's 28 states (`rotor_accel_*`).
fn rotor<M: Markers>() {
    use super::accel::AccelEstimator;
    use super::RotorEstimator;
    // Displacement-like readings for the probes, acceleration-like ones for the accelerometers.
    rotor_phases::<M, _, _>(RotorEstimator::new(), ["rotor_node_step", "rotor_node_switch", "rotor_node_steady"], 1e-6);
    rotor_phases::<M, _, _>(AccelEstimator::accel(), ["rotor_accel_step", "rotor_accel_switch", "rotor_accel_steady"], 1e-2);
}

/// [`rotor`]'s three steps of one estimator, readings of size `scale`.
fn rotor_phases<M: Markers, const N: usize, const R: usize>(
    mut est: super::RotorEstimator<N, R>,
    labels: [&str; 3],
    scale: f32,
) {
    use super::STEADY_AFTER;
    let [step, switch, steady] = labels;
    let y = |k: u32| Some([scale * k as f32, -0.5 * scale * k as f32, 2.0 * scale, 0.25 * scale * k as f32]);
    let mut k = 0;
    while k < 3 {
        est.step(y(k));
        k += 1;
    }
    // Measures one step; `steady`: whether the steady-state filter must be in use after it.
    let measured =
        |est: &mut super::RotorEstimator<N, R>, label: &str, k: u32, steady: bool| {
            M::start();
            core::hint::black_box(est.step(core::hint::black_box(y(k))));
            M::end();
            if est.is_steady() != steady {
                defmt::error!("bench {=str}: steady-state filter in use: {=bool}", label, est.is_steady());
                exit(1)
            }
            defmt::info!(
                "bench {=str} n={=usize} m={=usize} resets={=u32}",
                label,
                N,
                4usize,
                est.health().covariance_resets
            );
        };
    measured(&mut est, step, k, false);
    k += 1;
    while k < STEADY_AFTER {
        est.step(y(k));
        k += 1;
    }
    measured(&mut est, switch, k, true);
    k += 1;
    for _ in 0..3 {
        est.step(y(k));
        k += 1;
    }
    measured(&mut est, steady, k, true);
}

