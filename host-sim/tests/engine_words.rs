//! The loop engine's core knows no system and no domain: its code (comments aside) names no
//! system and no word of one domain, alone or inside an identifier (`rotor`, `RotorSystem`,
//! `disk_mass`). The effect vocabulary's kind names (`bearing_defect`, `actuator_health`,
//! `clearance`) are the exception: users' scripts rely on them. A system's knowledge lives in
//! its folder under `systems/`, and a domain's toolkits under `diagnostics/`.

use std::path::{Path, PathBuf};

/// Words that belong to a system or a domain, matched case-insensitively inside identifiers.
const WORDS: [&str; 13] = [
    "systems::",
    "rotor",
    "crank",
    "oscillator",
    "uuv",
    "vehicle",
    "boom",
    "bearing",
    "disk",
    "thruster",
    "envelope",
    "kurtogram",
    "unbalance",
];

/// The effect vocabulary's kind names, in both spellings, allowed where they stand whole.
const KINDS: [&str; 6] =
    ["bearing_defect", "BearingDefect", "actuator_health", "ActuatorHealth", "clearance", "Clearance"];

/// `src` without its comments (line, doc and block comments; string literals are code and
/// kept, a `//` inside one included).
fn code(src: &str) -> String {
    let mut out = String::with_capacity(src.len());
    let b = src.as_bytes();
    let (mut i, mut in_str) = (0, false);
    while i < b.len() {
        if in_str {
            if b[i] == b'\\' && i + 1 < b.len() {
                out.push_str(&src[i..i + 2]);
                i += 2;
                continue;
            }
            in_str = b[i] != b'"';
        } else if src[i..].starts_with("'\"'") {
            out.push_str("'\"'");
            i += 3;
            continue;
        } else if b[i] == b'"' {
            in_str = true;
        } else if src[i..].starts_with("//") {
            i += src[i..].find('\n').unwrap_or(src.len() - i);
            continue;
        } else if src[i..].starts_with("/*") {
            i += src[i..].find("*/").map_or(src.len() - i, |e| e + 2);
            continue;
        }
        let c = src[i..].chars().next().unwrap_or(' ');
        out.push(c);
        i += c.len_utf8();
    }
    out
}

/// `(line, word)` for each system or domain word in `src`'s code.
fn offences(src: &str) -> Vec<(usize, &'static str)> {
    let mut found = Vec::new();
    for (n, line) in code(src).lines().enumerate() {
        let mut line = line.to_string();
        for k in KINDS {
            line = line.replace(k, "");
        }
        let lower = line.to_lowercase();
        found.extend(WORDS.iter().filter(|w| lower.contains(*w)).map(|w| (n + 1, *w)));
    }
    found
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("reading {}: {e}", dir.display())).flatten() {
        let path = entry.path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn the_engine_core_names_no_system_and_no_domain_word() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/residual_loop");
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    assert!(files.len() >= 10, "the engine's files were not found under {}", root.display());
    let mut report = Vec::new();
    for f in &files {
        let src = std::fs::read_to_string(f).unwrap();
        for (line, word) in offences(&src) {
            report.push(format!("{}:{line}: `{word}`", f.display()));
        }
    }
    assert!(report.is_empty(), "the engine core names a system or a domain word:\n{}", report.join("\n"));
}

#[test]
fn the_check_sees_words_in_code_and_strings_but_not_in_comments_or_kind_names() {
    let src = "/// A rotor's disk.\nfn f(disk_mass: f64) {} // unbalance\nlet s = \"RotorSystem\";\n/* boom */ let k = EffectKind::BearingDefect;\nlet c = \"clearance\"; let u = UuvState;\nlet q = \"a // b\"; let v = vehicle;\nlet e = '\"'; let d = disk; // \"\n";
    assert_eq!(offences(src), vec![(2, "disk"), (3, "rotor"), (5, "uuv"), (6, "vehicle"), (7, "disk")]);
}
