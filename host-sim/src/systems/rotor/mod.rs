//! Reference finite-element model of a flexible rotor on linear bearings (`f64`, host only).
//!
//! This is the "truth" for the rotor virtual-sensing work (the rotor paper: a 1 m shaft with two
//! disks on two roller bearings, unbalance forces estimated from four displacement probes). It
//! builds the full FE model, analyses it (modes, Campbell diagram, unbalance response) and
//! simulates it in time with sensor models, so that estimators built on *reduced* models can be
//! judged against it.
//!
//! # Model
//!
//! `M q̈ + (C + Ω G) q̇ + K q = f(t)`, with
//! * Timoshenko shaft elements (shear deformation, rotary inertia, gyroscopic matrix,
//!   consistent mass; [`element`]), optional Rayleigh shaft damping `α M + β K`;
//! * rigid disks and point masses (mass, polar and diametral inertia, gyroscopic);
//! * linear bearings with direct and cross stiffness and damping.
//!
//! # Conventions
//!
//! * The shaft lies along `z` from node 0 at `z = 0` to the last node; `x` is horizontal, `y`
//!   vertical, (x, y, z) right-handed. Nodes are numbered 0, 1, … without gaps (37 elements →
//!   nodes 0..=37).
//! * Four DOFs per node, in the order `[x, y, α, β]`: displacements x and y (m), rotation α about
//!   the x axis and β about the y axis (rad). For the bending line, `β = ∂x/∂z` and
//!   `α = −∂y/∂z` (right-hand rule). Global index of DOF `d` of node `n`: `4 n + d` ([`dof`]).
//!   This is ROSS's lateral ordering `x, y, α, β` with the same signs.
//! * The rotor spins at Ω (rad/s) about `+z`: a positive speed turns x toward y. A **forward**
//!   whirl orbit also runs x → y (counter-clockwise seen from +z), a backward one y → x.
//! * Unbalance `U = m e` at phase φ: `F_x = U Ω² cos(Ωt + φ)`, `F_y = U Ω² sin(Ωt + φ)`.
//! * Bearing force on the shaft: `−K_b [x, y]ᵀ − C_b [ẋ, ẏ]ᵀ`.
//!
//! # Linear algebra
//!
//! Dense matrices from [`faer`] (pure Rust, well maintained): it has what this model needs and
//! nalgebra lacks, the eigenvectors of a general real matrix (nalgebra's `Schur` gives complex
//! eigenvalues but no eigenvectors of a non-symmetric matrix, and the mode shapes and whirl
//! directions of a gyroscopic, damped rotor need them), plus fast blocked products for the
//! matrix exponential of the ~300-state system. The models are small (152 DOFs for the paper
//! rotor), so dense storage is simpler than sparse and fast enough.
//!
//! ```
//! use edgekf_sim::systems::rotor::{RotorConfig, RotorModel};
//! let cfg = RotorConfig::from_toml_str(include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml"))).unwrap();
//! let model = RotorModel::from_config(&cfg).unwrap();
//! assert_eq!(model.n_dofs(), 4 * 38);
//! let modes = model.modes(0.0).unwrap();
//! // The first bending mode of the paper rotor, in x and in y (ROSS: 22.4845 and 22.4852 Hz).
//! assert!((modes.modes[0].frequency_hz - 22.4845).abs() < 1e-3);
//! assert!((modes.modes[1].frequency_hz - 22.4852).abs() < 1e-3);
//! ```

pub mod assembly;
pub mod bearing_geometry;
pub mod bounds;
pub mod cli;
pub mod config;
pub mod demo;
pub mod element;
pub mod estimate;
pub mod loop_system;
pub mod matrix;
pub mod modal;
pub mod response;
pub mod sensor;
pub mod simulate;

pub use assembly::{RotorModel, SystemMatrices};
pub use config::{Direction, RotorConfig, SensorConfig, SensorKind};
pub use modal::{Campbell, ModalAnalysis, Mode, Whirl};
pub use response::UnbalanceResponse;
pub use simulate::{Method, Recording, SimOptions};

use std::path::{Path, PathBuf};

/// DOFs per node.
pub use element::NODE_DOFS;

/// Global index of DOF `d` (0 = x, 1 = y, 2 = α, 3 = β) of node `node`.
///
/// ```
/// assert_eq!(edgekf_sim::systems::rotor::dof(5, 1), 21);
/// ```
pub const fn dof(node: usize, d: usize) -> usize {
    NODE_DOFS * node + d
}

/// Why a rotor could not be built, analysed or simulated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RotorError {
    /// The configuration file could not be read.
    #[error("{}: cannot read: {reason}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        reason: String,
    },
    /// The configuration is malformed or a figure in it is not acceptable.
    #[error("{}{message}", origin.as_ref().map(|p| format!("{}: invalid rotor configuration: ", p.display())).unwrap_or_default())]
    Config {
        /// The file, when known.
        origin: Option<PathBuf>,
        /// What is wrong, naming the entry (TOML syntax errors carry line and column).
        message: String,
    },
    /// A request that the model cannot answer (e.g. a negative duration).
    #[error("{0}")]
    Invalid(String),
    /// A numerical step failed (singular matrix, eigen solver did not converge, non-finite result).
    #[error("numerical failure: {0}")]
    Numerical(String),
}

impl From<crate::linalg::LinalgError> for RotorError {
    fn from(e: crate::linalg::LinalgError) -> Self {
        RotorError::Numerical(e.0)
    }
}

impl RotorError {
    /// Attaches the file a configuration error came from.
    pub fn in_file(self, path: &Path) -> Self {
        match self {
            RotorError::Config { origin: None, message } => {
                RotorError::Config { origin: Some(path.to_owned()), message }
            }
            other => other,
        }
    }
}
