//! A figure: panels laid out on a grid, an optional title over them and legend column right of
//! them, drawn into one SVG document whose root element carries `role="img"` and an
//! `aria-label`, so that a screen reader can name it where the SVG is inlined or linked.

use super::legend::LegendColumn;
use super::{Panel, FONT};
use crate::report::escape::escape;
use anyhow::Result;
use plotters::prelude::*;

/// A figure of panels.
///
/// ```
/// use edgekf_sim::report::plot::{Entry, Figure, Key, LegendColumn, Line, Panel, RGBColor, Stroke};
///
/// let grey = RGBColor(120, 120, 120);
/// let panels: Vec<Panel> = ["left", "right"]
///     .iter()
///     .map(|title| {
///         let mut p = Panel::new(title, "t (s)", "y");
///         p.lines.push(Line::new("", grey, vec![(0.0, 0.2), (1.0, 0.8)]));
///         p
///     })
///     .collect();
/// let legend = LegendColumn { width: 120, entries: vec![Entry::new(Key::Line(Stroke::solid(grey, 1)), &["a ramp"])] };
/// let figure = Figure::new("Two ramps", (800, 240), panels).columns(2).titled("Ramps").with_legend(legend);
/// assert_eq!(figure.grid(), (1, 2));
/// let svg = figure.svg()?;
/// assert!(svg.starts_with("<svg role=\"img\" aria-label=\"Two ramps\""));
/// assert!(svg.contains("Ramps") && svg.contains("a ramp"));
/// # anyhow::Ok(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// What the figure shows, for screen readers (the SVG's `aria-label`).
    pub label: String,
    /// Title over the panels (none when empty).
    pub title: String,
    /// Width and height, px.
    pub size: (u32, u32),
    /// Panels in a row; the grid has as many rows as it needs.
    pub columns: usize,
    /// The panels, row by row.
    pub panels: Vec<Panel>,
    /// A legend column right of the panels.
    pub legend: Option<LegendColumn>,
}

impl Figure {
    /// A figure of `size` px with `panels` in one column, no title and no legend column.
    pub fn new(label: &str, size: (u32, u32), panels: Vec<Panel>) -> Self {
        Self { label: label.into(), title: String::new(), size, columns: 1, panels, legend: None }
    }

    /// The figure with the panels `columns` to a row.
    pub fn columns(self, columns: usize) -> Self {
        Self { columns, ..self }
    }

    /// The figure with a title over the panels.
    pub fn titled(self, title: &str) -> Self {
        Self { title: title.into(), ..self }
    }

    /// The figure with a legend column right of the panels.
    pub fn with_legend(self, legend: LegendColumn) -> Self {
        Self { legend: Some(legend), ..self }
    }

    /// The panels' grid: (rows, columns), at least one of each.
    pub fn grid(&self) -> (usize, usize) {
        let cols = self.columns.clamp(1, self.panels.len().max(1));
        (self.panels.len().div_ceil(cols).max(1), cols)
    }

    /// Draws the figure as an SVG document.
    pub fn svg(&self) -> Result<String> {
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, self.size).into_drawing_area();
            root.fill(&WHITE)?;
            let body = if self.title.is_empty() { root.clone() } else { root.titled(&self.title, (FONT, 17))? };
            let (panels, legend) = match &self.legend {
                Some(l) => {
                    let (panels, column) = body.split_horizontally(self.size.0.saturating_sub(l.width));
                    (panels, Some((column, l)))
                }
                None => (body, None),
            };
            for (area, panel) in panels.split_evenly(self.grid()).iter().zip(&self.panels) {
                panel.draw(area)?;
            }
            if let Some((area, l)) = legend {
                l.draw(&area)?;
            }
            root.present()?;
        }
        Ok(svg.replacen("<svg ", &format!("<svg role=\"img\" aria-label=\"{}\" ", escape(&self.label)), 1))
    }
}
