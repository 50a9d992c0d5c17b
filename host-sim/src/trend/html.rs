//! `trend.html`: the history for people, one self-contained page as `report.html` is (inline
//! CSS and SVG, no scripts): each indicator against the recordings' start, drawn with the
//! project's [plot kit](crate::report::plot), a table of the effects (first recording, rate of
//! change) and a table of the recordings (with those that failed and why).

use super::{Clock, Trend};
use crate::report::escape::escape as esc;
use crate::report::plot::{Axis, Figure, Line, Marker, Markers, Panel, RGBColor, Shape};
use anyhow::Result;

/// Colour of an indicator's series.
const SERIES: RGBColor = RGBColor(31, 100, 180);
/// Colour of the base model's NIS ("before", as in `report.html`).
const BEFORE: RGBColor = RGBColor(228, 108, 10);
/// Width of one panel, px; two side by side make the figure's width.
const PANEL_W: u32 = 480;
/// Height of one panel, px.
const PANEL_H: u32 = 220;

/// The page's style sheet (inline).
const STYLE: &str = "body{font-family:system-ui,-apple-system,\"Segoe UI\",Roboto,Helvetica,Arial,sans-serif;margin:0;color:#222;line-height:1.4}
main{max-width:980px;margin:0 auto;padding:1em}
h2{font-size:1.25em;border-bottom:1px solid #ddd;padding-bottom:.2em;margin-top:1.8em}
table{border-collapse:collapse;margin:.5em 0;font-size:.92em}
th,td{border:1px solid #ddd;padding:.25em .55em;text-align:left;vertical-align:top}
thead th{background:#f4f4f4}
td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
.bad{color:#b42318;font-weight:bold}
.note{color:#555;font-size:.9em}
svg{max-width:100%;height:auto;display:block}
";

/// Renders the history `trend` of `system` as a page; `failed` lists the recordings that gave
/// no report (name, why).
pub fn render(system: &str, trend: &Trend, failed: &[(String, String)]) -> Result<String> {
    let mut out = String::with_capacity(1 << 16);
    let title = format!("History — {system}");
    out.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    out.push_str(&format!("<title>{}</title>\n<style>\n{STYLE}</style>\n</head>\n<body>\n<main>\n", esc(&title)));
    out.push_str(&format!("<h1>{}</h1>\n", esc(&title)));
    out.push_str(&format!(
        "<p>{} recording{} in order of their start; {}.</p>\n",
        trend.recordings.len(),
        if trend.recordings.len() == 1 { "" } else { "s" },
        match trend.clock {
            Clock::Absolute => "t is each recording's start, s since 1970-01-01 UTC",
            Clock::Index => "their t starts at 0, so they are ordered by file name and t is the recording's number",
        }
    ));
    effects_table(&mut out, trend);
    out.push_str("<h2>Indicators</h2>\n");
    out.push_str(&plots(trend)?);
    out.push_str(
        "<p class=\"note\">Each indicator against the recording's start: the effects' values in their \
         reports' units with their 95 % intervals where the reports give them (absent where the loop did \
         not add the effect), the mean NIS per channel before (orange) and after (blue) the \
         loop, and with a baseline each level's ratio to it.</p>\n",
    );
    recordings_table(&mut out, trend, failed);
    out.push_str(&format!(
        "<p class=\"note\">Written by edgekf {}.</p>\n</main>\n</body>\n</html>\n",
        env!("CARGO_PKG_VERSION")
    ));
    Ok(out)
}

/// A number with four significant digits (`-` for none).
fn num(v: Option<f64>) -> String {
    match v {
        Some(v) if v.is_finite() => format!("{v:.4e}"),
        _ => "-".into(),
    }
}

/// The effects: where each first appears and how fast it changes.
fn effects_table(out: &mut String, trend: &Trend) {
    out.push_str("<h2>Effects</h2>\n");
    if trend.effects.is_empty() {
        out.push_str("<p>The loop added no effect on any recording.</p>\n");
        return;
    }
    let per_day = trend.clock == Clock::Absolute;
    out.push_str(
        "<table>\n<thead><tr><th>effect</th><th>unit</th><th>first seen</th><th>in recordings</th><th>slope per recording</th>",
    );
    if per_day {
        out.push_str("<th>slope per day</th>");
    }
    out.push_str("</tr></thead>\n<tbody>\n");
    for e in &trend.effects {
        let first = trend.recordings.get(e.first.wrapping_sub(1)).map_or("-", |p| p.name.as_str());
        out.push_str(&format!(
            "<tr><td>{}</td><td>{}</td><td>recording {} ({})</td><td class=\"num\">{} of {}</td><td class=\"num\">{}</td>",
            esc(&e.column),
            esc(&e.unit),
            e.first,
            esc(first),
            e.seen,
            trend.recordings.len(),
            num(e.per_recording)
        ));
        if per_day {
            out.push_str(&format!("<td class=\"num\">{}</td>", num(e.per_day)));
        }
        out.push_str("</tr>\n");
    }
    out.push_str(
        "</tbody>\n</table>\n<p class=\"note\">Slopes are least-squares fits of the effect's value (in its \
         unit) over the recordings that have it, per recording and, where t is absolute, per day.</p>\n",
    );
}

/// One panel per indicator (the NIS before and after share one), two to a row.
fn plots(trend: &Trend) -> Result<String> {
    let x_desc = match trend.clock {
        Clock::Absolute => "start (days from the first)",
        Clock::Index => "recording",
    };
    let x: Vec<f64> = match trend.clock {
        Clock::Absolute => trend.t.iter().map(|t| (t - trend.t[0]) / super::DAY_S).collect(),
        Clock::Index => trend.t.clone(),
    };
    let series = |column: &str| -> Vec<(f64, f64)> {
        (0..x.len()).filter_map(|k| trend.value(k, column).filter(|v| v.is_finite()).map(|v| (x[k], v))).collect()
    };
    let mut panels = Vec::new();
    for column in trend.columns.iter().filter(|c| !c.starts_with("nis_")) {
        let unit = trend.effects.iter().find(|e| &e.column == column).map_or("ratio", |e| e.unit.as_str());
        let mut p = panel(column, x_desc, unit, &x, vec![(column.as_str(), SERIES, series(column))]);
        // Each value's 95 % interval as a vertical bar, where the report gives one.
        let bars: Vec<[(f64, f64); 2]> = (0..x.len())
            .filter_map(|k| trend.interval(k, column).map(|[lo, hi]| [(x[k], lo), (x[k], hi)]))
            .filter(|b| b.iter().all(|q| q.1.is_finite()))
            .collect();
        let ends: Vec<f64> = bars.iter().flatten().map(|q| q.1).chain(series(column).iter().map(|q| q.1)).collect();
        if !bars.is_empty() {
            p.y = Axis::linear(&ends);
        }
        p.lines.extend(bars.into_iter().map(|b| Line::new("", SERIES, b.to_vec())));
        panels.push(p);
    }
    let nis = vec![("before", BEFORE, series("nis_before")), ("after", SERIES, series("nis_after"))];
    panels.push(panel("NIS mean per channel", x_desc, "NIS / channel", &x, nis));
    let rows = panels.len().div_ceil(2) as u32;
    Figure::new("indicators against the recordings' start", (2 * PANEL_W, PANEL_H * rows), panels).columns(2).svg()
}

/// A named series of one colour: its legend name, colour and points.
type Series<'a> = (&'a str, RGBColor, Vec<(f64, f64)>);

/// A panel of `series` over the history's `x`, lines with a marker on
/// each recording.
fn panel(title: &str, x_desc: &str, y_desc: &str, x: &[f64], series: Vec<Series<'_>>) -> Panel {
    let mut p = Panel::new(title, x_desc, y_desc);
    p.x = Axis::linear(x);
    let ys: Vec<f64> = series.iter().flat_map(|s| s.2.iter().map(|q| q.1)).collect();
    p.y = Axis::linear(&ys);
    for (name, colour, points) in series {
        p.lines.push(Line::new(name, colour, points.clone()));
        p.markers.push(Markers::new("", Marker::new(Shape::Circle, 3, colour), points));
    }
    p
}

/// The recordings in order, with their `t`, and those that failed.
fn recordings_table(out: &mut String, trend: &Trend, failed: &[(String, String)]) {
    out.push_str("<h2>Recordings</h2>\n<table>\n<thead><tr><th>#</th><th>recording</th><th>t</th><th>effects</th></tr></thead>\n<tbody>\n");
    for (k, p) in trend.recordings.iter().enumerate() {
        let effects: Vec<String> = p.effects.iter().map(|(c, v)| format!("{c} = {v:.4e}")).collect();
        out.push_str(&format!(
            "<tr><td class=\"num\">{}</td><td>{}</td><td class=\"num\">{}</td><td>{}</td></tr>\n",
            k + 1,
            esc(&p.name),
            trend.t[k],
            esc(&effects.join("; "))
        ));
    }
    out.push_str("</tbody>\n</table>\n");
    if !failed.is_empty() {
        out.push_str("<h2>Recordings that failed</h2>\n<ul>\n");
        for (name, why) in failed {
            out.push_str(&format!("<li><span class=\"bad\">{}</span>: {}</li>\n", esc(name), esc(why)));
        }
        out.push_str("</ul>\n");
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Point, Trend};
    use super::*;

    #[test]
    fn the_page_names_each_effect_and_each_failure() {
        let p = |name: &str, v: Option<f64>| Point {
            name: name.into(),
            start_s: 0.0,
            effects: v.map(|v| ("sensor_bias_ax".to_string(), v)).into_iter().collect(),
            nis: [2.0, 1.0],
            units: vec![("sensor_bias_ax".to_string(), "m/s^2".to_string())],
            intervals: v.map(|v| ("sensor_bias_ax".to_string(), [v - 0.01, v + 0.01])).into_iter().collect(),
            ..Point::default()
        };
        let trend = Trend::new(vec![p("r1", None), p("r2", Some(0.05)), p("r3", Some(0.06))]);
        let html = render("a <system>", &trend, &[("bad.csv".into(), "no column ax".into())]).unwrap();
        assert!(html.contains("History — a &lt;system&gt;"));
        assert!(html.contains("<td>sensor_bias_ax</td><td>m/s^2</td><td>recording 2 (r2)</td>"), "{html}");
        assert!(html.contains("1.0000e-2"), "the slope per recording");
        assert!(html.contains("bad.csv") && html.contains("no column ax"));
        assert_eq!(html.matches("<svg").count(), 1);
        // The two intervals are two bars more in the series' colour (grid lines aside).
        let blue = |t: &Trend| {
            let page = render("s", t, &[]).unwrap();
            page.split('<').filter(|e| e.starts_with("polyline") && e.contains("#1F64B4")).count()
        };
        let mut bare = trend.clone();
        bare.recordings.iter_mut().for_each(|p| p.intervals.clear());
        assert_eq!(blue(&trend), blue(&bare) + 2);
    }
}
