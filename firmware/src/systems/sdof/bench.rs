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
    crate::bench::one_step::<M, _>(|y| est.step(y));
    defmt::info!(
        "bench sdof_step n={=usize} m={=usize} resets={=u32}",
        2usize,
        1usize,
        est.counters().filter.covariance_resets
    );
}
