//! Effects and the augmented continuous model built from a [`ReducedRotor`] by composition.

use crate::rotor::{dof, RotorModel, SensorKind};
use crate::rotor_akf::ReducedRotor;
use anyhow::{bail, Context, Result};
use nalgebra::DMatrix;

/// A small model augmentation with its own states.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Effect {
    /// A constant offset on one sensor channel (index into the channels): one random-walk state
    /// added to that channel's output row. Value in the channel's unit (m for a probe).
    SensorBias {
        /// Channel index.
        channel: usize,
    },
    /// A force rotating forward at `order` × the running speed at a node: two states (`F_x`,
    /// `F_y`) rotating at `order·Ω`, entering the modal equations through the node's mode-shape
    /// rows (with the static correction of the truncated modes). Value: amplitude, N.
    HarmonicForce {
        /// Node.
        node: usize,
        /// Order of the running speed (1, 2, 3, …).
        order: u32,
    },
}

impl Effect {
    /// The kind as written in the report (`sensor_bias`, `harmonic_force`).
    pub fn kind(&self) -> &'static str {
        match self {
            Effect::SensorBias { .. } => "sensor_bias",
            Effect::HarmonicForce { .. } => "harmonic_force",
        }
    }

    /// Number of states the effect adds.
    pub fn states(&self) -> usize {
        match self {
            Effect::SensorBias { .. } => 1,
            Effect::HarmonicForce { .. } => 2,
        }
    }

    /// Number of free parameters the effect costs in the BIC (a bias: its value; a harmonic
    /// force: amplitude and phase).
    pub fn parameters(&self) -> usize {
        self.states()
    }

    /// Where it acts, for the report: the channel name or `node N`.
    pub fn location(&self, channels: &[String]) -> String {
        match *self {
            Effect::SensorBias { channel } => channels.get(channel).cloned().unwrap_or_else(|| format!("#{channel}")),
            Effect::HarmonicForce { node, .. } => format!("node {node}"),
        }
    }

    /// Unit of the value.
    pub fn unit(&self) -> &'static str {
        match self {
            Effect::SensorBias { .. } => "m",
            Effect::HarmonicForce { .. } => "N",
        }
    }
}

/// Noise and prior of the effects' states.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EffectTuning {
    /// Random-walk density of a bias state, m²/s.
    pub bias_psd: f64,
    /// Prior standard deviation of a bias, m.
    pub bias_std: f64,
    /// Random-walk density of a harmonic force's states, N²/s.
    pub force_psd: f64,
    /// Prior standard deviation of a harmonic force's states, N.
    pub force_std: f64,
}

impl Default for EffectTuning {
    fn default() -> Self {
        Self { bias_psd: 1e-16, bias_std: 1e-3, force_psd: 1e-3, force_std: 10.0 }
    }
}

/// The base model plus effects: `ẋ = A x + w`, `y = C x + v`, and the virtual outputs.
#[derive(Debug, Clone)]
pub struct AugmentedModel {
    /// Continuous system matrix.
    pub a: DMatrix<f64>,
    /// Continuous process-noise density.
    pub qc: DMatrix<f64>,
    /// Sensor rows.
    pub c: DMatrix<f64>,
    /// Measurement-noise covariance per sample.
    pub r: DMatrix<f64>,
    /// Initial covariance.
    pub p0: DMatrix<f64>,
    /// Displacement rows of every node (node-major `n0_x, n0_y, …`), effects included.
    pub displacement: DMatrix<f64>,
    /// The effects, with the index of their first state.
    pub effects: Vec<(Effect, usize)>,
}

/// What [`augment`] needs besides the reduced model: the static flexibility of the FE model
/// (for the truncated modes' static correction of new forces).
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

/// Builds `red` plus `effects` (the reduced model's displacement rows give the mode shapes at
/// the translational DOFs: the first `r` columns are `Φ`).
pub fn augment(
    red: &ReducedRotor,
    model: &RotorModel,
    flex: &Flexibility,
    effects: &[Effect],
    tuning: &EffectTuning,
) -> Result<AugmentedModel> {
    let n0 = red.states();
    let extra: usize = effects.iter().map(Effect::states).sum();
    let ns = n0 + extra;
    let r = red.frequencies_hz.len();
    let grow = |m: &DMatrix<f64>, rows: usize| {
        let mut out = DMatrix::<f64>::zeros(rows, ns);
        out.view_mut((0, 0), (m.nrows(), m.ncols())).copy_from(m);
        out
    };
    let mut a = grow(&red.a, ns);
    let mut qc = grow(&red.qc, ns);
    let mut p0 = grow(&red.p0, ns);
    let mut c = grow(&red.c, red.c.nrows());
    let mut displacement = grow(&red.displacement, red.displacement.nrows());
    let sensors = &model.config().sensors;
    let lambda: Vec<f64> = red.frequencies_hz.iter().map(|f| (2.0 * std::f64::consts::PI * f).powi(2)).collect();
    let nodes = red.displacement.nrows() / 2;
    let mut next = n0;
    let mut placed = Vec::new();
    for &e in effects {
        let s = next;
        match e {
            Effect::SensorBias { channel } => {
                if channel >= c.nrows() {
                    bail!("no channel #{channel}");
                }
                c[(channel, s)] = 1.0;
                qc[(s, s)] = tuning.bias_psd;
                p0[(s, s)] = tuning.bias_std.powi(2);
            }
            Effect::HarmonicForce { node, order } => {
                if node >= nodes {
                    bail!("no node {node}");
                }
                if sensors.iter().any(|s| !matches!(s.kind, SensorKind::Displacement { .. })) {
                    bail!("harmonic_force effects support displacement probes only (accelerometer rows not built yet)");
                }
                let w = order as f64 * red.speed;
                a[(s, s + 1)] = -w;
                a[(s + 1, s)] = w;
                for d in 0..2 {
                    qc[(s + d, s + d)] = tuning.force_psd;
                    p0[(s + d, s + d)] = tuning.force_std.powi(2);
                }
                // Modal input: Φᵀ at the node's x and y DOFs.
                for i in 0..r {
                    a[(r + i, s)] = red.displacement[(2 * node, i)];
                    a[(r + i, s + 1)] = red.displacement[(2 * node + 1, i)];
                }
                // Static correction of the truncated modes: K⁻¹ S − Φ Λ⁻¹ Φᵀ S.
                let ndof = flex.k.nrows();
                let mut sf = DMatrix::<f64>::zeros(ndof, 2);
                sf[(dof(node, 0), 0)] = 1.0;
                sf[(dof(node, 1), 1)] = 1.0;
                let k_inv_sf = flex.k.clone().lu().solve(&sf).context("the stiffness matrix is singular")?;
                let corr = |dof_row: usize, out_row: usize, col: usize| {
                    let phi_f = |m: usize| red.displacement[(2 * node + col, m)];
                    let modal: f64 = (0..r).map(|m| red.displacement[(out_row, m)] * phi_f(m) / lambda[m]).sum();
                    k_inv_sf[(dof_row, col)] - modal
                };
                for q in 0..nodes {
                    for d in 0..2 {
                        for col in 0..2 {
                            displacement[(2 * q + d, s + col)] = corr(dof(q, d), 2 * q + d, col);
                        }
                    }
                }
                for (i, sensor) in sensors.iter().enumerate() {
                    let d = sensor.direction.dof();
                    for col in 0..2 {
                        c[(i, s + col)] = corr(dof(sensor.node, d), 2 * sensor.node + d, col);
                    }
                }
            }
        }
        placed.push((e, s));
        next += e.states();
    }
    Ok(AugmentedModel { a, qc, c, r: red.r.clone(), p0, displacement, effects: placed })
}
