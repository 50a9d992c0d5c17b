//! The plot kit: figures for people, drawn by `plotters`' SVG backend into one SVG string. The
//! HTML report of `edgekf loop` and the README's figures (`examples/crank_plots.rs`) both draw
//! with it, so every figure of the project shares one look and one set of fixes. It knows no
//! system: it takes numbers in data coordinates.
//!
//! * [`Figure`]: panels on a grid, a title, a [`LegendColumn`], an `aria-label`; [`Figure::svg`]
//!   draws it.
//! * [`Panel`]: axes ([`Axis`], linear or log; [`Mesh`] for the ticks), [`Band`]s, [`Line`]s
//!   (solid or dashed [`Stroke`]) and [`Markers`] (a [`Marker`] of a [`Shape`] and [`Fill`],
//!   labelled if wanted), with a legend in the emptiest corner.
//! * [`min_max`]: long series decimated to each pixel column's extremes, so spikes survive.
//! * [`clip`]: a non-finite point breaks a line instead of the plot; lines are cut at the axes.
//!
//! Text stays SVG text in the viewer's sans-serif font, so no font file is needed.
//!
//! ```
//! use edgekf_sim::report::plot::{Axis, Figure, Line, Marker, Markers, Panel, RGBColor, Shape};
//!
//! let blue = RGBColor(31, 100, 180);
//! let mut panel = Panel::new("a damped sine", "t (s)", "x (mm)");
//! let wave: Vec<(f64, f64)> = (0..=200).map(|k| k as f64 / 100.0).map(|t| (t, (-t).exp() * (9.0 * t).sin())).collect();
//! panel.x = Axis::span(&wave.iter().map(|p| p.0).collect::<Vec<_>>());
//! panel.y = Axis::Linear(-1.0, 1.0);
//! panel.lines.push(Line::new("x", blue, wave));
//! panel.markers.push(Markers::new("start", Marker::new(Shape::Circle, 4, blue), vec![(0.0, 0.0)]));
//! let svg = Figure::new("A damped sine against time", (480, 220), vec![panel]).svg()?;
//! assert!(svg.starts_with("<svg role=\"img\" aria-label=\"A damped sine against time\""));
//! assert!(svg.contains("a damped sine") && svg.contains("<polyline"));
//! # anyhow::Ok(())
//! ```

mod axis;
mod clip;
mod decimate;
mod figure;
mod legend;
mod panel;
mod series;
mod shapes;

pub use axis::{tick, Axis};
pub use clip::clip;
pub use decimate::{min_max, min_max_points};
pub use figure::Figure;
pub use legend::{Entry, LegendColumn};
pub use panel::{Mesh, Panel};
pub use plotters::style::RGBColor;
pub use series::Key;
pub use series::{Band, Fill, Line, Marker, Markers, Shape, Stroke};

/// Font family of the figures' text (rendered by the viewer).
const FONT: &str = "sans-serif";

/// A drawing area of the SVG backend.
type Area<'a> = plotters::drawing::DrawingArea<plotters::backend::SVGBackend<'a>, plotters::coord::Shift>;

#[cfg(test)]
mod tests {
    use super::*;

    const BLUE: RGBColor = RGBColor(31, 100, 180);
    const ORANGE: RGBColor = RGBColor(228, 108, 10);

    /// The SVG of one panel, 480 × 220 px.
    fn svg(panel: Panel) -> String {
        Figure::new("test", (480, 220), vec![panel]).svg().unwrap()
    }

    /// The SVG elements (`<polyline …/>`, …) that draw in `colour`.
    fn elements<'a>(svg: &'a str, tag: &str, colour: RGBColor) -> Vec<&'a str> {
        let colour = format!("#{:02X}{:02X}{:02X}", colour.0, colour.1, colour.2);
        svg.split('<').filter(|e| e.starts_with(tag) && e.contains(&colour)).collect()
    }

    #[test]
    fn panel_with_nan_and_log_axis_renders() {
        let mut p = Panel::new("a <test> & more", "f (Hz)", "dB");
        p.x = Axis::Log(1.0, 500.0);
        p.y = Axis::Linear(-10.0, 10.0);
        p.lines.push(Line::new("x", BLUE, vec![(0.0, 1.0), (2.0, f64::NAN), (3.0, 2.0), (4.0, 50.0), (f64::NAN, 1.0)]));
        let peak = Marker::new(Shape::Circle, 4, ORANGE);
        p.markers.push(Markers::new("m", peak, vec![(14.0, 3.0)]).labelled(vec!["1x".into()], true));
        let svg = Figure::new("test", (960, 220), vec![p]).svg().unwrap();
        assert!(svg.starts_with("<svg role=\"img\""));
        assert!(svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("a &lt;test&gt; &amp; more") && svg.contains(">\n1x\n</text>"));
        assert!(!svg.contains("NaN"));
    }

    #[test]
    fn a_missing_sample_splits_the_drawn_line() {
        let mut p = Panel::new("", "t", "y");
        let mut points: Vec<(f64, f64)> = (0..=20).map(|k| (k as f64 / 20.0, 0.5)).collect();
        p.lines.push(Line::new("", BLUE, points.clone()));
        assert_eq!(elements(&svg(p.clone()), "polyline", BLUE).len(), 1);
        points[10].1 = f64::NAN;
        p.lines[0].points = points;
        assert_eq!(elements(&svg(p), "polyline", BLUE).len(), 2);
    }

    #[test]
    fn dashed_lines_are_drawn_in_dashes() {
        let mut p = Panel::new("", "t", "y");
        p.lines.push(Line::new("", BLUE, vec![(0.0, 0.5), (1.0, 0.5)]).dashed(6, 4));
        let dashes = elements(&svg(p.clone()), "polyline", BLUE).len();
        assert!(dashes > 20, "{dashes} dashes over about 400 px");
        p.lines[0].stroke.dash = None;
        assert_eq!(elements(&svg(p), "polyline", BLUE).len(), 1);
    }

    #[test]
    fn markers_are_drawn_in_their_shape_and_fill() {
        let mut p = Panel::new("", "t", "y");
        let points = vec![(0.5, 0.5)];
        for (shape, colour) in
            [(Shape::Circle, BLUE), (Shape::Square, ORANGE), (Shape::Triangle, RGBColor(44, 160, 44))]
        {
            p.markers.push(Markers::new("", Marker::new(shape, 3, colour), points.clone()));
        }
        p.markers.push(Markers::new("", Marker::new(Shape::Circle, 7, RGBColor(9, 9, 9)).hollow(), points.clone()));
        let outlined = Marker::new(Shape::Circle, 5, RGBColor(1, 2, 3)).outlined(RGBColor(4, 5, 6));
        p.markers.push(Markers::new("", outlined, points));
        let svg = svg(p);
        assert_eq!(elements(&svg, "circle", BLUE).len(), 1);
        assert_eq!(elements(&svg, "rect", ORANGE).len(), 1);
        assert_eq!(elements(&svg, "polygon", RGBColor(44, 160, 44)).len(), 1);
        let hollow = elements(&svg, "circle", RGBColor(9, 9, 9));
        assert!(hollow.len() == 1 && hollow[0].contains("fill=\"none\""), "{hollow:?}");
        assert_eq!(elements(&svg, "circle", RGBColor(1, 2, 3)).len(), 1);
        assert_eq!(elements(&svg, "circle", RGBColor(4, 5, 6)).len(), 1);
    }

    #[test]
    fn named_series_get_legend_entries() {
        let mut p = Panel::new("", "t", "y");
        p.lines.push(Line::new("shown", BLUE, vec![(0.0, 0.2), (1.0, 0.3)]));
        p.lines.push(Line::new("off the axes", BLUE, vec![(0.0, 5.0), (1.0, 6.0)]));
        p.bands.push(Band {
            name: "band".into(),
            lo: 0.4,
            hi: 0.6,
            fill: RGBColor(236, 236, 236),
            edge: Stroke::dashed(ORANGE, 1, 6, 4),
        });
        p.legend_extra.push((Key::Marker(Marker::new(Shape::Cross, 5, ORANGE)), "extra".into()));
        let svg = svg(p);
        for text in ["shown", "band", "extra"] {
            assert!(svg.contains(&format!(">\n{text}\n</text>")), "{text}");
        }
        assert!(!svg.contains("off the axes"), "a line that shows nothing has no legend entry");
    }

    #[test]
    fn a_legend_column_sits_right_of_the_panels() {
        let mut p = Panel::new("", "t", "y");
        p.lines.push(Line::new("", BLUE, vec![(0.0, 0.2), (1.0, 0.3)]));
        let key = Key::LineMarker(Stroke::solid(BLUE, 2), Marker::new(Shape::Square, 3, BLUE));
        let column = LegendColumn {
            width: 150,
            entries: vec![Entry::heading(&["runs"]), Entry::new(key, &["run 1: +0.5 %", "(features −2 %)"])],
        };
        let svg = Figure::new("with legend", (600, 300), vec![p]).titled("A title").with_legend(column).svg().unwrap();
        for text in ["A title", "runs", "run 1: +0.5 %", "(features −2 %)"] {
            assert!(svg.contains(&format!(">\n{text}\n</text>")), "{text}");
        }
        let square = elements(&svg, "rect", BLUE);
        assert_eq!(square.len(), 1);
        let x: f64 = square[0].split("x=\"").nth(1).and_then(|s| s.split('"').next()).unwrap().parse().unwrap();
        assert!(x >= 450.0, "the legend's key is in the column: x = {x}");
    }

    #[test]
    fn the_label_is_escaped_and_panels_fill_a_grid() {
        let panel = Panel::new("", "t", "y");
        let figure = Figure::new("a \"quoted\" <label>", (960, 440), vec![panel.clone(); 3]).columns(2);
        assert_eq!(figure.grid(), (2, 2));
        let svg = figure.svg().unwrap();
        assert!(svg.starts_with("<svg role=\"img\" aria-label=\"a &quot;quoted&quot; &lt;label&gt;\" "));
        assert_eq!(Figure::new("", (10, 10), vec![panel; 2]).columns(5).grid(), (1, 2));
    }
}
