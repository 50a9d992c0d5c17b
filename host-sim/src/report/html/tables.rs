//! The page's tables: the effects added, the before/after comparison (the run, each channel's
//! innovation, the virtual-sensing errors; the final model's value green where it is better
//! and red where it is worse), what is not identifiable or unexplained, and every candidate
//! tried. Each cell's text is escaped when written.

use super::format::{fixed, num, order, p_value, value_with_unit};
use super::{h2, para};
use crate::io::config_edit::{ConfigEdit, Op};
use crate::report::escape::escape as esc;
use crate::report::text::shown;
use crate::residual_loop::report::Refused;
use crate::residual_loop::signature::{ChannelSignature, Signature};
use crate::residual_loop::{
    AddedEffect, Correction, EffectCorrection, LoopReport, NotIdentifiable, RunSummary, Traces, Trial,
};

/// A table cell: text (escaped when written) and a class.
struct Cell {
    /// The text.
    text: String,
    /// CSS classes (`num`, `better`, …), may be empty.
    class: String,
}

impl Cell {
    /// A text cell.
    fn text(text: impl Into<String>) -> Self {
        Self { text: text.into(), class: String::new() }
    }

    /// A right-aligned number cell with an optional verdict class.
    fn num(text: impl Into<String>, verdict: &str) -> Self {
        Self { text: text.into(), class: format!("num {verdict}").trim().to_string() }
    }

    /// The `<td>`.
    fn html(&self) -> String {
        match self.class.as_str() {
            "" => format!("<td>{}</td>", esc(&self.text)),
            c => format!("<td class=\"{c}\">{}</td>", esc(&self.text)),
        }
    }
}

/// A table with one header row and rows of cells; `row_class` gives a row's class.
fn table(head: &[&str], rows: &[Vec<Cell>], row_class: impl Fn(usize) -> &'static str) -> String {
    let mut s = String::from("<table>\n<thead><tr>");
    for h in head {
        s.push_str(&format!("<th>{}</th>", esc(h)));
    }
    s.push_str("</tr></thead>\n<tbody>\n");
    for (i, row) in rows.iter().enumerate() {
        match row_class(i) {
            "" => s.push_str("<tr>"),
            c => s.push_str(&format!("<tr class=\"{c}\">")),
        }
        row.iter().for_each(|c| s.push_str(&c.html()));
        s.push_str("</tr>\n");
    }
    s.push_str("</tbody>\n</table>\n");
    s
}

/// Parameter, defect line and order of an effect, where present.
fn effect_detail(e: &AddedEffect) -> String {
    let d = &e.detail;
    let onset = d.onset_s.map(|o| format!("from {o:.3} s"));
    let parts: Vec<String> = [d.parameter.clone(), d.line.clone(), d.order.map(order), onset, d.not_modelled.clone()]
        .into_iter()
        .flatten()
        .collect();
    if parts.is_empty() {
        "–".into()
    } else {
        parts.join(", ")
    }
}

/// Frequencies as `14.00, 28.00`; `–` when none.
fn frequencies(f: &[f64]) -> String {
    if f.is_empty() {
        "–".into()
    } else {
        f.iter().map(|v| format!("{v:.2}")).collect::<Vec<_>>().join(", ")
    }
}

/// A section that is one table: its heading, then the table, or `none` when it has no rows.
fn table_section(out: &mut String, title: &str, none: &str, head: &[&str], rows: &[Vec<Cell>]) {
    h2(out, title);
    if rows.is_empty() {
        para(out, "", none);
    } else {
        out.push_str(&table(head, rows, |_| ""));
    }
}

/// The effects added, in order.
pub(super) fn effects(out: &mut String, added: &[AddedEffect]) {
    let rows: Vec<Vec<Cell>> = added
        .iter()
        .enumerate()
        .map(|(i, e)| {
            vec![
                Cell::num((i + 1).to_string(), ""),
                Cell::text(e.kind.as_str()),
                Cell::text(&e.location),
                Cell::text(effect_detail(e)),
                Cell::num(value_with_unit(e.value, &e.unit), ""),
                Cell::num(
                    e.interval.map_or("–".into(), |[a, b]| {
                        format!("{} … {}", value_with_unit(a, &e.unit), value_with_unit(b, &e.unit))
                    }),
                    "",
                ),
                match &e.detail.named_by {
                    Some(_) => Cell::num("–".to_string(), ""),
                    None => Cell::num(fixed(e.delta_log_likelihood, 1), ""),
                },
                match &e.detail.named_by {
                    Some(test) => Cell::text(format!("named by {test}")),
                    None => Cell::num(fixed(e.bic_penalty, 1), ""),
                },
                Cell::text(frequencies(&e.explains)),
            ]
        })
        .collect();
    let head = [
        "#",
        "kind",
        "location",
        "parameter / line / order",
        "value",
        "95 % interval",
        "Δ log-likelihood",
        "BIC cost",
        "lines explained (Hz)",
    ];
    table_section(out, "Effects added", "No effect was added: the base model is kept.", &head, &rows);
}

/// How a statistic improves, for highlighting the final model's value.
#[derive(Debug, Clone, Copy)]
enum Better {
    /// Smaller is better (RMS, errors): compared in ratio, 3 % margin.
    Lower,
    /// Larger is better (log-likelihood): one unit margin.
    Higher,
    /// Closer to 1 is better (NIS): compared in log.
    NearOne,
    /// Larger is better below 0.01 (whiteness p): compared in decades.
    PValue,
    /// Closer to 0 is better outside ±2 (bias z).
    NearZero,
    /// 1 (yes) is better than 0 (no).
    Flag,
}

impl Better {
    /// The value's badness on a scale where [`Better::margin`] is a meaningful difference.
    fn badness(self, v: f64) -> Option<f64> {
        let b = match self {
            Better::Lower if v > 0.0 => v.ln(),
            Better::Lower => return None,
            Better::Higher | Better::Flag => -v,
            Better::NearOne if v > 0.0 => v.ln().abs(),
            Better::NearOne => return None,
            Better::PValue => -v.max(1e-300).log10().min(-2.0),
            Better::NearZero => v.abs().max(2.0),
        };
        b.is_finite().then_some(b)
    }

    /// The smallest difference in badness that is highlighted.
    fn margin(self) -> f64 {
        match self {
            Better::Lower => 0.03,
            Better::Higher | Better::NearZero => 1.0,
            Better::NearOne => 0.05,
            Better::PValue | Better::Flag => 0.5,
        }
    }

    /// `better`, `worse` or `""` for `after` against `before`.
    fn verdict(self, before: f64, after: f64) -> &'static str {
        match (self.badness(before), self.badness(after)) {
            (Some(b), Some(a)) if a < b - self.margin() => "better",
            (Some(b), Some(a)) if a > b + self.margin() => "worse",
            _ => "",
        }
    }
}

/// A before/after pair of cells, the after one highlighted.
fn pair(before: f64, after: f64, show: impl Fn(f64) -> String, better: Better) -> [Cell; 2] {
    [Cell::num(show(before), ""), Cell::num(show(after), better.verdict(before, after))]
}

/// A row `<th>label</th>` followed by cells.
fn labelled_row(label_html: &str, cells: &[Cell]) -> String {
    let mut s = format!("<tr><th scope=\"row\">{label_html}</th>");
    cells.iter().for_each(|c| s.push_str(&c.html()));
    s.push_str("</tr>\n");
    s
}

/// The before/after tables: the run, each channel, the virtual-sensing errors.
pub(super) fn comparison(out: &mut String, r: &LoopReport) {
    h2(out, "Before and after");
    para(out, "note", "Green: the final model is better; red: it is worse.");
    overall_table(out, &r.before, &r.after);
    channel_table(out, &r.traces, &r.before, &r.after);
    error_table(out, &r.traces, &r.before, &r.after);
}

/// Whole-run statistics before and after.
fn overall_table(out: &mut String, b: &RunSummary, a: &RunSummary) {
    let yes = |v: f64| if v > 0.5 { "yes".to_string() } else { "no".to_string() };
    let flag = |s: &RunSummary| if s.consistent { 1.0 } else { 0.0 };
    let rows = [
        ("consistent (unbiased, white, NIS within its bounds)", pair(flag(b), flag(a), yes, Better::Flag)),
        ("log-likelihood", pair(b.log_likelihood, a.log_likelihood, |v| fixed(v, 1), Better::Higher)),
        ("NIS mean per channel (1 when consistent)", pair(b.nis_mean, a.nis_mean, |v| fixed(v, 3), Better::NearOne)),
        ("whiteness p (smallest over the channels)", pair(b.whiteness_p, a.whiteness_p, p_value, Better::PValue)),
    ];
    let metrics: Vec<(String, [Cell; 2])> = b
        .metrics
        .iter()
        .map(|(k, vb)| {
            (k.replace('_', " "), pair(*vb, a.metrics.get(k).copied().unwrap_or(f64::NAN), num, Better::Lower))
        })
        .collect();
    out.push_str(
        "<h3>The run</h3>\n<table>\n<thead><tr><th></th><th>before</th><th>after</th></tr></thead>\n<tbody>\n",
    );
    for (label, cells) in rows {
        out.push_str(&labelled_row(&esc(label), &cells));
    }
    // A system's own error figures against truth (the boom's `peak_error_pct`).
    for (label, cells) in metrics {
        out.push_str(&labelled_row(&esc(&label), &cells));
    }
    out.push_str("</tbody>\n</table>\n");
}

/// One channel's cells: RMS, NIS, whiteness p and bias z, before and after.
fn channel_cells(name: &str, scale: f64, b: &RunSummary, a: &RunSummary) -> Vec<Cell> {
    let sig = |s: &RunSummary| s.channels.iter().find(|c| c.name == name).cloned();
    let (cb, ca) = (sig(b), sig(a));
    let field = |c: &Option<ChannelSignature>, f: fn(&ChannelSignature) -> f64| c.as_ref().map_or(f64::NAN, f);
    let rms = |s: &RunSummary| s.innovation_rms.get(name).map_or(f64::NAN, |v| v * scale);
    let mut cells = Vec::with_capacity(8);
    cells.extend(pair(rms(b), rms(a), num, Better::Lower));
    cells.extend(pair(field(&cb, |c| c.nis), field(&ca, |c| c.nis), |v| fixed(v, 3), Better::NearOne));
    cells.extend(pair(field(&cb, |c| c.whiteness_p), field(&ca, |c| c.whiteness_p), p_value, Better::PValue));
    cells.extend(pair(field(&cb, |c| c.z), field(&ca, |c| c.z), |v| fixed(v, 1), Better::NearZero));
    cells
}

/// Per-channel innovation statistics before and after.
fn channel_table(out: &mut String, tr: &Traces, b: &RunSummary, a: &RunSummary) {
    out.push_str("<h3>Each channel's innovation</h3>\n<table>\n<thead>\n");
    out.push_str("<tr><th rowspan=\"2\">channel</th><th colspan=\"2\">RMS</th><th colspan=\"2\">NIS mean</th>");
    out.push_str("<th colspan=\"2\">whiteness p</th><th colspan=\"2\">bias z (mean / s.e.)</th></tr>\n<tr>");
    out.push_str(&"<th>before</th><th>after</th>".repeat(4));
    out.push_str("</tr>\n</thead>\n<tbody>\n");
    let mut names: Vec<&String> = b.channels.iter().map(|c| &c.name).collect();
    names.extend(b.innovation_rms.keys().filter(|k| !b.channels.iter().any(|c| &c.name == *k)));
    for name in names {
        let (scale, unit) = shown(&tr.channels, name);
        let label = format!("{} <span class=\"unit\">{}</span>", esc(name), esc(unit));
        out.push_str(&labelled_row(&label, &channel_cells(name, scale, b, a)));
    }
    out.push_str("</tbody>\n</table>\n");
}

/// RMS error of the virtual-sensing rows against the truth, before and after (when the data
/// had `truth_` columns).
fn error_table(out: &mut String, tr: &Traces, b: &RunSummary, a: &RunSummary) {
    if b.error_rms.is_empty() && a.error_rms.is_empty() {
        para(out, "note", "The data file has no truth_ columns: no virtual-sensing errors.");
        return;
    }
    out.push_str("<h3>Virtual sensing against the truth</h3>\n<table>\n<thead><tr><th>row</th>");
    out.push_str("<th>error RMS before</th><th>error RMS after</th></tr></thead>\n<tbody>\n");
    for k in b.error_rms.keys().chain(a.error_rms.keys().filter(|k| !b.error_rms.contains_key(*k))) {
        let (scale, unit) = shown(&tr.rows, k);
        let shown = |s: &RunSummary| s.error_rms.get(k).map_or(f64::NAN, |v| v * scale);
        let label = format!("{} <span class=\"unit\">{}</span>", esc(k), esc(unit));
        out.push_str(&labelled_row(&label, &pair(shown(b), shown(a), num, Better::Lower)));
    }
    out.push_str("</tbody>\n</table>\n");
}

/// Effects or locations the data cannot resolve.
pub(super) fn not_identifiable(out: &mut String, list: &[NotIdentifiable]) {
    let rows: Vec<Vec<Cell>> = list
        .iter()
        .map(|n| {
            vec![
                Cell::text(n.kind.as_str()),
                Cell::text(&n.location),
                Cell::text(n.parameter.clone().unwrap_or_else(|| "–".into())),
                Cell::text(&n.statistic),
                Cell::num(num(n.value), ""),
                Cell::text(&n.reason),
            ]
        })
        .collect();
    let head = ["kind", "location", "parameter", "statistic", "value", "why"];
    table_section(out, "Not identifiable", "Nothing was found that the data cannot resolve.", &head, &rows);
}

/// Candidates fitted and not kept, with the reason.
pub(super) fn refused(out: &mut String, list: &[Refused]) {
    let rows: Vec<Vec<Cell>> = list
        .iter()
        .map(|r| {
            vec![
                Cell::text(r.kind.as_str()),
                Cell::text(&r.location),
                Cell::text(r.parameter.clone().unwrap_or_else(|| "–".into())),
                Cell::num(r.value.map_or("–".into(), num), ""),
                Cell::text(&r.reason),
            ]
        })
        .collect();
    let head = ["kind", "location", "parameter", "value", "why not kept"];
    table_section(out, "Refused", "No candidate was refused.", &head, &rows);
}

/// How each added effect enters the configuration (`--corrected-config`).
pub(super) fn corrections(out: &mut String, list: &[EffectCorrection]) {
    let rows: Vec<Vec<Cell>> = list
        .iter()
        .map(|c| {
            let (verdict, what) = match &c.correction {
                Correction::Model { edits } => ("into the model", edits_text(edits)),
                Correction::Indicator { edits, note } if edits.is_empty() => ("a fault the node tracks", note.clone()),
                Correction::Indicator { edits, note } => {
                    ("a fault the node tracks", format!("{note}; {}", edits_text(edits)))
                }
                Correction::NotCarried { reason } => ("not carried", reason.clone()),
            };
            vec![Cell::text(&c.effect), Cell::text(verdict), Cell::text(what)]
        })
        .collect();
    let head = ["effect", "as", "keys or why"];
    table_section(out, "Into the configuration", "No effect was added.", &head, &rows);
}

/// `path ×1.1, path +0.01`: a correction's edits as people read them.
fn edits_text(edits: &[ConfigEdit]) -> String {
    let one = |e: &ConfigEdit| match e.op {
        Op::Scale(f) => format!("{} ×{}", e.path, num(f)),
        Op::Add(d) => format!("{} +{}", e.path, num(d)),
        Op::Set(v) => format!("{} = {}", e.path, num(v)),
        Op::Switch(on) => format!("{} = {on}", e.path),
    };
    edits.iter().map(one).collect::<Vec<_>>().join(", ")
}

/// Signatures that no effect of the library explains.
pub(super) fn unexplained(out: &mut String, list: &[Signature]) {
    let rows: Vec<Vec<Cell>> = list
        .iter()
        .map(|s| {
            vec![
                Cell::text(&s.channel),
                Cell::num(s.frequency_hz.map_or("–".into(), |f| fixed(f, 2)), ""),
                Cell::text(&s.statistic),
                Cell::num(num(s.value), ""),
                Cell::text(&s.description),
            ]
        })
        .collect();
    let head = ["channel", "frequency (Hz)", "statistic", "value", "description"];
    table_section(out, "Unexplained", "Nothing is left unexplained.", &head, &rows);
}

/// Every candidate evaluated, in a collapsed `<details>`.
pub(super) fn trials(out: &mut String, list: &[Trial]) {
    h2(out, "Candidates tried");
    out.push_str(&format!(
        "<details>\n<summary>{} candidate{} (kept ones in bold)</summary>\n",
        list.len(),
        if list.len() == 1 { "" } else { "s" }
    ));
    let rows: Vec<Vec<Cell>> = list
        .iter()
        .map(|t| {
            vec![
                Cell::num(t.iteration.to_string(), ""),
                Cell::text(t.kind.as_str()),
                Cell::text(&t.location),
                Cell::text(t.order.map_or("–".into(), order)),
                Cell::text(t.parameter.clone().unwrap_or_else(|| "–".into())),
                Cell::num(t.value.map_or("–".into(), |v| value_with_unit(v, &t.unit)), ""),
                Cell::num(fixed(t.delta_log_likelihood, 1), ""),
                Cell::num(format!("{} / {}", fixed(t.delta_halves[0], 1), fixed(t.delta_halves[1], 1)), ""),
                Cell::num(fixed(t.bic_penalty, 1), ""),
                Cell::text(if t.accepted { "yes" } else { "no" }),
            ]
        })
        .collect();
    let head = [
        "iteration",
        "kind",
        "location",
        "order",
        "parameter",
        "value",
        "Δ log-likelihood",
        "Δ halves",
        "BIC cost",
        "kept",
    ];
    out.push_str(&table(&head, &rows, |i| if list[i].accepted { "kept" } else { "" }));
    out.push_str("</details>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn highlights_improvements() {
        assert_eq!(Better::Lower.verdict(10.0, 1.0), "better");
        assert_eq!(Better::Lower.verdict(1.0, 1.01), "");
        assert_eq!(Better::NearOne.verdict(5.0, 1.02), "better");
        assert_eq!(Better::NearOne.verdict(1.02, 0.3), "worse");
        assert_eq!(Better::PValue.verdict(1e-30, 0.4), "better");
        assert_eq!(Better::PValue.verdict(0.2, 0.6), "");
        assert_eq!(Better::Higher.verdict(-100.0, 50.0), "better");
        assert_eq!(Better::NearZero.verdict(30.0, 0.5), "better");
        assert_eq!(Better::Lower.verdict(f64::NAN, 1.0), "");
        assert_eq!(Better::Flag.verdict(0.0, 1.0), "better");
        assert_eq!(Better::Flag.verdict(1.0, 1.0), "");
    }
}
