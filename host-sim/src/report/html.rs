//! `report.html` of `edgekf loop <system>`: one self-contained page (inline CSS and SVG; no
//! scripts, external styles, fonts or images) for people to read what the residual loop found:
//! why it stopped, the effects it added, the innovation statistics before and after, plots of
//! the normalised innovations, their spectra, the NIS and the virtual-sensing estimates
//! against the truth, and what is left unexplained or not identifiable.
//!
//! The plots are drawn by `plotters`' SVG backend. Its text stays SVG text, rendered by the
//! viewer's sans-serif font, so no font file is needed. Long series are decimated to the
//! minimum and maximum of each pixel column (spikes survive), and missing samples (NaN) break
//! the lines instead of breaking the plot.
//!
//! ```no_run
//! # fn write(report: &edgekf_sim::residual_loop::LoopReport) -> anyhow::Result<()> {
//! let page = edgekf_sim::report::html::render(report)?;
//! std::fs::write("report/report.html", page)?;
//! # Ok(())
//! # }
//! ```

use super::text::shown;
use crate::residual_loop::filter::Run;
use crate::residual_loop::search::{AddedEffect, LoopReport, NotIdentifiable, RunSummary, Traces, Trial};
use crate::residual_loop::signature::{ChannelSignature, Signature};
use anyhow::Result;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Colour of the base model's series ("before").
const BEFORE: RGBColor = RGBColor(228, 108, 10);
/// Colour of the final model's series ("after").
const AFTER: RGBColor = RGBColor(31, 100, 180);
/// Colour of the truth (drawn wide, under the estimates).
const TRUTH: RGBColor = RGBColor(175, 175, 175);
/// Colour of reference lines (NIS = 1, ±3).
const REFERENCE: RGBColor = RGBColor(120, 120, 120);
/// Width of one plot panel, px; two side by side make a figure's width.
const PANEL_W: u32 = 480;
/// Height of one plot panel, px.
const PANEL_H: u32 = 220;
/// Samples in the NIS moving average.
const NIS_WINDOW: usize = 100;
/// Font family of the plots' text (rendered by the viewer).
const FONT: &str = "sans-serif";

/// The page's style sheet (inline).
const STYLE: &str = r#"body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,Helvetica,Arial,sans-serif;margin:0;color:#222;background:#fff;line-height:1.4}
main{max-width:980px;margin:0 auto;padding:1em}
h1{font-size:1.6em;margin-bottom:.2em}
h2{font-size:1.25em;border-bottom:1px solid #ddd;padding-bottom:.2em;margin-top:1.8em}
h3{font-size:1.05em;margin-bottom:.3em}
table{border-collapse:collapse;margin:.5em 0;font-size:.92em}
th,td{border:1px solid #ddd;padding:.25em .55em;text-align:left;vertical-align:top}
thead th{background:#f4f4f4}
td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
.better{background:#dcf2dc}
.worse{background:#fbdede}
tr.kept td{font-weight:bold}
.good{color:#1a7f37;font-weight:bold}
.bad{color:#b42318;font-weight:bold}
.note{color:#555;font-size:.9em}
.unit{color:#666;font-weight:normal}
.before{color:#e46c0a;font-weight:bold}
.after{color:#1f64b4;font-weight:bold}
figure{margin:1.2em 0}
figcaption{font-size:.9em;color:#444;margin-top:.3em}
svg{max-width:100%;height:auto;display:block}
details summary{cursor:pointer;font-weight:bold}
"#;

/// Renders the loop's report as a self-contained HTML page.
///
/// Every text taken from the report is escaped; the plots are inline SVG.
pub fn render(report: &LoopReport) -> Result<String> {
    let mut html = String::with_capacity(1 << 18);
    head(&mut html, report);
    verdict(&mut html, report);
    effects(&mut html, &report.effects_added);
    comparison(&mut html, report);
    plots(&mut html, report)?;
    not_identifiable(&mut html, &report.not_identifiable);
    unexplained(&mut html, &report.unexplained);
    trials(&mut html, &report.trials);
    html.push_str(&format!(
        "<p class=\"note\">Written by edgekf {}.</p>\n</main>\n</body>\n</html>\n",
        env!("CARGO_PKG_VERSION")
    ));
    Ok(html)
}

// ---------------------------------------------------------------------------------------------
// Text

/// Escapes `s` for HTML text and attribute values.
fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A number with about four significant digits; `–` when not finite.
fn num(v: f64) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        return format!("{v:.3e}");
    }
    let decimals = if a == 0.0 { 0 } else { (3 - a.log10().floor() as i32).clamp(0, 6) as usize };
    format!("{v:.decimals$}")
}

/// `v` with `decimals` decimals; `–` when not finite.
fn fixed(v: f64, decimals: usize) -> String {
    if v.is_finite() {
        format!("{v:.decimals$}")
    } else {
        "–".into()
    }
}

/// A p-value: three decimals, or scientific below 0.001.
fn p_value(p: f64) -> String {
    if p == 0.0 {
        "0".into()
    } else if p.is_finite() && p < 1e-3 {
        format!("{p:.1e}")
    } else {
        fixed(p, 3)
    }
}

/// An order of the running speed: `2x`, `3.572x`.
fn order(o: f64) -> String {
    if (o - o.round()).abs() < 1e-9 {
        format!("{o:.0}x")
    } else {
        format!("{o:.3}x")
    }
}

/// An effect's value in its unit: a factor as `1.050 (+5.0 %)`, metres in µm, seconds in ms
/// or µs.
fn value_with_unit(v: f64, unit: &str) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    match unit {
        "1" => format!("{v:.3} ({:+.1} %)", (v - 1.0) * 100.0),
        "m" => format!("{} µm", num(v * 1e6)),
        "s" if v.abs() < 1e-3 => format!("{} µs", num(v * 1e6)),
        "s" => format!("{} ms", num(v * 1e3)),
        _ => format!("{} {unit}", num(v)),
    }
}

/// `running speed` → `Running speed`.
fn capitalised(s: &str) -> String {
    let mut c = s.chars();
    c.next().map_or_else(String::new, |f| f.to_uppercase().chain(c).collect())
}

// ---------------------------------------------------------------------------------------------
// HTML building blocks

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

/// A section heading.
fn h2(out: &mut String, title: &str) {
    out.push_str(&format!("<h2>{}</h2>\n", esc(title)));
}

/// A paragraph of escaped text, with a class unless `class` is empty.
fn para(out: &mut String, class: &str, text: &str) {
    match class {
        "" => out.push_str(&format!("<p>{}</p>\n", esc(text))),
        c => out.push_str(&format!("<p class=\"{c}\">{}</p>\n", esc(text))),
    }
}

// ---------------------------------------------------------------------------------------------
// Sections

/// Document head, style sheet and title.
fn head(out: &mut String, r: &LoopReport) {
    let title = format!("Residual loop — {}", r.system);
    out.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    out.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    out.push_str(&format!("<title>{}</title>\n<style>\n{STYLE}</style>\n</head>\n<body>\n<main>\n", esc(&title)));
    out.push_str(&format!("<h1>{}</h1>\n", esc(&title)));
}

/// `consistent` / `not consistent` as a coloured span.
fn consistency(s: &RunSummary) -> &'static str {
    if s.consistent {
        "<span class=\"good\">consistent</span>"
    } else {
        "<span class=\"bad\">not consistent</span>"
    }
}

/// The outcome in two sentences, and why the loop stopped.
fn verdict(out: &mut String, r: &LoopReport) {
    out.push_str(&format!(
        "<p>System <strong>{}</strong>. Base model: innovations {}. Final model ({} effect{} added): innovations {}.</p>\n",
        esc(&r.system),
        consistency(&r.before),
        r.effects_added.len(),
        if r.effects_added.len() == 1 { "" } else { "s" },
        consistency(&r.after),
    ));
    for (label, text) in &r.section.lines {
        out.push_str(&format!("<p><strong>{}:</strong> {}.</p>\n", esc(&capitalised(label)), esc(text)));
    }
    out.push_str(&format!("<p><strong>Why the loop stopped:</strong> {}.</p>\n", esc(&r.stopped)));
}

/// Parameter, defect line and order of an effect, where present.
fn effect_detail(e: &AddedEffect) -> String {
    let d = &e.detail;
    let parts: Vec<String> = [d.parameter.clone(), d.line.clone(), d.order.map(order)].into_iter().flatten().collect();
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

/// The effects added, in order.
fn effects(out: &mut String, added: &[AddedEffect]) {
    h2(out, "Effects added");
    if added.is_empty() {
        para(out, "", "No effect was added: the base model is kept.");
        return;
    }
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
                Cell::num(fixed(e.delta_log_likelihood, 1), ""),
                Cell::num(fixed(e.bic_penalty, 1), ""),
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
        "Δ log-likelihood",
        "BIC cost",
        "lines explained (Hz)",
    ];
    out.push_str(&table(&head, &rows, |_| ""));
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
fn comparison(out: &mut String, r: &LoopReport) {
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
    out.push_str(
        "<h3>The run</h3>\n<table>\n<thead><tr><th></th><th>before</th><th>after</th></tr></thead>\n<tbody>\n",
    );
    for (label, cells) in rows {
        out.push_str(&labelled_row(&esc(label), &cells));
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
    cells.extend(pair(rms(b), rms(a), |v| fixed(v, 3), Better::Lower));
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
        out.push_str(&labelled_row(&label, &pair(shown(b), shown(a), |v| fixed(v, 3), Better::Lower)));
    }
    out.push_str("</tbody>\n</table>\n");
}

/// Effects or locations the data cannot resolve.
fn not_identifiable(out: &mut String, list: &[NotIdentifiable]) {
    h2(out, "Not identifiable");
    if list.is_empty() {
        para(out, "", "Nothing was found that the data cannot resolve.");
        return;
    }
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
    out.push_str(&table(&["kind", "location", "parameter", "statistic", "value", "why"], &rows, |_| ""));
}

/// Signatures that no effect of the library explains.
fn unexplained(out: &mut String, list: &[Signature]) {
    h2(out, "Unexplained");
    if list.is_empty() {
        para(out, "", "Nothing is left unexplained.");
        return;
    }
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
    out.push_str(&table(&["channel", "frequency (Hz)", "statistic", "value", "description"], &rows, |_| ""));
}

/// Every candidate evaluated, in a collapsed `<details>`.
fn trials(out: &mut String, list: &[Trial]) {
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

// ---------------------------------------------------------------------------------------------
// Plots: the page's figures

/// The plots section: innovations, spectra, NIS, and (with truth) the virtual sensing.
fn plots(out: &mut String, r: &LoopReport) -> Result<()> {
    h2(out, "Plots");
    out.push_str(
        "<p class=\"note\"><span class=\"before\">Orange: before</span> (the base model); \
         <span class=\"after\">blue: after</span> (the final model).</p>\n",
    );
    let figures = [
        (innovation_plot(r)?, "Normalised innovations e/√S per channel against time (min/max per pixel column), before and after on the same scale. A consistent model gives white noise of unit variance, nearly all within ±3."),
        (spectrum_plot(r)?, "Welch spectra of the normalised innovations (the DC bin left out: a bias shows in the time plot and the tables), log frequency up to the Nyquist frequency; the grey line is the level of white noise of unit variance. Dots mark the lines the loop detected, labelled by where they sit."),
        (nis_plot(r)?, "NIS per sample divided by the number of channels, moving average over 100 samples (log scale). A consistent model stays near 1."),
    ];
    for (svg, caption) in &figures {
        figure(out, svg, caption);
    }
    let rows = truth_rows(r);
    if rows.is_empty() {
        para(
            out,
            "note",
            "No truth_ columns in the data: the virtual-sensing estimates cannot be compared with the truth.",
        );
        return Ok(());
    }
    let zoom =
        "Virtual-sensing estimates against the truth (wide grey line) over about four periods at the end of the run.";
    figure(out, &zoom_plot(r, &rows)?, zoom);
    let error = "Virtual-sensing error (estimate − truth) over the run. The range is set by the run after its first 10 %: the filters' start-up may leave the plot.";
    figure(out, &error_plot(r, &rows)?, error);
    Ok(())
}

/// A `<figure>` with an inline SVG and a caption.
fn figure(out: &mut String, svg: &str, caption: &str) {
    out.push_str("<figure>\n");
    out.push_str(svg);
    out.push_str(&format!("<figcaption>{}</figcaption>\n</figure>\n", esc(caption)));
}

/// Indices of the virtual-sensing rows that have a truth series.
fn truth_rows(r: &LoopReport) -> Vec<usize> {
    let tr = &r.traces;
    (0..tr.rows.len()).filter(|&j| matches!(tr.truth.get(j), Some(Some(v)) if !v.is_empty())).collect()
}

/// `e/√S` of channel `i` of `run` (NaN where missing).
fn normalised(run: &Run, i: usize) -> Vec<f64> {
    match (run.innovation.get(i), run.variance.get(i)) {
        (Some(e), Some(s)) => e.iter().zip(s).map(|(e, s)| e / s.sqrt()).collect(),
        _ => Vec::new(),
    }
}

/// A half-range for symmetric plots: the largest finite `|v|`, padded, at least `floor`.
fn symmetric_limit<'a>(series: impl IntoIterator<Item = &'a [f64]>, floor: f64) -> f64 {
    let max = series.into_iter().flatten().filter(|v| v.is_finite()).fold(0.0f64, |m, v| m.max(v.abs()));
    (1.05 * max).max(floor)
}

/// Normalised innovations per channel against time: before on the left, after on the right,
/// on the same scale.
fn innovation_plot(r: &LoopReport) -> Result<String> {
    let tr = &r.traces;
    let mut panels = Vec::new();
    for (i, name) in tr.channels.iter().map(|c| &c.name).enumerate() {
        let (zb, za) = (normalised(&tr.before, i), normalised(&tr.after, i));
        let lim = symmetric_limit([zb.as_slice(), za.as_slice()], 4.0);
        for (z, label, colour) in [(&zb, "before", BEFORE), (&za, "after", AFTER)] {
            let mut p = Panel::new(format!("{name} — {label}"), "t (s)", "e/√S");
            p.x = Axis::span(&tr.t);
            p.y = Axis::Linear(-lim, lim);
            p.lines.push(Line::horizontal("±3", REFERENCE, p.x, 3.0));
            p.lines.push(Line::horizontal("", REFERENCE, p.x, -3.0));
            p.lines.push(Line::new(label, colour, min_max(&tr.t, z, PANEL_W as usize)));
            panels.push(p);
        }
    }
    grid_svg(&panels, 2, "Normalised innovations before and after")
}

/// Spectrum `psd` with bin width `bw` as (Hz, dB), the DC bin left out.
fn spectrum_db(psd: &[f32], bw: f64) -> Vec<(f64, f64)> {
    psd.iter().enumerate().skip(1).map(|(k, &p)| (k as f64 * bw, 10.0 * (p as f64).log10())).collect()
}

/// The level (dB re 1/Hz) of white noise of unit variance in a one-sided spectrum of `bins`
/// bins (DC to Nyquist) `bw` apart: `1 / f_Nyquist`.
fn white_level_db(bins: usize, bw: f64) -> f64 {
    -10.0 * (bins.saturating_sub(1) as f64 * bw).log10()
}

/// The detected lines of a channel as markers on its spectrum: (Hz, dB at the nearest bin,
/// class).
fn peak_marks(sig: Option<&ChannelSignature>, spectrum: &[(f64, f64)], bw: f64) -> Vec<(f64, f64, String)> {
    let Some(sig) = sig else { return Vec::new() };
    sig.peaks
        .iter()
        .filter_map(|p| {
            let k = (p.frequency_hz / bw).round() as usize;
            let db = spectrum.get(k.checked_sub(1)?)?.1;
            db.is_finite().then(|| (p.frequency_hz, db, p.class.clone()))
        })
        .collect()
}

/// Spectra of the normalised innovations, before and after overlaid, one panel per channel,
/// log frequency up to the Nyquist frequency, the detected lines marked.
fn spectrum_plot(r: &LoopReport) -> Result<String> {
    let mut panels = Vec::new();
    for (i, name) in r.traces.channels.iter().map(|c| &c.name).enumerate() {
        let mut p = Panel::new(format!("{name}: spectrum of e/√S"), "frequency (Hz)", "PSD (dB re 1/Hz)");
        let mut all = Vec::new();
        let mut white = None;
        for (s, label, colour, above) in [(&r.before, "before", BEFORE, true), (&r.after, "after", AFTER, false)] {
            let (bw, psd) = (s.bin_width_hz, s.spectra.get(i).map_or(&[][..], Vec::as_slice));
            let spec = spectrum_db(psd, bw);
            let marks = peak_marks(s.channels.iter().find(|c| &c.name == name), &spec, bw);
            p.markers.push(Markers { name: format!("lines {label}"), colour, points: marks, above });
            white = white.or((psd.len() > 1).then(|| white_level_db(psd.len(), bw)));
            all.extend(spec.iter().copied());
            p.lines.push(Line::new(label, colour, spec));
        }
        p.x = Axis::log_frequency(&all);
        p.y = Axis::linear(&all.iter().map(|v| v.1).chain(white).collect::<Vec<_>>()).headroom(0.15);
        if let Some(level) = white {
            p.lines.insert(0, Line::horizontal("", REFERENCE, p.x, level));
        }
        panels.push(p);
    }
    grid_svg(&panels, 2, "Spectra of the normalised innovations before and after")
}

/// Trailing moving average over `window` samples of the finite values of `v`, divided by
/// `scale` (NaN where the window has no finite value).
fn moving_average(v: &[f64], window: usize, scale: f64) -> Vec<f64> {
    let window = window.max(1);
    let (mut sum, mut count) = (0.0, 0usize);
    let mut out = Vec::with_capacity(v.len());
    for k in 0..v.len() {
        if v[k].is_finite() {
            sum += v[k];
            count += 1;
        }
        if k >= window && v[k - window].is_finite() {
            sum -= v[k - window];
            count -= 1;
        }
        out.push(if count > 0 { sum / count as f64 / scale } else { f64::NAN });
    }
    out
}

/// NIS per sample over the number of channels, smoothed, before and after, with the line at 1.
fn nis_plot(r: &LoopReport) -> Result<String> {
    let tr = &r.traces;
    let m = tr.channels.len().max(1) as f64;
    let title = format!("NIS / {} channels, moving average over {NIS_WINDOW} samples", tr.channels.len());
    let mut p = Panel::new(title, "t (s)", "NIS / channels");
    let width = 2 * PANEL_W as usize;
    let b = min_max(&tr.t, &moving_average(&tr.before.nis, NIS_WINDOW, m), width);
    let a = min_max(&tr.t, &moving_average(&tr.after.nis, NIS_WINDOW, m), width);
    p.x = Axis::span(&tr.t);
    p.y = Axis::log_around(b.iter().chain(&a).map(|v| v.1), 1.0);
    p.lines.push(Line::horizontal("1 (consistent)", REFERENCE, p.x, 1.0));
    p.lines.push(Line::new("before", BEFORE, b));
    p.lines.push(Line::new("after", AFTER, a));
    grid_svg(&[p], 1, "NIS before and after")
}

/// Where the zoom window of a truth series starts: about four periods before the end (its
/// mean crossings over the second half of the run give the period), at least 20 samples.
fn zoom_start(truth: &[f64]) -> usize {
    let n = truth.len();
    let half = &truth[n / 2..];
    let finite: Vec<f64> = half.iter().copied().filter(|v| v.is_finite()).collect();
    let mean = finite.iter().sum::<f64>() / finite.len().max(1) as f64;
    let crossings = finite.windows(2).filter(|w| (w[0] - mean).signum() != (w[1] - mean).signum()).count();
    let len = if crossings >= 2 { 4 * 2 * half.len() / crossings } else { n / 10 };
    n - len.clamp(20.min(n), half.len().max(20).min(n))
}

/// `series[from..]` against `t[from..]`, times `scale`.
fn tail(t: &[f64], series: Option<&Vec<f64>>, from: usize, scale: f64) -> Vec<(f64, f64)> {
    let Some(s) = series else { return Vec::new() };
    t.iter().zip(s).skip(from).map(|(&t, &v)| (t, v * scale)).collect()
}

/// Estimated against true displacement of each virtual-sensing row near the end of the run.
fn zoom_plot(r: &LoopReport, rows: &[usize]) -> Result<String> {
    let tr = &r.traces;
    let mut panels = Vec::new();
    for &j in rows {
        let truth = tr.truth[j].as_deref().unwrap_or_default();
        let from = zoom_start(truth);
        let row = &tr.rows[j];
        let scale = row.display_scale;
        let mut p =
            Panel::new(format!("{}: estimate and truth (end of the run)", row.name), "t (s)", &row.display_unit);
        let lines = [
            ("truth", TRUTH, 5, tail(&tr.t, tr.truth[j].as_ref(), from, scale)),
            ("before", BEFORE, 1, tail(&tr.t, tr.before.outputs.get(j), from, scale)),
            ("after", AFTER, 1, tail(&tr.t, tr.after.outputs.get(j), from, scale)),
        ];
        let values: Vec<f64> = lines.iter().flat_map(|l| l.3.iter().map(|v| v.1)).collect();
        p.x = Axis::span(&tr.t[from.min(tr.t.len())..]);
        p.y = Axis::linear(&values);
        for (label, colour, width, points) in lines {
            p.lines.push(Line { width, ..Line::new(label, colour, min_max_points(&points, PANEL_W as usize)) });
        }
        panels.push(p);
    }
    grid_svg(&panels, 2, "Virtual-sensing estimates against the truth")
}

/// `(est − truth) · scale` (NaN where either is missing).
fn error_series(est: Option<&Vec<f64>>, truth: &[f64], scale: f64) -> Vec<f64> {
    let Some(est) = est else { return Vec::new() };
    est.iter().zip(truth).map(|(e, t)| (e - t) * scale).collect()
}

/// The virtual-sensing error of each row over the run, before and after overlaid; the range
/// is set by the run after its first 10 % (the filters' start-up may leave the plot).
fn error_plot(r: &LoopReport, rows: &[usize]) -> Result<String> {
    let tr = &r.traces;
    let mut panels = Vec::new();
    for &j in rows {
        let truth = tr.truth[j].as_deref().unwrap_or_default();
        let row = &tr.rows[j];
        let scale = row.display_scale;
        let (eb, ea) =
            (error_series(tr.before.outputs.get(j), truth, scale), error_series(tr.after.outputs.get(j), truth, scale));
        let mut p =
            Panel::new(format!("{}: estimate − truth", row.name), "t (s)", &format!("error ({})", row.display_unit));
        let settled = |e: &[f64]| e.get(e.len() / 10..).unwrap_or_default().to_vec();
        let lim = symmetric_limit([settled(&eb).as_slice(), settled(&ea).as_slice()], 1e-3) * 1.15;
        p.x = Axis::span(&tr.t);
        p.y = Axis::Linear(-lim, lim);
        p.lines.push(Line::new("before", BEFORE, min_max(&tr.t, &eb, PANEL_W as usize)));
        p.lines.push(Line::new("after", AFTER, min_max(&tr.t, &ea, PANEL_W as usize)));
        panels.push(p);
    }
    grid_svg(&panels, 2, "Virtual-sensing error before and after")
}

// ---------------------------------------------------------------------------------------------
// Plots: series preparation

/// Decimates `(t, y)` for a plot `columns` pixels wide: the minimum and the maximum of each
/// column in time order, so spikes survive. A column without a finite value gives a NaN point,
/// which breaks the line.
fn min_max(t: &[f64], y: &[f64], columns: usize) -> Vec<(f64, f64)> {
    let points: Vec<(f64, f64)> = t.iter().copied().zip(y.iter().copied()).collect();
    min_max_points(&points, columns)
}

/// [`min_max`] on points.
fn min_max_points(points: &[(f64, f64)], columns: usize) -> Vec<(f64, f64)> {
    let n = points.len();
    let columns = columns.max(1);
    if n <= 2 * columns {
        return points.to_vec();
    }
    let mut out = Vec::with_capacity(2 * columns);
    for c in 0..columns {
        let bucket = &points[c * n / columns..(c + 1) * n / columns];
        let finite = || bucket.iter().enumerate().filter(|(_, p)| p.1.is_finite());
        let lo = finite().min_by(|a, b| a.1 .1.total_cmp(&b.1 .1)).map(|(i, _)| i);
        let hi = finite().max_by(|a, b| a.1 .1.total_cmp(&b.1 .1)).map(|(i, _)| i);
        match (lo, hi) {
            (Some(lo), Some(hi)) => {
                out.push(bucket[lo.min(hi)]);
                if lo != hi {
                    out.push(bucket[lo.max(hi)]);
                }
            }
            _ => out.push((bucket[0].0, f64::NAN)),
        }
    }
    out
}

/// The part of the segment `p`–`q` (in axis fractions) whose `y` lies in `0..=1`, if any;
/// an end inside is returned unchanged.
fn clip_segment(p: (f64, f64), q: (f64, f64)) -> Option<((f64, f64), (f64, f64))> {
    let dy = q.1 - p.1;
    let (t0, t1) = if dy == 0.0 {
        (0.0, 1.0)
    } else {
        let (a, b) = (-p.1 / dy, (1.0 - p.1) / dy);
        (a.min(b).max(0.0), a.max(b).min(1.0))
    };
    let inside = dy != 0.0 || (0.0..=1.0).contains(&p.1);
    let at = |t: f64| {
        if t <= 0.0 {
            p
        } else if t >= 1.0 {
            q
        } else {
            (p.0 + t * (q.0 - p.0), p.1 + t * dy)
        }
    };
    (inside && t0 <= t1).then(|| (at(t0), at(t1)))
}

/// The drawable runs of the polyline `points` on axes `x`, `y`: a non-finite point, or one
/// outside the x range, breaks the line; the line leaves and re-enters through the y range's
/// ends (clipped, as a plot should).
fn clip(points: &[(f64, f64)], x: Axis, y: Axis) -> Vec<Vec<(f64, f64)>> {
    let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut prev: Option<(f64, f64)> = None;
    for &(px, py) in points {
        let cur = x.fraction(px).filter(|f| (0.0..=1.0).contains(f)).zip(y.fraction(py));
        match (prev, cur) {
            (Some(p), Some(q)) => {
                if let Some((a, b)) = clip_segment(p, q) {
                    match runs.last_mut() {
                        Some(run) if run.last() == Some(&a) => run.push(b),
                        _ => runs.push(vec![a, b]),
                    }
                }
            }
            (None, Some(q)) if (0.0..=1.0).contains(&q.1) => runs.push(vec![q]),
            _ => {}
        }
        prev = cur;
    }
    runs.iter().map(|run| run.iter().map(|&(fx, fy)| (x.value(fx), y.value(fy))).collect()).collect()
}

// ---------------------------------------------------------------------------------------------
// Plots: drawing

/// A drawing area of the SVG backend.
type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// A chart on the SVG backend.
type Chart<'a, 'b, X, Y> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<X, Y>>;

/// An axis: its scale and range.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Axis {
    /// Linear from the first to the second value.
    Linear(f64, f64),
    /// Logarithmic from the first to the second value (both positive).
    Log(f64, f64),
}

impl Axis {
    /// The smallest and largest finite values of `v` (None when there are none).
    fn extent(v: &[f64]) -> Option<(f64, f64)> {
        let (lo, hi) = v
            .iter()
            .filter(|x| x.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| (lo.min(x), hi.max(x)));
        (lo <= hi).then_some((lo, hi))
    }

    /// A linear axis exactly over the finite values of `v` (time axes).
    fn span(v: &[f64]) -> Self {
        match Self::extent(v) {
            Some((lo, hi)) if hi > lo => Axis::Linear(lo, hi),
            Some((lo, _)) => Axis::Linear(lo - 0.5, lo + 0.5),
            None => Axis::Linear(0.0, 1.0),
        }
    }

    /// A linear axis over the finite values of `v`, padded by 5 % (`0..1` when there are none).
    fn linear(v: &[f64]) -> Self {
        match Self::extent(v) {
            Some((lo, hi)) if hi > lo => Axis::Linear(lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo)),
            Some((lo, _)) => Axis::Linear(lo - lo.abs().max(1.0) * 0.5, lo + lo.abs().max(1.0) * 0.5),
            None => Axis::Linear(0.0, 1.0),
        }
    }

    /// The axis with its end raised by `fraction` of its length (room for labels over the
    /// highest points).
    fn headroom(self, fraction: f64) -> Self {
        match self {
            Axis::Linear(a, b) => Axis::Linear(a, b + fraction * (b - a)),
            Axis::Log(a, b) => Axis::Log(a, b * (b / a).powf(fraction)),
        }
    }

    /// A log axis over the positive finite values, always including `keep` (with a margin).
    fn log_around(v: impl IntoIterator<Item = f64>, keep: f64) -> Self {
        let (lo, hi) = v
            .into_iter()
            .filter(|x| x.is_finite() && *x > 0.0)
            .fold((keep, keep), |(lo, hi), x| (lo.min(x), hi.max(x)));
        Axis::Log(lo / 1.5, hi * 1.5)
    }

    /// A log frequency axis from the lowest to the highest frequency of `spectrum`.
    fn log_frequency(spectrum: &[(f64, f64)]) -> Self {
        let f: Vec<f64> = spectrum.iter().map(|p| p.0).filter(|f| *f > 0.0).collect();
        match Self::extent(&f) {
            Some((lo, hi)) if hi > lo => Axis::Log(lo, hi),
            _ => Axis::Log(1.0, 1000.0),
        }
    }

    /// The range's ends.
    fn ends(self) -> (f64, f64) {
        match self {
            Axis::Linear(a, b) | Axis::Log(a, b) => (a, b),
        }
    }

    /// Where `v` sits along the axis (0 at the start, 1 at the end; outside for values out of
    /// range); None when the axis cannot place it (not finite, or not positive on a log axis).
    fn fraction(self, v: f64) -> Option<f64> {
        let f = match self {
            Axis::Linear(a, b) => (v - a) / (b - a),
            Axis::Log(a, b) if v > 0.0 => (v / a).ln() / (b / a).ln(),
            Axis::Log(..) => return None,
        };
        f.is_finite().then_some(f)
    }

    /// The value at fraction `f` along the axis (the inverse of [`Axis::fraction`]).
    fn value(self, f: f64) -> f64 {
        match self {
            Axis::Linear(a, b) => a + f * (b - a),
            Axis::Log(a, b) => a * (b / a).powf(f),
        }
    }
}

/// One line of a panel.
struct Line {
    /// Legend entry (none when empty).
    name: String,
    /// Colour.
    colour: RGBColor,
    /// Stroke width, px.
    width: u32,
    /// Points; a non-finite point breaks the line, which is clipped to the panel.
    points: Vec<(f64, f64)>,
}

impl Line {
    /// A line one pixel wide.
    fn new(name: &str, colour: RGBColor, points: Vec<(f64, f64)>) -> Self {
        Self { name: name.into(), colour, width: 1, points }
    }

    /// A horizontal reference line at `y` across `x`.
    fn horizontal(name: &str, colour: RGBColor, x: Axis, y: f64) -> Self {
        let (a, b) = x.ends();
        Self::new(name, colour, vec![(a, y), (b, y)])
    }
}

/// Labelled markers (the detected spectral lines).
struct Markers {
    /// Legend entry.
    name: String,
    /// Colour.
    colour: RGBColor,
    /// (x, y, label).
    points: Vec<(f64, f64, String)>,
    /// Labels above the marker (else below).
    above: bool,
}

/// What one panel shows.
struct Panel {
    /// Caption.
    title: String,
    /// X axis.
    x: Axis,
    /// X axis description (with unit).
    x_desc: String,
    /// Y axis.
    y: Axis,
    /// Y axis description (with unit).
    y_desc: String,
    /// Lines, drawn in order.
    lines: Vec<Line>,
    /// Markers, drawn over the lines.
    markers: Vec<Markers>,
}

impl Panel {
    /// An empty panel with linear `0..1` axes.
    fn new(title: String, x_desc: &str, y_desc: &str) -> Self {
        Self {
            title,
            x: Axis::Linear(0.0, 1.0),
            x_desc: x_desc.into(),
            y: Axis::Linear(0.0, 1.0),
            y_desc: y_desc.into(),
            lines: Vec::new(),
            markers: Vec::new(),
        }
    }

    /// Draws the panel on `area`.
    fn draw(&self, area: &Area<'_>) -> Result<()> {
        let lin = |a: f64, b: f64| RangedCoordf64::from(a..b);
        let log = |a: f64, b: f64| LogCoord::from((a..b).log_scale());
        match (self.x, self.y) {
            (Axis::Linear(a, b), Axis::Linear(c, d)) => self.draw_on(area, lin(a, b), lin(c, d)),
            (Axis::Log(a, b), Axis::Linear(c, d)) => self.draw_on(area, log(a, b), lin(c, d)),
            (Axis::Linear(a, b), Axis::Log(c, d)) => self.draw_on(area, lin(a, b), log(c, d)),
            (Axis::Log(a, b), Axis::Log(c, d)) => self.draw_on(area, log(a, b), log(c, d)),
        }
    }

    /// Draws the panel with the coordinate types `x`, `y`: mesh, lines, markers, legend.
    fn draw_on<X, Y>(&self, area: &Area<'_>, x: X, y: Y) -> Result<()>
    where
        X: Ranged<ValueType = f64> + ValueFormatter<f64>,
        Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let mut chart = ChartBuilder::on(area)
            .caption(&self.title, (FONT, 15))
            .margin(6)
            .margin_right(14)
            .x_label_area_size(36)
            .y_label_area_size(58)
            .build_cartesian_2d(x, y)?;
        chart
            .configure_mesh()
            .x_desc(&self.x_desc)
            .y_desc(&self.y_desc)
            .x_labels(8)
            .y_labels(6)
            .max_light_lines(3)
            .x_label_formatter(&tick)
            .y_label_formatter(&tick)
            .label_style((FONT, 12))
            .axis_desc_style((FONT, 13))
            .bold_line_style(RGBColor(225, 225, 225))
            .light_line_style(RGBColor(244, 244, 244))
            .draw()?;
        let mut legend = false;
        for line in &self.lines {
            legend |= self.draw_line(&mut chart, line)?;
        }
        for m in &self.markers {
            legend |= self.draw_markers(&mut chart, m)?;
        }
        if legend {
            chart
                .configure_series_labels()
                .position(self.legend_corner())
                .label_font((FONT, 12))
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(190, 190, 190))
                .draw()?;
        }
        Ok(())
    }

    /// Draws `line` (one path per drawable run); true when it added a legend entry.
    fn draw_line<X, Y>(&self, chart: &mut Chart<'_, '_, X, Y>, line: &Line) -> Result<bool>
    where
        X: Ranged<ValueType = f64>,
        Y: Ranged<ValueType = f64>,
    {
        let runs = clip(&line.points, self.x, self.y);
        let (colour, width) = (line.colour, line.width);
        for (k, run) in runs.iter().enumerate() {
            let drawn = chart.draw_series(LineSeries::new(run.iter().copied(), colour.stroke_width(width)))?;
            if k == 0 && !line.name.is_empty() {
                drawn.label(&line.name).legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(width.clamp(2, 4)))
                });
            }
        }
        Ok(!runs.is_empty() && !line.name.is_empty())
    }

    /// Draws labelled markers; true when it added a legend entry.
    fn draw_markers<X, Y>(&self, chart: &mut Chart<'_, '_, X, Y>, m: &Markers) -> Result<bool>
    where
        X: Ranged<ValueType = f64>,
        Y: Ranged<ValueType = f64>,
    {
        let colour = m.colour;
        let dy = if m.above { -18 } else { 5 };
        let style = (FONT, 12).into_font().color(&colour);
        let inside = |axis: Axis, v: f64| axis.fraction(v).is_some_and(|f| (0.0..=1.0).contains(&f));
        let points: Vec<&(f64, f64, String)> =
            m.points.iter().filter(|(x, y, _)| inside(self.x, *x) && inside(self.y, *y)).collect();
        if points.is_empty() {
            return Ok(false);
        }
        chart
            .draw_series(points.iter().map(|(x, y, label)| {
                EmptyElement::at((*x, *y))
                    + Circle::new((0, 0), 4, colour.filled())
                    + Text::new(label.clone(), (5, dy), style.clone())
            }))?
            .label(&m.name)
            .legend(move |(x, y)| Circle::new((x + 9, y), 4, colour.filled()));
        Ok(true)
    }

    /// The corner for the legend with the fewest points of the lines under it (upper right on
    /// a tie).
    fn legend_corner(&self) -> SeriesLabelPosition {
        let corners = [
            (SeriesLabelPosition::UpperRight, (0.65, 1.0), (0.6, 1.0)),
            (SeriesLabelPosition::UpperLeft, (0.0, 0.35), (0.6, 1.0)),
            (SeriesLabelPosition::LowerRight, (0.65, 1.0), (0.0, 0.4)),
            (SeriesLabelPosition::LowerLeft, (0.0, 0.35), (0.0, 0.4)),
        ];
        let points: Vec<(f64, f64)> = self
            .lines
            .iter()
            .flat_map(|l| &l.points)
            .filter_map(|&(x, y)| self.x.fraction(x).zip(self.y.fraction(y)))
            .collect();
        let under = |(fx, fy): ((f64, f64), (f64, f64))| {
            points.iter().filter(|(x, y)| (fx.0..=fx.1).contains(x) && (fy.0..=fy.1).contains(y)).count()
        };
        corners.into_iter().min_by_key(|c| under((c.1, c.2))).map_or(SeriesLabelPosition::UpperRight, |c| c.0)
    }
}

/// An axis tick label: short, without trailing zeros.
fn tick(v: &f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        return "0".into();
    }
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.0e}");
    }
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Draws `panels` on a grid `cols` panels wide into one SVG (`label` is its accessible name).
fn grid_svg(panels: &[Panel], cols: usize, label: &str) -> Result<String> {
    let cols = cols.clamp(1, panels.len().max(1));
    let rows = panels.len().div_ceil(cols).max(1);
    let size = (2 * PANEL_W, PANEL_H * rows as u32);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE)?;
        for (area, panel) in root.split_evenly((rows, cols)).iter().zip(panels) {
            panel.draw(area)?;
        }
        root.present()?;
    }
    Ok(svg.replacen("<svg ", &format!("<svg role=\"img\" aria-label=\"{}\" ", esc(label)), 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::residual_loop::search::{Channel, EffectKind, Traces};
    use crate::residual_loop::signature::PeakSignature;
    use std::collections::BTreeMap;

    /// A run of `n` samples on two channels and one row, with gaps (NaN).
    fn run(n: usize, offset: f64) -> Run {
        let wave = |k: usize, f: f64| (k as f64 * f).sin();
        let gap = |k: usize, v: f64| if (500..540).contains(&k) { f64::NAN } else { v };
        Run {
            innovation: (0..2)
                .map(|i| (0..n).map(|k| gap(k, 1e-6 * (wave(k, 0.7 + i as f64) + offset))).collect())
                .collect(),
            variance: vec![vec![1e-12; n]; 2],
            nis: (0..n).map(|k| gap(k, 2.0 + offset * offset)).collect(),
            outputs: vec![(0..n).map(|k| gap(k, 1e-4 * wave(k, 0.088) + 1e-6 * offset)).collect()],
            ..Run::default()
        }
    }

    /// A summary of a run: `rms` m on both channels, one spectral line of class `class`.
    fn summary(rms: f64, class: &str) -> RunSummary {
        let peak =
            PeakSignature { frequency_hz: 14.0, prominence_db: 20.0, class: class.into(), order: None, line: None };
        let channel = |name: &str| ChannelSignature {
            name: name.into(),
            mean: 0.0,
            standard_error: 1.0,
            z: 0.5,
            rms,
            nis: 1.0,
            nis_halves: [1.0, 1.0],
            step: None,
            whiteness_p: 0.5,
            peaks: vec![peak.clone()],
        };
        let mut spectrum: Vec<f32> = (0..513).map(|k| 1e-3 * (1.0 + (k % 7) as f32)).collect();
        spectrum[100] = f32::NAN;
        spectrum[101] = 0.0;
        RunSummary {
            innovation_rms: [("n5_x".to_string(), rms), ("n5_y".to_string(), rms)].into(),
            nis_mean: 1.0,
            nis_consistent: true,
            whiteness_p: 0.5,
            consistent: false,
            error_rms: BTreeMap::from([("n12_x".to_string(), rms)]),
            log_likelihood: -10.0,
            channels: vec![channel("n5_x"), channel("n5_y")],
            bin_width_hz: 1000.0 / 1024.0,
            spectra: vec![spectrum, Vec::new()],
        }
    }

    /// A hand-made report with gaps, an empty spectrum and markup in its texts.
    fn synthetic() -> LoopReport {
        let n = 3000;
        LoopReport {
            schema_version: crate::residual_loop::search::SCHEMA_VERSION,
            system: "rotor <test>".into(),
            source: Default::default(),
            effects_added: vec![AddedEffect {
                kind: EffectKind::SensorScale,
                location: "n5_x".into(),
                value: 1.05,
                unit: "1".into(),
                detail: Default::default(),
                explains: vec![14.0],
                delta_log_likelihood: 100.0,
                bic_penalty: 4.7,
            }],
            before: summary(2e-6, "1x & <friends>"),
            after: summary(1e-6, "natural 0"),
            not_identifiable: Vec::new(),
            unexplained: vec![Signature {
                channel: "n5_y".into(),
                frequency_hz: Some(14.0),
                statistic: "peak_db".into(),
                value: 20.0,
                description: "a \"line\" <here>".into(),
            }],
            refused: Vec::new(),
            trials: Vec::new(),
            stopped: "the innovations are white".into(),
            section: Default::default(),
            traces: Traces {
                t: (0..n).map(|k| k as f64 * 1e-3).collect(),
                channels: ["n5_x", "n5_y"].map(|n| Channel::new(n, "m").shown_in(1e6, "µm")).to_vec(),
                rows: vec![Channel::new("n12_x", "m").shown_in(1e6, "µm")],
                truth: vec![Some((0..n).map(|k| 1e-4 * (k as f64 * 0.088).sin()).collect())],
                before: run(n, 3.0),
                after: run(n, 0.0),
            },
        }
    }

    #[test]
    fn synthetic_page_with_gaps_renders() {
        let html = render(&synthetic()).unwrap();
        assert_eq!(html.matches("<svg").count(), 5);
        assert_eq!(html.matches("</svg>").count(), 5);
        assert!(!html.contains("NaN"));
        assert!(html.contains("<title>Residual loop — rotor &lt;test&gt;</title>"));
        assert!(html.contains(">\n1x &amp; &lt;friends&gt;\n</text>"), "the peak's class labels its marker");
        assert!(html.contains("<td>a &quot;line&quot; &lt;here&gt;</td>"));
        assert!(html.contains("<td class=\"num\">1.050 (+5.0 %)</td>"));
        assert!(html.contains("<td class=\"num\">2.000</td><td class=\"num better\">1.000</td>"));
        assert!(!html.contains("<script") && !html.contains("src=") && !html.contains("href="));
    }

    #[test]
    fn escapes_markup() {
        assert_eq!(esc("<a href=\"x\">&'"), "&lt;a href=&quot;x&quot;&gt;&amp;&#39;");
    }

    #[test]
    fn values_in_their_units() {
        assert_eq!(value_with_unit(1.05, "1"), "1.050 (+5.0 %)");
        assert_eq!(value_with_unit(0.98, "1"), "0.980 (-2.0 %)");
        assert_eq!(value_with_unit(20e-6, "m"), "20.00 µm");
        assert_eq!(value_with_unit(2.5e-4, "s"), "250.0 µs");
        assert_eq!(value_with_unit(f64::NAN, "N"), "–");
        assert_eq!(order(2.0), "2x");
        assert_eq!(order(3.5721), "3.572x");
        assert_eq!(p_value(0.0), "0");
        assert_eq!(p_value(2.5e-7), "2.5e-7");
        assert_eq!(p_value(0.25), "0.250");
    }

    #[test]
    fn min_max_keeps_spikes_and_breaks_at_gaps() {
        let t: Vec<f64> = (0..10_000).map(|k| k as f64).collect();
        let mut y = vec![0.0; 10_000];
        y[1234] = 50.0;
        y[7000] = -40.0;
        y[5000..5100].fill(f64::NAN);
        let d = min_max(&t, &y, 100);
        assert!(d.len() <= 200);
        assert!(d.contains(&(1234.0, 50.0)) && d.contains(&(7000.0, -40.0)));
        assert_eq!(d.iter().filter(|p| p.1.is_nan()).count(), 1);
        let runs = clip(&d, Axis::Linear(0.0, 10_000.0), Axis::Linear(-50.0, 50.0));
        assert_eq!(runs.len(), 2);
        assert_eq!(runs.iter().map(Vec::len).sum::<usize>(), d.len() - 1);
        // Short series are left alone.
        assert_eq!(min_max(&t[..10], &y[..10], 100).len(), 10);
    }

    #[test]
    fn lines_leave_and_reenter_through_the_border() {
        let points = [(0.0, 0.0), (1.0, 2.0), (2.0, 0.0), (3.0, f64::NAN), (4.0, 0.5), (5.0, 0.5), (6.0, -3.0)];
        let runs = clip(&points, Axis::Linear(0.0, 6.0), Axis::Linear(-1.0, 1.0));
        let expected = [
            vec![(0.0, 0.0), (0.5, 1.0)],
            vec![(1.5, 1.0), (2.0, 0.0)],
            vec![(4.0, 0.5), (5.0, 0.5), (5.0 + 3.0 / 7.0, -1.0)],
        ];
        assert_eq!(runs.len(), expected.len());
        for (run, want) in runs.iter().zip(&expected) {
            assert_eq!(run.len(), want.len());
            for (p, q) in run.iter().zip(want) {
                assert!((p.0 - q.0).abs() < 1e-9 && (p.1 - q.1).abs() < 1e-9, "{runs:?}");
            }
        }
        // Log axes: non-positive values break the line; x outside the range too.
        let points = [(1.0, 1.0), (2.0, 0.0), (3.0, 10.0), (4.0, 10.0), (9.0, 1.0)];
        let runs = clip(&points, Axis::Linear(0.0, 5.0), Axis::Log(0.1, 100.0));
        assert_eq!(runs.len(), 2, "{runs:?}");
        assert_eq!(runs[1].len(), 2);
        assert!((runs[1][0].1 - 10.0).abs() < 1e-9);
    }

    #[test]
    fn moving_average_skips_missing_samples() {
        let v = [2.0, f64::NAN, 4.0, 6.0, f64::NAN, f64::NAN, f64::NAN];
        let m = moving_average(&v, 2, 2.0);
        assert_eq!(m[0], 1.0);
        assert_eq!(m[1], 1.0);
        assert_eq!(m[2], 2.0);
        assert_eq!(m[3], 2.5);
        assert_eq!(m[4], 3.0);
        assert!(m[6].is_nan());
    }

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

    #[test]
    fn zoom_window_spans_a_few_periods() {
        // 1 kHz, 10 Hz sine over 3 s: four periods are 400 samples.
        let truth: Vec<f64> =
            (0..3000).map(|k| (std::f64::consts::TAU * 10.0 * k as f64 / 1000.0 + 0.3).sin()).collect();
        let from = zoom_start(&truth);
        assert!((380..=420).contains(&(3000 - from)), "{from}");
        assert_eq!(zoom_start(&[f64::NAN; 5]), 0);
    }

    #[test]
    fn panel_with_nan_and_log_axis_renders() {
        let mut p = Panel::new("a <test> & more".into(), "f (Hz)", "dB");
        p.x = Axis::Log(1.0, 500.0);
        p.y = Axis::Linear(-10.0, 10.0);
        p.lines.push(Line::new(
            "x",
            AFTER,
            vec![(0.0, 1.0), (2.0, f64::NAN), (3.0, 2.0), (4.0, 50.0), (f64::NAN, 1.0)],
        ));
        p.markers.push(Markers {
            name: "m".into(),
            colour: BEFORE,
            points: vec![(14.0, 3.0, "1x".into())],
            above: true,
        });
        let svg = grid_svg(&[p], 1, "test").unwrap();
        assert!(svg.starts_with("<svg role=\"img\""));
        assert!(svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("a &lt;test&gt; &amp; more") && svg.contains(">\n1x\n</text>"));
        assert!(!svg.contains("NaN"));
    }
}
