//! The evidence behind a named bearing family, drawn for the report: the squared envelope
//! spectrum of the channel and band the family was found in, prewhitened, as dB over its local
//! median, the family's members marked where they were found. An engineer checks a bearing
//! diagnosis by looking at exactly this plot.

use crate::diagnostics::bearings::family::{self, FamilyFit, Verdict};
use crate::report::plot::{Axis, Figure, Line, Marker, Markers, Panel, RGBColor, Shape};
use crate::residual_loop::SystemFigure;

/// The SES's colour.
const SES: RGBColor = RGBColor(31, 100, 180);
/// The members' colour and the carry level's.
const MEMBER: RGBColor = RGBColor(200, 40, 40);
const LEVEL: RGBColor = RGBColor(120, 120, 120);

/// The figure for `verdict` (none for `Nothing`), from `channels` sampled at `fs` (the same
/// channels the detector read) at a shaft speed of `shaft_hz`.
pub(super) fn figure(verdict: &Verdict, channels: &[(&str, &[f64])], fs: f64, shaft_hz: f64) -> Option<SystemFigure> {
    let fits: Vec<&FamilyFit> = match verdict {
        Verdict::Named(f) => vec![f],
        Verdict::CannotTell(a, b) => vec![a, b],
        Verdict::Nothing => return None,
    };
    let panels: Vec<Panel> = fits.iter().filter_map(|f| panel(f, *channels.get(f.channel)?, fs, shaft_hz)).collect();
    if panels.is_empty() {
        return None;
    }
    let rows = panels.len() as u32;
    let svg = Figure::new("Squared envelope spectrum of the named bearing family", (960, 240 * rows), panels)
        .columns(1)
        .svg()
        .ok()?;
    let caption = format!(
        "Squared envelope spectrum of the prewhitened vibration in the band the family was found in, in dB over \
         its local median (one shaft order either side); the channel, band and score are in the panel's title. Red dots: the family's members where they were found, \
         labelled; grey: the {:.0} dB a member must reach (and the family's chance below {:.0e}) for the data to \
         carry it.",
        family::CARRY.min_db,
        family::CARRY.false_alarm
    );
    Some(SystemFigure { svg, caption })
}

/// One family's panel: up to its highest member and a shaft order beyond.
fn panel(f: &FamilyFit, (name, x): (&str, &[f64]), fs: f64, shaft_hz: f64) -> Option<Panel> {
    let top = f.members.iter().map(|m| m.hz).fold(0.0, f64::max) + shaft_hz;
    let (df, power, floor) = family::envelope_spectrum(x, fs, &f.band, top, shaft_hz);
    let db: Vec<(f64, f64)> = power
        .iter()
        .zip(&floor)
        .enumerate()
        .skip(1)
        .filter(|(_, (p, m))| **p > 0.0 && **m > 0.0)
        .map(|(k, (p, m))| (k as f64 * df, 10.0 * (p / m).log10()))
        .collect();
    if db.len() < 2 {
        return None;
    }
    let title = format!(
        "{} at {}: {name}, band {:.0}–{:.0} Hz, score {:.1}",
        f.family.name(),
        f.bearing,
        f.band.low_hz,
        f.band.high_hz,
        f.score
    );
    let mut p = Panel::new(&title, "frequency (Hz)", "dB over the local median");
    let shown: Vec<_> = f.members.iter().filter(|m| m.strength_db.is_finite() && !m.on_order).collect();
    let points = shown.iter().map(|m| (m.hz, m.strength_db)).collect();
    let labels = shown.iter().map(|m| m.label.clone()).collect();
    p.x = Axis::linear(&db.iter().map(|q| q.0).collect::<Vec<_>>());
    p.y = Axis::linear(&db.iter().map(|q| q.1).chain([family::CARRY.min_db]).collect::<Vec<_>>()).headroom(0.45);
    p.lines.push(Line::horizontal("", LEVEL, p.x, family::CARRY.min_db));
    p.lines.push(Line::new("SES", SES, db));
    p.markers.push(Markers::new("members", Marker::new(Shape::Circle, 4, MEMBER), points).labelled(labels, true));
    Some(p)
}
