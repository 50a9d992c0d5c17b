//! Legends: what a legend entry shows before its text ([`Key`]: a line, a marker, both, or a
//! band swatch), the boxed legend in a corner of a panel, and the [`LegendColumn`] beside the
//! panels, for figures whose legend says more than a name per series (a value per run, what
//! each marker convention means).

use super::series::Key;
use super::shapes::{draw_key, KEY_WIDTH};
use super::{Area, FONT};
use anyhow::Result;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Line spacing in the legend column, px.
const LINE_HEIGHT: i32 = 15;
/// Space between two entries of the legend column, px.
const ENTRY_GAP: i32 = 10;
/// Where the legend column's first entry starts below its top, px.
const COLUMN_TOP: i32 = 32;
/// Height of one entry of a panel's legend box, px.
const ROW_HEIGHT: i32 = 18;
/// Padding inside a panel's legend box, and its distance from the axes, px.
const PAD: i32 = 6;
/// Colour of legend text.
const TEXT: RGBColor = RGBColor(40, 40, 40);

/// One entry of a [`LegendColumn`]: an optional key and lines of text (the first one larger).
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// The key; none for a heading.
    pub key: Option<Key>,
    /// The text, one element a line.
    pub lines: Vec<String>,
}

impl Entry {
    /// An entry with a key.
    pub fn new(key: Key, lines: &[&str]) -> Self {
        Self { key: Some(key), lines: lines.iter().map(|s| s.to_string()).collect() }
    }

    /// A heading: text without a key.
    pub fn heading(lines: &[&str]) -> Self {
        Self { key: None, lines: lines.iter().map(|s| s.to_string()).collect() }
    }
}

/// A legend column right of a figure's panels.
#[derive(Debug, Clone, PartialEq)]
pub struct LegendColumn {
    /// Width, px.
    pub width: u32,
    /// Entries, top to bottom.
    pub entries: Vec<Entry>,
}

impl LegendColumn {
    /// Draws the entries on `area`, top to bottom.
    pub(super) fn draw(&self, area: &Area<'_>) -> Result<()> {
        let mut top = COLUMN_TOP;
        let text_x = 8 + KEY_WIDTH + 10;
        for entry in &self.entries {
            let n = entry.lines.len().max(1) as i32;
            for (i, line) in entry.lines.iter().enumerate() {
                let size = if i == 0 { 13 } else { 11 };
                let style = (FONT, size).into_font().color(&TEXT);
                area.draw(&Text::new(line.clone(), (text_x, top + LINE_HEIGHT * i as i32), style))?;
            }
            if let Some(key) = entry.key {
                draw_key(area, key, (8, top + (LINE_HEIGHT * n - 2) / 2))?;
            }
            top += LINE_HEIGHT * n + ENTRY_GAP;
        }
        Ok(())
    }
}

/// A corner of a panel's plotting area.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Corner {
    /// Upper right.
    UpperRight,
    /// Upper left.
    UpperLeft,
    /// Lower right.
    LowerRight,
    /// Lower left.
    LowerLeft,
}

/// Draws `entries` in a box in `corner` of the plotting area `area`.
pub(super) fn draw_box(area: &Area<'_>, entries: &[(Key, String)], corner: Corner) -> Result<()> {
    let style = (FONT, 12).into_font().color(&TEXT);
    let mut text_width = 0;
    for (_, text) in entries {
        text_width = text_width.max(area.estimate_text_size(text, &style)?.0 as i32);
    }
    let (w, h) = (3 * PAD + KEY_WIDTH + text_width + PAD, 2 * PAD + ROW_HEIGHT * entries.len() as i32);
    let (area_w, area_h) = area.dim_in_pixel();
    let (area_w, area_h) = (area_w as i32, area_h as i32);
    let x = match corner {
        Corner::UpperLeft | Corner::LowerLeft => PAD,
        Corner::UpperRight | Corner::LowerRight => area_w - w - PAD,
    };
    let y = match corner {
        Corner::UpperLeft | Corner::UpperRight => PAD,
        Corner::LowerLeft | Corner::LowerRight => area_h - h - PAD,
    };
    area.draw(&Rectangle::new([(x, y), (x + w, y + h)], WHITE.mix(0.85).filled()))?;
    area.draw(&Rectangle::new([(x, y), (x + w, y + h)], RGBColor(190, 190, 190).stroke_width(1)))?;
    let style = style.pos(Pos::new(HPos::Left, VPos::Center));
    for (i, (key, text)) in entries.iter().enumerate() {
        let middle = y + PAD + ROW_HEIGHT * i as i32 + ROW_HEIGHT / 2;
        draw_key(area, *key, (x + PAD, middle))?;
        area.draw(&Text::new(text.clone(), (x + 3 * PAD + KEY_WIDTH, middle), style.clone()))?;
    }
    Ok(())
}
