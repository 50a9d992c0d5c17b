//! The effect vocabulary every system's report uses: the kinds ([`EffectKind`], the README's
//! table), their extra fields ([`EffectDetail`]), how a system labels one ([`EffectLabel`]) and
//! an effect as it sits in a model ([`Applied`]: its fitted scalar and, for a change-point
//! effect, when it began).

use serde::Serialize;

/// The kinds of effect, one vocabulary for every system (the README's table gives each kind's
/// `location`, the unit of its `value` and its extra fields).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    /// A constant offset on a channel (channel unit; `drift` in unit/s where it drifts).
    SensorBias,
    /// A factor on a channel's declared scale.
    SensorScale,
    /// A pure delay of a channel, s.
    SensorDelay,
    /// A first-order lag of a channel, s (time constant).
    SensorLag,
    /// A force at an order of the running speed, N (`order`).
    HarmonicForce,
    /// A catch-all input at a node or channel, RMS in N or the channel's unit.
    UnknownInput,
    /// A factor on a component's declared parameter (`parameter`).
    Parameter,
    /// A mass added at a node, kg.
    PointMass,
    /// A mode the model lacks, Hz (`damping`).
    ExtraMode,
    /// A bearing defect: RMS of its impacts' vibration in the channel's unit (`line`,
    /// `harmonics`, `band_hz`, `damping` of the resonance they ring).
    BearingDefect,
    /// An actuator's health factor after the onset (1 = healthy; `onset_s`).
    ActuatorHealth,
    /// A joint's radial clearance, m.
    Clearance,
}

impl EffectKind {
    /// The name in reports (`sensor_bias`, …).
    pub fn as_str(self) -> &'static str {
        match self {
            EffectKind::SensorBias => "sensor_bias",
            EffectKind::SensorScale => "sensor_scale",
            EffectKind::SensorDelay => "sensor_delay",
            EffectKind::SensorLag => "sensor_lag",
            EffectKind::HarmonicForce => "harmonic_force",
            EffectKind::UnknownInput => "unknown_input",
            EffectKind::Parameter => "parameter",
            EffectKind::PointMass => "point_mass",
            EffectKind::ExtraMode => "extra_mode",
            EffectKind::BearingDefect => "bearing_defect",
            EffectKind::ActuatorHealth => "actuator_health",
            EffectKind::Clearance => "clearance",
        }
    }
}

impl std::fmt::Display for EffectKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl PartialEq<&str> for EffectKind {
    fn eq(&self, other: &&str) -> bool {
        self.as_str() == *other
    }
}

/// The extra fields of an effect, each used by the kinds the README's table names.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct EffectDetail {
    /// Order of the running speed (harmonic forces, bearing lines).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<f64>,
    /// The parameter (`mass`, `young`, `kxx`, …) of a `parameter` effect.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parameter: Option<String>,
    /// The defect line (`BPFO`, `BPFI`, `BSF`, `FTF`) of a `bearing_defect`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub line: Option<String>,
    /// Harmonics of the defect line found in the envelope spectrum (1 = the line itself).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub harmonics: Option<Vec<u32>>,
    /// The band the defect's impulses ring in, Hz.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub band_hz: Option<[f64; 2]>,
    /// Drift of a bias, in the channel's unit per second.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drift: Option<f64>,
    /// Damping ratio of an extra mode.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// When the effect began, s on the data's `t` (change-point effects, fitted by the engine).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub onset_s: Option<f64>,
    /// The test that named the effect when its model was not fitted (its Δ log-likelihood
    /// and BIC cost are then 0): a bearing defect named by its family of envelope lines.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub named_by: Option<String>,
    /// Why the final model does not carry the effect although it was named (its vibration was
    /// not taken out, say): the report's "after" then does not show it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_modelled: Option<String>,
}

/// How an effect is written in the report.
#[derive(Debug, Clone, PartialEq)]
pub struct EffectLabel {
    /// Kind.
    pub kind: EffectKind,
    /// Channel name, `node N`, or a component.
    pub location: String,
    /// The kind's extra fields.
    pub detail: EffectDetail,
    /// Unit of the reported value (`1` for a factor).
    pub unit: String,
}

/// An effect in a model: what and where, its fitted scalar, and when it began.
///
/// ```
/// use edgekf_sim::residual_loop::Applied;
/// let bias = Applied { onset_s: Some(2.0), ..Applied::new("bias", 0.0) };
/// let t = [0.0, 1.0, 2.0, 3.0];
/// assert!(!bias.active_at(1.0) && bias.active_at(2.0));
/// assert_eq!(bias.first_sample(&t), 2);
/// assert_eq!(Applied::new("bias", 0.0).first_sample(&t), 0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Applied<E> {
    /// What and where (the system's own type).
    pub effect: E,
    /// The scalar the engine fitted (0 when the effect has none).
    pub theta: f64,
    /// The time of the first sample with the effect, s on the data's `t` (`None`: present from
    /// the start). Set only on effects the system says may start mid-run.
    pub onset_s: Option<f64>,
}

impl<E> Applied<E> {
    /// `effect` with scalar `theta`, present from the start.
    pub fn new(effect: E, theta: f64) -> Self {
        Self { effect, theta, onset_s: None }
    }

    /// Whether the effect acts at time `t`.
    pub fn active_at(&self, t: f64) -> bool {
        self.onset_s.is_none_or(|o| t >= o)
    }

    /// The index of the first sample of `t` at which the effect acts.
    pub fn first_sample(&self, t: &[f64]) -> usize {
        self.onset_s.map_or(0, |o| t.partition_point(|&s| s < o))
    }
}
