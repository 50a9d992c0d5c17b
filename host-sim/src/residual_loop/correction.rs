//! How each effect the loop added enters the configuration (`corrections` in `report.json`,
//! and the file `--corrected-config` writes): a model or calibration effect as edits of the
//! configuration's own keys, a fault as an indicator the node tracks (written into the model
//! it would silence its own alarm), and an effect no key holds yet with the reason. The
//! system says which ([`LoopSystem::correction`](super::LoopSystem::correction)); the engine
//! lists them and writes the file, the same for every system.

use crate::io::config_edit::{corrected, ConfigEdit, EditError};
use serde::Serialize;

/// How one effect enters the configuration.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "as")]
pub enum Correction {
    /// A model or calibration effect: the configuration's own keys, edited.
    Model {
        /// The edits, in order.
        edits: Vec<ConfigEdit>,
    },
    /// A fault: left out of the model, written as a limit the node tracks instead.
    Indicator {
        /// The edits, in order (none where the node already tracks it).
        edits: Vec<ConfigEdit>,
        /// What tracks it, as a sentence.
        note: String,
    },
    /// No key of the configuration holds it.
    NotCarried {
        /// Why, as a sentence.
        reason: String,
    },
}

impl Correction {
    /// A model or calibration effect made of `edits`.
    pub fn model(edits: impl IntoIterator<Item = ConfigEdit>) -> Self {
        Self::Model { edits: edits.into_iter().collect() }
    }

    /// A fault the node tracks as `note` says, with `edits` to its limits.
    pub fn indicator(edits: impl IntoIterator<Item = ConfigEdit>, note: impl Into<String>) -> Self {
        Self::Indicator { edits: edits.into_iter().collect(), note: note.into() }
    }

    /// An effect no key holds, because `reason`.
    pub fn not_carried(reason: impl Into<String>) -> Self {
        Self::NotCarried { reason: reason.into() }
    }

    /// The edits it makes (none when not carried).
    pub fn edits(&self) -> &[ConfigEdit] {
        match self {
            Self::Model { edits } | Self::Indicator { edits, .. } => edits,
            Self::NotCarried { .. } => &[],
        }
    }
}

/// One added effect's correction, as the report lists it (in `effects_added`' order).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EffectCorrection {
    /// The effect, as the report names it (`kind at location`).
    pub effect: String,
    /// How it enters the configuration.
    #[serde(flatten)]
    pub correction: Correction,
}

/// `config` (the text the loop ran with) with every correction's edits applied, each under a
/// comment naming `origin` (the report it came from) and the effect.
///
/// ```
/// use edgekf_sim::io::config_edit::{ConfigEdit, Op};
/// use edgekf_sim::residual_loop::correction::{corrected_config, Correction, EffectCorrection};
/// let fix = EffectCorrection {
///     effect: "parameter at tip".into(),
///     correction: Correction::model([ConfigEdit::new("tip.mass", Op::Scale(1.2))]),
/// };
/// let out = corrected_config("[tip]\nmass = 100.0\n", &[fix], "out/report.json").unwrap();
/// assert!(out.contains("mass = 120") && out.contains("# out/report.json, parameter at tip: was 100"));
/// ```
pub fn corrected_config(config: &str, corrections: &[EffectCorrection], origin: &str) -> Result<String, EditError> {
    let edits: Vec<(String, ConfigEdit)> = corrections
        .iter()
        .flat_map(|c| c.correction.edits().iter().map(|e| (format!("{origin}, {}", c.effect), e.clone())))
        .collect();
    corrected(config, &edits)
}
