//! Sensor models of the rotor simulation: the continuous-time Butterworth low-pass of an
//! accelerometer as a state-space block, and the white noise added at each output sample.
//!
//! The low-pass runs in continuous time inside the simulated system (its states are appended
//! to the rotor's), so its output is as exact as the rotor's response; it is then sampled at the
//! output rate and noise is added: `σ = noise_std` for a displacement probe, and
//! `σ = noise_density · √(sample_rate / 2)` for an accelerometer (white noise over the Nyquist
//! band). A raw-volts channel is `offset + sensitivity · (a + noise)`.

use std::f64::consts::PI;

/// One section of a Butterworth cascade with unity DC gain, corner `ωc`:
/// first order `ẏ = ωc (u − y)`, or second order `ÿ = ωc² (u − y) − (ωc/Q) ẏ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Section {
    /// `ẏ = ωc (u − y)`: one state `y`.
    First {
        /// Corner, rad/s.
        wc: f64,
    },
    /// `ÿ = ωc² (u − y) − (ωc/Q) ẏ`: states `[y, ẏ]`.
    Second {
        /// Corner, rad/s.
        wc: f64,
        /// Quality factor of the pole pair.
        q: f64,
    },
}

impl Section {
    /// Number of states.
    pub fn states(&self) -> usize {
        match self {
            Section::First { .. } => 1,
            Section::Second { .. } => 2,
        }
    }
}

/// The sections of an order-`order` Butterworth low-pass with −3 dB corner `corner_hz`: pole
/// pairs `Q_k = 1 / (2 sin((2k − 1) π / (2N)))`, k = 1 … ⌊N/2⌋, and one real pole if N is odd.
///
/// ```
/// use edgekf_sim::systems::rotor::sensor::{butterworth, Section};
/// let s = butterworth(2, 250.0);
/// assert_eq!(s.len(), 1);
/// let Section::Second { q, .. } = s[0] else { panic!() };
/// assert!((q - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-15);
/// ```
pub fn butterworth(order: usize, corner_hz: f64) -> Vec<Section> {
    let wc = 2.0 * PI * corner_hz;
    let mut out: Vec<Section> = (1..=order / 2)
        .map(|k| {
            let q = 1.0 / (2.0 * ((2 * k - 1) as f64 * PI / (2 * order) as f64).sin());
            Section::Second { wc, q }
        })
        .collect();
    if order % 2 == 1 {
        out.push(Section::First { wc });
    }
    out
}

/// Magnitude of the Butterworth response at `f_hz`: `1 / √(1 + (f/fc)^{2N})`.
pub fn butterworth_gain(order: usize, corner_hz: f64, f_hz: f64) -> f64 {
    1.0 / (1.0 + (f_hz / corner_hz).powi(2 * order as i32)).sqrt()
}
