//! The page's figures, drawn with the plot kit: the normalised innovations, their spectra
//! (with the detected lines marked), the NIS, and with the truth the virtual-sensing estimates
//! and their errors; before in orange, after in blue. Also the series each figure derives
//! from the report (normalised innovations, spectra in dB, the NIS moving average, the zoom
//! window at the end of the run).

use super::{h2, para};
use crate::report::escape::escape as esc;
use crate::report::plot::{min_max, min_max_points, Axis, Figure, Line, Marker, Markers, Panel, RGBColor, Shape};
use crate::residual_loop::filter::Run;
use crate::residual_loop::signature::ChannelSignature;
use crate::residual_loop::LoopReport;
use anyhow::Result;

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

/// Draws `panels` `cols` to a row into one SVG two panels wide (`label` is its accessible
/// name).
fn grid(panels: Vec<Panel>, cols: usize, label: &str) -> Result<String> {
    let rows = panels.len().div_ceil(cols.max(1)).max(1) as u32;
    Figure::new(label, (2 * PANEL_W, PANEL_H * rows), panels).columns(cols).svg()
}

/// The plots section: innovations, spectra, NIS, and (with truth) the virtual sensing.
pub(super) fn plots(out: &mut String, r: &LoopReport) -> Result<()> {
    h2(out, "Plots");
    out.push_str(
        "<p class=\"note\"><span class=\"before\">Orange: before</span> (the base model); \
         <span class=\"after\">blue: after</span> (the final model).</p>\n",
    );
    let (spectra, without) = spectrum_plot(r)?;
    let mut spectra_caption = "Welch spectra of the normalised innovations (the DC bin left out: a bias shows in the time plot and the tables), log frequency up to the Nyquist frequency; the grey line is the level of white noise of unit variance. Dots mark the lines the loop detected, labelled by where they sit.".to_string();
    if !without.is_empty() {
        spectra_caption.push_str(&format!(" No spectrum for {}: too few regular readings.", without.join(", ")));
    }
    let figures = [
        (innovation_plot(r)?, "Normalised innovations e/√S per channel against time (min/max per pixel column), before and after on the same scale. A consistent model gives white noise of unit variance, nearly all within ±3.".to_string()),
        (spectra, spectra_caption),
        (nis_plot(r)?, "NIS per sample divided by the number of channels, moving average over 100 samples (log scale). A consistent model stays near 1.".to_string()),
    ];
    for (svg, caption) in &figures {
        figure(out, svg, caption);
    }
    for f in &r.section.figures {
        figure(out, &f.svg, &f.caption);
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
    let (svg, windows) = zoom_plot(r, &rows)?;
    figure(out, &svg, &zoom_caption(&windows));
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
            let mut p = Panel::new(&format!("{name} — {label}"), "t (s)", "e/√S");
            p.x = Axis::span(&tr.t);
            p.y = Axis::Linear(-lim, lim);
            p.lines.push(Line::horizontal("±3", REFERENCE, p.x, 3.0));
            p.lines.push(Line::horizontal("", REFERENCE, p.x, -3.0));
            p.lines.push(Line::new(label, colour, min_max_sparse(&tr.t, z, PANEL_W as usize)));
            panels.push(p);
        }
    }
    grid(panels, 2, "Normalised innovations before and after")
}

/// [`min_max`] of a channel, its empty cells between readings left out where it has a reading
/// on fewer than half of the rows (a slower sensor, a DVL): drawn as they fall, its readings
/// would be dots and dashes that no eye finds, and its axes look empty.
fn min_max_sparse(t: &[f64], z: &[f64], columns: usize) -> Vec<(f64, f64)> {
    let readings: Vec<(f64, f64)> = t.iter().copied().zip(z.iter().copied()).filter(|p| p.1.is_finite()).collect();
    if 2 * readings.len() >= z.len() {
        return min_max(t, z, columns);
    }
    min_max_points(&readings, columns)
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
fn spectrum_plot(r: &LoopReport) -> Result<(String, Vec<String>)> {
    let mut panels = Vec::new();
    let mut without = Vec::new();
    for (i, name) in r.traces.channels.iter().map(|c| &c.name).enumerate() {
        let mut p = Panel::new(&format!("{name}: spectrum of e/√S"), "frequency (Hz)", "PSD (dB re 1/Hz)");
        let mut all = Vec::new();
        let mut white = None;
        for (s, label, colour, above) in [(&r.before, "before", BEFORE, true), (&r.after, "after", AFTER, false)] {
            let (bw, psd) = (s.bin_width_hz, s.spectra.get(i).map_or(&[][..], Vec::as_slice));
            let spec = spectrum_db(psd, bw);
            let marks = peak_marks(s.channels.iter().find(|c| &c.name == name), &spec, bw);
            let (points, labels) = marks.into_iter().map(|(f, db, class)| ((f, db), class)).unzip();
            let dot = Marker::new(Shape::Circle, 4, colour);
            p.markers.push(Markers::new(&format!("lines {label}"), dot, points).labelled(labels, above));
            white = white.or((psd.len() > 1).then(|| white_level_db(psd.len(), bw)));
            all.extend(spec.iter().copied());
            p.lines.push(Line::new(label, colour, spec));
        }
        // A channel without a spectrum (too few regular readings for Welch's segments) gets no
        // empty axes: the caption names it instead.
        if !all.iter().any(|q| q.0 > 0.0 && q.1.is_finite()) {
            without.push(name.clone());
            continue;
        }
        p.x = Axis::log_frequency(&all);
        p.y = Axis::linear(&all.iter().map(|v| v.1).chain(white).collect::<Vec<_>>()).headroom(0.15);
        if let Some(level) = white {
            p.lines.insert(0, Line::horizontal("", REFERENCE, p.x, level));
        }
        panels.push(p);
    }
    Ok((grid(panels, 2, "Spectra of the normalised innovations before and after")?, without))
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
    let mut p = Panel::new(&title, "t (s)", "NIS / channels");
    let width = 2 * PANEL_W as usize;
    let b = min_max(&tr.t, &moving_average(&tr.before.nis, NIS_WINDOW, m), width);
    let a = min_max(&tr.t, &moving_average(&tr.after.nis, NIS_WINDOW, m), width);
    p.x = Axis::span(&tr.t);
    p.y = Axis::log_around(b.iter().chain(&a).map(|v| v.1), 1.0);
    p.lines.push(Line::horizontal("1 (consistent)", REFERENCE, p.x, 1.0));
    p.lines.push(Line::new("before", BEFORE, b));
    p.lines.push(Line::new("after", AFTER, a));
    grid(vec![p], 1, "NIS before and after")
}

/// A zoom window: where it starts, and whether it spans periods of an oscillation (else it is
/// the run's last tenth).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Zoom {
    from: usize,
    periodic: bool,
}

/// Where the zoom window of a truth series starts: about four periods before the end where
/// it oscillates (its mean crossings over the second half of the run give the period; at
/// least ten samples between crossings, so that noise on a slow quantity is not read as an
/// oscillation), else the last tenth of the run; at least 20 samples.
fn zoom_start(truth: &[f64]) -> Zoom {
    let n = truth.len();
    let half = &truth[n / 2..];
    let finite: Vec<f64> = half.iter().copied().filter(|v| v.is_finite()).collect();
    let mean = finite.iter().sum::<f64>() / finite.len().max(1) as f64;
    let crossings = finite.windows(2).filter(|w| (w[0] - mean).signum() != (w[1] - mean).signum()).count();
    let periodic = crossings >= 2 && 10 * crossings <= finite.len();
    let len = if periodic { 4 * 2 * half.len() / crossings } else { n / 10 };
    Zoom { from: n - len.clamp(20.min(n), half.len().max(20).min(n)), periodic }
}

/// The zoom figure's caption: what its windows span (each row's own, in s).
fn zoom_caption(windows: &[(Zoom, f64)]) -> String {
    let longest = windows.iter().map(|w| w.1).fold(0.0, f64::max);
    let what = if !windows.is_empty() && windows.iter().all(|w| w.0.periodic) {
        format!("about four periods of each row's oscillation at the end of the run (at most {longest:.3} s)")
    } else if windows.iter().any(|w| w.0.periodic) {
        format!("the end of the run: four periods where a row oscillates, else its last tenth (at most {longest:.3} s)")
    } else {
        format!("the last tenth of the run ({longest:.3} s)")
    };
    format!("Virtual-sensing estimates against the truth (wide grey line) over {what}.")
}

/// `series[from..]` against `t[from..]`, times `scale`.
fn tail(t: &[f64], series: Option<&Vec<f64>>, from: usize, scale: f64) -> Vec<(f64, f64)> {
    let Some(s) = series else { return Vec::new() };
    t.iter().zip(s).skip(from).map(|(&t, &v)| (t, v * scale)).collect()
}

/// Estimated against true displacement of each virtual-sensing row near the end of the run,
/// and each row's window with its length in s.
fn zoom_plot(r: &LoopReport, rows: &[usize]) -> Result<(String, Vec<(Zoom, f64)>)> {
    let tr = &r.traces;
    let mut panels = Vec::new();
    let mut windows = Vec::new();
    for &j in rows {
        let truth = tr.truth[j].as_deref().unwrap_or_default();
        let zoom = zoom_start(truth);
        let from = zoom.from;
        let span = match (tr.t.get(from), tr.t.last()) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        };
        windows.push((zoom, span));
        let row = &tr.rows[j];
        let scale = row.display_scale;
        let mut p =
            Panel::new(&format!("{}: estimate and truth (end of the run)", row.name), "t (s)", &row.display_unit);
        let lines = [
            ("truth", TRUTH, 5, tail(&tr.t, tr.truth[j].as_ref(), from, scale)),
            ("before", BEFORE, 1, tail(&tr.t, tr.before.outputs.get(j), from, scale)),
            ("after", AFTER, 1, tail(&tr.t, tr.after.outputs.get(j), from, scale)),
        ];
        let values: Vec<f64> = lines.iter().flat_map(|l| l.3.iter().map(|v| v.1)).collect();
        p.x = Axis::span(&tr.t[from.min(tr.t.len())..]);
        p.y = Axis::linear(&values);
        for (label, colour, width, points) in lines {
            p.lines.push(Line::new(label, colour, min_max_points(&points, PANEL_W as usize)).width(width));
        }
        panels.push(p);
    }
    Ok((grid(panels, 2, "Virtual-sensing estimates against the truth")?, windows))
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
            Panel::new(&format!("{}: estimate − truth", row.name), "t (s)", &format!("error ({})", row.display_unit));
        let settled = |e: &[f64]| e.get(e.len() / 10..).unwrap_or_default().to_vec();
        let lim = symmetric_limit([settled(&eb).as_slice(), settled(&ea).as_slice()], 1e-3) * 1.15;
        p.x = Axis::span(&tr.t);
        p.y = Axis::Linear(-lim, lim);
        p.lines.push(Line::new("before", BEFORE, min_max(&tr.t, &eb, PANEL_W as usize)));
        p.lines.push(Line::new("after", AFTER, min_max(&tr.t, &ea, PANEL_W as usize)));
        panels.push(p);
    }
    grid(panels, 2, "Virtual-sensing error before and after")
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn zoom_window_spans_a_few_periods() {
        // 1 kHz, 10 Hz sine over 3 s: four periods are 400 samples.
        let truth: Vec<f64> =
            (0..3000).map(|k| (std::f64::consts::TAU * 10.0 * k as f64 / 1000.0 + 0.3).sin()).collect();
        let zoom = zoom_start(&truth);
        assert!(zoom.periodic && (380..=420).contains(&(3000 - zoom.from)), "{zoom:?}");
        assert_eq!(zoom_start(&[f64::NAN; 5]).from, 0);
        // A slow quantity with noise on it (a health factor) is not an oscillation: the last
        // tenth, and the caption says so.
        let noisy: Vec<f64> = (0..3000).map(|k| 0.9 + 1e-3 * ((k * 7919 % 13) as f64 - 6.0)).collect();
        let zoom = zoom_start(&noisy);
        assert_eq!(zoom, Zoom { from: 2700, periodic: false });
        assert_eq!(
            zoom_caption(&[(zoom, 30.0)]),
            "Virtual-sensing estimates against the truth (wide grey line) over the last tenth of the run (30.000 s)."
        );
    }
}
