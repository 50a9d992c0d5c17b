//! The small things the kit draws with `plotters` elements: a marker of any [`Shape`] and
//! [`Fill`] at a point of any coordinate system (data coordinates in a panel, pixels in a
//! legend), a stretch of stroke in pixels, and a legend [`Key`].

use super::series::{Fill, Key, Marker, Shape, Stroke};
use super::Area;
use anyhow::Result;
use plotters::coord::CoordTranslate;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

/// Width of a legend key, px.
pub(super) const KEY_WIDTH: i32 = 20;

/// Draws `marker` centred on `at` (in `area`'s coordinates).
pub(super) fn draw_marker<CT>(area: &DrawingArea<SVGBackend<'_>, CT>, at: CT::From, marker: Marker) -> Result<()>
where
    CT: CoordTranslate,
    CT::From: Clone,
{
    let s = marker.size as i32;
    let paint = match marker.fill {
        Fill::Hollow => marker.colour.stroke_width(1),
        Fill::Solid | Fill::Outlined(_) => marker.colour.filled(),
    };
    let centre = || EmptyElement::at(at.clone());
    // A triangle, point up: its top `s + 1` above the centre, its base `3/4` of that below.
    let (r, base) = (s + 1, 3 * (s + 1) / 4);
    let corners = [(0, -r), (-r, base), (r, base)];
    match marker.shape {
        Shape::Circle => area.draw(&(centre() + Circle::new((0, 0), s, paint)))?,
        Shape::Square => area.draw(&(centre() + Rectangle::new([(-s, -s), (s, s)], paint)))?,
        Shape::Triangle if paint.filled => area.draw(&(centre() + Polygon::new(corners.to_vec(), paint)))?,
        Shape::Triangle => area.draw(&(centre() + PathElement::new([&corners[..], &corners[..1]].concat(), paint)))?,
        Shape::Cross => area.draw(&(centre() + Cross::new((0, 0), s, marker.colour.stroke_width(2))))?,
    }
    if let Fill::Outlined(outline) = marker.fill {
        draw_marker(area, at, Marker { colour: outline, fill: Fill::Hollow, ..marker })?;
    }
    Ok(())
}

/// Draws `stroke` along the pixel path `points`.
pub(super) fn draw_stroke(area: &Area<'_>, stroke: Stroke, points: &[(i32, i32)]) -> Result<()> {
    let style = stroke.colour.stroke_width(stroke.width);
    match stroke.dash {
        Some((dash, gap)) => area.draw(&DashedPathElement::new(points.iter().copied(), dash, gap, style))?,
        None => area.draw(&PathElement::new(points.to_vec(), style))?,
    }
    Ok(())
}

/// Draws `key`, [`KEY_WIDTH`] px wide, from `(x, y)` (its left end, vertically centred).
pub(super) fn draw_key(area: &Area<'_>, key: Key, (x, y): (i32, i32)) -> Result<()> {
    let middle = (x + KEY_WIDTH / 2, y);
    let across = |y: i32| [(x, y), (x + KEY_WIDTH, y)];
    // Lines in a key are 2 to 4 px wide, so that thin ones show and wide ones do not swamp it.
    let visible = |s: Stroke| Stroke { width: s.width.clamp(2, 4), ..s };
    match key {
        Key::Line(stroke) => draw_stroke(area, visible(stroke), &across(y)),
        Key::Marker(marker) => draw_marker(area, middle, marker),
        Key::LineMarker(stroke, marker) => {
            draw_stroke(area, visible(stroke), &across(y))?;
            draw_marker(area, middle, marker)
        }
        Key::Band(fill, edge) => {
            area.draw(&Rectangle::new([(x, y - 6), (x + KEY_WIDTH, y + 6)], fill.filled()))?;
            draw_stroke(area, edge, &across(y - 6))?;
            draw_stroke(area, edge, &across(y + 6))
        }
    }
}
