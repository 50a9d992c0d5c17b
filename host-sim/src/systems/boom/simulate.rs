//! A run of the reference boom into a data file: the finite-element boom ([`beam`]) integrated
//! by Newmark's average acceleration at a fifth of the sample interval, the luffing drive
//! ([`runs`]), the true sensors ([`sensors`]).
//!
//! Where the numbers come from: the boom's constants from the configuration; the equation of
//! motion `M q̈ + C q̇ + (K + g sin φ K_G) q = −r φ̈ − g cos φ m_g` in the frame the turntable turns
//! (the deflection from the rigid boom's axis), with `C` Rayleigh damping refitted to the
//! configured ζ₁, ζ₂ whenever the length or the angle has moved (by 5 cm or 0.02 rad). The
//! matrices are rebuilt at every step as the boom telescopes (quasi-stationary in the length:
//! the mesh stretches with l(t)). Left out, each under 1 % of the inertia terms at these rates:
//! the sliding sections' Coriolis load (∝ l̇ φ̇), the rotation's softening (∝ φ̇² w) and its
//! centrifugal tension.
//!
//! With `[sim.lateral]` the boom also bends sideways, out of the luffing plane: the same
//! elements with the sideways EI, the same damping fit, driven by a gust load on every
//! element's mass and by nothing of the luffing. Only a gyro whose axis leans toward it sees
//! it; the estimators know nothing of it (a mode nobody declared).
//!
//! [`beam`]: super::beam
//! [`runs`]: super::runs
//! [`sensors`]: super::sensors

use super::band::BandCholesky;
use super::beam::{assemble, BeamMatrices};
use super::config::BoomConfig;
use super::modal::{frequencies, rayleigh, stiffness};
use super::runs::{Luffing, Scenario};
use super::sensors::{Gyro, GyroModel, Inclinometer, InclinometerModel};
use crate::io::data::DataFile;
use anyhow::{anyhow, bail, Result};
use nalgebra::{DMatrix, DVector};
use rand::Rng;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// Integration steps per sample.
pub const SUBSTEPS: usize = 5;

/// The input columns, in file order.
pub const MEASURED: [&str; 4] = ["gyro_rate", "incl_angle", "boom_length", "luff_rate_cmd"];
/// The truth columns, in file order.
pub const TRUTH: [&str; 6] = [
    "truth_tip_angle",
    "truth_tip_deflection",
    "truth_tip_vibration",
    "truth_root_angle",
    "truth_root_rate",
    "truth_gyro_bias",
];

/// What to simulate: the boom's run, its length and the noise's seed.
pub type SimOptions = crate::systems::common::SimOptions<Scenario>;

/// A simulated recording: time, the [`MEASURED`] then [`TRUTH`] columns.
#[derive(Debug, Clone, PartialEq)]
pub struct BoomRecording {
    /// Sample times from 0, s.
    pub t: Vec<f64>,
    /// The columns, in [`MEASURED`] then [`TRUTH`] order.
    pub columns: Vec<Vec<f64>>,
}

impl BoomRecording {
    /// Column names after `t`.
    pub fn names() -> Vec<&'static str> {
        MEASURED.iter().chain(&TRUTH).copied().collect()
    }

    /// The column `name`.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        crate::systems::common::column_of(&Self::names(), &self.columns, name)
    }

    /// As a data file (what a reader of the CSV would get).
    pub fn to_data_file(&self) -> DataFile {
        crate::systems::common::data_file(&Self::names(), &self.t, &self.columns)
    }

    /// The CSV text.
    pub fn to_csv(&self, path: &std::path::Path) -> Result<String, crate::io::data::DataError> {
        let cols: Vec<&[f64]> = self.columns.iter().map(|c| c.as_slice()).collect();
        crate::io::data::to_csv_string(path, &Self::names(), &self.t, &cols)
    }
}

/// The boom at one length with its damping: what each step needs.
struct Stage {
    beam: BeamMatrices,
    /// Rayleigh coefficients and the length and angle they were fitted at.
    damping: (f64, f64, f64, f64),
}

impl Stage {
    fn new(config: &BoomConfig, length: f64, angle: f64) -> Result<Self> {
        let beam = assemble(config, length);
        let damping = fit_damping(config, &beam, angle)?;
        Ok(Self { beam, damping })
    }

    /// Follows the boom to `length` and `angle`: the matrices rebuilt when it telescopes, the
    /// damping refitted when it has moved by 5 cm or 0.02 rad since the last fit.
    fn follow(&mut self, config: &BoomConfig, length: f64, angle: f64) -> Result<()> {
        let (_, _, l_fit, phi_fit) = self.damping;
        if (length - self.beam.length).abs() > 1e-12 {
            self.beam = assemble(config, length);
        }
        if (length - l_fit).abs() > 0.05 || (angle - phi_fit).abs() > 0.02 {
            self.damping = fit_damping(config, &self.beam, angle)?;
        }
        Ok(())
    }
}

/// Displacement, velocity and acceleration of the elements' DOFs.
struct Motion {
    q: DVector<f64>,
    qd: DVector<f64>,
    qdd: DVector<f64>,
}

impl Motion {
    fn at_rest(q: DVector<f64>) -> Self {
        let n = q.len();
        Self { q, qd: DVector::zeros(n), qdd: DVector::zeros(n) }
    }

    /// One step of Newmark's average acceleration over `dt` under the load `f`, at stiffness
    /// `k_tot`; `t1` names the step in an error.
    fn step(&mut self, stage: &Stage, k_tot: &DMatrix<f64>, f: DVector<f64>, dt: f64, t1: f64) -> Result<()> {
        let (a0, a1, a2) = (4.0 / (dt * dt), 2.0 / dt, 4.0 / dt);
        let (b, (ra, rb)) = (&stage.beam, (stage.damping.0, stage.damping.1));
        // C = ra M + rb K, so K_eff = K + a0 M + a1 C and C v = ra M v + rb K v.
        let k_eff = k_tot * (1.0 + a1 * rb) + &b.m * (a0 + a1 * ra);
        let cv = &self.q * a1 + &self.qd;
        let rhs = f + &b.m * (&self.q * a0 + &self.qd * a2 + &self.qdd + &cv * ra) + k_tot * (cv * rb);
        let q1 = BandCholesky::new(&k_eff)
            .ok_or_else(|| anyhow!("the simulation failed at t = {t1:.3} s: the step's matrix is singular"))?
            .solve(&rhs);
        let qdd1 = (&q1 - &self.q) * a0 - &self.qd * a2 - &self.qdd;
        self.qd += (&self.qdd + &qdd1) * (0.5 * dt);
        self.q = q1;
        self.qdd = qdd1;
        Ok(())
    }
}

/// The sideways boom of `[sim.lateral]` and its gust.
struct Lateral {
    config: BoomConfig,
    stage: Stage,
    motion: Motion,
    /// The gust's load per unit mass, m/s².
    gust: f64,
    /// Its RMS and how far the gyro's axis leans.
    rms: f64,
    lean: f64,
}

/// The gust's correlation time, s.
const GUST_TIME: f64 = 1.0;

impl Lateral {
    fn new(config: &BoomConfig, length: f64, angle: f64) -> Result<Option<Self>> {
        let Some(l) = config.sim.lateral else { return Ok(None) };
        let mut sideways = config.clone();
        for s in &mut sideways.section {
            s.ei *= l.ei_factor;
        }
        let stage = Stage::new(&sideways, length, angle)?;
        let motion = Motion::at_rest(DVector::zeros(stage.beam.dofs()));
        Ok(Some(Self { config: sideways, stage, motion, gust: 0.0, rms: l.gust, lean: l.misalignment }))
    }

    /// One sub-step at the boom's new `length` and `angle`.
    fn step(&mut self, length: f64, angle: f64, dt: f64, t1: f64, rng: &mut ChaCha8Rng) -> Result<()> {
        self.stage.follow(&self.config, length, angle)?;
        // Ornstein–Uhlenbeck: exact over dt, stationary RMS `rms`.
        let e = (-dt / GUST_TIME).exp();
        let white: f64 = rng.sample(StandardNormal);
        self.gust = e * self.gust + self.rms * (1.0 - e * e).sqrt() * white;
        let b = &self.stage.beam;
        let k_tot = stiffness(b, self.config.boom.gravity, angle);
        let f = &b.gm * self.gust;
        self.motion.step(&self.stage, &k_tot, f, dt, t1)
    }

    /// The tip's sideways slope rate, rad/s.
    fn tip_rate(&self) -> f64 {
        self.motion.qd[self.stage.beam.tip() + 1]
    }
}

fn fit_damping(config: &BoomConfig, beam: &BeamMatrices, angle: f64) -> Result<(f64, f64, f64, f64)> {
    let w = frequencies(beam, config.boom.gravity, angle)?;
    let (a, b) = rayleigh([w[0], w[1]], config.damping.zeta);
    Ok((a, b, beam.length, angle))
}

/// The static deflection at the stage's length and `angle`: gravity's sag.
fn sag(config: &BoomConfig, beam: &BeamMatrices, angle: f64) -> Result<DVector<f64>> {
    let g = config.boom.gravity;
    let k = stiffness(beam, g, angle);
    let chol = BandCholesky::new(&k).ok_or_else(|| anyhow!("the boom buckles at {:.2} m", beam.length))?;
    Ok(chol.solve(&(&beam.gm * (-g * angle.cos()))))
}

/// Flies `options`' run of the boom of `config`; `progress` is called with the simulated time
/// every 10 s.
pub fn simulate(config: &BoomConfig, options: &SimOptions, progress: &mut dyn FnMut(f64)) -> Result<BoomRecording> {
    if !(options.duration.is_finite() && options.duration > 0.0 && options.duration <= 3600.0) {
        bail!("--duration {} must lie in (0, 3600] s", options.duration);
    }
    let rate = config.gyro.sample_rate;
    let dt_sample = 1.0 / rate;
    let dt = dt_sample / SUBSTEPS as f64;
    let samples = (options.duration * rate).round() as usize;
    let (g, runs, scenario) = (config.boom.gravity, &config.runs, options.scenario);
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut gyro = Gyro::new(GyroModel::of(config));
    let mut luff = Luffing::at_rest(runs.start_angle);
    let mut incl = Inclinometer::new(InclinometerModel::of(config), luff.angle, dt_sample);
    let mut stage = Stage::new(config, scenario.length(runs, 0.0), luff.angle)?;
    let mut lateral = Lateral::new(config, stage.beam.length, luff.angle)?;
    // Its own stream, so that the sensors' noise is the same with and without it.
    let mut wind = ChaCha8Rng::seed_from_u64(options.seed.wrapping_add(3_000_003));
    // At rest in the static equilibrium.
    let mut m = Motion::at_rest(sag(config, &stage.beam, luff.angle)?);
    let mut t_out = Vec::with_capacity(samples);
    let mut cols = vec![Vec::with_capacity(samples); MEASURED.len() + TRUTH.len()];
    let mut next_progress = 10.0;
    for k in 0..samples {
        let t = k as f64 * dt_sample;
        // Record the sample at t (the state as it is now), then integrate to the next.
        let tip = stage.beam.tip();
        let length = stage.beam.length;
        let (q, qd) = (&m.q, &m.qd);
        let rate_true = match &lateral {
            Some(side) => (luff.rate + qd[tip + 1]) * side.lean.cos() + side.tip_rate() * side.lean.sin(),
            None => luff.rate + qd[tip + 1],
        };
        let static_tip = sag(config, &stage.beam, luff.angle)?[tip];
        let command = scenario.command(runs, t);
        let row = [
            gyro.read(rate_true, t, &mut rng),
            incl.read(luff.angle, &mut rng),
            length,
            command,
            luff.angle + q[tip + 1],
            q[tip],
            q[tip] - static_tip,
            luff.angle,
            luff.rate,
            gyro.bias(t),
        ];
        if row.iter().any(|v| !v.is_finite()) {
            bail!("the simulation failed at t = {t:.3} s: a non-finite state");
        }
        t_out.push(t);
        for (c, v) in cols.iter_mut().zip(row) {
            c.push(v);
        }
        if t >= next_progress {
            progress(t);
            next_progress += 10.0;
        }
        for s in 0..SUBSTEPS {
            let t1 = t + (s + 1) as f64 * dt;
            luff.step(&config.drive, command, dt);
            let length1 = scenario.length(runs, t1);
            stage.follow(config, length1, luff.angle)?;
            let b = &stage.beam;
            let k_tot = stiffness(b, g, luff.angle);
            let f = &b.r * (-luff.accel) + &b.gm * (-g * luff.angle.cos());
            m.step(&stage, &k_tot, f, dt, t1)?;
            if let Some(side) = &mut lateral {
                side.step(length1, luff.angle, dt, t1, &mut wind)?;
            }
        }
    }
    Ok(BoomRecording { t: t_out, columns: cols })
}

/// A record of the gyro with the boom at rest (`static.csv`): the baseline the estimators
/// identify the gyro's noise and bias from; its own noise stream (`seed` + 1 000 003).
pub fn static_record(config: &BoomConfig, duration: f64, seed: u64) -> Result<(Vec<f64>, Vec<f64>)> {
    if !(duration.is_finite() && duration > 0.0 && duration <= 3600.0) {
        bail!("the static record's length {duration} must lie in (0, 3600] s");
    }
    let rate = config.gyro.sample_rate;
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_add(1_000_003));
    let mut gyro = Gyro::new(GyroModel::of(config));
    let n = (duration * rate).round() as usize;
    let t: Vec<f64> = (0..n).map(|k| k as f64 / rate).collect();
    let rate_col = t.iter().map(|&tk| gyro.read(0.0, tk, &mut rng)).collect();
    Ok((t, rate_col))
}

/// The inclinometer over the same rest as [`static_record`] (the root at the runs' start
/// angle; its own noise stream, `seed` + 2 000 003): the static record's `incl_angle`, from
/// which the estimators take the inclinometer's noise when `[inclinometer] noise` is absent.
pub fn static_inclinometer(config: &BoomConfig, duration: f64, seed: u64) -> Result<Vec<f64>> {
    if !(duration.is_finite() && duration > 0.0 && duration <= 3600.0) {
        bail!("the static record's length {duration} must lie in (0, 3600] s");
    }
    let rate = config.inclinometer.sample_rate;
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_add(2_000_003));
    let angle = config.runs.start_angle;
    let mut incl = Inclinometer::new(InclinometerModel::of(config), angle, 1.0 / rate);
    Ok((0..(duration * rate).round() as usize).map(|_| incl.read(angle, &mut rng)).collect())
}
