//! Time response at constant speed from rest, with the sensors' outputs.
//!
//! # How
//!
//! The rotor, the accelerometers' Butterworth low-passes and the unbalance force form one linear
//! time-invariant system. The force is generated inside it by a two-state oscillator
//! `w = [cos Ωt, sin Ωt]` (`ẇ = Ω [[0, −1], [1, 0]] w`), so the augmented state
//! `z = [q, q̇, filter states, w]` obeys `ż = F z` with no input at all, and one output period
//! `Δt` is exactly `z_{k+1} = e^{FΔt} z_k` ([`Method::Exact`], the default). There is no
//! zero-order hold and no sub-stepping error: the force enters as the exact sinusoid, the filters
//! see the exact continuous acceleration.
//!
//! The recording keeps every node's x and y and the sensors, about 80 rows of `z`. They are
//! computed in `F`'s real modal form ([`crate::linalg::free_response`]: `e^{λΔt}` in closed form
//! per eigenvalue, `O(n)` a step, the outputs of 256 samples at a time as one matrix product).
//! Where `F` has no well-conditioned eigenbasis (a free rotor's rigid-body modes form a Jordan
//! block), `Φ = e^{FΔt}` is computed once (balanced scaling and squaring with a [13/13] Padé
//! approximant, [`super::linalg::expm`]) and each sample is one dense matrix–vector product.
//! Accuracy, measured in `tests/rotor.rs` and this module's tests on the paper rotor:
//! * the modal form and `Φ` agree to 1e-8 of the peak displacement (1.6e-7 of the peak
//!   acceleration) after 1 s, a slow drift of phase from rounding in the eigenvalues; `Φ` over
//!   1 ms and over 4 × 0.25 ms agree to 1e-10;
//! * with shaft damping, 2.5 s after start-up the response equals the independent steady
//!   unbalance solution ([`RotorModel::unbalance_response`]) to 2e-9 of the largest orbit;
//! * the clean accelerometer channel equals `−Ω² x` through the Butterworth response to 1e-8.
//!
//! Cost on the paper rotor (306 states), 4 s at 1 kHz: ~45 ms in release, of which ~30 ms is the
//! eigen decomposition; through `Φ` it took ~90 ms (the product streams the 740 kB `Φ` from
//! memory every sample).
//!
//! [`Method::Trapezoidal`] is the alternative for cross-checks: Newmark's average-acceleration
//! rule (the trapezoidal rule on the first-order form, unconditionally stable, second order,
//! period error `(ωh)²/12`) at `substeps` steps per sample, with the force evaluated exactly at
//! the step ends. Through the undamped start-up transient at 50 substeps (h = 20 µs) it stays
//! within 5e-4 of the peak of the exact run (its own period error on the higher modes); at 10
//! substeps it settles on the steady response to 8e-6.
//!
//! At t = 0 the rotor is at rest (`q = q̇ = 0`) and already turning at Ω, so the unbalance
//! force starts at full amplitude: the response is the steady unbalance response plus a free
//! vibration of every mode, which decays only as fast as the model is damped. The paper rotor
//! has 20 N·s/m bearings next to nodal points and no shaft damping: log decrements ~1e-9, so
//! its start-up transient never visibly decays (the response beats between the steady orbit
//! and up to about twice it). `damping_alpha`/`damping_beta` under `[shaft]` make it settle.

use super::assembly::RotorModel;
use super::config::{SensorConfig, SensorKind};
use super::sensor::{butterworth, Section};
use super::{dof, RotorError};
use crate::io::data::{self, DataError, DataFile};
use crate::linalg::free_response::ModalExponential;
use crate::linalg::{expm, mul, solve};
use faer::{Accum, Mat, MatRef, Par};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::path::Path;

/// How one output period is integrated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// `z_{k+1} = e^{FΔt} z_k` for the augmented system (exact; the default).
    #[default]
    Exact,
    /// Newmark average acceleration (trapezoidal rule) with this many steps per output sample.
    Trapezoidal {
        /// Steps per output sample (at least 1).
        substeps: u32,
    },
}

/// What to simulate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimOptions {
    /// Length of the run, s; the samples are at `t_k = k / sample_rate`, `k = 0 … duration·rate − 1`.
    pub duration: f64,
    /// Seed of the sensor noise.
    pub seed: u64,
    /// Add sensor noise (false: the measured channels equal the clean ones).
    pub noise: bool,
    /// Integration method.
    pub method: Method,
    /// Speed, rad/s; default (`None`): the configuration's `operation.speed`.
    pub speed: Option<f64>,
    /// Start on the steady unbalance response (a machine that has run for a while, as a
    /// recording of one in service does) instead of at rest: no start-up transient, whose
    /// free vibration of every mode tells where a force acts more than a running machine can.
    pub steady_start: bool,
}

impl Default for SimOptions {
    /// 1 s, seed 1, with noise, exact discretisation, the configured speed, from rest.
    fn default() -> Self {
        Self { duration: 1.0, seed: 1, noise: true, method: Method::Exact, speed: None, steady_start: false }
    }
}

/// Where a long simulation is (for progress messages).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Progress {
    /// The transition matrix is ready (`states` augmented states).
    Discretised {
        /// Size of the augmented state.
        states: usize,
    },
    /// `done` of `total` samples computed.
    Samples {
        /// Samples done.
        done: usize,
        /// Samples in all.
        total: usize,
    },
}

/// The unbalance force on one node over time (sum of its unbalances).
#[derive(Debug, Clone, PartialEq)]
pub struct ForceTrace {
    /// Node.
    pub node: usize,
    /// `F_x`, N.
    pub x: Vec<f64>,
    /// `F_y`, N.
    pub y: Vec<f64>,
}

/// One sensor's output over time.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    /// Channel name in the data file (`n5_x`, `n32_ay`, …).
    pub name: String,
    /// The sensor.
    pub sensor: SensorConfig,
    /// The output with noise (m, m/s² or V).
    pub measured: Vec<f64>,
    /// The output without noise (filtered, for an accelerometer).
    pub clean: Vec<f64>,
    /// Standard deviation of the added noise per sample, in the channel's unit.
    pub noise_std: f64,
}

/// A simulated run: time, every node's displacement, the forces, the sensors.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// Speed, rad/s.
    pub speed: f64,
    /// Sample rate, Hz.
    pub sample_rate: f64,
    /// Sample times `k / sample_rate`, s.
    pub t: Vec<f64>,
    /// `x[node][k]`: displacement of each node in x, m.
    pub x: Vec<Vec<f64>>,
    /// `y[node][k]`: displacement of each node in y, m.
    pub y: Vec<Vec<f64>>,
    /// Unbalance force per unbalanced node.
    pub forces: Vec<ForceTrace>,
    /// Sensor channels, in configuration order.
    pub channels: Vec<Channel>,
}

impl Recording {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Columns of the data file (without `t`), in order: the measured channels, then
    /// `truth_n<k>_x`, `truth_n<k>_y` for every node, `truth_f<k>_x`, `truth_f<k>_y` for each
    /// unbalanced node, and `truth_<channel>` (the noise-free, filtered output) for each
    /// accelerometer channel. A displacement channel's noise-free value is its node's
    /// `truth_n<k>_<dir>` column, so it gets no column of its own.
    pub fn columns(&self) -> (Vec<String>, Vec<&[f64]>) {
        let mut names = Vec::new();
        let mut cols: Vec<&[f64]> = Vec::new();
        for c in &self.channels {
            names.push(c.name.clone());
            cols.push(&c.measured);
        }
        for (k, (x, y)) in self.x.iter().zip(&self.y).enumerate() {
            names.push(format!("{}n{k}_x", data::TRUTH_PREFIX));
            cols.push(x);
            names.push(format!("{}n{k}_y", data::TRUTH_PREFIX));
            cols.push(y);
        }
        for f in &self.forces {
            names.push(format!("{}f{}_x", data::TRUTH_PREFIX, f.node));
            cols.push(&f.x);
            names.push(format!("{}f{}_y", data::TRUTH_PREFIX, f.node));
            cols.push(&f.y);
        }
        for c in self.channels.iter().filter(|c| !matches!(c.sensor.kind, SensorKind::Displacement { .. })) {
            names.push(format!("{}{}", data::TRUTH_PREFIX, c.name));
            cols.push(&c.clean);
        }
        (names, cols)
    }

    /// The run as a data file in memory.
    pub fn to_data_file(&self) -> DataFile {
        let (names, cols) = self.columns();
        DataFile { sha256: None, names, t: self.t.clone(), columns: cols.into_iter().map(<[f64]>::to_vec).collect() }
    }

    /// Writes the run as CSV with [`crate::io::data::write`].
    pub fn write_csv(&self, path: &Path) -> Result<(), DataError> {
        let (names, cols) = self.columns();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        data::write(path, &names, &self.t, &cols)
    }
}

/// The augmented continuous-time system `ż = F z` and where things sit in `z`.
struct Augmented {
    f: Mat<f64>,
    /// Index of the first exosystem state (`cos Ωt`); `sin Ωt` follows.
    exo: usize,
    /// Per sensor: how its clean output is read from z (a row vector over z).
    outputs: Vec<Vec<(usize, f64)>>,
}

impl Augmented {
    /// What the recording keeps of `z` as rows over it (every node's x and y, then each
    /// sensor's clean output), and the start: at rest, the force's oscillator at `cos 0 = 1`.
    fn recorded(&self, n_nodes: usize) -> (Mat<f64>, Vec<f64>) {
        let (nodes, size) = (2 * n_nodes, self.f.nrows());
        let rows = Mat::<f64>::from_fn(nodes + self.outputs.len(), size, |r, j| match r.checked_sub(nodes) {
            None => f64::from(u8::from(j == dof(r / 2, r % 2))),
            Some(c) => self.outputs[c].iter().filter(|&&(i, _)| i == j).map(|&(_, v)| v).sum(),
        });
        let mut z0 = vec![0.0; size];
        z0[self.exo] = 1.0;
        (rows, z0)
    }
}

impl RotorModel {
    /// Builds `F` for speed `speed` and the configured sensors at `sample_rate`.
    fn augmented(&self, speed: f64, sample_rate: f64) -> Result<Augmented, RotorError> {
        let n = self.n_dofs();
        let a = self.state_matrix(speed)?;
        let sensors = &self.config().sensors;
        let sections: Vec<Vec<Section>> = sensors
            .iter()
            .map(|s| match s.kind {
                SensorKind::Acceleration(c) if c.lowpass_order > 0 => {
                    butterworth(c.lowpass_order, c.corner_hz(sample_rate))
                }
                _ => Vec::new(),
            })
            .collect();
        let nf: usize = sections.iter().flatten().map(Section::states).sum();
        let exo = 2 * n + nf;
        let size = exo + 2;
        let mut f = Mat::<f64>::zeros(size, size);
        for i in 0..2 * n {
            for j in 0..2 * n {
                f[(i, j)] = a[(i, j)];
            }
        }
        // Unbalance: f(t) = Re(F̂) cos Ωt − Im(F̂) sin Ωt, entering q̈ through M⁻¹.
        let phasor = self.unbalance_phasor(speed);
        let s = Mat::<f64>::from_fn(n, 2, |i, c| if c == 0 { phasor[i].re } else { -phasor[i].im });
        let minv_s = solve(self.matrices().m.as_ref(), s.as_ref(), "M⁻¹ S")?;
        for i in 0..n {
            f[(n + i, exo)] = minv_s[(i, 0)];
            f[(n + i, exo + 1)] = minv_s[(i, 1)];
        }
        f[(exo, exo + 1)] = -speed;
        f[(exo + 1, exo)] = speed;

        // Sensors: displacement reads q; an accelerometer's input is the q̈ row of its DOF.
        let mut outputs = Vec::with_capacity(sensors.len());
        let mut next = 2 * n;
        for (sensor, secs) in sensors.iter().zip(&sections) {
            let d = dof(sensor.node, sensor.direction.dof());
            match sensor.kind {
                SensorKind::Displacement { .. } => outputs.push(vec![(d, 1.0)]),
                SensorKind::Acceleration(_) if secs.is_empty() => {
                    let row: Vec<(usize, f64)> =
                        (0..size).map(|j| (j, f[(n + d, j)])).filter(|(_, v)| *v != 0.0).collect();
                    outputs.push(row);
                }
                SensorKind::Acceleration(_) => {
                    // Input of the first section: the acceleration row; of the next: the previous output.
                    let mut input: Vec<(usize, f64)> =
                        (0..size).map(|j| (j, f[(n + d, j)])).filter(|(_, v)| *v != 0.0).collect();
                    for sec in secs {
                        let y = next;
                        match *sec {
                            Section::First { wc } => {
                                for &(j, v) in &input {
                                    f[(y, j)] += wc * v;
                                }
                                f[(y, y)] -= wc;
                                next += 1;
                            }
                            Section::Second { wc, q } => {
                                let yd = y + 1;
                                f[(y, yd)] = 1.0;
                                for &(j, v) in &input {
                                    f[(yd, j)] += wc * wc * v;
                                }
                                f[(yd, y)] -= wc * wc;
                                f[(yd, yd)] -= wc / q;
                                next += 2;
                            }
                        }
                        input = vec![(y, 1.0)];
                    }
                    outputs.push(input);
                }
            }
        }
        Ok(Augmented { f, exo, outputs })
    }

    /// The transition matrix over one output period.
    fn transition(&self, aug: &Augmented, dt: f64, speed: f64, method: Method) -> Result<Mat<f64>, RotorError> {
        let size = aug.f.nrows();
        match method {
            Method::Exact => {
                expm(Mat::from_fn(size, size, |i, j| aug.f[(i, j)] * dt).as_ref()).map_err(RotorError::from)
            }
            Method::Trapezoidal { substeps } => {
                let substeps = substeps.max(1);
                let h = dt / substeps as f64;
                let ns = aug.exo; // structural + filter states
                let lhs = Mat::<f64>::from_fn(ns, ns, |i, j| f64::from(u8::from(i == j)) - 0.5 * h * aug.f[(i, j)]);
                let (c, s) = ((speed * h).cos(), (speed * h).sin());
                let rot = [[c, -s], [s, c]];
                // RHS columns: (I + F h/2) for the state, (h/2) B (I + R) for the exosystem.
                let rhs = Mat::<f64>::from_fn(ns, size, |i, j| {
                    if j < ns {
                        f64::from(u8::from(i == j)) + 0.5 * h * aug.f[(i, j)]
                    } else {
                        let col = j - ns;
                        let b0 = aug.f[(i, ns)];
                        let b1 = aug.f[(i, ns + 1)];
                        // B (I + R) column `col`.
                        0.5 * h
                            * (b0 * (f64::from(u8::from(col == 0)) + rot[0][col])
                                + b1 * (f64::from(u8::from(col == 1)) + rot[1][col]))
                    }
                });
                let top = solve(lhs.as_ref(), rhs.as_ref(), "trapezoidal step")?;
                let step = Mat::<f64>::from_fn(size, size, |i, j| {
                    if i < ns {
                        top[(i, j)]
                    } else if j >= ns {
                        rot[i - ns][j - ns]
                    } else {
                        0.0
                    }
                });
                // step^substeps by binary powering.
                let mut result = Mat::<f64>::identity(size, size);
                let mut base = step;
                let mut e = substeps;
                while e > 0 {
                    if e & 1 == 1 {
                        result = mul(result.as_ref(), base.as_ref());
                    }
                    e >>= 1;
                    if e > 0 {
                        base = mul(base.as_ref(), base.as_ref());
                    }
                }
                Ok(result)
            }
        }
    }

    /// Simulates the rotor from rest at constant speed; see the module documentation.
    ///
    /// ```
    /// use edgekf_sim::systems::rotor::{RotorConfig, RotorModel, SimOptions};
    /// let cfg = RotorConfig::from_toml_str(include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml"))).unwrap();
    /// let model = RotorModel::from_config(&cfg).unwrap();
    /// let rec = model.simulate(&SimOptions { duration: 0.2, ..Default::default() }).unwrap();
    /// assert_eq!(rec.len(), 200);
    /// assert_eq!(rec.channels[0].name, "n5_x");
    /// assert_eq!(rec.x[12][0], 0.0); // from rest
    /// let (names, _) = rec.columns();
    /// assert!(names.contains(&"truth_n37_y".to_string()) && names.contains(&"truth_f23_x".to_string()));
    /// ```
    pub fn simulate(&self, opts: &SimOptions) -> Result<Recording, RotorError> {
        self.simulate_with_progress(opts, &mut |_| {})
    }

    /// [`simulate`](Self::simulate), reporting progress to `progress`.
    pub fn simulate_with_progress(
        &self,
        opts: &SimOptions,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Recording, RotorError> {
        let cfg = self.config();
        let fs = cfg.operation.sample_rate;
        let speed = opts.speed.unwrap_or(cfg.operation.speed);
        if !speed.is_finite() {
            return Err(RotorError::Invalid(format!("speed = {speed} rad/s must be finite")));
        }
        if !(opts.duration.is_finite() && opts.duration > 0.0) {
            return Err(RotorError::Invalid(format!("duration = {} s must be positive", opts.duration)));
        }
        let samples = (opts.duration * fs).round();
        if samples < 2.0 {
            return Err(RotorError::Invalid(format!(
                "duration = {} s gives fewer than 2 samples at {fs} Hz",
                opts.duration
            )));
        }
        let cells = samples * (2.0 * self.n_nodes() as f64 + 2.0 * cfg.unbalances.len() as f64);
        if cells > 2e8 {
            return Err(RotorError::Invalid(format!(
                "duration = {} s at {fs} Hz would hold {cells:.1e} values (over 2e8); simulate a shorter run",
                opts.duration
            )));
        }
        let samples = samples as usize;
        if let Method::Trapezoidal { substeps: 0 } = opts.method {
            return Err(RotorError::Invalid("trapezoidal method needs at least 1 substep".into()));
        }

        let aug = self.augmented(speed, fs)?;
        let size = aug.f.nrows();
        let n_nodes = self.n_nodes();
        let (rows, mut z0) = aug.recorded(n_nodes);
        if opts.steady_start {
            // q(t) = Re(Q e^{iΩt}): q(0) = Re Q, q̇(0) = −Ω Im Q.
            let q = self.unbalance_response(speed)?.q;
            let n = q.len();
            for (i, v) in q.iter().enumerate() {
                z0[i] = v.re;
                z0[n + i] = -speed * v.im;
            }
        }
        let modal = match opts.method {
            Method::Exact => ModalExponential::of(aug.f.as_ref(), 1.0 / fs),
            Method::Trapezoidal { .. } => None,
        };
        let out = match modal {
            Some(modal) => {
                progress(Progress::Discretised { states: size });
                modal.outputs(&z0, rows.as_ref(), samples, &mut |done| {
                    progress(Progress::Samples { done, total: samples })
                })
            }
            None => {
                let phi = self.transition(&aug, 1.0 / fs, speed, opts.method)?;
                progress(Progress::Discretised { states: size });
                stepped(&phi, &z0, rows.as_ref(), samples, &mut |done| {
                    progress(Progress::Samples { done, total: samples })
                })
            }
        };
        if !crate::linalg::all_finite(out.as_ref()) {
            return Err(RotorError::Numerical("time response: the state became non-finite".into()));
        }

        let column = |r: usize| out.col(r).iter().copied().collect::<Vec<f64>>();
        let mut rec = Recording {
            speed,
            sample_rate: fs,
            t: (0..samples).map(|k| k as f64 / fs).collect(),
            x: (0..n_nodes).map(|node| column(2 * node)).collect(),
            y: (0..n_nodes).map(|node| column(2 * node + 1)).collect(),
            forces: self
                .unbalance_forces(speed, 0.0)
                .into_iter()
                .map(|(node, _, _)| ForceTrace { node, x: Vec::with_capacity(samples), y: Vec::with_capacity(samples) })
                .collect(),
            channels: cfg
                .sensors
                .iter()
                .map(|s| Channel {
                    name: s.channel_name(),
                    sensor: *s,
                    measured: Vec::with_capacity(samples),
                    clean: Vec::with_capacity(samples),
                    noise_std: noise_std(s, fs),
                })
                .collect(),
        };
        let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
        for k in 0..samples {
            for (trace, (_, fx, fy)) in rec.forces.iter_mut().zip(self.unbalance_forces(speed, rec.t[k])) {
                trace.x.push(fx);
                trace.y.push(fy);
            }
            for (c, ch) in rec.channels.iter_mut().enumerate() {
                let value = out[(k, 2 * n_nodes + c)];
                let noise = if opts.noise && ch.noise_std > 0.0 {
                    let e: f64 = StandardNormal.sample(&mut rng);
                    e * ch.noise_std
                } else {
                    0.0
                };
                // A channel in volts: `offset + sensitivity · a`.
                let (offset, sens) = match ch.sensor.kind {
                    SensorKind::Acceleration(a) => a.sensitivity.map_or((0.0, 1.0), |s| (a.offset, s)),
                    SensorKind::Displacement { .. } => (0.0, 1.0),
                };
                ch.clean.push(offset + sens * value);
                ch.measured.push(offset + sens * value + noise);
            }
        }
        Ok(rec)
    }
}

/// `rows · Φᵏ z0` for `k < samples`, as a `samples × rows` matrix, one dense product a sample:
/// the path of a transition matrix without a modal form (and of the trapezoidal rule).
fn stepped(
    phi: &Mat<f64>,
    z0: &[f64],
    rows: MatRef<'_, f64>,
    samples: usize,
    progress: &mut dyn FnMut(usize),
) -> Mat<f64> {
    let size = z0.len();
    let mut z = Mat::<f64>::from_fn(size, 1, |i, _| z0[i]);
    let mut next = Mat::<f64>::zeros(size, 1);
    let mut out = Mat::<f64>::zeros(samples, rows.nrows());
    let report_every = (samples / 100).max(1);
    for k in 0..samples {
        let mut row = out.as_mut().subrows_mut(k, 1);
        faer::linalg::matmul::matmul(&mut row, Accum::Replace, z.transpose(), rows.transpose(), 1.0, Par::Seq);
        faer::linalg::matmul::matmul(&mut next, Accum::Replace, phi, &z, 1.0, Par::Seq);
        std::mem::swap(&mut z, &mut next);
        if (k + 1) % report_every == 0 || k + 1 == samples {
            progress(k + 1);
        }
    }
    out
}

/// Noise standard deviation per sample of a sensor, in its channel's unit.
fn noise_std(s: &SensorConfig, fs: f64) -> f64 {
    match s.kind {
        SensorKind::Displacement { noise_std } => noise_std,
        SensorKind::Acceleration(a) => a.noise_std(fs) * a.sensitivity.map_or(1.0, f64::abs),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::systems::rotor::RotorConfig;

    /// The largest difference between two `samples × rows` outputs, relative to the largest output.
    fn worst(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
        let peak = a.col_iter().flat_map(|c| c.iter().copied()).fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = (a - b).col_iter().flat_map(|c| c.iter().copied()).fold(0.0f64, |m, v| m.max(v.abs()));
        diff / peak
    }

    #[test]
    fn the_modal_free_response_equals_the_transition_matrixs() {
        // The paper rotor with accelerometers (their low-passes in the state), undamped, from
        // rest, 1 s at 1 kHz: every node's x and y and the clean channels, through the modal
        // form and through Φ = e^{FΔt} (balanced Padé), one dense product a sample.
        let text = include_str!("../../../configs/rotor_paper_accel.toml");
        let model = RotorModel::from_config(&RotorConfig::from_toml_str(text).unwrap()).unwrap();
        let (speed, dt, samples) = (model.config().operation.speed, 1e-3, 1000);
        let aug = model.augmented(speed, 1.0 / dt).unwrap();
        let nodes = 2 * model.n_nodes();
        let (rows, z0) = aug.recorded(model.n_nodes());
        let modal = ModalExponential::of(aug.f.as_ref(), dt).expect("the paper rotor has a modal form");
        let fast = modal.outputs(&z0, rows.as_ref(), samples, &mut |_| {});
        let phi = model.transition(&aug, dt, speed, Method::Exact).unwrap();
        let dense = stepped(&phi, &z0, rows.as_ref(), samples, &mut |_| {});
        // Both are exact to rounding, and part by a slow drift of phase (rounding in the slow
        // modes' frequencies, ~1e-14 of ‖F‖): 1.1e-8 of the peak displacement and 1.6e-7 of the
        // peak acceleration (the stiffer modes weigh more in it) after 1 s. On a stiff system
        // with a closed form, the modal form is as accurate as the transition matrix
        // (`linalg::free_response`'s tests).
        let split =
            |m: &Mat<f64>, from: usize, to: usize| Mat::<f64>::from_fn(samples, to - from, |k, r| m[(k, from + r)]);
        let (displacement, acceleration) = (
            worst(&split(&dense, 0, nodes), &split(&fast, 0, nodes)),
            worst(&split(&dense, nodes, rows.nrows()), &split(&fast, nodes, rows.nrows())),
        );
        eprintln!("modal against dense over 1 s: {displacement:.2e} of the peak displacement, {acceleration:.2e} of the peak acceleration");
        assert!(displacement < 5e-8 && acceleration < 5e-7, "{displacement:e}, {acceleration:e}");
        // A yardstick: the dense path against itself at a 4× finer Φ, every fourth sample.
        let phi4 = model.transition(&aug, dt / 4.0, speed, Method::Exact).unwrap();
        let fine = stepped(&phi4, &z0, rows.as_ref(), 4 * samples, &mut |_| {});
        let fine = Mat::<f64>::from_fn(samples, rows.nrows(), |k, r| fine[(4 * k, r)]);
        let yardstick = worst(&dense, &fine);
        eprintln!("dense at 1 ms against dense at 0.25 ms: {yardstick:.2e}");
        assert!(yardstick < 1e-9, "{yardstick:e}");
    }
}
