//! `edgekf boom estimate --plot`: the tip's vibration (against its truth where the recording
//! has it: a simulated one), the whole run and the first stop up close, and the estimate's
//! error where there is a truth to take it from.

use super::estimate::BoomEstimate;
use crate::report::plot::{min_max, Axis, Figure, Line, Panel, RGBColor};
use anyhow::{bail, Result};

const ESTIMATE: RGBColor = RGBColor(31, 100, 180);
const TRUTH: RGBColor = RGBColor(228, 108, 10);

/// The figure's SVG for `est` of `method`, against `truth` (`truth_tip_vibration`) where
/// given, with the operator's command `command` placing the close-up on the first stop.
pub fn vibration_figure(
    est: &BoomEstimate,
    method: &str,
    truth: Option<&[f64]>,
    command: Option<&[f64]>,
) -> Result<String> {
    let t = &est.t;
    let Some(vib) = est.column("tip_vibration") else { bail!("the estimate has no tip_vibration") };
    if t.len() < 2 || truth.is_some_and(|tr| tr.len() != t.len()) {
        bail!("nothing to draw: {} rows of estimate, {} of truth", t.len(), truth.map_or(0, <[f64]>::len));
    }
    let (first, last) = (t[0], t[t.len() - 1]);
    // The close-up: from a second before the first stop (the command back to 0) for 12 s.
    let stop =
        command.and_then(|c| (1..c.len()).find(|&i| c[i - 1] != 0.0 && c[i] == 0.0)).map_or(first, |i| t[i] - 1.0);
    let limit =
        truth.into_iter().flatten().chain(vib).filter(|v| v.is_finite()).fold(0.0f64, |m, v| m.max(v.abs())) * 1.1;
    let mut panels = Vec::new();
    for (title, from, to) in [
        (format!("tip vibration, {method}"), first, last),
        (format!("after the first stop, {:.0} s", stop + 1.0), stop, (stop + 12.0).min(last)),
    ] {
        let rows: Vec<usize> = (0..t.len()).filter(|&i| t[i] >= from && t[i] <= to).collect();
        let series = |v: &[f64]| -> Vec<(f64, f64)> {
            let (x, y): (Vec<f64>, Vec<f64>) = rows.iter().map(|&i| (t[i], v[i])).unzip();
            if rows.len() > 2000 {
                min_max(&x, &y, 800)
            } else {
                x.into_iter().zip(y).collect()
            }
        };
        let mut p = Panel::new(&title, "t (s)", "m");
        p.x = Axis::Linear(from, to);
        p.y = Axis::Linear(-limit, limit);
        if let Some(truth) = truth {
            p.lines.push(Line::new("truth", TRUTH, series(truth)).width(2).dashed(6, 3));
        }
        p.lines.push(Line::new("estimate", ESTIMATE, series(vib)).width(1));
        panels.push(p);
    }
    let Some(truth) = truth else {
        return Figure::new("Boom tip vibration (no truth in the recording)", (960, 480), panels).svg();
    };
    let error: Vec<f64> = vib.iter().zip(truth).map(|(e, tr)| e - tr).collect();
    let (x, y): (Vec<f64>, Vec<f64>) =
        t.iter().zip(&error).filter(|(_, e)| e.is_finite()).map(|(a, b)| (*a, *b)).unzip();
    let mut p = Panel::new("estimate − truth", "t (s)", "m");
    p.x = Axis::Linear(first, last);
    p.y = Axis::linear(&y).headroom(0.1);
    p.lines.push(Line::new("error", ESTIMATE, min_max(&x, &y, 800)).width(1));
    panels.push(p);
    Figure::new("Boom tip vibration against truth", (960, 720), panels).svg()
}
