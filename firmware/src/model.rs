//! The node's estimator model, computed on the host in `f64` and compiled in: no
//! discretisation and no Riccati solve at start-up (which would cost about 15 KB of stack and a
//! few hundred thousand software-`f64` operations on the Cortex-M4F).
//!
//! Regenerate after changing `NodeConfig::default().estimator` (the test below fails until
//! then): `cargo run -p edgekf-sim -- oscillator export --out firmware/src/generated/harmonic.rs`.

use edgekf::export::{matrix, model};
use edgekf::systems::oscillator::{HarmonicForceEstimator, HarmonicForceParams, ModelError};

#[allow(missing_docs, clippy::excessive_precision, clippy::unreadable_literal)]
mod constants {
    include!("generated/harmonic.rs");
}

/// The estimator from the compiled-in model and gain, with `params` for the physical scaling
/// (natural frequency, modal mass) and the gate.
///
/// ```
/// use edgekf::systems::oscillator::HarmonicForceParams;
/// let est = edgekf_firmware::model::compiled_estimator(&HarmonicForceParams::default()).unwrap();
/// assert_eq!(est.counters().steps, 0);
/// ```
pub fn compiled_estimator(params: &HarmonicForceParams) -> Result<HarmonicForceEstimator<f32>, ModelError> {
    use constants::*;
    let m = model(&HARMONIC_A, &HARMONIC_C, &HARMONIC_Q, &HARMONIC_R);
    HarmonicForceEstimator::from_gain(params, &m, &matrix(&HARMONIC_GAIN), &matrix(&HARMONIC_S))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::node::NodeConfig;
    use edgekf::filter::solve_riccati;

    /// The committed constants are what the node's configured model computes, bit for bit.
    #[test]
    fn compiled_constants_match_the_configured_model() {
        let params = NodeConfig::default().estimator;
        let live = params.discrete_model().unwrap();
        let ss = solve_riccati(&live, 1e-12, 100_000).unwrap();
        let compiled =
            model(&constants::HARMONIC_A, &constants::HARMONIC_C, &constants::HARMONIC_Q, &constants::HARMONIC_R);
        assert_eq!(compiled, live, "regenerate firmware/src/generated/harmonic.rs (see module docs)");
        assert_eq!(matrix(&constants::HARMONIC_GAIN), ss.gain);
        assert_eq!(matrix(&constants::HARMONIC_S), ss.innovation);
    }

    #[test]
    fn compiled_and_computed_estimators_agree() {
        let params = NodeConfig::default().estimator;
        let mut a = compiled_estimator(&params).unwrap();
        let mut b = HarmonicForceEstimator::<f32>::new(&params).unwrap();
        for k in 0..500 {
            let y = libm::sinf(k as f32 * 0.0879) * 3.0;
            assert_eq!(a.step(Some(y)), b.step(Some(y)));
        }
    }
}
