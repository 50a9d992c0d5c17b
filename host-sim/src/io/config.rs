//! Configuration files (TOML): one parser for every system, whose errors are one line with the
//! line and column of the problem (the `toml` crate's own message spans several lines, with a
//! drawing of the offending text, which does not fit a one-line error convention).

use serde::de::DeserializeOwned;

/// A TOML text that does not parse into the expected configuration.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("line {line}, column {column} (`{text}`): {message}")]
pub struct TomlError {
    /// 1-based line of the problem.
    pub line: usize,
    /// 1-based column (in characters).
    pub column: usize,
    /// That line of the file (trimmed, at most 60 characters): it names the key.
    pub text: String,
    /// What is wrong, one line.
    pub message: String,
}

/// Parses `text` as a `T`.
///
/// ```
/// use edgekf_sim::io::config::parse_toml;
/// #[derive(serde::Deserialize, Debug)]
/// #[serde(deny_unknown_fields)]
/// struct Sensor { rate: f64 }
/// let e = parse_toml::<Sensor>("# a sensor\nrate = \"fast\"\n").unwrap_err();
/// assert_eq!((e.line, e.column), (2, 8));
/// assert_eq!(e.to_string(), "line 2, column 8 (`rate = \"fast\"`): invalid type: string \"fast\", expected f64");
/// assert!(!e.to_string().contains('\n'));
/// assert_eq!(parse_toml::<Sensor>("rate = 100.0").unwrap().rate, 100.0);
/// ```
pub fn parse_toml<T: DeserializeOwned>(text: &str) -> Result<T, TomlError> {
    toml::from_str(text).map_err(|e| {
        let at = e.span().map_or(0, |s| s.start).min(text.len());
        let before = &text[..at];
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        let message = e.message().split_whitespace().collect::<Vec<_>>().join(" ");
        let text: String = text.lines().nth(line - 1).unwrap_or("").trim().chars().take(60).collect();
        TomlError { line, column, text, message }
    })
}
