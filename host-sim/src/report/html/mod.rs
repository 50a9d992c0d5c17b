//! `report.html` of `edgekf loop <system>`: one self-contained page (inline CSS and SVG; no
//! scripts, external styles, fonts or images) for people to read what the residual loop found:
//! why it stopped, the effects it added, the innovation statistics before and after, plots of
//! the normalised innovations, their spectra, the NIS and the virtual-sensing estimates
//! against the truth, and what is left unexplained or not identifiable.
//!
//! This module is the page: its head and style sheet, the verdict, and the order of the
//! sections. `tables` writes the tables, `figures` the plots (with the
//! [plot kit](crate::report::plot)), `format` the numbers; every text taken from the report
//! is escaped.
//!
//! ```no_run
//! # fn write(report: &edgekf_sim::residual_loop::LoopReport) -> anyhow::Result<()> {
//! let page = edgekf_sim::report::html::render(report)?;
//! std::fs::write("report/report.html", page)?;
//! # Ok(())
//! # }
//! ```

mod figures;
mod findings;
mod format;
mod tables;

use crate::report::escape::escape as esc;
use crate::residual_loop::{LoopReport, RunSummary};
use anyhow::Result;
use figures::plots;
use format::capitalised;
use tables::{comparison, corrections, effects, not_identifiable, refused, trials, unexplained};

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
    findings::findings(&mut html, report);
    effects(&mut html, &report.effects_added);
    comparison(&mut html, report);
    plots(&mut html, report)?;
    corrections(&mut html, &report.corrections);
    not_identifiable(&mut html, &report.not_identifiable);
    refused(&mut html, &report.refused);
    unexplained(&mut html, &report.unexplained);
    trials(&mut html, &report.trials);
    html.push_str(&format!(
        "<p class=\"note\">Written by edgekf {}.</p>\n</main>\n</body>\n</html>\n",
        env!("CARGO_PKG_VERSION")
    ));
    Ok(html)
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

#[cfg(test)]
mod tests {
    use super::*;

    use crate::residual_loop::filter::Run;
    use crate::residual_loop::signature::{ChannelSignature, PeakSignature, Signature};
    use crate::residual_loop::{AddedEffect, Channel, EffectKind, Traces};
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
            rms_standard_error: 0.01 * rms,
            nis: 1.0,
            nis_halves: [1.0, 1.0],
            step: None,
            whiteness_p: 0.5,
            peaks: vec![peak.clone()],
            order_lines: Vec::new(),
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
            metrics: BTreeMap::from([("peak_error_pct".to_string(), rms * 1e6)]),
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
            schema_version: crate::residual_loop::SCHEMA_VERSION,
            system: "rotor <test>".into(),
            source: Default::default(),
            tuning: None,
            effects_added: vec![AddedEffect {
                kind: EffectKind::SensorScale,
                location: "n5_x".into(),
                value: 1.05,
                unit: "1".into(),
                detail: crate::residual_loop::EffectDetail { onset_s: Some(2.4), ..Default::default() },
                explains: vec![14.0],
                delta_log_likelihood: 100.0,
                bic_penalty: 4.7,
                interval: Some([1.04, 1.06]),
            }],
            corrections: vec![crate::residual_loop::EffectCorrection {
                effect: "sensor_scale at n5_x".into(),
                correction: crate::residual_loop::Correction::model([crate::io::config_edit::ConfigEdit::new(
                    "sensor[node=5].scale",
                    crate::io::config_edit::Op::Scale(1.05),
                )]),
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
            refused: vec![crate::residual_loop::report::Refused {
                kind: EffectKind::Parameter,
                location: "disk 12".into(),
                parameter: Some("mass".into()),
                value: Some(1.3),
                reason: "at the bound <1.3>".into(),
            }],
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
        assert!(html.contains("from 2.400 s"), "a change-point effect shows its onset");
        // A system's own figures are rows of the run's table, to four significant digits.
        assert!(html.contains("peak error pct</th><td class=\"num\">2.000</td><td class=\"num better\">1.000</td>"));
        // What was refused and how each effect enters the configuration are on the page too.
        assert!(html.contains("<td>at the bound &lt;1.3&gt;</td>") && html.contains("<td>mass</td>"));
        assert!(html.contains("<td>sensor[node=5].scale ×1.050</td>") && html.contains("<td>into the model</td>"));
        assert!(html.contains("<td class=\"num\">2.000</td><td class=\"num better\">1.000</td>"));
        assert!(!html.contains("<script") && !html.contains("src=") && !html.contains("href="));
    }
}
