//! Rust source for a node's constants (`edgekf boom export`, `edgekf uuv export`): each value a
//! `pub const` item whose initialiser is the value's `Debug` form. The shared crate's plain
//! data (public fields of `f64`, `usize`, `bool`, arrays, and structs of those) prints as its
//! own struct literal, and `f64`'s `Debug` round-trips the bits, so the image compiles exactly
//! the host's numbers. A value that is not finite is refused: its `Debug` (`NaN`, `inf`) is no
//! literal.

use anyhow::{bail, Result};
use std::fmt::Debug;

/// A generated file, built item by item.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstFile {
    text: String,
}

impl ConstFile {
    /// A file opening with `header`, each line a `//` comment.
    pub fn new(header: &[&str]) -> Self {
        let text = header.iter().map(|l| format!("// {l}\n")).collect();
        Self { text }
    }

    /// Adds `pub const NAME: TYPE = value;` under the doc comment `doc`.
    ///
    /// ```
    /// use edgekf_sim::io::rust_consts::ConstFile;
    /// let mut f = ConstFile::new(&["Generated."]);
    /// f.item("Lag and noise.", "PAIR", "(f64, f64)", &(0.3, 5e-4)).unwrap();
    /// assert!(f.item("Broken.", "BAD", "f64", &f64::NAN).is_err());
    /// let text = "// Generated.\n/// Lag and noise.\npub const PAIR: (f64, f64) = (\n    0.3,\n    0.0005,\n);\n";
    /// assert_eq!(f.finish(), text);
    /// ```
    pub fn item(&mut self, doc: &str, name: &str, ty: &str, value: &impl Debug) -> Result<&mut Self> {
        let literal = format!("{value:#?}");
        if let Some(bad) = literal.split(|c: char| !c.is_alphanumeric()).find(|w| matches!(*w, "NaN" | "inf")) {
            bail!("{name}: a value is {bad}, not a number the node can be built with");
        }
        for line in doc.lines() {
            self.text.push_str(&format!("/// {line}\n"));
        }
        self.text.push_str(&format!("pub const {name}: {ty} = {literal};\n"));
        Ok(self)
    }

    /// The file's text.
    pub fn finish(self) -> String {
        self.text
    }
}
