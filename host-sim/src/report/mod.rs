//! What the residual loop writes: `report.json` for scripts, `report.html` (with its plots) and
//! the printed table for people.
//!
//! * [`html`]: the self-contained HTML page with SVG plots;
//! * [`text`]: the printed table and the report files.

pub mod html;
pub mod text;
