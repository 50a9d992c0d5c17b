//! The baseline every system can have: what the model leaves unexplained on a healthy record
//! (the gain floor: the best next effect's gain beyond its BIC cost, per scalar measurement)
//! and each channel's innovation level there. A system whose healthy parts live in its
//! configuration needs no more; a record under diagnosis is then judged against that floor
//! ([`FLOOR_MARGIN`] times it) and its innovation levels compared with the healthy ones.

use super::baseline::{BaselineSource, Comparison};
use super::report::LoopReport;
use super::{search, LoopOptions, LoopSystem};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// How much more than its baseline's gain floor an effect must gain on a record under
/// diagnosis: two records of the same healthy machine differ, and the best next effect of one
/// gains up to about twice what it gains on the other (the two halves of CWRU 097).
pub const FLOOR_MARGIN: f64 = 2.0;

/// A healthy baseline of levels (`edgekf baseline <system>` for a system without its own).
///
/// ```
/// use edgekf_sim::residual_loop::levels::LevelBaseline;
/// let text = "system = \"press\"\ngain_floor = 1e-4\nnis_mean = 1.1\n\n[source]\ndata = \"healthy.csv\"\n\n\
///             [[channel]]\nchannel = \"ax\"\ninnovation_rms = 5e-4\n";
/// let b = LevelBaseline::from_toml(text, "press").unwrap();
/// assert_eq!(b.channels[0].channel, "ax");
/// assert!(LevelBaseline::from_toml(text, "mill").is_err());
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LevelBaseline {
    /// The system it belongs to.
    pub system: String,
    /// The operating condition, as the user named it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub condition: Option<String>,
    /// What the healthy record leaves unexplained, per scalar measurement (see the module).
    pub gain_floor: f64,
    /// The configured model's mean NIS per channel on the healthy record (1 when its noise
    /// levels are right).
    pub nis_mean: f64,
    /// The factor on the system's tunable process noise the healthy record asked for (see
    /// [`tuning`](super::tuning)), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise_scale: Option<f64>,
    /// Where it was learned.
    #[serde(default)]
    pub source: BaselineSource,
    /// Each channel's innovations on the healthy record, with the configured model.
    #[serde(default, rename = "channel")]
    pub channels: Vec<InnovationLevel>,
}

/// One channel's innovations on a healthy record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InnovationLevel {
    /// The channel.
    pub channel: String,
    /// RMS innovation, in the channel's unit.
    pub innovation_rms: f64,
    /// Its standard error from the healthy record's blocks (absent from baselines learned
    /// before it was kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std_error: Option<f64>,
}

impl LevelBaseline {
    /// Learns it from `sys` built on a healthy record: the configured model's innovation levels,
    /// then one round of the loop without a floor for what it leaves unexplained.
    pub fn learn<S: LoopSystem>(sys: &mut S, condition: Option<String>, options: &LoopOptions) -> Result<Self> {
        let say = |s: String| {
            if options.progress {
                eprintln!("baseline: {s}");
            }
        };
        let run = sys.run(&[])?.1;
        let n_meas = run.measurements().max(2) as f64;
        let summary = sys.summarise(&run);
        say("measuring what the healthy record leaves unexplained (one round of the loop)".into());
        let probe =
            LoopOptions { max_effects: 1, screen_parameters: false, progress: false, gain_floor: 0.0, ..*options };
        let report = search(sys, &probe)?;
        let gain_floor = leftover_gain(&report, n_meas, &say);
        let noise_scale = report.tuning.map(|t| t.scale);
        Ok(Self {
            system: S::NAME.to_string(),
            condition,
            gain_floor,
            nis_mean: summary.nis_mean,
            noise_scale,
            source: BaselineSource { version: env!("CARGO_PKG_VERSION").into(), ..BaselineSource::default() },
            channels: summary
                .innovation_rms
                .iter()
                .map(|(c, &rms)| InnovationLevel {
                    channel: c.clone(),
                    innovation_rms: rms,
                    std_error: summary
                        .channels
                        .iter()
                        .find(|s| &s.name == c)
                        .map(|s| s.rms_standard_error)
                        .filter(|se| se.is_finite()),
                })
                .collect(),
        })
    }

    /// This baseline as learned from `source`, the recording's SHA-256 from its one read.
    pub fn with_source(mut self, source: &BaselineSource, data_sha256: Option<&str>) -> Self {
        self.source = BaselineSource { data_sha256: data_sha256.unwrap_or_default().to_string(), ..source.clone() };
        self
    }

    /// Reads a baseline of `system` from TOML text.
    pub fn from_toml(text: &str, system: &str) -> Result<Self> {
        let b: Self = toml::from_str(text).context("not a baseline file")?;
        if b.system != system {
            bail!("a baseline of `{}`, not of `{system}`", b.system);
        }
        if !(b.gain_floor.is_finite() && b.gain_floor >= 0.0) {
            bail!("gain_floor must be a finite number ≥ 0, not {}", b.gain_floor);
        }
        Ok(b)
    }

    /// Reads a baseline of `system` from a file.
    pub fn load(path: &Path, system: &str) -> Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
        Self::from_toml(&text, system).with_context(|| path.display().to_string())
    }

    /// The file's text.
    pub fn to_toml(&self) -> Result<String> {
        Ok(toml::to_string_pretty(self)?)
    }

    /// `options` with this baseline's floor: an effect must gain [`FLOOR_MARGIN`] times what
    /// the healthy record leaves unexplained.
    pub fn options(&self, options: &LoopOptions) -> LoopOptions {
        LoopOptions { gain_floor: FLOOR_MARGIN * self.gain_floor, noise_scale: self.noise_scale, ..*options }
    }

    /// Puts the baseline (`baseline`) and the record's innovation levels against its
    /// (`baseline_comparison`, kind `innovation_rms` per channel, the configured model on both)
    /// into `report`.
    pub fn annotate(&self, report: &mut LoopReport) {
        let comparisons: Vec<Comparison> = self
            .channels
            .iter()
            .filter_map(|l| {
                let now = report.before.channels.iter().find(|c| c.name == l.channel)?;
                let c = Comparison::new("innovation_rms", &l.channel, None, "", now.rms, l.innovation_rms);
                Some(c.with_errors(Some(now.rms_standard_error), l.std_error))
            })
            .collect();
        let about = serde_json::json!({
            "condition": self.condition,
            "data": self.source.data,
            "data_sha256": self.source.data_sha256,
            "gain_floor": self.gain_floor,
            "nis_mean": self.nis_mean,
            "noise_scale": self.noise_scale,
        });
        let section = &mut report.section;
        section.fields.insert("baseline".into(), about);
        section.fields.insert("baseline_comparison".into(), serde_json::json!(comparisons));
        let floor = format!("{:.2e} per measurement, from {}", self.gain_floor, self.source.data);
        section.lines.push(("baseline".into(), floor));
        for c in &comparisons {
            let text = format!(
                "×{:.2} the baseline's ({:.3e} against {:.3e}){}",
                c.ratio_to_baseline,
                c.value,
                c.baseline_value,
                c.spread()
            );
            section.lines.push((format!("innovations of {}", c.location), text));
        }
    }
}

/// Closes a loop with `close`: under the baseline of `system` at `path` where one is given
/// (its floor in the options, its levels beside the record's in the report), else as is.
pub fn close_with(
    path: Option<&Path>,
    system: &str,
    options: &LoopOptions,
    close: impl FnOnce(&LoopOptions) -> Result<LoopReport>,
) -> Result<LoopReport> {
    let Some(path) = path else { return close(options) };
    let baseline = LevelBaseline::load(path, system)?;
    let mut report = close(&baseline.options(options))?;
    baseline.annotate(&mut report);
    Ok(report)
}

/// What a healthy record leaves unexplained, per scalar measurement: the best next effect's
/// gain beyond its BIC cost in `leftover` (one round of the loop without a floor), never below 0.
pub fn leftover_gain(leftover: &LoopReport, n_meas: f64, say: &dyn Fn(String)) -> f64 {
    let beyond = |t: &super::report::Trial| t.delta_log_likelihood - t.bic_penalty;
    let best = leftover.trials.iter().max_by(|a, b| beyond(a).total_cmp(&beyond(b)));
    let gain_floor = best.map_or(0.0, |t| beyond(t).max(0.0) / n_meas);
    if let Some(t) = best {
        say(format!(
            "best next effect: {} at {} (Δ log-likelihood {:.1}, BIC cost {:.1}): gain floor {gain_floor:.2e} per measurement",
            t.kind, t.location, t.delta_log_likelihood, t.bic_penalty
        ));
    }
    gain_floor
}
