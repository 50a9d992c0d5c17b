//! One panel: a titled chart with its axes, grid and tick labels, and what it shows (bands,
//! then lines, then markers), with a legend in the corner that covers the fewest of its lines'
//! points. Drawing clips every line to the axes and leaves out what the axes cannot place.

use super::legend::{draw_box, Corner};
use super::series::Key;
use super::series::{Band, Line, Markers};
use super::shapes::draw_marker;
use super::{clip, tick, Area, Axis, FONT};
use anyhow::Result;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

/// A chart on the SVG backend.
type Chart<'a, 'b, X, Y> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<X, Y>>;

/// How a panel's axes are labelled and its grid drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mesh {
    /// About how many tick labels along x.
    pub x_labels: usize,
    /// About how many tick labels along y.
    pub y_labels: usize,
    /// Light grid lines between two labelled ones, at most.
    pub light_lines: usize,
    /// Positive y tick labels with a `+` (for errors and deviations).
    pub signed_y: bool,
}

impl Default for Mesh {
    /// 8 labels along x, 6 along y, up to 3 light lines between labelled ones.
    fn default() -> Self {
        Self { x_labels: 8, y_labels: 6, light_lines: 3, signed_y: false }
    }
}

/// What one panel shows.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Caption (none when empty).
    pub title: String,
    /// X axis.
    pub x: Axis,
    /// X axis description (with unit).
    pub x_desc: String,
    /// Y axis.
    pub y: Axis,
    /// Y axis description (with unit).
    pub y_desc: String,
    /// Tick labels and grid.
    pub mesh: Mesh,
    /// Bands, drawn first.
    pub bands: Vec<Band>,
    /// Lines, drawn in order over the bands.
    pub lines: Vec<Line>,
    /// Markers, drawn over the lines.
    pub markers: Vec<Markers>,
    /// Legend entries of no single series (after those of the named series).
    pub legend_extra: Vec<(Key, String)>,
}

impl Panel {
    /// An empty panel with linear `0..1` axes.
    pub fn new(title: &str, x_desc: &str, y_desc: &str) -> Self {
        Self {
            title: title.into(),
            x: Axis::Linear(0.0, 1.0),
            x_desc: x_desc.into(),
            y: Axis::Linear(0.0, 1.0),
            y_desc: y_desc.into(),
            mesh: Mesh::default(),
            bands: Vec::new(),
            lines: Vec::new(),
            markers: Vec::new(),
            legend_extra: Vec::new(),
        }
    }

    /// Draws the panel on `area`.
    pub(super) fn draw(&self, area: &Area<'_>) -> Result<()> {
        let lin = |a: f64, b: f64| RangedCoordf64::from(a..b);
        let log = |a: f64, b: f64| LogCoord::from((a..b).log_scale());
        match (self.x, self.y) {
            (Axis::Linear(a, b), Axis::Linear(c, d)) => self.draw_on(area, lin(a, b), lin(c, d)),
            (Axis::Log(a, b), Axis::Linear(c, d)) => self.draw_on(area, log(a, b), lin(c, d)),
            (Axis::Linear(a, b), Axis::Log(c, d)) => self.draw_on(area, lin(a, b), log(c, d)),
            (Axis::Log(a, b), Axis::Log(c, d)) => self.draw_on(area, log(a, b), log(c, d)),
        }
    }

    /// Draws the panel with the coordinate types `x`, `y`: mesh, bands, lines, markers, legend.
    fn draw_on<X, Y>(&self, area: &Area<'_>, x: X, y: Y) -> Result<()>
    where
        X: Ranged<ValueType = f64> + ValueFormatter<f64>,
        Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let mut builder = ChartBuilder::on(area);
        if !self.title.is_empty() {
            builder.caption(&self.title, (FONT, 15));
        }
        let mut chart =
            builder.margin(6).margin_right(14).x_label_area_size(36).y_label_area_size(58).build_cartesian_2d(x, y)?;
        // A key point a rounding error away from zero (a symmetric range's middle) reads 0.
        let (lo, hi) = self.y.ends();
        let tiny = 1e-9 * (hi - lo).abs();
        let y_tick = |v: &f64| {
            let v = if v.abs() < tiny { 0.0 } else { *v };
            if self.mesh.signed_y && v > 0.0 {
                format!("+{}", tick(v))
            } else {
                tick(v)
            }
        };
        chart
            .configure_mesh()
            .x_desc(&self.x_desc)
            .y_desc(&self.y_desc)
            .x_labels(self.mesh.x_labels)
            .y_labels(self.mesh.y_labels)
            .max_light_lines(self.mesh.light_lines)
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&y_tick)
            .label_style((FONT, 12))
            .axis_desc_style((FONT, 13))
            .bold_line_style(RGBColor(225, 225, 225))
            .light_line_style(RGBColor(244, 244, 244))
            .draw()?;
        let mut legend = Vec::new();
        for band in &self.bands {
            if self.draw_band(&mut chart, band)? && !band.name.is_empty() {
                legend.push((Key::Band(band.fill, band.edge), band.name.clone()));
            }
        }
        for line in &self.lines {
            if self.draw_line(&mut chart, line)? && !line.name.is_empty() {
                legend.push((Key::Line(line.stroke), line.name.clone()));
            }
        }
        for m in &self.markers {
            if self.draw_markers(&mut chart, m)? && !m.name.is_empty() {
                legend.push((Key::Marker(m.marker), m.name.clone()));
            }
        }
        legend.extend(self.legend_extra.iter().cloned());
        if !legend.is_empty() {
            draw_box(&chart.plotting_area().strip_coord_spec(), &legend, self.legend_corner())?;
        }
        Ok(())
    }

    /// Draws `band` (its part inside the y range) and its edges; true when any of it shows.
    fn draw_band<X, Y>(&self, chart: &mut Chart<'_, '_, X, Y>, band: &Band) -> Result<bool>
    where
        X: Ranged<ValueType = f64>,
        Y: Ranged<ValueType = f64>,
    {
        let ((x0, x1), (y0, y1)) = (self.x.ends(), self.y.ends());
        let (lo, hi) = (band.lo.max(y0.min(y1)), band.hi.min(y0.max(y1)));
        if lo.is_nan() || hi.is_nan() || lo > hi {
            return Ok(false);
        }
        chart.draw_series([Rectangle::new([(x0, lo), (x1, hi)], band.fill.filled())])?;
        for y in [band.lo, band.hi] {
            let edge = Line { name: String::new(), stroke: band.edge, points: vec![(x0, y), (x1, y)] };
            self.draw_line(chart, &edge)?;
        }
        Ok(true)
    }

    /// Draws `line` (one path per drawable run); true when any of it shows.
    fn draw_line<X, Y>(&self, chart: &mut Chart<'_, '_, X, Y>, line: &Line) -> Result<bool>
    where
        X: Ranged<ValueType = f64>,
        Y: Ranged<ValueType = f64>,
    {
        let runs = clip(&line.points, self.x, self.y);
        let style = line.stroke.colour.stroke_width(line.stroke.width);
        for run in &runs {
            match line.stroke.dash {
                None => chart.draw_series(LineSeries::new(run.iter().copied(), style))?,
                Some((dash, gap)) => chart.draw_series(DashedLineSeries::new(run.iter().copied(), dash, gap, style))?,
            };
        }
        Ok(!runs.is_empty())
    }

    /// Draws markers and their labels; true when any of them shows.
    fn draw_markers<X, Y>(&self, chart: &mut Chart<'_, '_, X, Y>, m: &Markers) -> Result<bool>
    where
        X: Ranged<ValueType = f64>,
        Y: Ranged<ValueType = f64>,
    {
        let placed = m.placed(self.x, self.y);
        let dy = if m.labels_above { -18 } else { 5 };
        let style = (FONT, 12).into_font().color(&m.marker.colour);
        // Labels already drawn, as pixel boxes: a label that would cover one is left out (its
        // marker stays), so close lines of one class make one readable label, not a pile.
        let mut drawn: Vec<[i32; 4]> = Vec::new();
        for p in &placed {
            draw_marker(chart.plotting_area(), p.at, p.marker)?;
            if let Some(label) = p.label {
                let (x, y) = chart.backend_coord(&p.at);
                // About 7 px a character and 14 px high at 12 px (the checker's estimate too).
                let b = [x + 5, y + dy, x + 5 + 7 * label.chars().count() as i32, y + dy + 14];
                if drawn.iter().any(|d| b[0] < d[2] && d[0] < b[2] && b[1] < d[3] && d[1] < b[3]) {
                    continue;
                }
                drawn.push(b);
                let text = Text::new(label.to_string(), (5, dy), style.clone());
                chart.plotting_area().draw(&(EmptyElement::at(p.at) + text))?;
            }
        }
        Ok(!placed.is_empty())
    }

    /// The corner for the legend with the fewest points of the lines under it (upper right on
    /// a tie).
    fn legend_corner(&self) -> Corner {
        let corners = [
            (Corner::UpperRight, (0.65, 1.0), (0.6, 1.0)),
            (Corner::UpperLeft, (0.0, 0.35), (0.6, 1.0)),
            (Corner::LowerRight, (0.65, 1.0), (0.0, 0.4)),
            (Corner::LowerLeft, (0.0, 0.35), (0.0, 0.4)),
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
        corners.into_iter().min_by_key(|c| under((c.1, c.2))).map_or(Corner::UpperRight, |c| c.0)
    }
}
