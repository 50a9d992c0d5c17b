//! What a loop run reports: [`LoopReport`] (`report.json`'s layout, [`SCHEMA_VERSION`]) and its
//! parts, the same for every system.

use super::correction::{Correction, EffectCorrection};
use super::filter::Run;
use super::signature::{Channel, RunSummary, Signature};
use super::vocabulary::{EffectDetail, EffectKind, EffectLabel};
use crate::io::config_edit::{ConfigEdit, Op};
use serde::Serialize;

/// The version of `report.json`'s layout: raised when a field changes meaning or goes away
/// (adding a field does not raise it).
pub const SCHEMA_VERSION: u32 = 2;

/// An effect the loop kept.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AddedEffect {
    /// The kind ([`EffectKind`]).
    pub kind: EffectKind,
    /// Channel name, `node N`, or a component (`disk 12`, `shaft`, `bearing 4`).
    pub location: String,
    /// Estimated size in SI units (a state's size, a force's amplitude, averaged over the
    /// second half of the stretch the effect acts on), or the factor on the declared value for
    /// `sensor_scale` and `parameter`.
    pub value: f64,
    /// Unit of `value` (`1` for a factor).
    pub unit: String,
    /// The kind's extra fields.
    #[serde(flatten)]
    pub detail: EffectDetail,
    /// Spectral lines (Hz) of the innovations that were there before this effect and are gone
    /// after it.
    pub explains: Vec<f64>,
    /// Gain in log-likelihood (0 for an effect named by a test of its own whose model was not
    /// fitted: [`EffectDetail::named_by`]).
    pub delta_log_likelihood: f64,
    /// Its cost: `½ p ln n`, plus a baseline's gain floor over the run.
    pub bic_penalty: f64,
    /// The 95 % interval of `value` from the profile likelihood of the effect's scalar in the
    /// final model (absent for an effect whose size is a state the filter estimates).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interval: Option<[f64; 2]>,
}

/// A candidate the loop fitted and refused.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Refused {
    /// The kind.
    pub kind: EffectKind,
    /// Where.
    pub location: String,
    /// The component parameter, for a `parameter` effect (`mass`, `kxx`, `x_uu`…).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parameter: Option<String>,
    /// The fitted value, as an added effect would report it, where the fit gave one.
    pub value: Option<f64>,
    /// Why it was refused (at a bound of its range, one half of the run only, no usable model).
    pub reason: String,
}

impl Refused {
    /// The refusal of the effect `label` names, with its fitted `value` if any.
    pub fn of(label: &EffectLabel, value: Option<f64>, reason: impl Into<String>) -> Self {
        Self {
            kind: label.kind,
            location: label.location.clone(),
            parameter: label.detail.parameter.clone(),
            value,
            reason: reason.into(),
        }
    }

    /// Whether it is about the same effect as `n` (kind, place and parameter).
    pub fn is_about(&self, n: &NotIdentifiable) -> bool {
        (self.kind, &self.location, &self.parameter) == (n.kind, &n.location, &n.parameter)
    }
}

/// Where a report came from, so that it can be traced and rerun.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Source {
    /// The data file.
    pub data: Option<String>,
    /// SHA-256 of the data file's bytes, hex.
    pub data_sha256: Option<String>,
    /// The configuration file.
    pub config: Option<String>,
    /// The healthy baseline the loop started from, if any.
    pub baseline: Option<String>,
    /// The command line.
    pub command: Option<String>,
    /// edgekf's version.
    pub version: String,
}

/// A system's own part of a report, beside the engine's fields (a running speed, say).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SystemSection {
    /// Fields written at the top level of `report.json`.
    #[serde(flatten)]
    pub fields: serde_json::Map<String, serde_json::Value>,
    /// The same for people: `(label, text)`, printed under the verdict and on the page.
    #[serde(skip)]
    pub lines: Vec<(String, String)>,
    /// The system's own figures for the page (the evidence behind a diagnosis of its own).
    #[serde(skip)]
    pub figures: Vec<SystemFigure>,
}

/// A system's figure on the report page.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SystemFigure {
    /// Inline SVG.
    pub svg: String,
    /// What it shows, in words.
    pub caption: String,
}

/// An effect (or location) the data cannot resolve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NotIdentifiable {
    /// Kind.
    pub kind: EffectKind,
    /// Location.
    pub location: String,
    /// The parameter, for `parameter`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parameter: Option<String>,
    /// The statistic behind the verdict (`max_delta_log_likelihood`, `delta_log_likelihood_gap`).
    pub statistic: String,
    /// Its value.
    pub value: f64,
    /// Why, in words.
    pub reason: String,
    /// What the model already carries that gives the same innovations (`kind at location`),
    /// where the system names it ([`Rivals::carried`](super::system::Rivals::carried)).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub rivals: Vec<String>,
}

impl NotIdentifiable {
    /// The verdict on the effect `label` names, from `statistic`'s `value`, for `reason`.
    pub fn of(label: &EffectLabel, statistic: &str, value: f64, reason: String) -> Self {
        Self {
            kind: label.kind,
            location: label.location.clone(),
            parameter: label.detail.parameter.clone(),
            statistic: statistic.into(),
            value,
            reason,
            rivals: Vec::new(),
        }
    }

    /// Whether it is about the same effect as `other` (kind, place and parameter).
    pub fn is_about(&self, other: &NotIdentifiable) -> bool {
        (self.kind, &self.location, &self.parameter) == (other.kind, &other.location, &other.parameter)
    }

    /// Whether it is about the effect `label` names (kind, place and parameter).
    pub fn names(&self, label: &EffectLabel) -> bool {
        (self.kind, &self.location, &self.parameter) == (label.kind, &label.location, &label.detail.parameter)
    }
}

/// One candidate evaluated.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trial {
    /// Iteration.
    pub iteration: usize,
    /// Kind.
    pub kind: EffectKind,
    /// Location.
    pub location: String,
    /// Order (harmonic forces, bearing lines).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<f64>,
    /// Parameter name (parameter effects).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parameter: Option<String>,
    /// The fitted onset, s on the data's `t` (change-point fits).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub onset_s: Option<f64>,
    /// Unit of `value`.
    pub unit: String,
    /// Fitted value (scalar effects), as reported.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value: Option<f64>,
    /// Gain in log-likelihood over the current model.
    pub delta_log_likelihood: f64,
    /// The gain in the first and in the second half of the run (of the stretch after the
    /// onset, for a change-point fit).
    pub delta_halves: [f64; 2],
    /// What each half would gain if the effect lasted through the run, where a half gained
    /// less than it must (a half that cannot see the effect need not pay for it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delta_halves_expected: Option<[f64; 2]>,
    /// `½ p ln n`, plus a baseline's gain floor over the run.
    pub bic_penalty: f64,
    /// Kept.
    pub accepted: bool,
}

/// The series behind the report's plots (not serialised).
#[derive(Debug, Clone, Default)]
pub struct Traces {
    /// Time, s.
    pub t: Vec<f64>,
    /// Sensor channels.
    pub channels: Vec<Channel>,
    /// Virtual-sensing rows (`n12_x`, …).
    pub rows: Vec<Channel>,
    /// `truth_` column of each row, where the file has one.
    pub truth: Vec<Option<Vec<f64>>>,
    /// The base model's run.
    pub before: Run,
    /// The final model's run.
    pub after: Run,
}

impl Traces {
    /// The data's time, channels, virtual rows and their `truth_` columns (the engine fills in
    /// the runs).
    pub fn new(t: &[f64], channels: &[Channel], rows: &[Channel], truth: &[Option<&[f64]>]) -> Self {
        let truth = truth.iter().map(|c| c.map(<[f64]>::to_vec)).collect();
        Self { t: t.to_vec(), channels: channels.to_vec(), rows: rows.to_vec(), truth, ..Self::default() }
    }
}

/// What the loop found.
#[derive(Debug, Clone, Serialize)]
pub struct LoopReport {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The system (its registry name).
    pub system: String,
    /// Where the report came from.
    pub source: Source,
    /// Effects kept, in order.
    pub effects_added: Vec<AddedEffect>,
    /// How each kept effect enters the configuration (`--corrected-config`), in the same
    /// order, then the tuning's.
    pub corrections: Vec<EffectCorrection>,
    /// The process noise the engine set from the data before the search, if it paid
    /// ([`tuning`](super::tuning)).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tuning: Option<Tuning>,
    /// The base model.
    pub before: RunSummary,
    /// The final model.
    pub after: RunSummary,
    /// Effects the data cannot resolve.
    pub not_identifiable: Vec<NotIdentifiable>,
    /// Signatures left that no effect of the library explains (empty when the final
    /// innovations are consistent).
    pub unexplained: Vec<Signature>,
    /// Candidates fitted and refused, with the reason.
    pub refused: Vec<Refused>,
    /// Every candidate evaluated.
    pub trials: Vec<Trial>,
    /// Why the loop stopped.
    pub stopped: String,
    /// The system's own fields (a running speed, say), at the top level of the JSON.
    #[serde(flatten)]
    pub section: SystemSection,
    /// The series behind the plots.
    #[serde(skip)]
    pub traces: Traces,
}

/// The scale the engine kept, in `report.json`'s `tuning`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Tuning {
    /// What the noise stands for.
    pub what: String,
    /// The factor on the configuration's process noise densities.
    pub scale: f64,
    /// What it raised the base model's log-likelihood by.
    pub delta_log_likelihood: f64,
    /// What it had to raise it by to be kept (the BIC of one parameter and the gain floor).
    pub penalty: f64,
}

impl Tuning {
    /// How the scale enters the configuration: each key multiplied by it.
    ///
    /// ```
    /// use edgekf_sim::residual_loop::tuning::Tuning;
    /// let t = Tuning { what: "motion".into(), scale: 0.1, delta_log_likelihood: 50.0, penalty: 6.0 };
    /// let c = t.correction(&[("estimator.process.velocity".to_string(), 0.02)]);
    /// assert_eq!(c.effect, "process_noise of motion");
    /// assert_eq!(c.correction.edits()[0].absent, Some(0.02));
    /// ```
    pub fn correction(&self, keys: &[(String, f64)]) -> EffectCorrection {
        let edits = keys.iter().map(|(k, v)| ConfigEdit::or_absent(k, Op::Scale(self.scale), *v));
        EffectCorrection { effect: format!("process_noise of {}", self.what), correction: Correction::model(edits) }
    }
}
