//! Reference multibody simulator of a planar slider-crank with revolute clearance joints, the
//! mechanism of the clearance paper (Rodríguez et al., "Desarrollo de filtros de Kalman para
//! monitorización de holguras en maquinaria industrial"), in `f64`.
//!
//! The mechanism stands in a vertical plane: a crank A–B pivoting at the ground joint A (the
//! origin), a connecting rod B–C, and a slider at C on a horizontal, frictionless guide through
//! A (the x axis, slider on the +x side). Gravity acts along −y. There is no drive: the
//! mechanism is released from rest and falls. Any of the joints A (crank–ground), B
//! (crank–rod) and C (rod–slider) can have a radial clearance; the journal then moves inside
//! its bearing (two more degrees of freedom) and is held by a Lankarani–Nikravesh contact force
//! when it indents it. The sensor is an angular accelerometer on the crank.
//!
//! * [`config`]: [`CrankConfig`], the TOML configuration (paper's values by default);
//! * [`mechanism`]: [`Mechanism`], kinematics and equations of motion (R-matrix velocity
//!   transformation with a closed-form position solution: see its docs for why);
//! * [`state`]: [`State`], what a simulation can be started from and continued with;
//! * [`contact`]: the Lankarani–Nikravesh law with Hertz stiffness;
//! * [`integrate`]: symplectic Euler (the paper's) and adaptive Dormand–Prince with contact
//!   events;
//! * [`simulate`](mod@simulate): [`SimOptions`] → [`CrankRecording`] (sensor channel, truth, final
//!   state), CSV output;
//! * [`spectrum`] and [`feature`]: the paper's spectral clearance feature;
//! * [`estimate`]: clearance estimation from a recording: the paper's UKF
//!   ([`estimate::ukf`], sigma points are clearance simulations) and a fast learned model
//!   ([`estimate::model`], no simulation) that also names the joint;
//! * [`cli`]: `edgekf crank simulate | feature | estimate | train`.
//!
//! Measured (paper's mechanism, released at 30°; `cargo test -p edgekf-sim --test crank --
//! --nocapture`, and `edgekf crank simulate … --duration 10` in release for the timings):
//!
//! * ideal mechanism: constraints hold to 2.8e-17 m; over 2 s the energy stays within 8e-11 J
//!   of its 0.0625 J with the adaptive integrator (tolerance 1e-10) and within 1.2e-4 J with
//!   symplectic Euler at 1e-5 s (5.5e-4 J over 10 s: that scheme is first order and not
//!   symplectic in these non-canonical coordinates);
//! * 0.25 mm at A: ~150 impacts per second, contact forces up to ~1 kN, indentations of a few
//!   µm; mechanical + dissipated energy constant to 2.2e-10 J over 0.5 s (adaptive 1e-10),
//!   2.5e-7 J over 10 s (adaptive 1e-8). Symplectic Euler at 1e-5 s lets the energy climb by up
//!   to 6.5e-5 J in 0.5 s (1.2e-4 J in 10 s): a contact that starts inside a step starts at an
//!   indentation of up to `v h`, with elastic energy no force paid for. The adaptive integrator
//!   starts every contact at its located onset instead;
//! * 0.1 mm at B and C (0.25 mm at A): the journals at B and C carry little mass and reach
//!   ~1 m/s, so an impact lasts ~3 steps of 1e-5 s; symplectic Euler pumps energy in and
//!   diverges after 2.2 s (an error, not a panic). At 2e-6 s, or adaptive, 10 s run through;
//! * 10 s at 1e-5 s (symplectic Euler, release build): 0.15 s ideal, 0.25 s with 0.25 mm at A;
//!   adaptive at 1e-8: 0.06 s ideal, 0.49 s with 0.25 mm at A (1.75 M evaluations), 2.95 s with
//!   clearances at all three joints;
//! * over 0.05 s, adaptive 1e-8 is 1 600–47 000× more accurate than symplectic Euler at 1e-5 s
//!   for 0.56–3.2× its work (`integrator_comparison`).
//!
//! An estimator runs one short simulation per sigma point per window, each from the previous
//! window's state, with the sigma point's clearance carried over by
//! [`Mechanism::transfer_state`]:
//!
//! ```
//! use edgekf_sim::systems::crank::{feature, CrankConfig, Mechanism, SimOptions};
//! let cfg = CrankConfig::default();
//! let truth = Mechanism::new(&cfg, [Some(0.25e-3), None, None])?;
//! let window = SimOptions { duration: 0.05, ..SimOptions::from_config(&cfg, 0.05) };
//! let rec = truth.simulate(&window)?;
//! let a = feature::spectral_feature(&rec.crank_alpha, window.sample_rate).unwrap().a;
//! assert!(a > 0.0);
//! // A sigma point with a smaller clearance continues from the same instant.
//! let sigma = Mechanism::new(&cfg, [Some(0.2e-3), None, None])?;
//! let start = sigma.transfer_state(&truth, &rec.final_state);
//! let next = sigma.simulate(&SimOptions { initial: Some(start), ..window })?;
//! assert_eq!(next.t[0], 0.05);
//! # Ok::<(), edgekf_sim::systems::crank::CrankError>(())
//! ```

pub mod cli;
pub mod config;
pub mod contact;
pub mod demo;
mod error;
pub mod estimate;
pub mod feature;
pub mod integrate;
pub mod mechanism;
mod parallel;
pub mod simulate;
pub mod spectrum;
pub mod state;
#[cfg(feature = "studies")]
pub mod studies;

pub use config::CrankConfig;
pub use error::CrankError;
pub use integrate::{IntegrationStats, Integrator};
pub use mechanism::{Dynamics, Energy, Mechanism, Pose};
pub use simulate::{CrankRecording, SimOptions};
pub use state::State;

use std::fmt;
use std::str::FromStr;

/// A revolute joint of the slider-crank.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Joint {
    /// Crank to ground.
    A,
    /// Crank to connecting rod.
    B,
    /// Connecting rod to slider.
    C,
}

impl Joint {
    /// A, B, C.
    pub const ALL: [Joint; 3] = [Joint::A, Joint::B, Joint::C];

    /// 0, 1, 2 for A, B, C: the index into per-joint arrays.
    pub const fn index(self) -> usize {
        self as usize
    }

    /// `"A"`, `"B"` or `"C"`.
    pub const fn name(self) -> &'static str {
        match self {
            Joint::A => "A",
            Joint::B => "B",
            Joint::C => "C",
        }
    }
}

impl fmt::Display for Joint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Joint {
    type Err = String;

    /// `A`, `B` or `C` (either case).
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "A" | "a" => Ok(Joint::A),
            "B" | "b" => Ok(Joint::B),
            "C" | "c" => Ok(Joint::C),
            _ => Err(format!("`{s}` is not a joint: expected A (crank–ground), B (crank–rod) or C (rod–slider)")),
        }
    }
}
