//! Edits to a user's TOML configuration that keep its comments, order and layout (through
//! `toml_edit`): how a corrected configuration carries what the loop found back into the
//! model. A key path names a number through tables and arrays of tables; an entry of an array
//! of tables is picked by its keys, by its place (`#n`, from 1 as the entries stand in the
//! file), or `*` for every entry:
//! `tip.mass`, `section[*].ei`, `section[#3].ei`, `disk[node=12].mass`, `sensor[node=5,direction=x].bias`;
//! `point_mass[+node=12].mass` appends a new entry with those keys. A key the configuration
//! lacks is added when the edit says what the model takes without it.

use serde::Serialize;
use thiserror::Error;
use toml_edit::{DocumentMut, Item, Table, Value};

/// What an edit does to the number at its path.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "op", content = "by")]
pub enum Op {
    /// Multiplies it.
    Scale(f64),
    /// Adds to it.
    Add(f64),
    /// Replaces it.
    Set(f64),
    /// Makes the key a switch in this position (the edit's `absent` is then ignored: a
    /// missing switch is added).
    Switch(bool),
}

/// One change to one key path, with the note the corrected file shows above it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConfigEdit {
    /// The key path (see the module's doc).
    pub path: String,
    /// What is done to the number there.
    pub op: Op,
    /// The value the model takes when the key is absent (the edit then adds the key); `None`
    /// makes a missing key an error.
    pub absent: Option<f64>,
}

impl ConfigEdit {
    /// `op` on the number at `path`, which must exist.
    pub fn new(path: impl Into<String>, op: Op) -> Self {
        Self { path: path.into(), op, absent: None }
    }

    /// `op` on the number at `path`, or on `absent` where the configuration lacks the key.
    pub fn or_absent(path: impl Into<String>, op: Op, absent: f64) -> Self {
        Self { path: path.into(), op, absent: Some(absent) }
    }
}

/// Why an edit could not be applied.
#[derive(Debug, Error, PartialEq)]
pub enum EditError {
    /// The file is not TOML.
    #[error("the configuration is not valid TOML: {0}")]
    Parse(String),
    /// The path is not of the form the module's doc gives.
    #[error("`{0}` is not a key path")]
    Path(String),
    /// Nothing in the file matches the path, and the edit has no value for a missing key.
    #[error("the configuration has no `{0}`")]
    Missing(String),
    /// The value at the path is not a number.
    #[error("`{0}` is not a number")]
    NotNumber(String),
}

/// The selector key of an entry picked by its place (`[#n]`).
const PLACE: &str = "#";

/// One step of a key path: a key, and for an array of tables the entries it picks.
#[derive(Debug, Clone, PartialEq)]
struct Step {
    key: String,
    /// `None`: a plain table or value; `Some(vec![])`: every entry (`*`); else `key=value`s.
    select: Option<Vec<(String, String)>>,
    /// A new entry with the selector's keys (`[+key=value]`).
    append: bool,
}

fn parse_path(path: &str) -> Result<Vec<Step>, EditError> {
    let bad = || EditError::Path(path.to_string());
    let mut steps = Vec::new();
    for part in path.split('.') {
        let mut append = false;
        let (key, select) = match part.split_once('[') {
            None => (part, None),
            Some((key, rest)) => {
                let mut inner = rest.strip_suffix(']').ok_or_else(bad)?;
                if let Some(new) = inner.strip_prefix('+') {
                    (append, inner) = (true, new);
                }
                let select = if inner == "*" {
                    Vec::new()
                } else if let Some(n) = inner.strip_prefix('#') {
                    n.parse::<usize>().ok().filter(|n| *n >= 1).ok_or_else(bad)?;
                    vec![(PLACE.to_string(), n.to_string())]
                } else {
                    let pairs = inner.split(',').map(|kv| kv.split_once('=').map(|(k, v)| (k.trim(), v.trim())));
                    pairs
                        .map(|p| p.map(|(k, v)| (k.to_string(), v.to_string())).ok_or_else(bad))
                        .collect::<Result<_, _>>()?
                };
                (key, Some(select))
            }
        };
        if key.is_empty() {
            return Err(bad());
        }
        if append && select.as_ref().is_none_or(Vec::is_empty) {
            return Err(bad());
        }
        steps.push(Step { key: key.to_string(), select, append });
    }
    if steps.last().is_none_or(|s| s.select.is_some()) {
        return Err(bad());
    }
    Ok(steps)
}

/// Whether a table's `key` reads as `want` (a number compared as a number, a string as text).
fn matches(table: &Table, key: &str, want: &str) -> bool {
    match table.get(key).and_then(Item::as_value) {
        Some(Value::String(s)) => s.value() == want,
        Some(Value::Integer(i)) => want.parse::<i64>().is_ok_and(|w| w == *i.value()),
        Some(Value::Float(f)) => want.parse::<f64>().is_ok_and(|w| w == *f.value()),
        Some(Value::Boolean(b)) => want.parse::<bool>().is_ok_and(|w| w == *b.value()),
        _ => false,
    }
}

/// The tables the path's steps but the last lead to (created where a plain table is missing
/// and the edit may add its key).
fn tables<'a>(root: &'a mut Table, steps: &[Step], create: bool) -> Vec<&'a mut Table> {
    let mut here = vec![root];
    for step in steps {
        let mut next = Vec::new();
        for table in here {
            if step.select.is_none() && create && !table.contains_key(&step.key) {
                table.insert(&step.key, Item::Table(Table::new()));
            }
            if step.append {
                append(table, step);
            }
            match (table.get_mut(&step.key), &step.select) {
                (Some(Item::Table(t)), None) => next.push(t),
                (Some(Item::ArrayOfTables(array)), Some(select)) => {
                    let last = array.len().saturating_sub(1);
                    let picked = |i: usize, t: &Table| {
                        if step.append {
                            i == last
                        } else {
                            select
                                .iter()
                                .all(|(k, v)| if k == PLACE { v.parse() == Ok(i + 1) } else { matches(t, k, v) })
                        }
                    };
                    next.extend(array.iter_mut().enumerate().filter(|(i, t)| picked(*i, t)).map(|(_, t)| t));
                }
                _ => {}
            }
        }
        here = next;
    }
    here
}

/// A new entry of the array of tables `step.key` (made if missing) with the selector's keys,
/// numbers as numbers and anything else as text; the path goes on into it (the last entry).
fn append(table: &mut Table, step: &Step) {
    if !table.contains_key(&step.key) {
        table.insert(&step.key, Item::ArrayOfTables(toml_edit::ArrayOfTables::new()));
    }
    let Some(Item::ArrayOfTables(array)) = table.get_mut(&step.key) else { return };
    let mut entry = Table::new();
    for (k, v) in step.select.iter().flatten() {
        let value = match (v.parse::<i64>(), v.parse::<f64>()) {
            (Ok(i), _) => toml_edit::value(i),
            (_, Ok(f)) => toml_edit::value(f),
            _ => toml_edit::value(v.as_str()),
        };
        entry.insert(k, value);
    }
    array.push(entry);
}

/// Applies `edit` to `doc`, with `note` as a comment line above each key it changes.
fn apply(doc: &mut DocumentMut, edit: &ConfigEdit, note: &str) -> Result<(), EditError> {
    let steps = parse_path(&edit.path)?;
    let (last, parents) = steps.split_last().ok_or_else(|| EditError::Path(edit.path.clone()))?;
    let found = tables(doc.as_table_mut(), parents, edit.absent.is_some());
    if found.is_empty() {
        return Err(EditError::Missing(edit.path.clone()));
    }
    for table in found {
        if let Op::Switch(on) = edit.op {
            let old = table.get(&last.key).and_then(Item::as_bool).map_or("absent".to_string(), |b| b.to_string());
            table.insert(&last.key, toml_edit::value(on));
            mark(table, &last.key, &format!("{note}: was {old}"));
            continue;
        }
        let old = match table.get(&last.key) {
            None => edit.absent.ok_or_else(|| EditError::Missing(edit.path.clone()))?,
            Some(item) => match item.as_value() {
                Some(Value::Float(f)) => *f.value(),
                Some(Value::Integer(i)) => *i.value() as f64,
                _ => return Err(EditError::NotNumber(edit.path.clone())),
            },
        };
        let new = match edit.op {
            Op::Scale(f) => old * f,
            Op::Add(d) => old + d,
            Op::Set(v) => v,
            Op::Switch(_) => continue,
        };
        let keep = table.get(&last.key).and_then(Item::as_value).map(|v| v.decor().suffix().cloned());
        table.insert(&last.key, toml_edit::value(new));
        if let (Some(Some(suffix)), Some(v)) = (keep, table.get_mut(&last.key).and_then(Item::as_value_mut)) {
            v.decor_mut().set_suffix(suffix);
        }
        mark(table, &last.key, &format!("{note}: was {old}"));
    }
    Ok(())
}

/// Puts `line` as a comment above `key` (after any comment already there).
fn mark(table: &mut Table, key: &str, line: &str) {
    if let Some(mut k) = table.key_mut(key) {
        let prefix = k.leaf_decor().prefix().and_then(|p| p.as_str()).unwrap_or("").to_string();
        k.leaf_decor_mut().set_prefix(format!("{prefix}# {line}\n"));
    }
}

/// `text` with every `(note, edit)` applied in order; the rest of the file (comments, order,
/// layout) as it was.
///
/// ```
/// use edgekf_sim::io::config_edit::{corrected, ConfigEdit, Op};
/// let text = "[tip]\nmass = 300.0 # kg\n\n[[disk]]\nnode = 12\nmass = 2.0\n";
/// let edits = [
///     ("report.json: tip mass ×1.5".to_string(), ConfigEdit::new("tip.mass", Op::Scale(1.5))),
///     ("report.json: bias".to_string(), ConfigEdit::or_absent("disk[node=12].bias", Op::Add(0.1), 0.0)),
/// ];
/// let out = corrected(text, &edits).unwrap();
/// let v: toml::Table = toml::from_str(&out).unwrap();
/// assert_eq!(v["tip"]["mass"].as_float(), Some(450.0));
/// assert_eq!(v["disk"][0]["bias"].as_float(), Some(0.1));
/// assert!(out.contains("# kg") && out.contains("# report.json: tip mass ×1.5: was 300"));
/// ```
pub fn corrected(text: &str, edits: &[(String, ConfigEdit)]) -> Result<String, EditError> {
    let mut doc: DocumentMut = text.parse().map_err(|e: toml_edit::TomlError| EditError::Parse(e.to_string()))?;
    for (note, edit) in edits {
        apply(&mut doc, edit, note)?;
    }
    Ok(doc.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    const BOOM: &str = "[[section]]\nei = 2.0\n\n[[section]]\nei = 4.0\n\n[gyro]\nscale = 1.0\n";

    fn value(text: &str, path: &[&str], i: Option<usize>) -> f64 {
        let v: toml::Table = toml::from_str(text).unwrap();
        let mut item = &v[path[0]];
        if let Some(i) = i {
            item = &item[i];
        }
        item[path[1]].as_float().unwrap()
    }

    #[test]
    fn every_entry_of_an_array_is_scaled() {
        let out = corrected(BOOM, &[("n".into(), ConfigEdit::new("section[*].ei", Op::Scale(0.5)))]).unwrap();
        assert_eq!((value(&out, &["section", "ei"], Some(0)), value(&out, &["section", "ei"], Some(1))), (1.0, 2.0));
    }

    #[test]
    fn a_place_picks_the_nth_entry_as_it_stands_in_the_file() {
        let out = corrected(BOOM, &[("n".into(), ConfigEdit::new("section[#2].ei", Op::Scale(0.8)))]).unwrap();
        assert_eq!((value(&out, &["section", "ei"], Some(0)), value(&out, &["section", "ei"], Some(1))), (2.0, 3.2));
        let third = corrected(BOOM, &[("n".into(), ConfigEdit::new("section[#3].ei", Op::Scale(0.8)))]);
        assert_eq!(third, Err(EditError::Missing("section[#3].ei".into())));
    }

    #[test]
    fn a_selector_picks_one_entry_by_number_or_text() {
        let text = "[[sensor]]\nnode = 5\ndirection = \"x\"\n\n[[sensor]]\nnode = 5\ndirection = \"y\"\n";
        let edit = ConfigEdit::or_absent("sensor[node=5,direction=y].bias", Op::Add(2.0), 0.0);
        let out = corrected(text, &[("n".into(), edit)]).unwrap();
        let v: toml::Table = toml::from_str(&out).unwrap();
        assert!(v["sensor"][0].get("bias").is_none());
        assert_eq!(v["sensor"][1]["bias"].as_float(), Some(2.0));
    }

    #[test]
    fn a_missing_table_is_added_where_the_model_has_a_default() {
        let out = corrected(BOOM, &[("n".into(), ConfigEdit::or_absent("inclinometer.offset", Op::Add(0.01), 0.0))]);
        assert_eq!(value(&out.unwrap(), &["inclinometer", "offset"], None), 0.01);
    }

    #[test]
    fn an_entry_is_appended_to_an_array_of_tables_made_if_missing() {
        let edit = ConfigEdit::or_absent("point_mass[+node=12].mass", Op::Set(0.05), 0.0);
        let out = corrected(BOOM, &[("n".into(), edit.clone()), ("n".into(), edit)]).unwrap();
        let v: toml::Table = toml::from_str(&out).unwrap();
        let masses = v["point_mass"].as_array().unwrap();
        assert_eq!(masses.len(), 2);
        assert_eq!((masses[1]["node"].as_integer(), masses[1]["mass"].as_float()), (Some(12), Some(0.05)));
        assert_eq!(value(&out, &["section", "ei"], Some(1)), 4.0);
    }

    #[test]
    fn a_switch_is_turned_on_or_added() {
        let text = "[estimator]\ncurrent = false # off\n";
        let edits = [
            ("n".to_string(), ConfigEdit::or_absent("estimator.current", Op::Switch(true), 0.0)),
            ("n".to_string(), ConfigEdit::or_absent("estimator.sensor_biases", Op::Switch(true), 0.0)),
        ];
        let v: toml::Table = toml::from_str(&corrected(text, &edits).unwrap()).unwrap();
        assert_eq!(
            (v["estimator"]["current"].as_bool(), v["estimator"]["sensor_biases"].as_bool()),
            (Some(true), Some(true))
        );
    }

    #[test]
    fn bad_paths_missing_keys_and_text_are_errors_not_guesses() {
        let one = |path: &str| corrected(BOOM, &[("n".into(), ConfigEdit::new(path, Op::Set(1.0)))]);
        assert_eq!(one("tip.mass"), Err(EditError::Missing("tip.mass".into())));
        assert_eq!(one("section[ei].x"), Err(EditError::Path("section[ei].x".into())));
        assert_eq!(one("section[*]"), Err(EditError::Path("section[*]".into())));
        assert_eq!(one("section[#0].ei"), Err(EditError::Path("section[#0].ei".into())));
        assert_eq!(one("section[#x].ei"), Err(EditError::Path("section[#x].ei".into())));
        assert!(matches!(corrected("[a\n", &[]), Err(EditError::Parse(_))));
        let text = "[gyro]\nname = \"g\"\n";
        let e = corrected(text, &[("n".into(), ConfigEdit::new("gyro.name", Op::Set(1.0)))]);
        assert_eq!(e, Err(EditError::NotNumber("gyro.name".into())));
    }
}
