//! What the loop prints and writes: the summary table of the command line, and the report
//! files (`report.json`, `report.html`) of a report directory.

use crate::io::output::write_atomic;
use crate::residual_loop::{Channel, LoopReport, RunSummary};
use anyhow::{Context, Result};
use std::path::Path;

/// The files of a report directory.
pub const REPORT_FILES: [&str; 2] = ["report.json", "report.html"];

/// Writes `dir/report.json` and `dir/report.html`, creating `dir` if needed; both are made
/// before either is written, and each is written whole ([`write_atomic`]).
pub fn write_report(report: &LoopReport, dir: &Path) -> Result<()> {
    let json = serde_json::to_string_pretty(report)?;
    let html = super::html::render(report)?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for (name, text) in REPORT_FILES.iter().zip([json, html]) {
        let path = dir.join(name);
        write_atomic(&path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// The summary the CLI prints: effects, then a before/after table.
pub fn summary_table(r: &LoopReport) -> String {
    let mut s = String::new();
    s.push_str(&format!("{}: {} effect(s) added; {}\n", r.system, r.effects_added.len(), r.stopped));
    for (label, text) in &r.section.lines {
        s.push_str(&format!("  {label} {text}\n"));
    }
    for e in &r.effects_added {
        let order = e.detail.order.map(|o| format!(" at {o}x")).unwrap_or_default();
        let what = e.detail.parameter.as_ref().or(e.detail.line.as_ref()).map(|p| format!(" {p}")).unwrap_or_default();
        let from = e.detail.onset_s.map(|o| format!(" from {o:.3} s")).unwrap_or_default();
        let mut evidence = match &e.detail.named_by {
            Some(test) => format!("named by {test}"),
            None => format!("Δ log-likelihood {:.1}, BIC cost {:.1}", e.delta_log_likelihood, e.bic_penalty),
        };
        if let Some(why) = &e.detail.not_modelled {
            evidence.push_str(&format!("; {why}"));
        }
        s.push_str(&format!(
            "  + {}{} at {}{}{}: {}{} ({evidence})\n",
            e.kind,
            order,
            e.location,
            what,
            from,
            show_value(e.value, &e.unit),
            e.interval.map(|i| format!(", 95 % {}", show_interval(i, &e.unit))).unwrap_or_default(),
        ));
    }
    if let Some(t) = &r.tuning {
        s.push_str(&format!(
            "  tuned: process noise of {} ×{:.4} (Δ log-likelihood {:.1}, cost {:.1})\n",
            t.what, t.scale, t.delta_log_likelihood, t.penalty
        ));
    }
    let row = |name: &str, f: &dyn Fn(&RunSummary) -> String| {
        format!("  {name:<28} {:>14} {:>14}\n", f(&r.before), f(&r.after))
    };
    s.push_str(&format!("  {:<28} {:>14} {:>14}\n", "", "before", "after"));
    s.push_str(&row("log-likelihood", &|x| format!("{:.1}", x.log_likelihood)));
    s.push_str(&row("NIS mean / channel", &|x| format!("{:.3}", x.nis_mean)));
    s.push_str(&row("whiteness p (min)", &|x| format!("{:.2e}", x.whiteness_p)));
    for k in r.before.innovation_rms.keys() {
        let (scale, unit) = shown(&r.traces.channels, k);
        s.push_str(&row(&format!("innovation RMS {k} {unit}"), &|x| readable(x.innovation_rms[k] * scale)));
    }
    for k in r.before.error_rms.keys() {
        let (scale, unit) = shown(&r.traces.rows, k);
        s.push_str(&row(&format!("error RMS {k} {unit}"), &|x| {
            x.error_rms.get(k).map_or("-".into(), |v| readable(v * scale))
        }));
    }
    for k in r.before.metrics.keys() {
        s.push_str(&row(k, &|x| x.metrics.get(k).map_or("-".into(), |v| readable(*v))));
    }
    for u in &r.not_identifiable {
        let what = u.parameter.as_ref().map(|p| format!(" {p}")).unwrap_or_default();
        s.push_str(&format!("  not identifiable: {} {}{}: {}\n", u.kind, u.location, what, u.reason));
    }
    for u in &r.unexplained {
        s.push_str(&format!("  unexplained: {}: {}\n", u.channel, u.description));
    }
    s
}

/// A value with its unit as people read it: factors as `×1.0500 (+5.00 %)`, metres in µm,
/// seconds in ms.
pub fn show_value(v: f64, unit: &str) -> String {
    match unit {
        "1" => format!("×{v:.4} ({:+.2} %)", (v - 1.0) * 100.0),
        "m" => format!("{:.3} µm", v * 1e6),
        "s" => format!("{:.3} ms", v * 1e3),
        _ => format!("{v:.4} {unit}"),
    }
}

/// An interval `[a, b]` of a value in `unit`, in [`show_value`]'s units.
///
/// ```
/// use edgekf_sim::report::text::show_interval;
/// assert_eq!(show_interval([0.9, 1.1], "1"), "×0.9000 … ×1.1000");
/// assert_eq!(show_interval([1e-6, 2e-6], "m"), "1.000 … 2.000 µm");
/// ```
pub fn show_interval([a, b]: [f64; 2], unit: &str) -> String {
    match unit {
        "1" => format!("×{a:.4} … ×{b:.4}"),
        "m" => format!("{:.3} … {:.3} µm", a * 1e6, b * 1e6),
        "s" => format!("{:.3} … {:.3} ms", a * 1e3, b * 1e3),
        _ => format!("{a:.4} … {b:.4} {unit}"),
    }
}

/// The display scale and unit of `name` among `list` (SI, unlabelled, if it is not there).
pub(crate) fn shown<'a>(list: &'a [Channel], name: &str) -> (f64, &'a str) {
    list.iter().find(|c| c.name == name).map_or((1.0, ""), |c| (c.display_scale, c.display_unit.as_str()))
}

/// Three decimals where that keeps three significant digits, else scientific notation.
fn readable(v: f64) -> String {
    if (1e-2..1e5).contains(&v.abs()) {
        format!("{v:.3}")
    } else {
        format!("{v:.3e}")
    }
}
