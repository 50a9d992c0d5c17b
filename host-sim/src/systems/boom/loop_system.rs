//! The boom as a system of the residual loop (`edgekf loop boom`): the model-based filter as
//! the configuration declares it (the shared `ModelEstimator`, in `f64`), read from the gyro
//! and the inclinometer, and a library of what the declaration may have wrong or left out:
//!
//! * `sensor_lag` on `incl_angle`: the inclinometer's first-order lag, 0 to `[bounds] lag` s;
//! * `sensor_bias` on `incl_angle`: an offset, ±0.05 rad;
//! * `sensor_scale` on `gyro_rate`: a factor 0.95–1.05 on the declared scale;
//! * `sensor_bias` on `gyro_rate` with `drift`: a steady drift of the gyro's bias beside the
//!   random walk the filter gives it, ±1e-3 rad/s per s;
//! * `parameter` of `boom`, `ei`: a factor 0.8–1.25 on every section's bending stiffness;
//! * `parameter` of `section N`, `ei`: a factor 0.5–1.5 on one section's (damage, or a
//!   section of another gauge): its mode shifts differ from a load's or the whole boom's;
//! * `parameter` of `tip`, `mass`: a factor 0.5–2.5 on the platform's mass (its load: the
//!   crew and their kit), its rotary inertia scaled with it;
//! * `extra_mode` at `gyro_rate`: a lightly damped mode the reduced boom lacks (its sideways
//!   bending seen by a gyro that leans toward it, say), proposed by a line in the gyro's
//!   innovations at none of the reduced boom's frequencies; its frequency is fitted within two
//!   bins of the line, in the filter's [`ExtraMode`] slot.
//!
//! The parameters are proposed load first, then the whole boom, then each section. Where the
//! data cannot tell a load from a stiffness (the gyro sees the first mode best, and each moves
//! it), the loop adds neither and lists each as not identifiable with the others as rivals: a
//! boom corrected in the wrong one estimates its tip worse than the declared boom does.
//!
//! Each is a setting of the filter fitted by maximum likelihood. A parameter re-reduces the
//! boom; only the extra mode uses states, the slot the filter keeps for it. The report's
//! `before` and `after` carry the paper's peak error (`peak_error_pct`) where the data has
//! `truth_tip_vibration`.

use super::config::BoomConfig;
use super::estimate::model_settings;
use super::peaks::peak_errors;
use super::simulate::MEASURED;
use crate::io::config_edit::{ConfigEdit, Op};
use crate::io::data::DataFile;
use crate::residual_loop::filter::Run;
use crate::residual_loop::optimize::ScalarRange;
use crate::residual_loop::signature::{ReferenceLines, SEGMENT};
use crate::residual_loop::{
    search, Applied, Channel, EffectDetail, EffectKind, EffectLabel, Fitting, LoopOptions, LoopReport, LoopSystem,
    RunSummary, SystemSection, Traces,
};
use crate::residual_loop::{Correction, Recording};
use anyhow::{anyhow, Context, Result};
use edgekf::systems::boom::{Ar2, ExtraMode, ModelEstimator, ModelSettings};

/// Seconds of the filter's start left out of the statistics (the bias and the AR noise settle).
const SETTLE_S: f64 = 5.0;
/// Log-likelihood per scalar reading an effect must gain beyond its BIC cost: what the reduced
/// boom leaves unexplained on data that matches its configuration (its third mode 1 % stiff,
/// the fourth left out). On seeds 11–20 of 60 s matched data the best next effect (a gyro
/// scale of about 1.001) gained at most 12.1 over 12 000 readings, 6e-4 a reading beyond its
/// cost; an undeclared 0.3 s inclinometer lag gains 1.1 a reading.
pub const MODEL_FLOOR: f64 = 2e-3;
/// The largest drift of the gyro's bias fitted, rad/s per s.
const MAX_DRIFT: f64 = 1e-3;
/// The largest inclinometer offset fitted, rad.
const MAX_OFFSET: f64 = 0.05;
/// An extra mode's damping ratio: not fitted (a line's width says little in a few minutes).
const EXTRA_ZETA: f64 = 0.02;
/// Lines proposed as extra modes in a round, strongest first.
const EXTRA_LINES: usize = 2;

/// What the boom's model may lack.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Effect {
    /// The inclinometer's first-order lag, s.
    InclinometerLag,
    /// An offset on the inclinometer, rad.
    InclinometerOffset,
    /// A factor on the gyro's declared scale.
    GyroScale,
    /// A drift of the gyro's bias, rad/s per s.
    GyroDrift,
    /// A factor on every section's EI.
    Stiffness,
    /// A factor on one section's EI (index from 0, as the configuration lists them).
    SectionStiffness(u8),
    /// A factor on the platform's mass and rotary inertia.
    PlatformMass,
    /// A mode the reduced boom lacks, seen by the gyro. Value: its frequency, Hz.
    ExtraMode {
        /// Frequency of the line that proposed it, mHz.
        seed_mhz: u32,
        /// Its rate's level: the gyro's innovation RMS when it was proposed, µrad/s.
        level_urad: u32,
    },
}

/// The boom, its data and the loop's options.
pub struct BoomSystem<'a> {
    config: BoomConfig,
    settings: ModelSettings,
    data: &'a DataFile,
    columns: [&'a [f64]; 4],
    channels: Vec<Channel>,
    rows: Vec<Channel>,
    options: LoopOptions,
    /// The reduced boom's frequencies (Hz) at the recording's middle length and first angle:
    /// lines there are the boom's own, not an extra mode's.
    naturals: Vec<f64>,
}

impl<'a> BoomSystem<'a> {
    /// The boom and filter of `config` on `data` (one timeline, the channels of `edgekf boom
    /// simulate`), with the gyro model `ar` and the inclinometer's noise `incl_noise` (rad)
    /// where the configuration gives none.
    pub fn new(
        config: &BoomConfig,
        data: &'a DataFile,
        ar: Ar2,
        incl_noise: f64,
        options: &LoopOptions,
    ) -> Result<Self> {
        let col = |n: &str| data.column(n).ok_or_else(|| anyhow!("the data has no `{n}` column"));
        let columns = [col(MEASURED[0])?, col(MEASURED[1])?, col(MEASURED[2])?, col(MEASURED[3])?];
        let settings = model_settings(config, ar, incl_noise)?;
        let finite = |c: &[f64]| c.iter().copied().filter(|v| v.is_finite()).collect::<Vec<_>>();
        let (lengths, angles) = (finite(columns[2]), finite(columns[1]));
        let naturals = match (lengths.get(lengths.len() / 2), angles.first()) {
            (Some(&l), Some(&a)) => settings
                .constants
                .reduce(l, a - settings.inclinometer.1)
                .map_or(Vec::new(), |r| r.modes.iter().map(|m| m.omega / std::f64::consts::TAU).collect()),
            _ => Vec::new(),
        };
        Ok(Self {
            config: config.clone(),
            settings,
            data,
            columns,
            channels: vec![Channel::new(MEASURED[0], "rad/s"), Channel::new(MEASURED[1], "rad")],
            rows: vec![Channel::new("tip_vibration", "m")],
            options: *options,
            naturals,
        })
    }

    /// The filter's settings with `effects` applied.
    fn settings_with(&self, effects: &[Applied<Effect>]) -> ModelSettings {
        let mut s = self.settings;
        for a in effects {
            let factor = a.theta.exp();
            match a.effect {
                // The lag's uncertainty stays the declared one: the fit compares lags, not how
                // far each is trusted.
                Effect::InclinometerLag => s.inclinometer.0 = a.theta.max(0.0),
                Effect::InclinometerOffset => s.inclinometer.1 += a.theta,
                Effect::GyroScale => s.gyro_scale *= factor,
                Effect::GyroDrift => s.bias_drift += a.theta,
                Effect::Stiffness => {
                    for section in s.constants.sections.iter_mut() {
                        section.ei *= factor;
                    }
                }
                Effect::SectionStiffness(i) => {
                    if let Some(section) = s.constants.sections[..s.constants.count].get_mut(usize::from(i)) {
                        section.ei *= factor;
                    }
                }
                Effect::PlatformMass => {
                    s.constants.tip_mass *= factor;
                    s.constants.tip_inertia *= factor;
                }
                Effect::ExtraMode { level_urad, .. } => {
                    s.extra_mode = Some(ExtraMode { hz: a.theta, zeta: EXTRA_ZETA, level: level_urad as f64 * 1e-6 });
                }
            }
        }
        s
    }

    /// One effect per section of the configuration: its EI.
    fn sections(&self) -> impl Iterator<Item = Effect> {
        (0..self.settings.constants.count.min(usize::from(u8::MAX))).map(|i| Effect::SectionStiffness(i as u8))
    }

    /// The innovation spectra's bin width, Hz (at the boom's rates the spectra use
    /// [`SEGMENT`]-sample segments).
    fn bin_width_hz(&self) -> f64 {
        1.0 / (self.settings.dt * SEGMENT as f64)
    }

    /// The data as the engine reads them: the tip vibration's truth where simulated.
    fn recording(&self) -> Recording<'_> {
        Recording::of(self.data, &self.channels, &self.rows, &["truth_tip_vibration"], 1.0 / self.settings.dt)
    }

    /// Each effect's scalar range and grid: factors within what a boom's settings can be off
    /// by, a lag up to `[bounds] lag`, an extra mode within two bins of its line.
    fn scalar(&self, e: &Effect) -> (ScalarRange, usize) {
        match e {
            Effect::InclinometerLag => (
                ScalarRange {
                    low: 0.0,
                    high: self.config.bounds.lag,
                    neutral: self.settings.inclinometer.0,
                    log: false,
                    tolerance: 1e-3,
                },
                6,
            ),
            Effect::InclinometerOffset => {
                (ScalarRange { low: -MAX_OFFSET, high: MAX_OFFSET, neutral: 0.0, log: false, tolerance: 1e-5 }, 5)
            }
            Effect::GyroScale => (ScalarRange::factor(0.95, 1.05, 1e-4), 5),
            Effect::Stiffness => (ScalarRange::factor(0.8, 1.25, 1e-4), 5),
            Effect::SectionStiffness(_) => (ScalarRange::factor(0.5, 1.5, 1e-4), 5),
            Effect::PlatformMass => (ScalarRange::factor(0.5, 2.5, 1e-4), 5),
            Effect::ExtraMode { seed_mhz, .. } => {
                let (f, w) = (*seed_mhz as f64 * 1e-3, 2.0 * self.bin_width_hz());
                (ScalarRange { low: (f - w).max(0.05), high: f + w, neutral: f, log: false, tolerance: 1e-3 }, 5)
            }
            Effect::GyroDrift => {
                (ScalarRange { low: -MAX_DRIFT, high: MAX_DRIFT, neutral: 0.0, log: false, tolerance: 1e-8 }, 5)
            }
        }
    }
}

impl LoopSystem for BoomSystem<'_> {
    type Effect = Effect;
    type Model = ();

    const NAME: &'static str = "boom";

    fn run(&self, effects: &[Applied<Effect>]) -> Result<((), Run)> {
        let settings = self.settings_with(effects);
        let [gyro, incl, length, command] = self.columns;
        let first = length.iter().copied().find(|l| l.is_finite() && *l > 0.0).context("no finite boom_length")?;
        let mut est = ModelEstimator::<f64>::new(&settings, first)
            .map_err(|e| anyhow!("the boom's filter cannot start: {e:?}"))?;
        let n = self.data.len();
        let mut run = Run {
            innovation: vec![vec![f64::NAN; n]; 2],
            variance: vec![vec![f64::NAN; n]; 2],
            nis: vec![f64::NAN; n],
            log_det_s: vec![f64::NAN; n],
            outputs: vec![vec![f64::NAN; n]],
            effect_states: Vec::new(),
            frozen_at: None,
            last: None,
        };
        for k in 0..n {
            let e = est.step(gyro[k], incl[k], length[k], command[k]);
            let mut log_det = 0.0;
            let mut used = false;
            for c in 0..2 {
                if e.variance[c].is_finite() && e.variance[c] > 0.0 {
                    run.innovation[c][k] = e.innovation[c];
                    run.variance[c][k] = e.variance[c];
                    log_det += e.variance[c].ln();
                    used = true;
                }
            }
            if used {
                run.nis[k] = e.nis;
                run.log_det_s[k] = log_det;
            }
            run.outputs[0][k] = e.vibration;
        }
        Ok(((), run))
    }

    fn summarise(&self, run: &Run) -> RunSummary {
        let rec = self.recording();
        let lines = ReferenceLines { naturals: self.naturals.clone(), ..ReferenceLines::default() };
        let mut o = self.options.signatures;
        o.settle = o.settle.max(SETTLE_S);
        let mut s = rec.summarise(run, &lines, &o);
        if let (Some(truth), Some(rate)) = (rec.truth[0], self.data.column("truth_root_rate")) {
            let p = peak_errors(&self.data.t, &run.outputs[0], truth, rate);
            if p.peaks > 0 {
                s.metrics.insert("peak_error_pct".into(), p.mean_pct);
            }
        }
        s
    }

    /// First what the signatures name: the inclinometer's lag and offset when its innovations
    /// are biased or coloured (a lag the filter lacks leaves them correlated with the luffing
    /// rate), the gyro's scale when its are; then, as the catch-all, the other sensors'
    /// settings.
    fn candidates(&self, s: &RunSummary, _: &Run, _: &(), effects: &[Applied<Effect>]) -> Vec<Vec<Effect>> {
        let o = &self.options.signatures;
        let m = s.channels.len().max(1) as f64;
        let off = |c: usize| s.channels.get(c).is_some_and(|c| c.z.abs() >= o.bias_z || c.whiteness_p < o.alpha / m);
        let mut named = Vec::new();
        if off(1) {
            named.extend([Effect::InclinometerLag, Effect::InclinometerOffset]);
        }
        if off(0) {
            // Likelier in service first: a load on the platform changes every job; the whole
            // boom's stiffness only when it was configured wrongly, one section's by damage.
            named.extend([Effect::GyroScale, Effect::GyroDrift, Effect::PlatformMass, Effect::Stiffness]);
            named.extend(self.sections());
        }
        // Lines in the gyro's innovations at none of the boom's frequencies, for the one slot.
        if !effects.iter().any(|a| matches!(a.effect, Effect::ExtraMode { .. })) {
            let level = s.innovation_rms.get(MEASURED[0]).copied().unwrap_or(0.0);
            let level_urad = (level * 1e6).round().clamp(1.0, u32::MAX as f64) as u32;
            let mut seeds: Vec<(f64, u32)> = Vec::new();
            for p in s.channels.first().map_or(&[][..], |c| c.peaks.as_slice()) {
                let mhz = (p.frequency_hz * 1e3).round() as u32;
                let near = |m: &(f64, u32)| (m.1 as f64 - mhz as f64).abs() * 1e-3 < 2.0 * s.bin_width_hz;
                if p.class == "unexplained" && !seeds.iter().any(near) {
                    seeds.push((p.prominence_db, mhz));
                }
            }
            seeds.sort_by(|a, b| b.0.total_cmp(&a.0));
            named.extend(
                seeds.iter().take(EXTRA_LINES).map(|&(_, seed_mhz)| Effect::ExtraMode { seed_mhz, level_urad }),
            );
        }
        let in_model = |e: &Effect| effects.iter().any(|a| a.effect == *e);
        named.retain(|e| !in_model(e));
        let mut catch_all = if s.consistent {
            Vec::new()
        } else {
            vec![
                Effect::InclinometerLag,
                Effect::InclinometerOffset,
                Effect::GyroScale,
                Effect::GyroDrift,
                Effect::PlatformMass,
                Effect::Stiffness,
            ]
        };
        if !s.consistent {
            catch_all.extend(self.sections());
        }
        catch_all.retain(|e| !in_model(e) && !named.contains(e));
        vec![named, catch_all]
    }

    fn describe(&self, e: &Effect) -> (EffectLabel, Fitting) {
        (self.label(e), self.fitting(e))
    }

    /// The configuration's component parameters (the boom's EI, each section's, the
    /// platform's mass) and its sensors' settings (the inclinometer's lag and offset, the
    /// gyro's scale and drift).
    fn declared(&self) -> Vec<Effect> {
        let mut declared = vec![Effect::Stiffness];
        declared.extend(self.sections());
        declared.extend([
            Effect::PlatformMass,
            Effect::InclinometerLag,
            Effect::InclinometerOffset,
            Effect::GyroScale,
            Effect::GyroDrift,
        ]);
        declared
    }

    /// The fitted lag (s) or offset (rad), or the factor.
    fn value(&self, _: &(), _: &Run, effect: &Applied<Effect>) -> f64 {
        match effect.effect {
            Effect::InclinometerLag | Effect::InclinometerOffset | Effect::GyroDrift | Effect::ExtraMode { .. } => {
                effect.theta
            }
            Effect::GyroScale | Effect::Stiffness | Effect::SectionStiffness(_) | Effect::PlatformMass => {
                effect.theta.exp()
            }
        }
    }

    /// The boom's sections and tip, and the sensors as declared to the estimator (`[gyro]`,
    /// `[inclinometer]`; `[sim.*]` are the simulator's).
    fn correction(&self, effect: &Applied<Effect>, value: f64) -> Correction {
        let scale = |path: &str| ConfigEdit::new(path, Op::Scale(value));
        match effect.effect {
            Effect::Stiffness => Correction::model([scale("section[*].ei")]),
            Effect::SectionStiffness(i) => Correction::model([scale(&format!("section[#{}].ei", i + 1))]),
            Effect::PlatformMass => Correction::model([scale("tip.mass"), scale("tip.rotary_inertia")]),
            Effect::InclinometerLag => {
                Correction::model([ConfigEdit::or_absent("inclinometer.lag", Op::Set(value), 0.0)])
            }
            Effect::InclinometerOffset => {
                Correction::model([ConfigEdit::or_absent("inclinometer.offset", Op::Add(value), 0.0)])
            }
            Effect::GyroScale => Correction::model([ConfigEdit::or_absent("gyro.scale", Op::Scale(value), 1.0)]),
            Effect::GyroDrift => {
                Correction::not_carried("the estimator's gyro has no declared bias drift (only the simulator's has)")
            }
            Effect::ExtraMode { .. } => {
                Correction::not_carried("the reduced boom has no key for a mode beyond its own")
            }
        }
    }

    fn traces(&self) -> Traces {
        self.recording().traces()
    }

    /// What the configuration declared of the sensors the effects act on.
    fn section(&self, _: &(), _: &Run) -> SystemSection {
        let s = &self.settings;
        let mut section = SystemSection::default();
        section.fields.insert(
            "declared".into(),
            serde_json::json!({
                "inclinometer_lag_s": s.inclinometer.0,
                "inclinometer_offset_rad": s.inclinometer.1,
                "gyro_scale": s.gyro_scale,
            }),
        );
        section.lines.push((
            "declared".into(),
            format!(
                "inclinometer lag {} s, offset {} rad; gyro scale {}",
                s.inclinometer.0, s.inclinometer.1, s.gyro_scale
            ),
        ));
        section
    }
}

impl BoomSystem<'_> {
    /// How the report names `e`.
    pub fn label(&self, e: &Effect) -> EffectLabel {
        let parameter = |p: &str| EffectDetail { parameter: Some(p.into()), ..EffectDetail::default() };
        let (kind, location, unit, detail) = match e {
            Effect::InclinometerLag => (EffectKind::SensorLag, MEASURED[1].into(), "s", EffectDetail::default()),
            Effect::InclinometerOffset => (EffectKind::SensorBias, MEASURED[1].into(), "rad", EffectDetail::default()),
            Effect::GyroScale => (EffectKind::SensorScale, MEASURED[0].into(), "1", EffectDetail::default()),
            // Its value is the drift (rad/s per s), beside the bias the filter tracks.
            Effect::GyroDrift => (EffectKind::SensorBias, MEASURED[0].into(), "rad/s/s", EffectDetail::default()),
            Effect::Stiffness => (EffectKind::Parameter, "boom".into(), "1", parameter("ei")),
            Effect::SectionStiffness(i) => (EffectKind::Parameter, format!("section {}", i + 1), "1", parameter("ei")),
            Effect::PlatformMass => (EffectKind::Parameter, "tip".into(), "1", parameter("mass")),
            Effect::ExtraMode { .. } => (
                EffectKind::ExtraMode,
                MEASURED[0].into(),
                "Hz",
                EffectDetail { damping: Some(EXTRA_ZETA), ..EffectDetail::default() },
            ),
        };
        EffectLabel { kind, location, detail, unit: unit.into() }
    }

    /// One parameter for a setting; an extra mode's frequency and its two states' start.
    pub fn fitting(&self, e: &Effect) -> Fitting {
        let parameters = match e {
            Effect::ExtraMode { .. } => 3,
            _ => 1,
        };
        let (range, grid) = self.scalar(e);
        Fitting::scalar(parameters, range, grid)
    }
}

/// Closes the loop on `data` (one timeline) with the boom of `config`, the gyro model `ar` and
/// the inclinometer's noise `incl_noise` (rad) where the configuration gives none.
pub fn close_loop(
    config: &BoomConfig,
    data: &DataFile,
    ar: Ar2,
    incl_noise: f64,
    options: &LoopOptions,
) -> Result<LoopReport> {
    let options = LoopOptions { gain_floor: options.gain_floor.max(MODEL_FLOOR), ..*options };
    search(&mut BoomSystem::new(config, data, ar, incl_noise, &options)?, &options)
}

/// Learns a [`LevelBaseline`](crate::residual_loop::levels::LevelBaseline) from a healthy
/// recording with the configured boom (`edgekf baseline boom`). A loop under it takes the
/// larger of [`MODEL_FLOOR`] and the baseline's floor.
pub fn learn_baseline(
    config: &BoomConfig,
    data: &DataFile,
    ar: Ar2,
    incl_noise: f64,
    condition: Option<String>,
    options: &LoopOptions,
) -> Result<crate::residual_loop::levels::LevelBaseline> {
    let mut sys = BoomSystem::new(config, data, ar, incl_noise, options)?;
    crate::residual_loop::levels::LevelBaseline::learn(&mut sys, condition, options)
}
