//! `report.html` of the residual loop, from a real loop: the paper rotor with an undeclared
//! 20 µm bias on `n5_x`.

use edgekf_sim::report::html::render;
use edgekf_sim::residual_loop::{LoopOptions, LoopReport};
use edgekf_sim::systems::rotor::loop_system::cases::Case;
use edgekf_sim::systems::rotor::loop_system::close_loop;
use edgekf_sim::systems::rotor::loop_system::inject::inject_bias;
use edgekf_sim::systems::rotor::{RotorConfig, RotorModel, SimOptions};

fn biased_report() -> LoopReport {
    let cfg = RotorConfig::from_toml_str(include_str!("../configs/rotor_paper.toml")).unwrap();
    let model = RotorModel::from_config(&cfg).unwrap();
    let mut data =
        model.simulate(&SimOptions { duration: 3.0, seed: 3, ..SimOptions::default() }).unwrap().to_data_file();
    inject_bias(&mut data, "n5_x", 20e-6).unwrap();
    close_loop(&model, &data, &LoopOptions { screen_parameters: false, ..LoopOptions::default() }, &Default::default())
        .unwrap()
}

/// Writes `html` to `$EDGEKF_HTML_OUT/name` when that is set (to look at the page).
fn keep(html: &str, name: &str) {
    if let Ok(dir) = std::env::var("EDGEKF_HTML_OUT") {
        std::fs::write(std::path::Path::new(&dir).join(name), html).unwrap();
    }
}

/// The text of the first `<td>` after `marker`.
fn first_cell_after<'a>(html: &'a str, marker: &str) -> &'a str {
    let at = html.find(marker).unwrap_or_else(|| panic!("no {marker}"));
    let rest = &html[at + marker.len()..];
    let td = rest.find("<td").unwrap();
    let open = td + rest[td..].find('>').unwrap() + 1;
    let close = open + rest[open..].find("</td>").unwrap();
    &rest[open..close]
}

#[test]
fn report_page_shows_the_loop() {
    let report = biased_report();
    let html = render(&report).unwrap();
    keep(&html, "bias.html");

    // A self-contained document.
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
    for external in ["src=", "href=\"http", "href='http", "<script", "<link", "@import", "url("] {
        assert!(!html.contains(external), "the page refers to something outside: {external}");
    }
    assert!(html.len() < 2_000_000, "page of {} bytes", html.len());

    // Five plots (innovations, spectra, NIS, and with the truth: zoom and error), all closed.
    assert!(report.traces.truth.iter().any(Option::is_some));
    assert_eq!(html.matches("<svg").count(), 5);
    assert_eq!(html.matches("</svg>").count(), 5);
    for tag in ["table", "figure", "details", "main", "tbody"] {
        assert_eq!(html.matches(&format!("<{tag}>")).count(), html.matches(&format!("</{tag}>")).count(), "{tag}");
    }
    assert!(!html.contains("NaN"));

    // The effect the loop added: kind, location and value (20 µm).
    let bias = report.effects_added.iter().find(|e| e.kind == "sensor_bias").expect("the bias is found");
    assert_eq!(bias.location, "n5_x");
    let row = format!("<td>sensor_bias</td><td>{}</td><td>–</td>", bias.location);
    let shown = first_cell_after(&html, &row);
    assert!(shown.ends_with(" µm"), "{shown}");
    let um: f64 = shown.trim_end_matches(" µm").parse().unwrap();
    assert!((um - bias.value * 1e6).abs() < 0.01 && (um - 20.0).abs() < 2.0, "{um} µm");

    // The innovation RMS of n5_x before, in µm, as computed (four significant digits).
    let before: f64 = first_cell_after(&html, "<th scope=\"row\">n5_x ").parse().unwrap();
    assert!((before / (report.before.innovation_rms["n5_x"] * 1e6) - 1.0).abs() <= 5e-4, "{before}");
    // ... and the improvement is highlighted.
    assert!(report.after.innovation_rms["n5_x"] < 0.5 * report.before.innovation_rms["n5_x"]);
    assert!(html.contains("class=\"num better\""));

    // Why the loop stopped, and the candidates in a collapsed list.
    let escaped = report.stopped.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;");
    assert!(html.contains(&escaped.replace('"', "&quot;").replace('\'', "&#39;")));
    assert!(html.contains("<details>\n<summary>"));
    assert_eq!(html.matches("<tr class=\"kept\">").count(), report.trials.iter().filter(|t| t.accepted).count());
}

/// The `<svg>` element whose accessible name starts with `label`.
fn svg_named<'a>(html: &'a str, label: &str) -> &'a str {
    let at = html.find(&format!("<svg role=\"img\" aria-label=\"{label}")).unwrap_or_else(|| panic!("no {label}"));
    &html[at..at + html[at..].find("</svg>").unwrap()]
}

#[test]
fn spectral_lines_are_marked_and_labelled() {
    let data = Case::TwoX.data(3).unwrap();
    let options = LoopOptions { screen_parameters: false, ..LoopOptions::default() };
    let report = close_loop(&Case::declared().unwrap(), &data, &options, &Default::default()).unwrap();
    let html = render(&report).unwrap();
    keep(&html, "two_x.html");

    let force = report.effects_added.iter().find(|e| e.kind == "harmonic_force").expect("the 2x force is found");
    let row = format!("<td>harmonic_force</td><td>{}</td><td>2x</td>", force.location);
    assert!(html.contains(&row), "no effect row {row}");
    assert!(!force.explains.is_empty());
    let explained: Vec<String> = force.explains.iter().map(|f| format!("{f:.2}")).collect();
    assert!(html.contains(&format!("<td>{}</td></tr>", explained.join(", "))));

    // Every line detected before is marked on its channel's spectrum, labelled by its class.
    let spectra = svg_named(&html, "Spectra");
    let peaks: Vec<&str> = report.before.channels.iter().flat_map(|c| &c.peaks).map(|p| p.class.as_str()).collect();
    assert!(peaks.contains(&"2x"), "{peaks:?}");
    for class in peaks {
        assert!(spectra.contains(&format!(">\n{class}\n</text>")), "no label {class}");
    }
    assert!(spectra.contains("lines before"));
}
