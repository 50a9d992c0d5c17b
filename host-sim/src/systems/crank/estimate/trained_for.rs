//! What a fast model was trained for, and whether a mechanism and a recording fit it.
//!
//! The fast estimator's laws are learned from simulations of one mechanism: its masses,
//! lengths, inertias, gravity, contact law and sensor rate are baked into them, while the
//! release angle and the journal radius were varied over a range. A model applied to another
//! mechanism, or to a recording at another rate, would answer without complaint and be wrong.
//! So the model stores [`TrainedFor`], and `edgekf crank estimate --method fast` refuses a
//! mechanism or a recording that does not fit it, naming what differs and how to train a
//! model that fits; a release angle, journal radius or noise level outside what the model saw
//! is a warning.

use crate::systems::crank::CrankConfig;
use serde::{Deserialize, Serialize};

/// Relative difference above which two mechanism constants are different.
const SAME: f64 = 1e-9;

/// The mechanism and sensor a fast model was trained for.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainedFor {
    /// Crank mass (kg), length (m), inertia (kg·m²).
    pub crank: [f64; 3],
    /// Rod mass, length, inertia.
    pub rod: [f64; 3],
    /// Slider mass, kg.
    pub slider_mass: f64,
    /// Gravity, m/s².
    pub gravity: f64,
    /// Contact restitution, Young's modulus (Pa), Poisson's ratio.
    pub contact: [f64; 3],
    /// Journal radius of A, B, C as configured, m (the training scaled them by `radius_factor`).
    pub journal_radius: [f64; 3],
    /// Range of the factor on the journal radii.
    pub radius_factor: [f64; 2],
    /// Range of the release angle, degrees.
    pub release_deg: [f64; 2],
    /// Sensor noise standard deviation, rad/s².
    pub noise_std: f64,
    /// Sample rate, Hz.
    pub sample_rate: f64,
}

impl TrainedFor {
    /// `config`'s mechanism and sensor, trained over release angles `release_deg` and journal
    /// radius factors `radius_factor`.
    pub fn new(config: &CrankConfig, release_deg: [f64; 2], radius_factor: [f64; 2]) -> Self {
        let bar = |b: &crate::systems::crank::config::BarConfig| [b.mass, b.length, b.inertia];
        let c = &config.contact;
        Self {
            crank: bar(&config.crank),
            rod: bar(&config.rod),
            slider_mass: config.slider.mass,
            gravity: config.world.gravity,
            contact: [c.restitution, c.young, c.poisson],
            journal_radius: [
                c.journal_radius_a.unwrap_or(c.journal_radius),
                c.journal_radius_b.unwrap_or(c.journal_radius),
                c.journal_radius_c.unwrap_or(c.journal_radius),
            ],
            radius_factor,
            release_deg,
            noise_std: config.sensor.noise_std,
            sample_rate: config.sensor.sample_rate,
        }
    }

    /// Checks `config` against the model: `Err` with every constant that differs, or `Ok` with
    /// warnings for what lies outside the ranges the model saw.
    ///
    /// ```
    /// use edgekf_sim::systems::crank::estimate::trained_for::TrainedFor;
    /// use edgekf_sim::systems::crank::CrankConfig;
    /// let paper = CrankConfig::default();
    /// let t = TrainedFor::new(&paper, [20.0, 40.0], [0.8, 1.2]);
    /// assert_eq!(t.check(&paper), Ok(vec![]));
    /// let mut heavier = paper;
    /// heavier.slider.mass = 0.2;
    /// assert!(t.check(&heavier).unwrap_err().contains("slider mass 0.2 (the model's: 0.14)"));
    /// let mut steep = paper;
    /// steep.release.crank_angle_deg = 60.0;
    /// assert_eq!(t.check(&steep).unwrap().len(), 1);
    /// ```
    pub fn check(&self, config: &CrankConfig) -> Result<Vec<String>, String> {
        let other = Self::new(config, self.release_deg, self.radius_factor);
        let names = [
            ("crank mass", self.crank[0], other.crank[0]),
            ("crank length", self.crank[1], other.crank[1]),
            ("crank inertia", self.crank[2], other.crank[2]),
            ("rod mass", self.rod[0], other.rod[0]),
            ("rod length", self.rod[1], other.rod[1]),
            ("rod inertia", self.rod[2], other.rod[2]),
            ("slider mass", self.slider_mass, other.slider_mass),
            ("gravity", self.gravity, other.gravity),
            ("restitution", self.contact[0], other.contact[0]),
            ("Young's modulus", self.contact[1], other.contact[1]),
            ("Poisson's ratio", self.contact[2], other.contact[2]),
            ("sample rate", self.sample_rate, other.sample_rate),
        ];
        let differ: Vec<String> = names
            .iter()
            .filter(|(_, a, b)| (a - b).abs() > SAME * a.abs().max(b.abs()))
            .map(|(n, a, b)| format!("{n} {b} (the model's: {a})"))
            .collect();
        if !differ.is_empty() {
            return Err(format!(
                "the fast model was trained for another mechanism: {}; train one for this configuration with `edgekf crank train --config C --out model.toml` and pass it with --model",
                differ.join(", ")
            ));
        }
        let mut warnings = Vec::new();
        let angle = config.release.crank_angle_deg;
        if angle < self.release_deg[0] || angle > self.release_deg[1] {
            warnings.push(format!(
                "release angle {angle}° is outside the {}–{}° the model was trained on",
                self.release_deg[0], self.release_deg[1]
            ));
        }
        for (j, (a, b)) in self.journal_radius.iter().zip(other.journal_radius).enumerate() {
            let f = b / a;
            if f < self.radius_factor[0] || f > self.radius_factor[1] {
                warnings.push(format!(
                    "journal radius at {} {b} m is ×{f:.2} the model's {a} m, outside its ×{}–{}",
                    ["A", "B", "C"][j],
                    self.radius_factor[0],
                    self.radius_factor[1]
                ));
            }
        }
        let noise = other.noise_std / self.noise_std;
        if !(0.5..=2.0).contains(&noise) {
            warnings.push(format!(
                "sensor noise {} rad/s² is ×{noise:.2} the model's {} rad/s²",
                other.noise_std, self.noise_std
            ));
        }
        Ok(warnings)
    }

    /// Checks a recording's sample rate against the model's.
    pub fn check_rate(&self, rate: f64) -> Result<(), String> {
        if (rate - self.sample_rate).abs() > 1e-6 * self.sample_rate {
            return Err(format!(
                "the recording is sampled at {rate:.1} Hz, the fast model at {:.1} Hz: resample the data or train a model at this rate (sensor.sample_rate in the configuration)",
                self.sample_rate
            ));
        }
        Ok(())
    }

    /// The table `[trained_for]` of a model file.
    pub fn to_toml(&self) -> String {
        let list = |v: &[f64]| format!("[{}]", v.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", "));
        format!(
            "\n# The mechanism and sensor the model was trained for (checked by `crank estimate`)\n[trained_for]\ncrank = {}\nrod = {}\nslider_mass = {:?}\ngravity = {:?}\ncontact = {}\njournal_radius = {}\nradius_factor = {}\nrelease_deg = {}\nnoise_std = {:?}\nsample_rate = {:?}\n",
            list(&self.crank),
            list(&self.rod),
            self.slider_mass,
            self.gravity,
            list(&self.contact),
            list(&self.journal_radius),
            list(&self.radius_factor),
            list(&self.release_deg),
            self.noise_std,
            self.sample_rate
        )
    }
}
