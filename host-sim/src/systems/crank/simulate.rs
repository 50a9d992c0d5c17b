//! A simulation run: options in, a recording out (sensor channel, truth, final state, work).

use super::config::CrankConfig;
use super::error::CrankError;
use super::integrate::{self, IntegrationStats, Integrator};
use super::mechanism::{Dynamics, Mechanism};
use super::state::State;
use super::Joint;
use crate::io::data::{self, DataError, DataFile};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use std::path::Path;

/// What to simulate and how.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimOptions {
    /// Length of the run, s. The recording has `round(duration · sample_rate)` samples.
    pub duration: f64,
    /// Sample rate of the output, Hz.
    pub sample_rate: f64,
    /// Standard deviation of the white noise added to the measured crank angular
    /// acceleration, rad/s² (0: the measurement is the truth).
    pub noise_std: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// Integrator.
    pub integrator: Integrator,
    /// Start from this state instead of the release state (its `t` is kept: sample times are
    /// `initial.t + k / sample_rate`).
    pub initial: Option<State>,
}

impl SimOptions {
    /// The options a configuration gives for a run of `duration` s (seed 1, release state).
    pub fn from_config(config: &CrankConfig, duration: f64) -> Self {
        Self {
            duration,
            sample_rate: config.sensor.sample_rate,
            noise_std: config.sensor.noise_std,
            seed: 1,
            integrator: Integrator::from_config(&config.integrator),
            initial: None,
        }
    }

    /// Number of output samples.
    pub fn samples(&self) -> usize {
        let n = (self.duration * self.sample_rate).round();
        if (0.0..1e12).contains(&n) {
            n as usize
        } else {
            0
        }
    }

    fn validate(&self) -> Result<(), CrankError> {
        if !(self.sample_rate.is_finite() && self.sample_rate > 0.0) {
            return Err(CrankError::Options(format!("sample rate {} Hz must be positive", self.sample_rate)));
        }
        if !(self.duration.is_finite() && self.duration > 0.0) || self.samples() == 0 {
            return Err(CrankError::Options(format!(
                "duration {} s must be positive and hold at least one sample at {} Hz",
                self.duration, self.sample_rate
            )));
        }
        if !(self.noise_std.is_finite() && self.noise_std >= 0.0) {
            return Err(CrankError::Options(format!("noise std {} must be non-negative", self.noise_std)));
        }
        self.integrator.validate()
    }
}

/// One simulated run, column by column (every vector has one entry per sample).
#[derive(Debug, Clone, PartialEq)]
pub struct CrankRecording {
    /// Sample times, s.
    pub t: Vec<f64>,
    /// Measured crank angular acceleration (truth + noise), rad/s².
    pub crank_alpha: Vec<f64>,
    /// True crank angular acceleration, rad/s².
    pub truth_crank_alpha: Vec<f64>,
    /// True crank angle, rad (from the guide, counter-clockwise, unwrapped).
    pub truth_crank_angle: Vec<f64>,
    /// True crank angular velocity, rad/s.
    pub truth_crank_rate: Vec<f64>,
    /// True slider position along the guide, m.
    pub truth_slider_x: Vec<f64>,
    /// Force carried by joints A, B, C, N: the contact force at a clearance joint, the pin
    /// reaction at an ideal one (see [`Mechanism::joint_forces`]).
    pub truth_contact_force: [Vec<f64>; 3],
    /// Journal eccentricity `|e|` at joints A, B, C, m (0 at ideal joints; above the clearance
    /// while in contact).
    pub truth_eccentricity: [Vec<f64>; 3],
    /// Mechanical energy (kinetic + gravity + contact elastic), J.
    pub truth_energy: Vec<f64>,
    /// Energy dissipated by contact damping since the start of this run, J.
    pub truth_dissipated: Vec<f64>,
    /// The clearances simulated (m; `None`: ideal joint).
    pub clearances: [Option<f64>; 3],
    /// The state at the end, `t = t₀ + samples / sample_rate`: start the next window from it.
    pub final_state: State,
    /// Work done.
    pub stats: IntegrationStats,
    /// Largest constraint residual over the samples, m.
    pub max_constraint_residual: f64,
}

impl CrankRecording {
    /// The CSV columns after `t`, in order.
    pub const CHANNELS: [&'static str; 17] = [
        "crank_alpha",
        "truth_crank_alpha",
        "truth_crank_angle",
        "truth_crank_rate",
        "truth_slider_x",
        "truth_contact_force_A",
        "truth_contact_force_B",
        "truth_contact_force_C",
        "truth_eccentricity_A",
        "truth_eccentricity_B",
        "truth_eccentricity_C",
        "truth_clearance_A",
        "truth_clearance_B",
        "truth_clearance_C",
        "truth_energy",
        "truth_dissipated",
        "truth_balance",
    ];

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// `truth_energy + truth_dissipated`: constant for an exact integration, J.
    pub fn balance(&self) -> Vec<f64> {
        self.truth_energy.iter().zip(&self.truth_dissipated).map(|(e, d)| e + d).collect()
    }

    /// Largest `|E + D − (E₀ + D₀)|` over the run, J: how well energy is accounted for.
    pub fn energy_balance_error(&self) -> f64 {
        let b = self.balance();
        let b0 = b.first().copied().unwrap_or(0.0);
        b.iter().map(|v| (v - b0).abs()).fold(0.0, f64::max)
    }

    /// Largest climb of the mechanical energy above the lowest value it had reached before,
    /// `max_k (E_k − min_{i ≤ k} E_i)`, J. With restitution below 1 and no drive the energy can
    /// only stay or fall, so any climb is numerical error.
    pub fn energy_rise(&self) -> f64 {
        let mut low = f64::INFINITY;
        let mut rise: f64 = 0.0;
        for &e in &self.truth_energy {
            low = low.min(e);
            rise = rise.max(e - low);
        }
        rise
    }

    /// Largest force carried by `joint` over the run, N.
    pub fn peak_force(&self, joint: Joint) -> f64 {
        self.truth_contact_force[joint.index()].iter().copied().fold(0.0, f64::max)
    }

    /// The recording as a [`DataFile`] with the columns of [`CrankRecording::CHANNELS`].
    pub fn to_data_file(&self) -> DataFile {
        let n = self.len();
        let clearance = |j: Joint| vec![self.clearances[j.index()].unwrap_or(0.0); n];
        let columns = vec![
            self.crank_alpha.clone(),
            self.truth_crank_alpha.clone(),
            self.truth_crank_angle.clone(),
            self.truth_crank_rate.clone(),
            self.truth_slider_x.clone(),
            self.truth_contact_force[0].clone(),
            self.truth_contact_force[1].clone(),
            self.truth_contact_force[2].clone(),
            self.truth_eccentricity[0].clone(),
            self.truth_eccentricity[1].clone(),
            self.truth_eccentricity[2].clone(),
            clearance(Joint::A),
            clearance(Joint::B),
            clearance(Joint::C),
            self.truth_energy.clone(),
            self.truth_dissipated.clone(),
            self.balance(),
        ];
        DataFile {
            sha256: None,
            names: Self::CHANNELS.iter().map(|s| s.to_string()).collect(),
            t: self.t.clone(),
            columns,
        }
    }

    /// Writes the recording as a data CSV (see [`crate::io::data`]).
    pub fn write_csv(&self, path: &Path) -> Result<(), DataError> {
        let file = self.to_data_file();
        let cols: Vec<&[f64]> = file.columns.iter().map(Vec::as_slice).collect();
        data::write(path, &Self::CHANNELS, &file.t, &cols)
    }
}

impl Mechanism {
    /// Simulates the mechanism (see [`SimOptions`]).
    ///
    /// ```
    /// use edgekf_sim::systems::crank::{CrankConfig, Mechanism, SimOptions};
    /// let cfg = CrankConfig::default();
    /// let m = Mechanism::new(&cfg, [Some(0.25e-3), None, None]).unwrap();
    /// let rec = m.simulate(&SimOptions::from_config(&cfg, 0.02)).unwrap();
    /// assert_eq!(rec.len(), 200); // 10 kHz
    /// assert_eq!(rec.stats.steps, 2000); // symplectic Euler at 1e-5 s
    /// // The journal falls across the clearance and hits the bearing within 20 ms.
    /// assert!(rec.stats.impacts[0] >= 1);
    /// assert!(rec.max_constraint_residual < 1e-15);
    /// // Continue from where it stopped.
    /// let next = SimOptions { initial: Some(rec.final_state), ..SimOptions::from_config(&cfg, 0.02) };
    /// assert_eq!(m.simulate(&next).unwrap().t[0], 0.02);
    /// ```
    pub fn simulate(&self, opts: &SimOptions) -> Result<CrankRecording, CrankError> {
        self.simulate_with_progress(opts, &mut |_| {})
    }

    /// Like [`Mechanism::simulate`], calling `progress(fraction done)` about every 1 % of the
    /// samples.
    pub fn simulate_with_progress(
        &self,
        opts: &SimOptions,
        progress: &mut dyn FnMut(f64),
    ) -> Result<CrankRecording, CrankError> {
        opts.validate()?;
        let n = opts.samples();
        let mut state = opts.initial.unwrap_or_else(|| self.release_state());
        let mut rec = CrankRecording {
            t: Vec::with_capacity(n),
            crank_alpha: Vec::with_capacity(n),
            truth_crank_alpha: Vec::with_capacity(n),
            truth_crank_angle: Vec::with_capacity(n),
            truth_crank_rate: Vec::with_capacity(n),
            truth_slider_x: Vec::with_capacity(n),
            truth_contact_force: std::array::from_fn(|_| Vec::with_capacity(n)),
            truth_eccentricity: std::array::from_fn(|_| Vec::with_capacity(n)),
            truth_energy: Vec::with_capacity(n),
            truth_dissipated: Vec::with_capacity(n),
            clearances: self.clearances(),
            final_state: state,
            stats: IntegrationStats::default(),
            max_constraint_residual: 0.0,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
        let every = (n / 100).max(1);
        let mut sink = |s: &State, d: &Dynamics| {
            let alpha = d.crank_alpha();
            let noise: f64 =
                if opts.noise_std > 0.0 { opts.noise_std * rng.sample::<f64, _>(StandardNormal) } else { 0.0 };
            rec.t.push(s.t);
            rec.crank_alpha.push(alpha + noise);
            rec.truth_crank_alpha.push(alpha);
            rec.truth_crank_angle.push(s.crank_angle());
            rec.truth_crank_rate.push(s.crank_rate());
            rec.truth_slider_x.push(self.slider_position(s));
            let forces = self.joint_forces(s, d);
            for joint in Joint::ALL {
                let j = joint.index();
                let f = match self.clearance(joint) {
                    Some(_) => d.contact[j].total,
                    None => forces[j][0].hypot(forces[j][1]),
                };
                rec.truth_contact_force[j].push(f);
                let [x, y] = s.eccentricity(joint);
                rec.truth_eccentricity[j].push(x.hypot(y));
            }
            rec.truth_energy.push(self.energy(s).total());
            rec.truth_dissipated.push(s.dissipated);
            rec.max_constraint_residual = rec.max_constraint_residual.max(self.constraint_residual(s));
            let k = rec.t.len();
            if k % every == 0 {
                progress(k as f64 / n as f64);
            }
        };
        let period = 1.0 / opts.sample_rate;
        rec.stats = integrate::run(self, &mut state, period, n, &opts.integrator, &mut sink)?;
        rec.final_state = state;
        Ok(rec)
    }
}
