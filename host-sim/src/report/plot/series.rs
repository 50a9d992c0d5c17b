//! What a panel draws, in data coordinates: lines (solid or dashed; a non-finite point breaks
//! them), markers (circles, triangles, squares, crosses; filled, hollow or outlined; labelled
//! if wanted, and those beyond the y range drawn hollow at its edge if wanted) and horizontal
//! bands (a filled range of y with stroked edges).

use super::Axis;
use plotters::style::RGBColor;

/// How a line is stroked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stroke {
    /// Colour.
    pub colour: RGBColor,
    /// Width, px.
    pub width: u32,
    /// Dash and gap lengths, px; solid when `None`.
    pub dash: Option<(u32, u32)>,
}

impl Stroke {
    /// A solid stroke.
    pub fn solid(colour: RGBColor, width: u32) -> Self {
        Self { colour, width, dash: None }
    }

    /// A dashed stroke: `dash` px drawn, `gap` px left out.
    pub fn dashed(colour: RGBColor, width: u32, dash: u32, gap: u32) -> Self {
        Self { colour, width, dash: Some((dash, gap)) }
    }
}

/// One line of a panel.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// Legend entry (none when empty).
    pub name: String,
    /// How it is stroked.
    pub stroke: Stroke,
    /// Points; a non-finite point breaks the line, which is clipped to the panel.
    pub points: Vec<(f64, f64)>,
}

impl Line {
    /// A solid line one pixel wide.
    pub fn new(name: &str, colour: RGBColor, points: Vec<(f64, f64)>) -> Self {
        Self { name: name.into(), stroke: Stroke::solid(colour, 1), points }
    }

    /// A horizontal reference line at `y` across `x`.
    pub fn horizontal(name: &str, colour: RGBColor, x: Axis, y: f64) -> Self {
        let (a, b) = x.ends();
        Self::new(name, colour, vec![(a, y), (b, y)])
    }

    /// The line `width` px wide.
    pub fn width(mut self, width: u32) -> Self {
        self.stroke.width = width;
        self
    }

    /// The line dashed: `dash` px drawn, `gap` px left out.
    pub fn dashed(mut self, dash: u32, gap: u32) -> Self {
        self.stroke.dash = Some((dash, gap));
        self
    }
}

/// The shape of a marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// A circle of radius `size`.
    Circle,
    /// A triangle, point up, `size + 1` from its centre to its top.
    Triangle,
    /// A square `2 size` wide.
    Square,
    /// A diagonal cross `2 size` wide, always stroked (2 px).
    Cross,
}

/// How a marker is painted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fill {
    /// Filled with its colour.
    Solid,
    /// Only its outline, 1 px, in its colour.
    Hollow,
    /// Filled with its colour and outlined (1 px) in this one.
    Outlined(RGBColor),
}

/// The look of one marker.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Marker {
    /// Shape.
    pub shape: Shape,
    /// Size, px (see [`Shape`]).
    pub size: u32,
    /// Colour.
    pub colour: RGBColor,
    /// Paint.
    pub fill: Fill,
}

impl Marker {
    /// A filled marker.
    pub fn new(shape: Shape, size: u32, colour: RGBColor) -> Self {
        Self { shape, size, colour, fill: Fill::Solid }
    }

    /// The marker hollow.
    pub fn hollow(self) -> Self {
        Self { fill: Fill::Hollow, ..self }
    }

    /// The marker filled and outlined in `outline`.
    pub fn outlined(self, outline: RGBColor) -> Self {
        Self { fill: Fill::Outlined(outline), ..self }
    }
}

/// A series of markers of one look, optionally labelled.
#[derive(Debug, Clone, PartialEq)]
pub struct Markers {
    /// Legend entry (none when empty).
    pub name: String,
    /// The look of each marker.
    pub marker: Marker,
    /// Positions.
    pub points: Vec<(f64, f64)>,
    /// A text beside each marker (empty: none).
    pub labels: Vec<String>,
    /// Labels above the markers (else below).
    pub labels_above: bool,
    /// Markers beyond the y range are drawn hollow at its edge (else left out).
    pub at_edge: bool,
}

/// A marker as it is drawn: position inside the axes, look, label.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Placed<'a> {
    /// Position, in data coordinates, inside the axes.
    pub at: (f64, f64),
    /// The look (hollow when moved to the edge).
    pub marker: Marker,
    /// The label, if any.
    pub label: Option<&'a str>,
}

impl Markers {
    /// Unlabelled markers at `points`.
    pub fn new(name: &str, marker: Marker, points: Vec<(f64, f64)>) -> Self {
        Self { name: name.into(), marker, points, labels: Vec::new(), labels_above: false, at_edge: false }
    }

    /// The markers with `labels` (one per point), above or below them.
    pub fn labelled(self, labels: Vec<String>, above: bool) -> Self {
        Self { labels, labels_above: above, ..self }
    }

    /// The markers beyond the y range drawn hollow at its edge.
    pub fn at_edge(self) -> Self {
        Self { at_edge: true, ..self }
    }

    /// The markers to draw on axes `x`, `y`: those inside, and with [`Markers::at_edge`] those
    /// beyond the y range, hollow at its edge. Points outside the x range, or that the axes
    /// cannot place, are left out.
    pub(super) fn placed(&self, x: Axis, y: Axis) -> Vec<Placed<'_>> {
        let inside = |f: f64| (0.0..=1.0).contains(&f);
        self.points
            .iter()
            .enumerate()
            .filter_map(|(i, &(px, py))| {
                let (_, fy) = x.fraction(px).filter(|&f| inside(f)).zip(y.fraction(py))?;
                let label = self.labels.get(i).map(String::as_str);
                if inside(fy) {
                    Some(Placed { at: (px, py), marker: self.marker, label })
                } else if self.at_edge {
                    Some(Placed { at: (px, y.value(fy.clamp(0.0, 1.0))), marker: self.marker.hollow(), label })
                } else {
                    None
                }
            })
            .collect()
    }
}

/// A horizontal band: `lo ≤ y ≤ hi` filled across the panel, its edges stroked.
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    /// Legend entry (none when empty).
    pub name: String,
    /// Lower edge.
    pub lo: f64,
    /// Upper edge.
    pub hi: f64,
    /// Fill colour.
    pub fill: RGBColor,
    /// Stroke of both edges.
    pub edge: Stroke,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markers_beyond_the_axis_go_hollow_to_its_edge() {
        let dot = Marker::new(Shape::Square, 3, RGBColor(0, 0, 0));
        let points = vec![(1.0, 0.5), (2.0, 7.0), (3.0, -7.0), (9.0, 0.5), (4.0, f64::NAN)];
        let (x, y) = (Axis::Linear(0.0, 5.0), Axis::Linear(-1.0, 1.0));
        let plain = Markers::new("", dot, points.clone());
        assert_eq!(plain.placed(x, y), vec![Placed { at: (1.0, 0.5), marker: dot, label: None }]);
        let plain = plain.at_edge();
        let edge = plain.placed(x, y);
        let at: Vec<(f64, f64)> = edge.iter().map(|p| p.at).collect();
        assert_eq!(at, vec![(1.0, 0.5), (2.0, 1.0), (3.0, -1.0)]);
        let fills: Vec<Fill> = edge.iter().map(|p| p.marker.fill).collect();
        assert_eq!(fills, vec![Fill::Solid, Fill::Hollow, Fill::Hollow]);
    }

    #[test]
    fn labels_follow_their_markers() {
        let dot = Marker::new(Shape::Circle, 4, RGBColor(0, 0, 0));
        let m = Markers::new("lines", dot, vec![(-1.0, 0.5), (2.0, 0.5)]).labelled(vec!["a".into(), "b".into()], true);
        let placed = m.placed(Axis::Linear(0.0, 5.0), Axis::Linear(0.0, 1.0));
        assert_eq!(placed.len(), 1);
        assert_eq!(placed[0].label, Some("b"));
    }
}

/// What a legend entry shows before its text.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Key {
    /// A stretch of line.
    Line(Stroke),
    /// A marker.
    Marker(Marker),
    /// A stretch of line with a marker in its middle.
    LineMarker(Stroke, Marker),
    /// A band swatch: its fill, and its edges stroked.
    Band(RGBColor, Stroke),
}
