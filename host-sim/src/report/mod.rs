//! What the residual loop writes: `report.json` for scripts, `report.html` (with its plots) and
//! the printed table for people; and the plot kit that draws the project's figures.
//!
//! * [`html`]: the self-contained HTML page with SVG plots;
//! * [`plot`]: the plot kit (panels, axes, lines, markers, legends to one SVG), which knows no
//!   system: the page and the README's figures draw with it;
//! * [`text`]: the printed table and the report files;
//! * [`summary`]: the JSON summary of `edgekf <system> estimate --json`.

pub(crate) mod escape;
pub mod html;
pub mod plot;
pub mod summary;
pub mod text;
