//! The mount image's kernels in the bench image (`edgekf-bench`): the filter's step and its
//! start-up (the discretisation in software `f64`). Their budgets are in [`super::images`].

use crate::bench::Markers;
use crate::semihost::exit;
use edgekf::systems::sdof::SdofEstimator;

/// Runs and reports each kernel once.
pub fn run<M: Markers>() {
    M::start();
    let started = SdofEstimator::<f32>::new(core::hint::black_box(&super::params()));
    M::end();
    let Ok(mut est) = started else {
        defmt::error!("bench sdof: no estimator");
        exit(1)
    };
    defmt::info!("bench sdof_start n={=usize} m={=usize}", 2usize, 1usize);
    let resets = |e: &SdofEstimator<f32>| e.counters().filter.covariance_resets;
    crate::bench::one_step::<M, _, _>("sdof_step", (2, 1), &mut est, |e, y| e.step(y), resets);
}
