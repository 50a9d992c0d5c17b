//! `edgekf uuv estimate --plot`: each health factor against its truth, with ±2σ, and the
//! main thruster around its first change; or, for a filter that carries no health factor, the
//! speeds through the water it estimates.

use super::estimate::EstimateTable;
use crate::report::plot::{min_max, Axis, Figure, Line, Panel, RGBColor};
use anyhow::Result;

const ESTIMATE: RGBColor = RGBColor(31, 100, 180);
const SPREAD: RGBColor = RGBColor(150, 180, 220);
const TRUTH: RGBColor = RGBColor(228, 108, 10);

/// The rows of `t` in `from..=to` drawn as points: every one, or each pixel column's extremes
/// for a long run.
fn series(t: &[f64], rows: &[usize], v: &[f64]) -> Vec<(f64, f64)> {
    let (x, y): (Vec<f64>, Vec<f64>) = rows.iter().map(|&i| (t[i], v[i])).unzip();
    if rows.len() > 2000 {
        min_max(&x, &y, 800)
    } else {
        x.into_iter().zip(y).collect()
    }
}

/// The figure's SVG; `truth` holds `truth_k_t` and `truth_k_v` where the data had them. `None`
/// if the filter carries no health factor.
pub fn health_figure(table: &EstimateTable, truth: [Option<&[f64]>; 2]) -> Result<Option<String>> {
    let t = &table.t;
    let mut panels = Vec::new();
    for (j, (k, sd, name)) in
        [("k_t", "k_t_std", "main thruster"), ("k_v", "k_v_std", "vertical thruster")].into_iter().enumerate()
    {
        let (Some(est), Some(sd)) = (table.column(k), table.column(sd)) else { continue };
        if est.iter().all(|v| v.is_nan()) {
            continue;
        }
        let window = truth[j].and_then(|tr| (1..tr.len()).find(|&i| tr[i] != tr[i - 1])).map(|i| t[i]);
        let mut ranges = vec![(format!("{name}: {k}"), t[0], t[t.len() - 1])];
        if let Some(c) = window {
            ranges.push((format!("{name}: {k} from {:.0} s", c - 5.0), c - 5.0, c + 30.0));
        }
        for (title, from, to) in ranges {
            let rows: Vec<usize> = (0..t.len()).filter(|&i| t[i] >= from && t[i] <= to).collect();
            let series = |v: &[f64]| series(t, &rows, v);
            let upper: Vec<f64> = est.iter().zip(sd).map(|(k, s)| k + 2.0 * s).collect();
            let lower: Vec<f64> = est.iter().zip(sd).map(|(k, s)| k - 2.0 * s).collect();
            let mut p = Panel::new(&title, "t (s)", k);
            p.x = Axis::Linear(from.max(t[0]), to.min(t[t.len() - 1]));
            p.y = Axis::Linear(-0.2, 1.3);
            p.lines.push(Line::new("± 2σ", SPREAD, series(&upper)).width(1));
            p.lines.push(Line::new("", SPREAD, series(&lower)).width(1));
            if let Some(tr) = truth[j] {
                p.lines.push(Line::new("truth", TRUTH, series(tr)).width(2).dashed(6, 3));
            }
            p.lines.push(Line::new("estimate", ESTIMATE, series(est)).width(2));
            panels.push(p);
        }
    }
    if panels.is_empty() {
        return Ok(None);
    }
    let rows = panels.len().div_ceil(2);
    let title = if truth.iter().any(Option::is_some) {
        "Thruster health factors against truth"
    } else {
        "Thruster health factors (no truth in the recording)"
    };
    let figure = Figure::new(title, (960, 240 * rows as u32), panels).columns(2);
    Ok(Some(figure.svg()?))
}

/// The speeds u, v, w (body axes) the filter estimates, against `truth`
/// (`truth_u`, `truth_v`, `truth_w`) where the data have it: what `--plot` draws when the
/// configuration gives the filter no health factor, since the vehicle's motion is then what it
/// estimates (a figure asked for is a figure written).
pub fn speed_figure(table: &EstimateTable, truth: [Option<&[f64]>; 3]) -> Result<String> {
    let t = &table.t;
    if t.len() < 2 {
        anyhow::bail!("nothing to draw: {} row(s) of estimate", t.len());
    }
    let rows: Vec<usize> = (0..t.len()).collect();
    let mut panels = Vec::new();
    for (j, name) in ["u", "v", "w"].into_iter().enumerate() {
        let Some(est) = table.column(name) else { continue };
        let mut p = Panel::new(&format!("{name} (body axes)"), "t (s)", "m/s");
        p.x = Axis::Linear(t[0], t[t.len() - 1]);
        let drawn: Vec<f64> = est.iter().chain(truth[j].into_iter().flatten()).copied().collect();
        p.y = Axis::linear(&drawn).headroom(0.1);
        if let Some(tr) = truth[j] {
            p.lines.push(Line::new("truth", TRUTH, series(t, &rows, tr)).width(2).dashed(6, 3));
        }
        p.lines.push(Line::new("estimate", ESTIMATE, series(t, &rows, est)).width(1));
        panels.push(p);
    }
    let title = if truth.iter().any(Option::is_some) {
        "Vehicle speeds against truth (no health factor in the filter)"
    } else {
        "Vehicle speeds (no health factor in the filter, no truth in the recording)"
    };
    Figure::new(title, (960, 720), panels).svg()
}
