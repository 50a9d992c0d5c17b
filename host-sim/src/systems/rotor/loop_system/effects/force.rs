//! The force family: a force at a node, rotating at an order of the running speed (two states
//! turning at that rate) or unknown (two fast random walks), entering the modal equations
//! through the node's mode-shape rows with the static correction of the truncated modes.

use super::Parts;
use crate::systems::rotor::estimate::ReducedRotor;
use crate::systems::rotor::{dof, RotorModel, SensorKind};
use anyhow::{bail, Context, Result};
use nalgebra::DMatrix;

/// What [`augment`](super::augment()) needs besides the reduced model: the static stiffness of the FE model (for
/// the truncated modes' static correction of new forces).
#[derive(Debug, Clone)]
pub struct Flexibility {
    k: DMatrix<f64>,
}

impl Flexibility {
    /// The stiffness of `model` at `speed`.
    pub fn new(model: &RotorModel, speed: f64) -> Self {
        let sys = model.assemble(speed);
        let k = DMatrix::from_fn(sys.k.nrows(), sys.k.ncols(), |i, j| sys.k[(i, j)]);
        Self { k }
    }
}

/// A force at a node, as [`place`] writes it.
pub(super) struct Force {
    /// The node.
    pub node: usize,
    /// Its first state (`F_x`; `F_y` next).
    pub first: usize,
    /// The rate it turns forward at, rad/s (a harmonic force), or `None` (a random walk: an
    /// unknown input).
    pub turning: Option<f64>,
    /// The states' noise density.
    pub psd: f64,
    /// The states' prior standard deviation.
    pub std: f64,
}

/// The force `f` in the model `p` of `red` (reduced from `model`, of stiffness `flex`).
pub(super) fn place(p: &mut Parts, red: &ReducedRotor, model: &RotorModel, flex: &Flexibility, f: Force) -> Result<()> {
    let Force { node, first: s, turning, psd, std } = f;
    if let Some(w) = turning {
        p.a[(s, s + 1)] = -w;
        p.a[(s + 1, s)] = w;
    }
    add_force(p, red, model, flex, node, [Some(s), Some(s + 1)])?;
    for d in 0..2 {
        p.qc[(s + d, s + d)] = psd;
        p.p0[(s + d, s + d)] = std.powi(2);
    }
    Ok(())
}

/// A force at `node` whose `x` component is state `sx` and `y` component state `sy` (either
/// may be absent): modal input `Φᵀ` at the node's DOFs, and the static correction of the
/// truncated modes (`K⁻¹ S − Φ Λ⁻¹ Φᵀ S`) on every displacement and sensor row.
fn add_force(
    t: &mut Parts,
    red: &ReducedRotor,
    model: &RotorModel,
    flex: &Flexibility,
    node: usize,
    states: [Option<usize>; 2],
) -> Result<()> {
    let r = red.frequencies_hz.len();
    let nodes = red.displacement.nrows() / 2;
    if node >= nodes {
        bail!("no node {node}");
    }
    let lambda: Vec<f64> = red.frequencies_hz.iter().map(|f| (2.0 * std::f64::consts::PI * f).powi(2)).collect();
    let ndof = flex.k.nrows();
    let mut sf = DMatrix::<f64>::zeros(ndof, 2);
    sf[(dof(node, 0), 0)] = 1.0;
    sf[(dof(node, 1), 1)] = 1.0;
    let k_inv_sf = flex.k.clone().lu().solve(&sf).context("the stiffness matrix is singular")?;
    let corr = |dof_row: usize, out_row: usize, col: usize| {
        let modal: f64 =
            (0..r).map(|m| red.displacement[(out_row, m)] * red.displacement[(2 * node + col, m)] / lambda[m]).sum();
        k_inv_sf[(dof_row, col)] - modal
    };
    for (col, s) in states.iter().enumerate() {
        let Some(s) = *s else { continue };
        for i in 0..r {
            t.a[(r + i, s)] = red.displacement[(2 * node + col, i)];
        }
        for q in 0..nodes {
            for d in 0..2 {
                t.displacement[(2 * q + d, s)] = corr(dof(q, d), 2 * q + d, col);
            }
        }
        // Probes read the displacement; accelerometer rows are extended in `augment` once
        // every state is in place.
        for (i, sensor) in model.config().sensors.iter().enumerate() {
            if matches!(sensor.kind, SensorKind::Displacement { .. }) {
                let d = sensor.direction.dof();
                t.c[(i, s)] = corr(dof(sensor.node, d), 2 * sensor.node + d, col);
            }
        }
    }
    Ok(())
}
