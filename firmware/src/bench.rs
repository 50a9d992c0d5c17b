//! What the bench image's kernels share (QEMU images only). The kernels that belong to a system
//! live in its folder (`systems/<name>/bench.rs`, gathered by [`crate::systems::bench`]); the
//! shared core's own kernels stay in the bench binary.

/// The measured section's markers. The bench binary defines them as `#[no_mangle]` functions
/// (`bench_start`, `bench_end`) whose addresses the instruction-counting plugin is given; a
/// kernel calls `M::start()` right before the step it measures and `M::end()` right after. A
/// type parameter rather than function pointers, so that each call is a direct call, as when
/// the kernels were in the binary, and no other image carries the markers.
pub trait Markers {
    /// Marks the start of the measured section.
    fn start();
    /// Marks its end.
    fn end();
}

/// Measures one step of an estimator `est` that takes one accelerometer axis: three warm-up
/// steps (`0`, `0.1`, `0.2`), then `Some(0.25)` between the markers, reported as
/// `bench <label> n=<n> m=<m> resets=<resets(est)>`. Written once, so that the systems that
/// share this input (the oscillator, the mount) are measured and reported alike.
pub fn one_step<M: Markers, E, R>(
    label: &str,
    (n, m): (usize, usize),
    est: &mut E,
    mut step: impl FnMut(&mut E, Option<f32>) -> R,
    resets: impl Fn(&E) -> u32,
) {
    for k in 0..3 {
        step(est, Some(k as f32 * 0.1));
    }
    M::start();
    core::hint::black_box(step(est, core::hint::black_box(Some(0.25))));
    M::end();
    defmt::info!("bench {=str} n={=usize} m={=usize} resets={=u32}", label, n, m, resets(est));
}
