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
///
/// The steps: [`modal_basis`], [`force_inputs`] with their static correction, the modal and
/// force dynamics ([`Layout::dynamics`]), the output rows, the sensors with their low-passes
/// ([`Layout::sensors`]) and the priors ([`Layout::prior`]).
pub fn reduce(model: &RotorModel, speed: f64, tuning: &Tuning) -> Result<ReducedRotor> {
    let cfg = model.config();
    let sys = model.assemble(speed);
    let n = sys.n();
    let r = tuning.modes;
    if r == 0 || r > n {
        bail!("modes must be between 1 and {n}, not {r}");
    }
    let k = to_nalgebra(&sys.k);
    let modes = modal_basis(&to_nalgebra(&sys.m), &k, r)?;
    let force_nodes = cfg.unbalance_nodes();
    let forces = force_inputs(&force_nodes, n, &k, &modes)?;
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
    let lowpass_states: usize = sections.iter().flatten().map(Section::states).sum();
    let layout = Layout { r, u: force_nodes.len(), lowpass_start: 2 * r + 2 * force_nodes.len(), lowpass_states };
    let (mut a, qc_forces, mut g_modal) =
        layout.dynamics(&modes, &forces, &to_nalgebra(&sys.c_total(speed)), speed, tuning);
    let out_row = |d: usize| layout.displacement_row(&modes, &forces, d);
    let nodes = model.n_nodes();
    let mut displacement = DMatrix::<f64>::zeros(2 * nodes, layout.states());
    for node in 0..nodes {
        displacement.row_mut(2 * node).copy_from(&out_row(dof(node, 0)));
        displacement.row_mut(2 * node + 1).copy_from(&out_row(dof(node, 1)));
    }
    let mut force = DMatrix::<f64>::zeros(2 * layout.u, layout.states());
    for j in 0..2 * layout.u {
        force[(j, 2 * r + j)] = 1.0;
    }
    let sensors = layout.sensors(cfg, &sections, &modes, &out_row, &mut a, &mut g_modal, tuning);
    let qc = qc_forces + &g_modal * g_modal.transpose() * tuning.modal_psd;
    Ok(ReducedRotor {
        frequencies_hz: modes.frequencies_hz,
        force_nodes,
        a,
        qc,
        c: sensors.c,
        r: DMatrix::from_diagonal(&nalgebra::DVector::from_vec(sensors.noise)),
        displacement,
        force,
        p0: layout.prior(tuning),
        channels: sensors.channels,
        offsets: sensors.offsets,
        lowpass_start: layout.lowpass_start,
        accel_inputs: sensors.accel_inputs,
        speed,
        sample_rate,
    })
}

/// The kept modes: mass-normalised shapes `Φ` (DOF × mode), `ω²` and the frequencies.
struct Modes {
    phi: DMatrix<f64>,
    lambda: Vec<f64>,
    frequencies_hz: Vec<f64>,
}

/// The `r` lowest modes of `K φ = ω² M φ` with the symmetric part of `K`, through the Cholesky
/// factor of `M`: `L⁻¹ K L⁻ᵀ v = ω² v`, `φ = L⁻ᵀ v`.
fn modal_basis(m: &DMatrix<f64>, k: &DMatrix<f64>, r: usize) -> Result<Modes> {
    let n = m.nrows();
    let k_sym = (k + k.transpose()) * 0.5;
    let chol = m.clone().cholesky().context("the mass matrix is not positive definite")?;
    let l_inv = chol.l().try_inverse().context("singular mass factor")?;
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
    Ok(Modes { phi, lambda, frequencies_hz })
}

/// The force states' inputs: their modal participation `Φᵀ S_f` and the static correction of
/// the truncated modes `K⁻¹ S_f − Φ Λ⁻¹ Φᵀ S_f` (DOF × force state).
struct Forces {
    modal: DMatrix<f64>,
    residual: DMatrix<f64>,
}

/// Two force states per unbalance node, acting on its x and y DOFs.
fn force_inputs(nodes: &[usize], n: usize, k: &DMatrix<f64>, modes: &Modes) -> Result<Forces> {
    if nodes.is_empty() {
        bail!("the configuration has no [[unbalance]] node to estimate a force at");
    }
    let mut sf = DMatrix::<f64>::zeros(n, 2 * nodes.len());
    for (j, &node) in nodes.iter().enumerate() {
        sf[(dof(node, 0), 2 * j)] = 1.0;
        sf[(dof(node, 1), 2 * j + 1)] = 1.0;
    }
    let k_inv_sf = k.clone().lu().solve(&sf).context("the stiffness matrix is singular")?;
    let modal = modes.phi.transpose() * &sf;
    let r = modes.lambda.len();
    let lambda_inv = DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(r, modes.lambda.iter().map(|w| 1.0 / w)));
    let residual = &k_inv_sf - &modes.phi * &lambda_inv * &modal;
    Ok(Forces { modal, residual })
}

/// Where the states sit: `[η (r), η̇ (r), forces (2u), low-pass states]`.
struct Layout {
    r: usize,
    u: usize,
    lowpass_start: usize,
    lowpass_states: usize,
}

/// The sensors' part of the model.
struct Sensors {
    c: DMatrix<f64>,
    noise: Vec<f64>,
    channels: Vec<String>,
    offsets: Vec<f64>,
    accel_inputs: Vec<AccelInput>,
}

impl Layout {
    fn states(&self) -> usize {
        self.lowpass_start + self.lowpass_states
    }

    /// `A` of the modes (damping projected on them) and the forces (rotating phasors or random
    /// walks), the forces' process noise, and how the modal noise enters (the modal
    /// accelerations; the sensors add their low-pass inputs, so `Q` carries the cross terms).
    fn dynamics(
        &self,
        modes: &Modes,
        forces: &Forces,
        c_total: &DMatrix<f64>,
        speed: f64,
        tuning: &Tuning,
    ) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        let (r, u, ns) = (self.r, self.u, self.states());
        let mut a = DMatrix::<f64>::zeros(ns, ns);
        let cm = modes.phi.transpose() * c_total * &modes.phi;
        for i in 0..r {
            a[(i, r + i)] = 1.0;
            a[(r + i, i)] = -modes.lambda[i];
            for j in 0..r {
                a[(r + i, r + j)] = -cm[(i, j)];
            }
            for j in 0..2 * u {
                a[(r + i, 2 * r + j)] = forces.modal[(i, j)];
            }
        }
        let mut qc = DMatrix::<f64>::zeros(ns, ns);
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
        (a, qc, g_modal)
    }

    /// Displacement of DOF `d`: `Φ η + residual · forces`.
    fn displacement_row(&self, modes: &Modes, forces: &Forces, d: usize) -> DMatrix<f64> {
        let mut row = DMatrix::<f64>::zeros(1, self.states());
        for j in 0..self.r {
            row[(0, j)] = modes.phi[(d, j)];
        }
        for j in 0..2 * self.u {
            row[(0, 2 * self.r + j)] = forces.residual[(d, j)];
        }
        row
    }

    /// The sensor rows and noise; an accelerometer's low-pass sections become states, fed by
    /// the DOF's acceleration (written into `a` and the modal noise input `g_modal`).
    #[allow(clippy::too_many_arguments)]
    fn sensors(
        &self,
        cfg: &crate::systems::rotor::RotorConfig,
        sections: &[Vec<Section>],
        modes: &Modes,
        out_row: &dyn Fn(usize) -> DMatrix<f64>,
        a: &mut DMatrix<f64>,
        g_modal: &mut DMatrix<f64>,
        tuning: &Tuning,
    ) -> Sensors {
        let (r, ns) = (self.r, self.states());
        let sample_rate = cfg.operation.sample_rate;
        let mut out = Sensors {
            c: DMatrix::<f64>::zeros(cfg.sensors.len(), ns),
            noise: Vec::new(),
            channels: Vec::new(),
            offsets: Vec::new(),
            accel_inputs: Vec::new(),
        };
        let mut next = self.lowpass_start;
        for (i, (s, secs)) in cfg.sensors.iter().zip(sections).enumerate() {
            let d = dof(s.node, s.direction.dof());
            match s.kind {
                SensorKind::Displacement { noise_std } => {
                    out.c.row_mut(i).copy_from(&out_row(d));
                    // A perfect sensor still gets a floor, so R stays positive definite.
                    out.noise.push((noise_std * noise_std).max(1e-18) * tuning.measurement_scale);
                    out.offsets.push(0.0);
                }
                SensorKind::Acceleration(acc) => {
                    // Acceleration of the DOF: the second derivative of its displacement row,
                    // `row · A · A` over the noise-free dynamics. For the modal part that is Φ η̈;
                    // for the static correction of the forces it is residual · A_f² (−Ω²
                    // residual with rotating phasors, 0 with random walks).
                    let accel = &out_row(d) * &*a * &*a;
                    // The low-pass: the first section's input is the acceleration row, the next
                    // sections' the previous output; exact, like the reference simulator's.
                    // Without a low-pass (or with `sensor_lowpass` off) the row is read directly;
                    // the modal noise would then be a feed-through correlated with Q, which is
                    // left out.
                    let mut input: DMatrix<f64> = accel;
                    let row = 2 * s.node + s.direction.dof();
                    let sens = acc.sensitivity.unwrap_or(1.0);
                    out.accel_inputs.push(match secs.first() {
                        Some(Section::First { wc }) => AccelInput { channel: i, row, state: Some(next), gain: *wc },
                        Some(Section::Second { wc, .. }) => {
                            AccelInput { channel: i, row, state: Some(next + 1), gain: wc * wc }
                        }
                        None => AccelInput { channel: i, row, state: None, gain: sens },
                    });
                    for (k, sec) in secs.iter().enumerate() {
                        let y = next;
                        // Only the first section sees the acceleration (and its noise) directly.
                        let noise_gain = |g: &mut DMatrix<f64>, row: usize, f: f64| {
                            if k == 0 {
                                for m in 0..r {
                                    g[(row, m)] += f * modes.phi[(d, m)];
                                }
                            }
                        };
                        match *sec {
                            Section::First { wc } => {
                                for j in 0..ns {
                                    a[(y, j)] += wc * input[(0, j)];
                                }
                                noise_gain(g_modal, y, wc);
                                a[(y, y)] -= wc;
                                next += 1;
                            }
                            Section::Second { wc, q } => {
                                let yd = y + 1;
                                a[(y, yd)] = 1.0;
                                for j in 0..ns {
                                    a[(yd, j)] += wc * wc * input[(0, j)];
                                }
                                noise_gain(g_modal, yd, wc * wc);
                                a[(yd, y)] -= wc * wc;
                                a[(yd, yd)] -= wc / q;
                                next += 2;
                            }
                        }
                        input = DMatrix::<f64>::zeros(1, ns);
                        input[(0, y)] = 1.0;
                    }
                    out.c.row_mut(i).copy_from(&(input * sens));
                    let sigma = acc.noise_std(sample_rate) * sens.abs();
                    out.noise.push((sigma * sigma).max(1e-18) * tuning.measurement_scale);
                    out.offsets.push(if acc.sensitivity.is_some() { acc.offset } else { 0.0 });
                }
            }
            out.channels.push(s.channel_name());
        }
        out
    }

    /// The initial covariance: the modal and force priors of the tuning; the low-pass states
    /// start at rest with the rotor, with a small prior that keeps `P` positive definite.
    fn prior(&self, tuning: &Tuning) -> DMatrix<f64> {
        let ns = self.states();
        let mut p0 = DMatrix::<f64>::zeros(ns, ns);
        for i in 0..2 * self.r {
            p0[(i, i)] = tuning.initial_modal_std.powi(2);
        }
        for j in 0..2 * self.u {
            p0[(2 * self.r + j, 2 * self.r + j)] = tuning.initial_force_std.powi(2);
        }
        for i in self.lowpass_start..ns {
            p0[(i, i)] = 1e-6;
        }
        p0
    }
}
