//! The slider-crank image's kernels in the bench image (`edgekf-bench`). Their budgets are in
//! [`super::images`].

use crate::bench::Markers;
use crate::semihost::exit;

/// Runs and reports each kernel once.
pub fn run<M: Markers>() {
    crank::<M>();
    crank_release::<M>();
}

/// The slider-crank clearance estimator (`crate::crank`, 0.25 s windows at 10 kHz):
/// an ordinary sample (`crank_sample`: sums, differences, high-pass), the sample that closes a
/// window (`crank_window_end`: the exact median of 2 499 `|Δα|` by four radix passes, the
/// impact pass, ten window statistics, the model on the running features), and a whole window
/// (`crank_window`, 2 500 samples, including about 10 instructions per sample to synthesise the
/// input), whose count / 2 500 is the average per sample.
fn crank<M: Markers>() {
    use super::{Storage, WINDOW};
    // Noise-like values from a multiplicative hash, and an impact every 97 samples.
    let alpha = |k: u32| {
        let noise = (k.wrapping_mul(2_654_435_761) >> 20) as f32 - 2048.0;
        if k % 97 == 0 {
            noise + 30_000.0
        } else {
            noise
        }
    };
    let mut storage: Storage = [0.0; WINDOW - 1];
    let mut node = crank_node(&mut storage);
    let mut k = 0u32;
    let window = WINDOW as u32;
    // One whole window, then into the second one for an ordinary sample, then its last sample.
    M::start();
    while k < window {
        core::hint::black_box(node.step(core::hint::black_box(Some(alpha(k)))));
        k += 1;
    }
    M::end();
    defmt::info!("bench crank_window n={=usize} m={=usize} windows={=u32}", WINDOW, 1usize, node.windows());
    while k < window + 1000 {
        node.step(Some(alpha(k)));
        k += 1;
    }
    measured_crank_step::<M>(&mut node, alpha(k));
    defmt::info!("bench crank_sample n={=usize} m={=usize} windows={=u32}", WINDOW, 1usize, node.windows());
    k += 1;
    while k < 2 * window - 1 {
        node.step(Some(alpha(k)));
        k += 1;
    }
    let report = measured_crank_step::<M>(&mut node, alpha(k));
    if report.is_none() || node.windows() != 2 {
        defmt::error!("bench crank: the measured sample did not close the second window");
        exit(1)
    }
    defmt::info!("bench crank_window_end n={=usize} m={=usize} windows={=u32}", WINDOW, 1usize, node.windows());
}

/// The crank node on `storage`, or the bench ends with an error.
fn crank_node(
    storage: &mut super::Storage,
) -> super::CrankNode<'_> {
    match super::CrankNode::new(storage) {
        Ok(node) => node,
        Err(_) => {
            defmt::error!("bench crank: no estimator");
            exit(1)
        }
    }
}

/// One step of `node` on `x`, its instructions counted.
fn measured_crank_step<M: Markers>(
    node: &mut super::CrankNode<'_>,
    x: f32,
) -> Option<super::WindowReport> {
    M::start();
    let report = core::hint::black_box(node.step(core::hint::black_box(Some(x))));
    M::end();
    report
}

/// A sample while the release detector still looks for the first contact
/// (`crank_release_sample`: an ordinary sample plus the running quadratic fit, its 3 × 3 solve
/// and the threshold test). Only the samples before the first contact pay it, at most the first
/// 0.1 s of a recording.
fn crank_release<M: Markers>() {
    use super::{Storage, WINDOW};
    // Small noise-like values about a slow ramp: no contact.
    let alpha = |k: u32| ((k.wrapping_mul(2_654_435_761) >> 24) as f32 - 128.0) * 0.04 - 27.0 - 0.01 * k as f32;
    let mut storage: Storage = [0.0; WINDOW - 1];
    let mut node = crank_node(&mut storage);
    for k in 0..60 {
        node.step(Some(alpha(k)));
    }
    measured_crank_step::<M>(&mut node, alpha(60));
    if node.release_contact().is_some() {
        defmt::error!("bench crank: the release detector fired on a smooth ramp");
        exit(1)
    }
    defmt::info!("bench crank_release_sample n={=usize} m={=usize} windows={=u32}", WINDOW, 1usize, node.windows());
}

