//! The header rules of the data contract, once for the host's reader and the node's.
//!
//! Every CSV file `edgekf` reads starts with a header row. The host (`edgekf_sim::io::data`) and
//! the firmware (`line_feed`, the virtual ADXL355's feed) used to parse it each in their own way,
//! and disagreed on a repeated name (one kept the first column, one the last). Both now run
//! [`Header::parse`], so a file means the same on the chip as on the host:
//!
//! * a UTF-8 byte-order mark before the first field is dropped, and every field is trimmed;
//! * the first column is `t`, the time in seconds;
//! * no name is empty;
//! * no name repeats: which of two `ax` columns is the channel cannot be guessed, so the header
//!   is refused with both column numbers ([`HeaderError::Duplicate`]);
//! * a channel is found by its exact (trimmed) name; a wanted one that is absent is
//!   [`HeaderError::MissingChannel`].
//!
//! No allocation and no panics: the fields are any cloneable iterator of `&str` ([`fields`], a
//! `split(',')` without a panic path, on the chip; a `csv::StringRecord` on the host), walked again for each
//! question asked, and errors own their names in a fixed buffer ([`ColumnName`]) so that they
//! outlive the line they came from.
//!
//! ```
//! use edgekf::csv_header::{Header, HeaderError};
//! let header = Header::parse("\u{feff}t, ax ,truth_x".split(','), 64).unwrap();
//! assert_eq!(header.width(), 3);
//! assert_eq!(header.position("ax"), Some(1));
//! assert_eq!(header.find_all(["truth_x", "ax"]), Ok([2, 1]));
//!
//! let err = Header::parse("t,ax,ay,ax".split(','), 64).unwrap_err();
//! assert_eq!(err.to_string(), "duplicate column name `ax`: columns 2 and 4");
//! assert!(matches!(err, HeaderError::Duplicate { first: 2, second: 4, .. }));
//! ```

#![deny(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use core::fmt;

/// The UTF-8 byte-order mark some editors put before the first field.
pub const BOM: char = '\u{feff}';

/// Longest name an error keeps, bytes; a longer one is cut at a character boundary and shown
/// with `…`.
pub const NAME_BYTES: usize = 32;

/// A column name held by value (at most [`NAME_BYTES`] bytes), so that an error can name a
/// column after the header line's buffer is reused (the node reads lines into one buffer).
///
/// ```
/// use edgekf::csv_header::ColumnName;
/// assert_eq!(ColumnName::new("ax").as_str(), "ax");
/// let long = ColumnName::new("truth_contact_force_on_the_crank_pin_A");
/// assert!(long.is_truncated());
/// assert_eq!(long.to_string(), "truth_contact_force_on_the_crank…");
/// ```
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct ColumnName {
    bytes: [u8; NAME_BYTES],
    len: u8,
    truncated: bool,
}

impl ColumnName {
    /// Copies `name`, cut at the last character boundary within [`NAME_BYTES`] bytes.
    pub fn new(name: &str) -> Self {
        let mut len = name.len().min(NAME_BYTES);
        while !name.is_char_boundary(len) {
            len -= 1;
        }
        let mut bytes = [0u8; NAME_BYTES];
        for (b, s) in bytes.iter_mut().zip(name.as_bytes().get(..len).unwrap_or(&[])) {
            *b = *s;
        }
        // `len` ≤ NAME_BYTES = 32 fits a u8.
        Self { bytes, len: len as u8, truncated: len < name.len() }
    }

    /// The name as kept (without the `…` of a cut one).
    pub fn as_str(&self) -> &str {
        let kept = self.bytes.get(..usize::from(self.len)).unwrap_or(&[]);
        // Cut at a character boundary, so always UTF-8; the fallback is never taken.
        core::str::from_utf8(kept).unwrap_or("")
    }

    /// Whether the name was longer than [`NAME_BYTES`] and was cut.
    pub fn is_truncated(&self) -> bool {
        self.truncated
    }
}

impl fmt::Display for ColumnName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())?;
        if self.truncated {
            f.write_str("…")?;
        }
        Ok(())
    }
}

impl fmt::Debug for ColumnName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:?}", self.as_str())?;
        if self.truncated {
            f.write_str("…")?;
        }
        Ok(())
    }
}

impl PartialEq<&str> for ColumnName {
    fn eq(&self, other: &&str) -> bool {
        !self.truncated && self.as_str() == *other
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for ColumnName {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "{=str}{=str}", self.as_str(), if self.truncated { "…" } else { "" });
    }
}

/// Why a header breaks the rules. Column numbers are 1-based, as an editor or spreadsheet
/// counts them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HeaderError {
    /// The first column is not `t` (an empty header gives an empty `found`).
    FirstColumnNotTime {
        /// The first column's name.
        found: ColumnName,
    },
    /// A header cell is empty.
    EmptyName {
        /// Its column number.
        column: usize,
    },
    /// Two columns share a name.
    Duplicate {
        /// The name.
        name: ColumnName,
        /// Column number of its first appearance.
        first: usize,
        /// Column number of the repeat.
        second: usize,
    },
    /// More columns than the reader has room for.
    TooManyColumns {
        /// The most it accepts.
        max: usize,
    },
    /// A channel the reader needs is not in the header.
    MissingChannel {
        /// The channel.
        name: ColumnName,
    },
}

impl fmt::Display for HeaderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            HeaderError::FirstColumnNotTime { found } => {
                write!(f, "the first column must be `t` (time in seconds), found `{found}`")
            }
            HeaderError::EmptyName { column } => write!(f, "column {column} has an empty name"),
            HeaderError::Duplicate { name, first, second } => {
                write!(f, "duplicate column name `{name}`: columns {first} and {second}")
            }
            HeaderError::TooManyColumns { max } => write!(f, "more than {max} columns"),
            HeaderError::MissingChannel { name } => write!(f, "no column `{name}`"),
        }
    }
}

impl core::error::Error for HeaderError {}

/// The comma-separated fields of a line, as `str::split(',')` gives them, without its panic
/// path: `core`'s character searcher slices with bounds checks the optimiser cannot always
/// remove, which the node's no-panic proof would refuse. A comma is one byte, so a field
/// always ends on a character boundary and `str::get` always succeeds.
///
/// ```
/// use edgekf::csv_header::fields;
/// assert!(fields("t, ax,,é").eq(["t", " ax", "", "é"]));
/// assert!(fields("").eq([""]));
/// assert!(fields("a,").eq(["a", ""]));
/// ```
pub fn fields(line: &str) -> Fields<'_> {
    Fields { rest: Some(line) }
}

/// The iterator of [`fields`].
#[derive(Clone, Debug)]
pub struct Fields<'a> {
    rest: Option<&'a str>,
}

impl<'a> Iterator for Fields<'a> {
    type Item = &'a str;

    fn next(&mut self) -> Option<&'a str> {
        let line = self.rest?;
        match line.bytes().position(|b| b == b',') {
            Some(comma) => {
                self.rest = line.get(comma + 1..);
                line.get(..comma)
            }
            None => {
                self.rest = None;
                Some(line)
            }
        }
    }
}

/// The cleaned names of a header's fields: the first without a [`BOM`], all trimmed.
#[derive(Clone, Debug)]
pub struct Names<I> {
    fields: I,
    first: bool,
}

impl<'h, I: Iterator<Item = &'h str>> Iterator for Names<I> {
    type Item = &'h str;

    fn next(&mut self) -> Option<&'h str> {
        let field = self.fields.next()?;
        let field = if core::mem::take(&mut self.first) { field.strip_prefix(BOM).unwrap_or(field) } else { field };
        Some(field.trim())
    }
}

/// A header that follows the rules (see the [module docs](self)), over its fields.
#[derive(Clone, Debug)]
pub struct Header<I> {
    fields: I,
    width: usize,
}

impl<'h, I: Iterator<Item = &'h str> + Clone> Header<I> {
    /// Checks the header `fields` against the rules; `max_columns` bounds the width (the node's
    /// buffers; the host passes `usize::MAX`). The width is checked before the names, so the
    /// quadratic search for repeats never runs on more than `max_columns` fields.
    pub fn parse(fields: I, max_columns: usize) -> Result<Self, HeaderError> {
        let names = Names { fields, first: true };
        let mut width = 0usize;
        for _ in names.clone() {
            if width == max_columns {
                return Err(HeaderError::TooManyColumns { max: max_columns });
            }
            width += 1;
        }
        let first = names.clone().next().unwrap_or("");
        if first != "t" {
            return Err(HeaderError::FirstColumnNotTime { found: ColumnName::new(first) });
        }
        for (i, name) in names.clone().enumerate() {
            if name.is_empty() {
                return Err(HeaderError::EmptyName { column: i + 1 });
            }
            if let Some(j) = names.clone().take(i).position(|earlier| earlier == name) {
                return Err(HeaderError::Duplicate { name: ColumnName::new(name), first: j + 1, second: i + 1 });
            }
        }
        Ok(Self { fields: names.fields, width })
    }

    /// Number of columns, `t` included.
    pub fn width(&self) -> usize {
        self.width
    }

    /// The cleaned names, in file order (`t` first).
    pub fn names(&self) -> Names<I> {
        Names { fields: self.fields.clone(), first: true }
    }

    /// 0-based index of the column called `name`, if there is one (names are unique).
    pub fn position(&self, name: &str) -> Option<usize> {
        self.names().position(|n| n == name)
    }

    /// 0-based index of the channel `name`, which the reader needs.
    pub fn find(&self, name: &str) -> Result<usize, HeaderError> {
        self.position(name).ok_or(HeaderError::MissingChannel { name: ColumnName::new(name) })
    }

    /// 0-based indices of the channels `names`, in their order; the first absent one is the
    /// error.
    pub fn find_all<const M: usize>(&self, names: [&str; M]) -> Result<[usize; M], HeaderError> {
        let mut index = [0usize; M];
        for (slot, name) in index.iter_mut().zip(names) {
            *slot = self.find(name)?;
        }
        Ok(index)
    }
}

#[cfg(test)]
#[allow(clippy::indexing_slicing, clippy::unwrap_used)]
mod tests {
    use super::*;

    fn parse(line: &str) -> Result<Header<Fields<'_>>, HeaderError> {
        Header::parse(fields(line), 8)
    }

    #[test]
    fn fields_split_as_core_does() {
        for line in ["", ",", "a", "a,b", ",a,", "t, ax ,truth_x", "é,ü,,", "\u{feff}t,x"] {
            assert!(fields(line).eq(line.split(',')), "{line:?}");
        }
    }

    #[test]
    fn a_bom_and_spaces_are_not_part_of_a_name() {
        let h = parse("\u{feff} t ,ax\r").unwrap();
        assert_eq!(h.find("ax"), Ok(1));
        assert!(h.names().eq(["t", "ax"]));
        // A BOM anywhere else is a character of the name.
        assert_eq!(parse("t,\u{feff}ax").unwrap().position("ax"), None);
    }

    #[test]
    fn every_rule_has_its_error() {
        let name = ColumnName::new;
        assert_eq!(parse("").unwrap_err(), HeaderError::FirstColumnNotTime { found: name("") });
        assert_eq!(parse("ax,t").unwrap_err(), HeaderError::FirstColumnNotTime { found: name("ax") });
        assert_eq!(parse("t,ax,,ay").unwrap_err(), HeaderError::EmptyName { column: 3 });
        assert_eq!(
            parse("t,ay, ay ,ay").unwrap_err(),
            HeaderError::Duplicate { name: name("ay"), first: 2, second: 3 }
        );
        assert_eq!(parse("t,a,b,c,d,e,f,g").map(|h| h.width()), Ok(8));
        assert_eq!(parse("t,a,b,c,d,e,f,g,h").unwrap_err(), HeaderError::TooManyColumns { max: 8 });
        let h = parse("t,ax").unwrap();
        assert_eq!(h.find_all(["ax", "az"]), Err(HeaderError::MissingChannel { name: name("az") }));
        assert_eq!(h.find("t"), Ok(0));
    }

    #[test]
    fn messages_name_the_columns() {
        let text = |e: HeaderError| {
            let mut s = heapless::String::<96>::new();
            core::fmt::write(&mut s, format_args!("{e}")).unwrap();
            s
        };
        assert_eq!(text(parse("t,x,x").unwrap_err()), "duplicate column name `x`: columns 2 and 3");
        assert_eq!(text(parse("time").unwrap_err()), "the first column must be `t` (time in seconds), found `time`");
        assert_eq!(text(parse("t,ax").unwrap().find("ay").unwrap_err()), "no column `ay`");
    }

    #[test]
    fn long_names_are_cut_at_a_character_boundary() {
        // 31 ASCII bytes and a 2-byte `é`: the cut falls inside it and moves back to 31 bytes.
        let long = "abcdefghijklmnopqrstuvwxyz01234é";
        let n = ColumnName::new(long);
        assert_eq!((n.as_str().len(), n.is_truncated()), (31, true));
        assert!(n != long && ColumnName::new("ax") == "ax");
    }

    proptest::proptest! {
        #![proptest_config(proptest::test_runner::Config { cases: 512, failure_persistence: None, ..Default::default() })]

        /// Any line, however broken, gives a header or an error, never a panic; and a header it
        /// accepts follows every rule.
        #[test]
        fn any_line_is_accepted_only_if_it_follows_the_rules(line in "(\\PC|[,t ]|\u{feff}){0,40}") {
            if let Ok(h) = parse(&line) {
                let names: heapless::Vec<&str, 8> = h.names().collect();
                proptest::prop_assert_eq!(names.len(), h.width());
                proptest::prop_assert_eq!(names[0], "t");
                for (i, n) in names.iter().enumerate() {
                    proptest::prop_assert!(!n.is_empty());
                    proptest::prop_assert_eq!(h.position(n), Some(i));
                }
            }
        }
    }
}
