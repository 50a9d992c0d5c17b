//! Modal reduction of the FE rotor into the filter's continuous-time model.

use crate::systems::rotor::sensor::{butterworth, Section};
use crate::systems::rotor::{dof, RotorModel, SensorKind};
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
    /// Factor on the configured measurement-noise variance (1: the sensors' datasheet noise).
    pub measurement_scale: f64,
    /// Model the accelerometers' low-pass filters as states (default). `false` reads the
    /// acceleration directly, ignoring the filter's gain and phase lag (for comparison).
    pub sensor_lowpass: bool,
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
            measurement_scale: 1.0,
            sensor_lowpass: true,
        }
    }
}

impl Tuning {
    /// A tuning that trades some accuracy with a matched model for robustness to model error:
    /// a faster force random walk (1e-2 N²/s) and more modal process noise (1e-5). On the
    /// accelerometer rotor (rotor_paper_accel.toml) it keeps the disk-node RMS error at
    /// 0.7–1.1 µm with the shaft's Young's modulus 1 % off or the speed 0.05 % off in the filter's
    /// model, where the default tuning (0.25 µm matched) reaches 6 µm and 0.7 µm.
    pub fn robust() -> Self {
        Self { force_psd: 1e-2, modal_psd: 1e-5, ..Self::default() }
    }

    /// This tuning with the noise levels a configuration's `[filter]` declares put in place.
    ///
    /// ```
    /// use edgekf_sim::systems::rotor::config::FilterConfig;
    /// use edgekf_sim::systems::rotor::estimate::Tuning;
    /// let t = Tuning::default().with_filter(&FilterConfig { modal_psd: Some(1e-11), force_psd: None });
    /// assert_eq!((t.modal_psd, t.force_psd), (1e-11, Tuning::default().force_psd));
    /// ```
    pub fn with_filter(self, f: &crate::systems::rotor::config::FilterConfig) -> Self {
        Self {
            modal_psd: f.modal_psd.unwrap_or(self.modal_psd),
            force_psd: f.force_psd.unwrap_or(self.force_psd),
            ..self
        }
    }
}

/// Where an accelerometer's acceleration enters the reduced model (see
/// [`ReducedRotor::accel_inputs`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccelInput {
    /// Sensor channel.
    pub channel: usize,
    /// Row of [`ReducedRotor::displacement`] of the measured DOF.
    pub row: usize,
    /// The low-pass state whose derivative reads the acceleration (`None`: the channel's output
    /// row is the acceleration itself, times `gain`).
    pub state: Option<usize>,
    /// Factor on the acceleration (`ω_c` or `ω_c²` of the first section, or the sensitivity).
    pub gain: f64,
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
    /// Offset of each channel (V for an accelerometer read in volts, else 0): the filter sees
    /// `y − offset`.
    pub offsets: Vec<f64>,
    /// Index of the first sensor low-pass state (`= states()` when there is none).
    pub lowpass_start: usize,
    /// Where each accelerometer's acceleration enters the model: `(channel, displacement row,
    /// state, gain)`. The state's derivative gets `gain × (displacement row · A · A)`: the
    /// first low-pass section's input, or (without a low-pass) the channel's output row read
    /// directly with `state = usize::MAX`. Effects that add forces extend these rows.
    pub accel_inputs: Vec<AccelInput>,
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
/// Displacement sensors read the node DOF. An accelerometer reads the DOF's acceleration (modal
/// acceleration plus the static correction's second derivative) through its Butterworth
/// low-pass, whose sections become states of the model (2 per second-order section), so the
/// filter sees the same phase lag as the sensor.
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

    // Sensor low-pass sections (accelerometers), appended after the force states.
    let sample_rate = cfg.operation.sample_rate;
    let sections: Vec<Vec<Section>> = cfg
        .sensors
        .iter()
        .map(|s| match s.kind {
            SensorKind::Acceleration(a) if a.lowpass_order > 0 && tuning.sensor_lowpass => {
                butterworth(a.lowpass_order, a.corner_hz(sample_rate))
            }
            _ => Vec::new(),
        })
        .collect();
    let nf: usize = sections.iter().flatten().map(Section::states).sum();
    let lowpass_start = 2 * r + 2 * u;
    let ns = lowpass_start + nf;
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
    // How the modal process noise enters: the modal accelerations, and through them the
    // accelerometers' low-pass inputs (filled in below), so `Q` carries the cross terms.
    let mut g_modal = DMatrix::<f64>::zeros(ns, r);
    for i in 0..r {
        g_modal[(r + i, i)] = 1.0;
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

    let mut c = DMatrix::<f64>::zeros(cfg.sensors.len(), ns);
    let mut r_diag = Vec::new();
    let mut channels = Vec::new();
    let mut offsets = Vec::new();
    let mut accel_inputs = Vec::new();
    let mut next = lowpass_start;
    for (i, (s, secs)) in cfg.sensors.iter().zip(&sections).enumerate() {
        let d = dof(s.node, s.direction.dof());
        match s.kind {
            SensorKind::Displacement { noise_std } => {
                c.row_mut(i).copy_from(&out_row(d));
                // A perfect sensor still gets a floor, so R stays positive definite.
                r_diag.push((noise_std * noise_std).max(1e-18) * tuning.measurement_scale);
                offsets.push(0.0);
            }
            SensorKind::Acceleration(acc) => {
                // Acceleration of the DOF: the second derivative of its displacement row,
                // `row · A · A` over the noise-free dynamics. For the modal part that is Φ η̈; for
                // the static correction of the forces it is residual · A_f² (−Ω² residual with
                // rotating phasors, 0 with random walks).
                let accel = &out_row(d) * &a * &a;
                // The low-pass: the first section's input is the acceleration row, the next
                // sections' the previous output; exact, like the reference simulator's.
                // Without a low-pass (or with `sensor_lowpass` off) the row is read directly; the
                // modal noise would then be a feed-through correlated with Q, which is left out.
                let mut input: DMatrix<f64> = accel;
                let row = 2 * s.node + s.direction.dof();
                let sens = acc.sensitivity.unwrap_or(1.0);
                match secs.first() {
                    Some(Section::First { wc }) => {
                        accel_inputs.push(AccelInput { channel: i, row, state: Some(next), gain: *wc })
                    }
                    Some(Section::Second { wc, .. }) => {
                        accel_inputs.push(AccelInput { channel: i, row, state: Some(next + 1), gain: wc * wc })
                    }
                    None => accel_inputs.push(AccelInput { channel: i, row, state: None, gain: sens }),
                }
                for (k, sec) in secs.iter().enumerate() {
                    let y = next;
                    // Only the first section sees the acceleration (and its noise) directly.
                    let noise_gain = |g: &mut DMatrix<f64>, row: usize, f: f64| {
                        if k == 0 {
                            for m in 0..r {
                                g[(row, m)] += f * phi[(d, m)];
                            }
                        }
                    };
                    match *sec {
                        Section::First { wc } => {
                            for j in 0..ns {
                                a[(y, j)] += wc * input[(0, j)];
                            }
                            noise_gain(&mut g_modal, y, wc);
                            a[(y, y)] -= wc;
                            next += 1;
                        }
                        Section::Second { wc, q } => {
                            let yd = y + 1;
                            a[(y, yd)] = 1.0;
                            for j in 0..ns {
                                a[(yd, j)] += wc * wc * input[(0, j)];
                            }
                            noise_gain(&mut g_modal, yd, wc * wc);
                            a[(yd, y)] -= wc * wc;
                            a[(yd, yd)] -= wc / q;
                            next += 2;
                        }
                    }
                    input = DMatrix::<f64>::zeros(1, ns);
                    input[(0, y)] = 1.0;
                }
                c.row_mut(i).copy_from(&(input * sens));
                let sigma = acc.noise_std(sample_rate) * sens.abs();
                r_diag.push((sigma * sigma).max(1e-18) * tuning.measurement_scale);
                offsets.push(if acc.sensitivity.is_some() { acc.offset } else { 0.0 });
            }
        }
        channels.push(s.channel_name());
    }
    qc += &g_modal * g_modal.transpose() * tuning.modal_psd;
    let r_mat = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(r_diag));
    let mut p0 = DMatrix::<f64>::zeros(ns, ns);
    for i in 0..2 * r {
        p0[(i, i)] = tuning.initial_modal_std.powi(2);
    }
    for j in 0..2 * u {
        p0[(2 * r + j, 2 * r + j)] = tuning.initial_force_std.powi(2);
    }
    // The low-pass states start at rest with the rotor; a small prior keeps P positive definite.
    for i in lowpass_start..ns {
        p0[(i, i)] = 1e-6;
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
        offsets,
        lowpass_start,
        accel_inputs,
        speed,
        sample_rate,
    })
}
