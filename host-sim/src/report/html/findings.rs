//! The page's first section: one plain sentence per finding — what the loop added and what
//! to do about it, with how sure it is — and what the sensors cannot tell. Made from the
//! report's fields alone (kind, place, value, detail), so that it is the same for every system.

use super::format::{capitalised, value_with_unit};
use super::{h2, para};
use crate::residual_loop::{AddedEffect, EffectKind, LoopReport, NotIdentifiable};

/// What a bearing defect's line says about where the damage is.
fn bearing_part(line: Option<&str>) -> &'static str {
    match line {
        Some("BPFO") => "outer-race defect",
        Some("BPFI") => "inner-race defect",
        Some("BSF") => "rolling-element (ball) defect",
        Some("FTF") => "cage defect",
        _ => "defect",
    }
}

/// The finding's sentence: what it is and what to do.
fn sentence(e: &AddedEffect) -> String {
    let value = value_with_unit(e.value, &e.unit);
    let what = e.detail.parameter.as_deref().unwrap_or("parameter");
    let order = e.detail.order.map(|o| format!("{o}× "));
    let line = e.detail.line.as_deref();
    match e.kind {
        EffectKind::Parameter => format!(
            "{} {what} is {value} of the declared value: inspect the part, or update the model with the \
             corrected configuration",
            e.location
        ),
        EffectKind::PointMass => format!("{value} more mass at {}: rebalance, or update the model", e.location),
        EffectKind::HarmonicForce => format!(
            "a {}force of {value} at {} that the model lacks (unbalance, misalignment or looseness at that order)",
            order.unwrap_or_default(),
            e.location
        ),
        EffectKind::BearingDefect => {
            let harmonics = e.detail.harmonics.as_ref().map(|h| {
                let h: Vec<String> = h.iter().map(u32::to_string).collect();
                format!(", harmonics {}", h.join(", "))
            });
            let harmonics = harmonics.unwrap_or_default();
            format!(
                "{}: {} ({}{harmonics}): inspect or replace the bearing",
                e.location,
                bearing_part(line),
                line.unwrap_or("?")
            )
        }
        EffectKind::SensorBias => format!("sensor {} reads with an offset of {value}: recalibrate it", e.location),
        EffectKind::SensorScale => format!("sensor {} reads {value} of the truth: recalibrate it", e.location),
        EffectKind::SensorDelay | EffectKind::SensorLag => {
            format!("sensor {} lags by {value}: check its filter and timing", e.location)
        }
        EffectKind::ExtraMode => format!("a resonance the model lacks, at {value}: add it to the model"),
        EffectKind::UnknownInput => format!("an input the model lacks, at {}: find what drives it", e.location),
        EffectKind::ActuatorHealth => format!("{} delivers {value} of its nominal effect: inspect it", e.location),
        EffectKind::Clearance => format!("a clearance of {value} at {}: inspect the joint", e.location),
    }
}

/// How sure: the likelihood's margin over the cost, or the test that named it.
fn confidence(e: &AddedEffect) -> String {
    let mut s = match &e.detail.named_by {
        Some(test) => format!("named by {test}"),
        None => format!(
            "the data favour it by {:.0} in log-likelihood beyond its cost of {:.0}",
            e.delta_log_likelihood - e.bic_penalty,
            e.bic_penalty
        ),
    };
    if let Some([a, b]) = e.interval {
        s.push_str(&format!("; 95 % interval {} … {}", value_with_unit(a, &e.unit), value_with_unit(b, &e.unit)));
    }
    if let Some(why) = &e.detail.not_modelled {
        s.push_str(&format!("; {why}"));
    }
    s
}

/// What cannot be told, in a sentence.
fn unseen(n: &NotIdentifiable) -> String {
    let what = n.parameter.as_ref().map(|p| format!(" {p}")).unwrap_or_default();
    let rivals = if n.rivals.is_empty() { String::new() } else { format!(" (rivals: {})", n.rivals.join(", ")) };
    format!("{} at {}{what}{rivals}: {}", n.kind, n.location, n.reason)
}

/// The findings section.
pub(super) fn findings(out: &mut String, r: &LoopReport) {
    h2(out, "Findings");
    if r.effects_added.is_empty() {
        para(out, "", "Nothing found that the model lacks: no effect paid for itself.");
    }
    for e in &r.effects_added {
        para(out, "", &format!("{} — {}.", capitalised(&sentence(e)), confidence(e)));
    }
    for n in r.not_identifiable.iter().filter(|n| n.kind == EffectKind::BearingDefect || !n.rivals.is_empty()) {
        para(out, "note", &format!("These sensors cannot tell: {}.", unseen(n)));
    }
    against_baseline(out, r);
}

/// The baseline's comparison rows whose interval leaves 1 out, a sentence each; "no change
/// beyond noise" when every row with an interval holds 1.
fn against_baseline(out: &mut String, r: &LoopReport) {
    let Some(rows) = r.section.fields.get("baseline_comparison").and_then(|v| v.as_array()) else { return };
    let judged: Vec<&serde_json::Value> = rows.iter().filter(|c| c["beyond_noise"].is_boolean()).collect();
    let changed: Vec<&&serde_json::Value> = judged.iter().filter(|c| c["beyond_noise"] == true).collect();
    if !judged.is_empty() && changed.is_empty() {
        let text = format!("Against the baseline: no change beyond noise in the {} levels compared.", judged.len());
        para(out, "", &text);
    }
    for c in changed {
        let what = match c["order"].as_u64() {
            Some(o) => format!("{o}× level"),
            None => c["kind"].as_str().unwrap_or_default().replace('_', " "),
        };
        let (ratio, lo, hi) = (c["ratio_to_baseline"].as_f64(), c["interval"][0].as_f64(), c["interval"][1].as_f64());
        if let (Some(ratio), Some(lo), Some(hi)) = (ratio, lo, hi) {
            let place = c["location"].as_str().unwrap_or_default();
            let text = format!(
                "Against the baseline: the {what} at {place} is ×{ratio:.2} the baseline's (95 %: ×{lo:.2}–×{hi:.2})."
            );
            para(out, "", &text);
        }
    }
}
