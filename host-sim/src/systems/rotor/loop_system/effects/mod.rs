//! The library of effects and the augmented continuous model built from a [`ReducedRotor`] by
//! composition.
//!
//! An effect is a small augmentation of the base model. Some add states the filter estimates
//! (a bias, a force), some add one scalar the search fits by maximum likelihood (a sensor's scale
//! or delay, a component parameter, a mode's frequency), some both. Each says which residual
//! signatures point to it ([`Effect::signature`]).
//!
//! * [`augment`](mod@augment): the augmented model, composed family by family: [`sensor`],
//!   [`force`], [`mode`]; [`parameter`]: the effects that change the configuration itself (a
//!   component parameter, a point mass). A bearing defect is named before the search, on the
//!   innovations' envelope ([`bearings`](super::bearings)), never inside the filter.

pub mod augment;
pub mod force;
pub mod mode;
pub mod parameter;
pub mod sensor;

pub use self::augment::{augment, force_columns, AugmentedModel};
pub use self::force::Flexibility;
pub use self::parameter::{apply_parameters, Parameter};
pub use crate::residual_loop::optimize::ScalarRange;
use crate::residual_loop::EffectKind;
use crate::systems::rotor::bearing_geometry::BearingLine;
use crate::systems::rotor::bounds::Bounds;
use crate::systems::rotor::estimate::ReducedRotor;
use crate::systems::rotor::RotorConfig;
use nalgebra::DMatrix;

/// The matrices of the model being built, grown to every effect's states.
pub(in crate::systems::rotor::loop_system) struct Parts {
    pub a: DMatrix<f64>,
    pub qc: DMatrix<f64>,
    pub p0: DMatrix<f64>,
    pub c: DMatrix<f64>,
    pub displacement: DMatrix<f64>,
}

impl Parts {
    /// `red`'s matrices with `ns` state columns (the new ones zero).
    pub(super) fn grown(red: &ReducedRotor, ns: usize) -> Self {
        let grow = |mat: &DMatrix<f64>, rows: usize| {
            let mut out = DMatrix::<f64>::zeros(rows, ns);
            out.view_mut((0, 0), (mat.nrows(), mat.ncols())).copy_from(mat);
            out
        };
        Self {
            a: grow(&red.a, ns),
            qc: grow(&red.qc, ns),
            p0: grow(&red.p0, ns),
            c: grow(&red.c, red.c.nrows()),
            displacement: grow(&red.displacement, red.displacement.nrows()),
        }
    }
}

/// One kind of model augmentation, at one place.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Effect {
    /// A constant offset on a channel: one slow random-walk state on that channel's output row.
    /// Value in the channel's unit (m for a probe).
    SensorBias {
        /// Channel index.
        channel: usize,
    },
    /// A channel reads `s ×` the true signal: its output row is scaled. Value: `s`.
    SensorScale {
        /// Channel index.
        channel: usize,
    },
    /// A channel reads the signal `τ` late: its output row becomes `C e^{−Aτ}` (exact for the
    /// noise-free dynamics, so the rotating phasors carry the phase lag). Value: `τ`, s.
    SensorDelay {
        /// Channel index.
        channel: usize,
    },
    /// A channel reads the signal through a first-order lag of time constant `τ` (a sensor's
    /// or its conditioning's low-pass the configuration does not declare): one state per
    /// effect, `ẏ = (C x − y) / τ`, read instead of `C x`. Value: `τ`, s.
    SensorLag {
        /// Channel index.
        channel: usize,
    },
    /// A force rotating forward at `order ×` the running speed at a node (misalignment at 2×,
    /// looseness at 3×…): two states rotating at `order·Ω` entering the modal equations through
    /// the node's mode-shape rows, with the static correction of the truncated modes. Value:
    /// amplitude, N.
    HarmonicForce {
        /// Node.
        node: usize,
        /// Order of the running speed.
        order: u32,
    },
    /// An unknown force at a node, `F_x`, `F_y` as fast random walks: the catch-all for an
    /// input the library has no structure for. Value: RMS magnitude, N.
    UnknownInput {
        /// Node.
        node: usize,
    },
    /// A declared component parameter is off by a factor. Value: the factor.
    Parameter(Parameter),
    /// A mass the configuration does not declare, at a node (a coupling half, a balancing
    /// weight, a sensor's mount, a crack's lost stiffness read as such): a `[[mass]]` entry
    /// without inertias, applied to the configuration like a parameter. Value: mass, kg.
    PointMass {
        /// Node.
        node: usize,
    },
    /// A lightly damped mode the model lacks (a housing or foundation resonance), seen on
    /// every channel with its own amplitude: two states per channel oscillating at the mode's
    /// frequency, driven by white noise. Value: frequency, Hz (fitted; `seed_mhz` is where the
    /// spectral peak was).
    ExtraMode {
        /// Frequency of the spectral peak that proposed it, mHz.
        seed_mhz: u32,
    },
    /// A defect of a rolling-element bearing: impacts at a defect line's rate ringing a
    /// housing resonance, found and fitted by the engine's first stage on the innovations'
    /// envelope ([`impacts`](crate::diagnostics::bearings::impacts)), never inside the rotor's filter. Value: RMS of the
    /// impacts' vibration, in the channel's unit.
    BearingDefect {
        /// Bearing index (configuration order).
        bearing: usize,
        /// The line.
        line: BearingLine,
        /// The line's order of the running speed, in thousandths (from the bearing geometry).
        order_milli: u32,
    },
}

impl Effect {
    /// The kind as written in the report.
    pub fn kind(&self) -> EffectKind {
        match self {
            Effect::SensorBias { .. } => EffectKind::SensorBias,
            Effect::SensorScale { .. } => EffectKind::SensorScale,
            Effect::SensorDelay { .. } => EffectKind::SensorDelay,
            Effect::SensorLag { .. } => EffectKind::SensorLag,
            Effect::HarmonicForce { .. } => EffectKind::HarmonicForce,
            Effect::UnknownInput { .. } => EffectKind::UnknownInput,
            Effect::Parameter(_) => EffectKind::Parameter,
            Effect::PointMass { .. } => EffectKind::PointMass,
            Effect::ExtraMode { .. } => EffectKind::ExtraMode,
            Effect::BearingDefect { .. } => EffectKind::BearingDefect,
        }
    }

    /// What in the innovations points to this kind (for the report and the docs).
    pub fn signature(&self) -> &'static str {
        match self {
            Effect::SensorBias { .. } => "a channel's innovation mean many standard errors from zero",
            Effect::SensorScale { .. } | Effect::SensorDelay { .. } | Effect::SensorLag { .. } => {
                "a 1x (or natural-frequency) line on one channel that the other channels do not share"
            }
            Effect::HarmonicForce { .. } => "a line at an integer order of the running speed",
            Effect::UnknownInput { .. } => "non-white innovations with no line or bias to name",
            Effect::Parameter(_) => {
                "lines at the natural frequencies (the free response rings elsewhere) or a 1x residual"
            }
            Effect::PointMass { .. } => {
                "a 1x residual or natural-frequency lines in the directions a mass at the node would give"
            }
            Effect::ExtraMode { .. } => "a line at neither an order nor a natural frequency of the model",
            Effect::BearingDefect { .. } => {
                "a bearing defect line (BPFO, BPFI, BSF, FTF) and its harmonics in the envelope of the most impulsive band"
            }
        }
    }

    /// Number of states the effect adds for a model with `channels` sensor channels.
    pub fn states(&self, channels: usize) -> usize {
        match self {
            Effect::SensorBias { .. } | Effect::SensorLag { .. } => 1,
            Effect::HarmonicForce { .. } | Effect::UnknownInput { .. } => 2,
            Effect::ExtraMode { .. } => 2 * channels,
            Effect::SensorScale { .. }
            | Effect::SensorDelay { .. }
            | Effect::Parameter(_)
            | Effect::PointMass { .. }
            | Effect::BearingDefect { .. } => 0,
        }
    }

    /// The scalar the search fits by maximum likelihood, if the effect has one, within what
    /// `bounds` allow at `sample_rate` Hz on a rotor of `mass_kg`: a parameter's or a sensor
    /// scale's factor within `1 ± bounds.parameter`, a delay from 0 (a sensor cannot read the
    /// future) to `bounds.delay`, a lag's time constant from a tenth of a sample (none) to
    /// `bounds.lag`, a point mass from a ten-thousandth of the rotor's (none) to `bounds.mass`.
    pub fn scalar(&self, sample_rate: f64, bounds: &Bounds, mass_kg: f64) -> Option<ScalarRange> {
        match *self {
            Effect::SensorScale { .. } | Effect::Parameter(_) => {
                let (low, high) = bounds.factor_range();
                Some(ScalarRange::factor(low, high, 1e-5))
            }
            Effect::SensorDelay { .. } => Some(ScalarRange {
                low: 0.0,
                high: bounds.delay_s(sample_rate),
                neutral: 0.0,
                log: false,
                tolerance: 1e-4 / sample_rate,
            }),
            Effect::SensorLag { .. } => {
                let none = (0.1 / sample_rate).ln();
                Some(ScalarRange { low: none, high: bounds.lag.ln(), neutral: none, log: true, tolerance: 1e-3 })
            }
            Effect::PointMass { .. } => {
                let none = (1e-4 * mass_kg).ln();
                let high = bounds.mass_kg(mass_kg).ln();
                Some(ScalarRange { low: none, high, neutral: none, log: true, tolerance: 1e-3 })
            }
            Effect::ExtraMode { seed_mhz } => {
                let f = seed_mhz as f64 * 1e-3;
                let w = 2.0 * sample_rate / 1024.0;
                Some(ScalarRange { low: (f - w).max(0.1), high: f + w, neutral: f, log: false, tolerance: 1e-3 })
            }
            _ => None,
        }
    }

    /// Free parameters the effect costs in the BIC: its states' steady values and its scalar.
    pub fn parameters(&self, channels: usize) -> usize {
        match self {
            Effect::SensorBias { .. } => 1,
            Effect::ExtraMode { .. } => 2 * channels + 1,
            Effect::SensorScale { .. }
            | Effect::SensorDelay { .. }
            | Effect::SensorLag { .. }
            | Effect::Parameter(_)
            | Effect::PointMass { .. } => 1,
            _ => self.states(channels),
        }
    }

    /// Where it acts, for the report: a channel name, `node N`, or a component.
    pub fn location(&self, channels: &[String], cfg: &RotorConfig) -> String {
        let channel = |c: usize| channels.get(c).cloned().unwrap_or_else(|| format!("#{c}"));
        match *self {
            Effect::SensorBias { channel: c }
            | Effect::SensorScale { channel: c }
            | Effect::SensorDelay { channel: c }
            | Effect::SensorLag { channel: c } => channel(c),
            Effect::HarmonicForce { node, .. } | Effect::UnknownInput { node } | Effect::PointMass { node } => {
                format!("node {node}")
            }
            Effect::Parameter(p) => p.component(cfg),
            Effect::ExtraMode { .. } => "all channels".to_string(),
            Effect::BearingDefect { bearing, .. } => {
                format!("bearing {}", cfg.bearings.get(bearing).map_or("?".into(), |b| b.node.to_string()))
            }
        }
    }

    /// Unit of the reported value (`1` for a factor).
    pub fn unit(&self) -> &'static str {
        match self {
            Effect::SensorBias { .. } => "m",
            Effect::SensorScale { .. } | Effect::Parameter(_) => "1",
            Effect::SensorDelay { .. } | Effect::SensorLag { .. } => "s",
            Effect::HarmonicForce { .. } | Effect::UnknownInput { .. } => "N",
            Effect::BearingDefect { .. } => "m/s^2",
            Effect::ExtraMode { .. } => "Hz",
            Effect::PointMass { .. } => "kg",
        }
    }

    /// Whether it changes the configuration (a parameter, a point mass): the rotor is then
    /// reduced anew with it ([`apply_parameters`]).
    pub fn changes_structure(&self) -> bool {
        matches!(self, Effect::Parameter(_) | Effect::PointMass { .. })
    }

    /// The order of the running speed it acts at, if any.
    pub fn order(&self) -> Option<f64> {
        match *self {
            Effect::HarmonicForce { order, .. } => Some(order as f64),
            Effect::BearingDefect { order_milli, .. } => Some(order_milli as f64 * 1e-3),
            _ => None,
        }
    }
}

/// Noise and priors of the effects' states.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EffectTuning {
    /// Random-walk density of a bias state, m²/s.
    pub bias_psd: f64,
    /// Prior standard deviation of a bias, m.
    pub bias_std: f64,
    /// Random-walk density of a harmonic force's (or bearing defect's) states, N²/s.
    pub force_psd: f64,
    /// Prior standard deviation of a harmonic force's states, N.
    pub force_std: f64,
    /// Random-walk density of an unknown input, N²/s (fast: it may follow anything).
    pub unknown_psd: f64,
    /// Damping ratio of an extra mode.
    pub mode_damping: f64,
    /// Stationary standard deviation of an extra mode's response, as a multiple of the
    /// channel's noise standard deviation.
    pub mode_std: f64,
}

impl Default for EffectTuning {
    fn default() -> Self {
        Self {
            bias_psd: 1e-16,
            bias_std: 1e-3,
            force_psd: 1e-3,
            force_std: 10.0,
            unknown_psd: 1e2,
            mode_damping: 0.01,
            mode_std: 10.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::systems::rotor::config::PointMassConfig;
    use crate::systems::rotor::estimate::{reduce, Tuning};
    use crate::systems::rotor::RotorModel;

    fn paper() -> RotorModel {
        let cfg =
            RotorConfig::from_toml_str(include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml")))
                .unwrap();
        RotorModel::from_config(&cfg).unwrap()
    }

    #[test]
    fn every_kind_builds_with_its_states() {
        let model = paper();
        let speed = model.config().operation.speed;
        let red = reduce(&model, speed, &Tuning::default()).unwrap();
        let flex = Flexibility::new(&model, speed);
        let kinds = [
            (Effect::SensorBias { channel: 1 }, 0.0),
            (Effect::SensorScale { channel: 2 }, 0.1f64.ln_1p()),
            (Effect::SensorDelay { channel: 0 }, 1e-3),
            (Effect::HarmonicForce { node: 12, order: 2 }, 0.0),
            (Effect::UnknownInput { node: 20 }, 0.0),
            (Effect::ExtraMode { seed_mhz: 55_000 }, 55.0),
        ];
        let m = augment(&red, &model, &flex, &kinds, &EffectTuning::default()).unwrap();
        let added: usize = kinds.iter().map(|(e, _)| e.states(4)).sum();
        assert_eq!(added, 1 + 2 + 2 + 8);
        assert_eq!(m.a.nrows(), red.states() + added);
        // The scale multiplies row 2 of the base model's C.
        let base = &red.c;
        for j in 0..red.states() {
            assert!((m.c[(2, j)] - 1.1 * base[(2, j)]).abs() <= 1e-12 * base[(2, j)].abs().max(1e-30));
        }
        // The delayed row differs from the base row; the others (but the bias column) do not.
        assert!((0..red.states()).any(|j| (m.c[(0, j)] - base[(0, j)]).abs() > 1e-3 * base[(0, j)].abs()));
        assert_eq!(m.c[(1, red.states())], 1.0);
        // The 2x force's states rotate at 2 Ω.
        let s = red.states() + 1;
        assert!((m.a[(s + 1, s)] - 2.0 * speed).abs() < 1e-12);
        // A bearing defect is the envelope stage's, never the filter's.
        let defect = [(Effect::BearingDefect { bearing: 0, line: BearingLine::Bpfo, order_milli: 3585 }, 0.0)];
        assert!(augment(&red, &model, &flex, &defect, &EffectTuning::default()).is_err());
    }

    /// On the accelerometer rotor, a 1× force added as an effect at disk node 12 must enter the
    /// model exactly as the reduction's own unbalance phasor there does: same modal input,
    /// displacement rows, low-pass inputs and sensor rows.
    #[test]
    fn a_force_effect_reaches_accelerometers_like_the_unbalance_does() {
        let cfg = RotorConfig::from_toml_str(include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/configs/rotor_paper_accel.toml"
        )))
        .unwrap();
        let model = RotorModel::from_config(&cfg).unwrap();
        let speed = cfg.operation.speed;
        let red = reduce(&model, speed, &Tuning::default()).unwrap();
        assert_eq!(red.accel_inputs.len(), 4);
        let flex = Flexibility::new(&model, speed);
        let e = [(Effect::HarmonicForce { node: 12, order: 1 }, 0.0)];
        let m = augment(&red, &model, &flex, &e, &EffectTuning::default()).unwrap();
        let r = red.frequencies_hz.len();
        let j = cfg.unbalances.iter().position(|u| u.node == 12).unwrap();
        let (base, new) = (2 * r + 2 * j, red.states());
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1e-300);
        for k in 0..2 {
            // Every row but the force states' own (their rotation is in their own rows).
            for i in (0..2 * r).chain(red.lowpass_start..red.states()) {
                assert!(
                    close(m.a[(i, base + k)], m.a[(i, new + k)]),
                    "A[{i}, {k}]: {} vs {}",
                    m.a[(i, base + k)],
                    m.a[(i, new + k)]
                );
            }
            for i in 0..m.displacement.nrows() {
                assert!(close(m.displacement[(i, base + k)], m.displacement[(i, new + k)]), "displacement row {i}");
            }
            for i in 0..4 {
                assert!(close(m.c[(i, base + k)], m.c[(i, new + k)]), "C[{i}]");
            }
        }
        // And it does reach the low-pass states.
        assert!((red.lowpass_start..red.states()).any(|y| m.a[(y, new)] != 0.0));
    }

    #[test]
    fn a_parameter_factor_changes_the_configuration() {
        let model = paper();
        let cfg = model.config();
        let e = [
            (Effect::Parameter(Parameter::DiskMass(0)), 1.1f64.ln()),
            (Effect::Parameter(Parameter::BearingKxx(1)), 0.5f64.ln()),
        ];
        let out = apply_parameters(cfg, &e).unwrap();
        assert!((out.disks[0].mass / cfg.disks[0].mass - 1.1).abs() < 1e-12);
        assert!((out.bearings[1].kxx / cfg.bearings[1].kxx - 0.5).abs() < 1e-12);
        assert_eq!(out.disks[1], cfg.disks[1]);
        assert_eq!(Parameter::BearingKxx(1).component(cfg), "bearing 33");
        assert_eq!(Parameter::DiskMass(0).component(cfg), "disk 12");
        assert!(Parameter::DiskMass(0).apply(&mut cfg.clone(), f64::NAN).is_err());
        // The paper rotor: 2 disk masses, Young, density, and kxx, kyy, cxx, cyy of both bearings.
        assert_eq!(Parameter::all(cfg).len(), 2 + 2 + 8);
    }

    #[test]
    fn a_point_mass_joins_the_configuration_within_its_bound() {
        let model = paper();
        let cfg = model.config();
        let e = [(Effect::PointMass { node: 18 }, 0.8f64.ln())];
        let out = apply_parameters(cfg, &e).unwrap();
        assert_eq!(out.masses.len(), cfg.masses.len() + 1);
        assert_eq!(*out.masses.last().unwrap(), PointMassConfig { node: 18, mass: 0.8, ip: 0.0, id: 0.0 });
        assert!(apply_parameters(cfg, &[(Effect::PointMass { node: 18 }, f64::INFINITY)]).is_err());
        // From a ten-thousandth of the rotor's mass (none) to 0.3 of it (the default bound).
        let mass = cfg.mass();
        let r = e[0].0.scalar(1000.0, &cfg.bounds, mass).unwrap();
        assert!((r.high.exp() - 0.3 * mass).abs() < 1e-12 && r.neutral == r.low && r.log);
        assert_eq!((e[0].0.location(&[], cfg), e[0].0.unit()), ("node 18".to_string(), "kg"));
        assert!(e[0].0.changes_structure());
    }

    /// A force's columns at a disk are the unbalance's there (the same modal input).
    #[test]
    fn force_columns_at_a_disk_are_the_unbalance_columns() {
        let model = paper();
        let speed = model.config().operation.speed;
        let red = reduce(&model, speed, &Tuning::default()).unwrap();
        let flex = Flexibility::new(&model, speed);
        let (b, d) = force_columns(&red, &model, &flex, 23, 1).unwrap();
        let r = red.frequencies_hz.len();
        let j = model.config().unbalances.iter().position(|u| u.node == 23).unwrap();
        for k in 0..2 {
            for i in 0..2 * r {
                assert!((b[(i, k)] - red.a[(i, 2 * r + 2 * j + k)]).abs() <= 1e-9 * b[(i, k)].abs().max(1e-12));
            }
        }
        assert_eq!((b.nrows(), d.nrows()), (red.states(), red.c.nrows()));
    }
}
