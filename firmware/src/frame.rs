//! Report frames, each defined once: the [`frame!`](crate::frame!) macro turns one struct
//! definition with its defmt format string into the struct, the `defmt::info!` call that
//! emits it (behind the `defmt` feature) and the parser the host uses on the decoded line.
//!
//! Why a macro: defmt needs a literal format string, so the emitter cannot be built from a
//! field list at run time; the macro puts the literal next to the fields, and a compile-time
//! check ([`format_matches`]) refuses a format whose placeholders do not list the fields, in
//! order, with their types. The parser is generated from the same field list, so the emitter
//! and the parser cannot drift apart.
//!
//! A frame's text is its tag, then one space-separated token per field: the value, optionally
//! labelled `field=value` (as in `start odr=1000 watermark=48`).

use core::fmt;

/// A value a frame carries: its defmt type and its parser.
pub trait FrameField: Sized + fmt::Display {
    /// The defmt type in the placeholder, e.g. `"{=u32}"`.
    const DEFMT: &'static str;
    /// Parses a decoded value.
    fn parse_token(token: &str) -> Option<Self>;
}

macro_rules! frame_field {
    ($($ty:ty => $defmt:literal),*) => {
        $(impl FrameField for $ty {
            const DEFMT: &'static str = $defmt;
            fn parse_token(token: &str) -> Option<Self> {
                token.parse().ok()
            }
        })*
    };
}
frame_field!(u8 => "{=u8}", u16 => "{=u16}", u32 => "{=u32}", f32 => "{=f32}");

/// Why a decoded line is not a valid frame of the kind its tag names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameError {
    /// Fewer or more values than the frame has fields.
    Count {
        /// The frame's tag.
        tag: &'static str,
        /// Fields the frame has.
        expected: usize,
        /// Values on the line.
        found: usize,
    },
    /// A value that does not parse as its field's type.
    Value {
        /// The frame's tag.
        tag: &'static str,
        /// The field.
        field: &'static str,
    },
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameError::Count { tag, expected, found } => {
                write!(f, "`{tag}` frame: expected {expected} values, found {found}")
            }
            FrameError::Value { tag, field } => write!(f, "`{tag}` frame: bad value for `{field}`"),
        }
    }
}

/// One kind of report frame. Implemented by [`frame!`](crate::frame!) only.
pub trait Frame: Sized + 'static {
    /// The defmt format string: the tag, then one placeholder per field.
    const FORMAT: &'static str;
    /// The first word of every line of this kind.
    const TAG: &'static str = tag_of(Self::FORMAT);
    /// Field names, in order.
    const FIELDS: &'static [&'static str];

    /// Emits the frame as one defmt message at level info.
    #[cfg(feature = "defmt")]
    fn emit(&self);

    /// Writes the values, each preceded by a space and its label if the format has one.
    fn write_values(&self, w: &mut dyn fmt::Write) -> fmt::Result;

    /// Builds the frame from the value tokens (the tag already removed), labels stripped.
    fn from_values(values: &mut dyn Iterator<Item = &str>) -> Result<Self, FrameError>;

    /// The frame as a decoded line reads (floats in shortest round-trip form, which may differ
    /// in spelling from defmt's but parses to the same bits).
    fn write_line(&self, w: &mut dyn fmt::Write) -> fmt::Result {
        w.write_str(Self::TAG)?;
        self.write_values(w)
    }

    /// Parses a decoded line: `None` if it is not of this kind, `Some(Err)` if it is but
    /// malformed.
    fn parse(line: &str) -> Option<Result<Self, FrameError>> {
        let mut tokens = line.split_whitespace();
        if tokens.next() != Some(Self::TAG) {
            return None;
        }
        let found = line.split_whitespace().count() - 1;
        if found != Self::FIELDS.len() {
            return Some(Err(FrameError::Count { tag: Self::TAG, expected: Self::FIELDS.len(), found }));
        }
        Some(Self::from_values(&mut tokens))
    }
}

/// Where a node's frames go: defmt on the chip ([`Defmt`]), a list of lines on the host.
pub trait FrameSink {
    /// Takes one frame.
    fn frame<F: Frame>(&mut self, frame: &F);
}

/// Frames out through defmt (RTT on the board, semihosting under QEMU).
#[cfg(feature = "defmt")]
#[derive(Debug, Default, Clone, Copy)]
pub struct Defmt;

#[cfg(feature = "defmt")]
impl FrameSink for Defmt {
    fn frame<F: Frame>(&mut self, frame: &F) {
        frame.emit();
    }
}

/// Parses one value token of field `field` of frame `tag`, with or without its `field=` label.
#[doc(hidden)]
pub fn value<T: FrameField>(token: Option<&str>, tag: &'static str, field: &'static str) -> Result<T, FrameError> {
    let token = token.ok_or(FrameError::Value { tag, field })?;
    let token = match token.split_once('=') {
        Some((label, rest)) if label == field => rest,
        _ => token,
    };
    T::parse_token(token).ok_or(FrameError::Value { tag, field })
}

/// The label (with its `=`) the format gives the `index`-th field, or `""`.
#[doc(hidden)]
pub fn label(format: &str, index: usize) -> &str {
    format.split(' ').nth(index + 1).and_then(|t| t.find("{=").map(|i| &t[..i])).unwrap_or("")
}

/// The first space-separated word of `format`.
pub const fn tag_of(format: &str) -> &str {
    let bytes = format.as_bytes();
    let mut n = 0;
    while n < bytes.len() && bytes[n] != b' ' {
        n += 1;
    }
    match core::str::from_utf8(bytes.split_at(n).0) {
        Ok(tag) => tag,
        Err(_) => "",
    }
}

const fn eq_at(hay: &[u8], at: usize, needle: &[u8]) -> bool {
    if at + needle.len() > hay.len() {
        return false;
    }
    let mut i = 0;
    while i < needle.len() {
        if hay[at + i] != needle[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// Whether `format` is a tag without `{` followed, for each field in order, by one token
/// `{=type}` or `name={=type}` (single spaces, nothing after the last). Evaluated at compile
/// time for every frame.
///
/// ```
/// use edgekf_firmware::frame::format_matches;
/// assert!(format_matches("stack {=u32} {=u32}", &["boot", "used"], &["{=u32}", "{=u32}"]));
/// assert!(format_matches("start odr={=f32}", &["odr"], &["{=f32}"]));
/// assert!(!format_matches("stack {=u32} {=u16}", &["boot", "used"], &["{=u32}", "{=u32}"]));
/// assert!(!format_matches("stack {=u32}", &["boot", "used"], &["{=u32}", "{=u32}"]));
/// assert!(!format_matches("start rate={=f32}", &["odr"], &["{=f32}"]));
/// ```
pub const fn format_matches(format: &str, fields: &[&str], types: &[&str]) -> bool {
    let f = format.as_bytes();
    if fields.len() != types.len() || f.is_empty() {
        return false;
    }
    let mut at = 0;
    while at < f.len() && f[at] != b' ' {
        if f[at] == b'{' {
            return false;
        }
        at += 1;
    }
    let mut k = 0;
    while k < fields.len() {
        if at >= f.len() || f[at] != b' ' {
            return false;
        }
        at += 1;
        let (name, ty) = (fields[k].as_bytes(), types[k].as_bytes());
        if eq_at(f, at, name) && eq_at(f, at + name.len(), b"=") {
            at += name.len() + 1;
        }
        if !eq_at(f, at, ty) {
            return false;
        }
        at += ty.len();
        k += 1;
    }
    at == f.len()
}

/// Defines a report frame: the struct, its [`Frame`] implementation (defmt emission behind
/// this crate's `defmt` feature, and the parser) and a compile-time check that the format
/// string lists the fields. Meant for this crate's frames (the `defmt` feature it tests is the
/// crate's own).
///
/// ```
/// use edgekf_firmware::frame::Frame;
/// edgekf_firmware::frame! {
///     /// Stack use.
///     pub struct Use = "use {=u32} used={=u32}" {
///         /// Bytes at start-up.
///         pub boot: u32,
///         /// Bytes in the loop.
///         pub used: u32,
///     }
/// }
/// assert_eq!(Use::parse("use 10 used=20"), Some(Ok(Use { boot: 10, used: 20 })));
/// ```
///
/// A format that does not list the fields, in order and with their types, does not compile:
///
/// ```compile_fail
/// edgekf_firmware::frame! {
///     /// The second placeholder is a `u16`, the field a `u32`.
///     pub struct Use = "use {=u32} {=u16}" {
///         /// Bytes at start-up.
///         pub boot: u32,
///         /// Bytes in the loop.
///         pub used: u32,
///     }
/// }
/// ```
#[macro_export]
macro_rules! frame {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident = $format:literal {
            $( $(#[$fmeta:meta])* $fvis:vis $field:ident : $ty:ty ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Default)]
        $vis struct $name {
            $( $(#[$fmeta])* $fvis $field: $ty, )*
        }

        const _: () = assert!(
            $crate::frame::format_matches(
                $format,
                &[$(stringify!($field)),*],
                &[$(<$ty as $crate::frame::FrameField>::DEFMT),*],
            ),
            concat!("the format of ", stringify!($name), " does not list its fields with their types")
        );

        impl $crate::frame::Frame for $name {
            const FORMAT: &'static str = $format;
            const FIELDS: &'static [&'static str] = &[$(stringify!($field)),*];

            #[cfg(feature = "defmt")]
            fn emit(&self) {
                ::defmt::info!($format $(, self.$field)*);
            }

            #[allow(unused_variables, unused_mut, unused_assignments)]
            fn write_values(&self, w: &mut dyn ::core::fmt::Write) -> ::core::fmt::Result {
                let mut index = 0;
                $(
                    w.write_char(' ')?;
                    w.write_str($crate::frame::label(Self::FORMAT, index))?;
                    write!(w, "{}", self.$field)?;
                    index += 1;
                )*
                Ok(())
            }

            #[allow(unused_variables)]
            fn from_values(
                values: &mut dyn Iterator<Item = &str>,
            ) -> Result<Self, $crate::frame::FrameError> {
                Ok(Self {
                    $( $field: $crate::frame::value(values.next(), Self::TAG, stringify!($field))?, )*
                })
            }
        }
    };
}

frame! {
    /// The end of a run: everything before it was emitted.
    pub struct Done = "done" {}
}

frame! {
    /// Stack high-water marks, bytes (see [`crate::stack`]).
    pub struct StackFrame = "stack {=u32} {=u32} {=u32}" {
        /// Deepest extent during start-up.
        pub boot: u32,
        /// Deepest extent in the main loop (measured after a repaint at the end of start-up).
        pub used: u32,
        /// Space available.
        pub total: u32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::String;

    frame! {
        /// A frame with a label and every field type.
        struct Sample = "sample {=u8} n={=u16} {=u32} {=f32}" {
            a: u8,
            n: u16,
            c: u32,
            x: f32,
        }
    }

    fn line<F: Frame>(f: &F) -> String {
        let mut s = String::new();
        f.write_line(&mut s).unwrap();
        s
    }

    #[test]
    fn lines_round_trip_and_bad_lines_are_refused() {
        let s = Sample { a: 7, n: 300, c: 70_000, x: -1.25e-7 };
        assert_eq!(line(&s), "sample 7 n=300 70000 -0.000000125");
        assert_eq!(Sample::parse(&line(&s)), Some(Ok(s)));
        assert_eq!(Sample::parse("sample 7 300 70000 NaN").unwrap().unwrap().x.to_bits(), f32::NAN.to_bits());
        assert_eq!(Sample::parse("other 1 2 3 4"), None);
        assert_eq!(
            Sample::parse("sample 1 2 3"),
            Some(Err(FrameError::Count { tag: "sample", expected: 4, found: 3 }))
        );
        assert_eq!(Sample::parse("sample 1 2 3 x"), Some(Err(FrameError::Value { tag: "sample", field: "x" })));
        assert_eq!(Sample::parse("sample 256 2 3 1"), Some(Err(FrameError::Value { tag: "sample", field: "a" })));
        assert_eq!(Done::parse("done"), Some(Ok(Done {})));
        assert_eq!((Done::TAG, StackFrame::TAG, StackFrame::FIELDS.len()), ("done", "stack", 3));
    }
}
