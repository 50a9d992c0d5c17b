//! Modal reduction of the FE rotor into the filter's continuous-time model.

use crate::rotor::{dof, RotorModel, SensorKind};
use anyhow::{bail, Context, Result};
use nalgebra::{DMatrix, SymmetricEigen};

/// How the unknown unbalance forces are modelled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ForceModel {
    /// One forward-rotating phasor per unbalance node (2 states), slow random walk. Default.
    Phasor,
    /// `F_x`, `F_y` as independent random walks (2 states per node): the paper's model.
    RandomWalk,
}

/// Filter tuning (continuous-time spectral densities, initial uncertainty).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tuning {
    /// Modes kept.
    pub modes: usize,
    /// Force model.
    pub force_model: ForceModel,
    /// Spectral density of the force states' random walk, N²/s.
    pub force_psd: f64,
    /// Spectral density of unmodelled modal acceleration, (m/s²)² kg / s (modal units).
    pub modal_psd: f64,
    /// Prior standard deviation of each force state, N.
    pub initial_force_std: f64,
    /// Prior standard deviation of each modal displacement, m·√kg (the rotor starts at rest).
    pub initial_modal_std: f64,
}

impl Default for Tuning {
    /// 8 modes, phasor forces, tuned on the paper rotor over a grid (force density 1e-3…1 N²/s,
    /// modal density 1e-12…1e-6): disk-node RMS error 0.30 µm at these values, 1.7 µm at
    /// 1 N²/s. The prior on the forces (10 N) lets the time-varying gain find them in well
    /// under 0.5 s; the small random walk then keeps the estimate quiet.
    fn default() -> Self {
        Self {
            modes: 8,
            force_model: ForceModel::Phasor,
            force_psd: 1e-3,
            modal_psd: 1e-9,
            initial_force_std: 10.0,
            initial_modal_std: 1e-6,
        }
    }
}

/// The reduced model: state `x = [η (r), η̇ (r), forces (2u)]`, `ẋ = A x + w`, measured
/// `y = C x + v`, and the virtual outputs.
#[derive(Debug, Clone)]
pub struct ReducedRotor {
    /// Natural frequencies of the kept modes (non-rotating), Hz.
    pub frequencies_hz: Vec<f64>,
    /// Unbalance nodes, in configuration order (forces at these nodes are estimated).
    pub force_nodes: Vec<usize>,
    /// Continuous system matrix.
    pub a: DMatrix<f64>,
    /// Continuous process-noise density.
    pub qc: DMatrix<f64>,
    /// Sensor rows (one per configured sensor).
    pub c: DMatrix<f64>,
    /// Measurement-noise covariance per sample.
    pub r: DMatrix<f64>,
    /// Rows giving `x`, `y` displacement of every node (node-major: `n0_x, n0_y, n1_x, …`).
    pub displacement: DMatrix<f64>,
    /// Rows giving `F_x`, `F_y` at each force node.
    pub force: DMatrix<f64>,
    /// Initial state covariance.
    pub p0: DMatrix<f64>,
    /// Channel names of the sensors, in order.
    pub channels: Vec<String>,
    /// Speed, rad/s.
    pub speed: f64,
    /// Sample rate, Hz.
    pub sample_rate: f64,
}

impl ReducedRotor {
    /// Number of states.
    pub fn states(&self) -> usize {
        self.a.nrows()
    }
}

fn to_nalgebra(m: &faer::Mat<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)])
}

/// Reduces `model` at `speed` (rad/s) for its configured sensors and unbalance nodes.
///
/// The modes are those of `K φ = ω² M φ` with the symmetric part of `K` (bearings included),
/// mass-normalised. The truncated modes' static contribution to the displacement at every DOF
/// from the force states (`K⁻¹ − Φ Λ⁻¹ Φᵀ`) is added to the output rows, which costs no states.
/// Displacement sensors read the node DOF; accelerometers are not supported here yet (error).
pub fn reduce(model: &RotorModel, speed: f64, tuning: &Tuning) -> Result<ReducedRotor> {
    let cfg = model.config();
    let sys = model.assemble(speed);
    let n = sys.n();
    let r = tuning.modes;
    if r == 0 || r > n {
        bail!("modes must be between 1 and {n}, not {r}");
    }
    let m = to_nalgebra(&sys.m);
    let k = to_nalgebra(&sys.k);
    let c_total = to_nalgebra(&sys.c_total(speed));
    let k_sym = (&k + k.transpose()) * 0.5;

    // Mass-normalised modes through the Cholesky factor of M: L⁻¹ K L⁻ᵀ v = ω² v, φ = L⁻ᵀ v.
    let chol = m.clone().cholesky().context("the mass matrix is not positive definite")?;
    let l = chol.l();
    let l_inv = l.clone().try_inverse().context("singular mass factor")?;
    let sym = &l_inv * &k_sym * l_inv.transpose();
    let eig = SymmetricEigen::new((&sym + sym.transpose()) * 0.5);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let kept = &order[..r];
    if eig.eigenvalues[kept[0]] <= 0.0 {
        bail!("the rotor has a rigid-body or unstable mode (ω² = {}); check the bearings", eig.eigenvalues[kept[0]]);
    }
    let v = DMatrix::from_fn(n, r, |i, j| eig.eigenvectors[(i, kept[j])]);
    let phi = l_inv.transpose() * v;
    let lambda: Vec<f64> = kept.iter().map(|&i| eig.eigenvalues[i]).collect();
    let frequencies_hz = lambda.iter().map(|w2| w2.sqrt() / (2.0 * std::f64::consts::PI)).collect();

    // Force states: two per unbalance node, acting on its x and y DOFs.
    let force_nodes = cfg.unbalance_nodes();
    let u = force_nodes.len();
    if u == 0 {
        bail!("the configuration has no [[unbalance]] node to estimate a force at");
    }
    let mut sf = DMatrix::<f64>::zeros(n, 2 * u);
    for (j, &node) in force_nodes.iter().enumerate() {
        sf[(dof(node, 0), 2 * j)] = 1.0;
        sf[(dof(node, 1), 2 * j + 1)] = 1.0;
    }
    // Static correction: K⁻¹ S_f − Φ Λ⁻¹ Φᵀ S_f.
    let k_inv_sf = k.clone().lu().solve(&sf).context("the stiffness matrix is singular")?;
    let phi_t_sf = phi.transpose() * &sf;
    let lambda_inv = DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(r, lambda.iter().map(|w| 1.0 / w)));
    let residual = &k_inv_sf - &phi * &lambda_inv * &phi_t_sf;

    let ns = 2 * r + 2 * u;
    let mut a = DMatrix::<f64>::zeros(ns, ns);
    let cm = phi.transpose() * &c_total * &phi;
    for i in 0..r {
        a[(i, r + i)] = 1.0;
        a[(r + i, i)] = -lambda[i];
        for j in 0..r {
            a[(r + i, r + j)] = -cm[(i, j)];
        }
        for j in 0..2 * u {
            a[(r + i, 2 * r + j)] = phi_t_sf[(i, j)];
        }
    }
    let mut qc = DMatrix::<f64>::zeros(ns, ns);
    for i in 0..r {
        qc[(r + i, r + i)] = tuning.modal_psd;
    }
    for j in 0..u {
        let (a0, a1) = (2 * r + 2 * j, 2 * r + 2 * j + 1);
        if tuning.force_model == ForceModel::Phasor {
            // ṗ_x = −Ω p_y, ṗ_y = Ω p_x: forward rotation at the running speed.
            a[(a0, a1)] = -speed;
            a[(a1, a0)] = speed;
        }
        qc[(a0, a0)] = tuning.force_psd;
        qc[(a1, a1)] = tuning.force_psd;
    }

    // Displacement of every DOF: Φ η + residual · forces.
    let out_row = |d: usize| {
        let mut row = DMatrix::<f64>::zeros(1, ns);
        for j in 0..r {
            row[(0, j)] = phi[(d, j)];
        }
        for j in 0..2 * u {
            row[(0, 2 * r + j)] = residual[(d, j)];
        }
        row
    };
    let nodes = model.n_nodes();
    let mut displacement = DMatrix::<f64>::zeros(2 * nodes, ns);
    for node in 0..nodes {
        displacement.row_mut(2 * node).copy_from(&out_row(dof(node, 0)));
        displacement.row_mut(2 * node + 1).copy_from(&out_row(dof(node, 1)));
    }
    let mut force = DMatrix::<f64>::zeros(2 * u, ns);
    for j in 0..2 * u {
        force[(j, 2 * r + j)] = 1.0;
    }

    let sample_rate = cfg.operation.sample_rate;
    let mut c = DMatrix::<f64>::zeros(cfg.sensors.len(), ns);
    let mut r_diag = Vec::new();
    let mut channels = Vec::new();
    for (i, s) in cfg.sensors.iter().enumerate() {
        match s.kind {
            SensorKind::Displacement { noise_std } => {
                c.row_mut(i).copy_from(&out_row(dof(s.node, s.direction.dof())));
                // A perfect sensor still gets a floor, so R stays positive definite.
                r_diag.push((noise_std * noise_std).max(1e-18));
            }
            SensorKind::Acceleration(_) => {
                bail!("sensor {}: accelerometer channels are not supported by the reduced model yet", s.channel_name())
            }
        }
        channels.push(s.channel_name());
    }
    let r_mat = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(r_diag));
    let mut p0 = DMatrix::<f64>::zeros(ns, ns);
    for i in 0..2 * r {
        p0[(i, i)] = tuning.initial_modal_std.powi(2);
    }
    for j in 0..2 * u {
        p0[(2 * r + j, 2 * r + j)] = tuning.initial_force_std.powi(2);
    }
    Ok(ReducedRotor {
        frequencies_hz,
        force_nodes,
        a,
        qc,
        c,
        r: r_mat,
        displacement,
        force,
        p0,
        channels,
        speed,
        sample_rate,
    })
}
