//! Checks on the SVG figures a report page embeds, read as the plot kit writes them (plotters'
//! SVG): each panel's axes are a black vertical and a black horizontal line meeting at the
//! lower left; a plotted series is a coloured polyline of one pixel; a label is a `<text>`.
//!
//! * every panel has a series with points inside its axes (no empty axes);
//! * every series has most of its points inside one panel's axes;
//! * no two labels' boxes overlap (a box estimated from the font size and the text's length:
//!   0.55 em a character, 1 em high, placed by its anchor and baseline shift).

/// What is wrong with the figures of `html`, one line each (empty when nothing is).
pub fn svg_defects(html: &str) -> Vec<String> {
    let mut out = Vec::new();
    for svg in html.split("<svg").skip(1).map(|s| s.split("</svg>").next().unwrap_or_default()) {
        let name = attr(svg, "aria-label").unwrap_or("?").to_string();
        out.extend(figure_defects(svg).into_iter().map(|d| format!("{name}: {d}")));
    }
    out
}

/// The value of `name="…"` in `tag`.
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let at = tag.find(&key)? + key.len();
    tag[at..].split('"').next()
}

/// The elements `<tag …>` of `svg` with their text up to the next `<`.
fn elements<'a>(svg: &'a str, tag: &str) -> Vec<(&'a str, &'a str)> {
    let open = format!("<{tag} ");
    svg.split('<')
        .filter(|e| e.starts_with(&open[1..]))
        .map(|e| e.split_once('>').map_or((e, ""), |(a, t)| (a, t.trim())))
        .collect()
}

type Pt = (f64, f64);

fn points(tag: &str) -> Vec<Pt> {
    attr(tag, "points")
        .unwrap_or_default()
        .split_whitespace()
        .filter_map(|p| p.split_once(',').and_then(|(x, y)| Some((x.parse().ok()?, y.parse().ok()?))))
        .collect()
}

/// One figure's defects.
fn figure_defects(svg: &str) -> Vec<String> {
    let lines: Vec<(&str, Vec<Pt>)> = elements(svg, "polyline").into_iter().map(|(a, _)| (a, points(a))).collect();
    let axes = axes(&lines);
    let series: Vec<&Vec<Pt>> = lines
        .iter()
        .filter(|(a, p)| attr(a, "stroke") != Some("#000000") && attr(a, "stroke-width") == Some("1") && p.len() > 2)
        .map(|(_, p)| p)
        .collect();
    let inside =
        |b: &[f64; 4], p: &Pt| b[0] - 1.0 <= p.0 && p.0 <= b[2] + 1.0 && b[1] - 1.0 <= p.1 && p.1 <= b[3] + 1.0;
    let mut out = Vec::new();
    for b in &axes {
        if !series.iter().any(|s| s.iter().filter(|p| inside(b, p)).count() >= 2) {
            out.push(format!("empty axes at x {}–{}, y {}–{}", b[0], b[2], b[1], b[3]));
        }
    }
    for s in &series {
        let most = axes.iter().map(|b| s.iter().filter(|p| inside(b, p)).count()).max().unwrap_or(0);
        if 2 * most < s.len() {
            out.push(format!("a series with {most} of its {} points inside its axes", s.len()));
        }
    }
    out.extend(overlaps(svg));
    out
}

/// Each panel's plotting box `[left, top, right, bottom]`: a black vertical line whose foot
/// meets the start of a black horizontal one.
fn axes(lines: &[(&str, Vec<Pt>)]) -> Vec<[f64; 4]> {
    let black: Vec<&Vec<Pt>> =
        lines.iter().filter(|(a, p)| attr(a, "stroke") == Some("#000000") && p.len() == 2).map(|(_, p)| p).collect();
    let mut out = Vec::new();
    for v in black.iter().filter(|p| p[0].0 == p[1].0 && (p[0].1 - p[1].1).abs() > 20.0) {
        let (x, top, foot) = (v[0].0, v[0].1.min(v[1].1), v[0].1.max(v[1].1));
        for h in black.iter().filter(|p| p[0].1 == p[1].1 && (p[0].0 - p[1].0).abs() > 20.0) {
            let (y, left, right) = (h[0].1, h[0].0.min(h[1].0), h[0].0.max(h[1].0));
            if (left - x).abs() <= 2.0 && (y - foot).abs() <= 2.0 {
                out.push([x, top, right, y]);
            }
        }
    }
    out
}

/// Pairs of labels whose estimated boxes overlap by more than a pixel each way.
fn overlaps(svg: &str) -> Vec<String> {
    let boxes: Vec<(String, [f64; 4])> = elements(svg, "text")
        .into_iter()
        .filter(|(_, t)| !t.is_empty())
        .filter_map(|(a, t)| {
            let num = |k| attr(a, k).and_then(|v| v.parse::<f64>().ok());
            let (x, y, f) = (num("x")?, num("y")?, num("font-size").unwrap_or(10.0));
            let (mut w, mut h) = (0.55 * f * t.chars().count() as f64, f);
            let top = match attr(a, "dy") {
                Some("0.76em") => y,
                Some(d) if d.ends_with("ex") => y - h,
                _ => y - 0.8 * h,
            };
            let left = match attr(a, "text-anchor") {
                Some("middle") => x - w / 2.0,
                Some("end") => x - w,
                _ => x,
            };
            if attr(a, "transform").is_some_and(|t| t.starts_with("rotate")) {
                // Turned upright about (x, y): the box turns with it.
                std::mem::swap(&mut w, &mut h);
                return Some((t.to_string(), [x - w / 2.0, y - h / 2.0, x + w / 2.0, y + h / 2.0]));
            }
            Some((t.to_string(), [left, top, left + w, top + h]))
        })
        .collect();
    let mut out = Vec::new();
    for (i, (ta, a)) in boxes.iter().enumerate() {
        for (tb, b) in &boxes[i + 1..] {
            if a[2].min(b[2]) - a[0].max(b[0]) > 1.0 && a[3].min(b[3]) - a[1].max(b[1]) > 1.0 {
                out.push(format!("labels `{ta}` and `{tb}` overlap"));
            }
        }
    }
    out
}

#[test]
fn the_checker_finds_empty_axes_a_stray_series_and_a_label_pile() {
    let axes = "<polyline stroke=\"#000000\" stroke-width=\"1\" points=\"10,10 10,110 \"/>\
                <polyline stroke=\"#000000\" stroke-width=\"1\" points=\"10,110 210,110 \"/>";
    let series = |pts: &str| format!("<polyline stroke=\"#1F64B4\" stroke-width=\"1\" points=\"{pts}\"/>");
    let text = |x: u32, t: &str| format!("<text x=\"{x}\" y=\"50\" font-size=\"12\">\n{t}\n</text>");
    let svg = |body: String| format!("<svg role=\"img\" aria-label=\"f\">{axes}{body}</svg>");
    assert!(svg_defects(&svg(series("20,20 30,30 40,40 "))).is_empty());
    assert_eq!(svg_defects(&svg(String::new())), ["f: empty axes at x 10–210, y 10–110"]);
    let stray = svg(series("20,20 30,30 400,400 500,500 600,600 "));
    assert!(svg_defects(&stray).iter().any(|d| d.contains("2 of its 5 points")), "{:?}", svg_defects(&stray));
    let pile = svg(series("20,20 30,30 40,40 ") + &text(50, "natural 0") + &text(60, "natural 0"));
    assert_eq!(svg_defects(&pile), ["f: labels `natural 0` and `natural 0` overlap"]);
}
