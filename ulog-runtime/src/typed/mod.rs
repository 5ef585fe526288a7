//! Typed topics: Rust structs as ULog formats.
//!
//! `#[derive(ULog)]` on a struct with named fields implements [`ULog`]: the format (name,
//! fields, the formats it nests), the packed little-endian encoder, and a decoder that reads
//! through a [`DecodePlan`]. A struct with a `timestamp` field also implements [`Topic`], so it
//! can be written ([`Writer::topic`](crate::Writer::topic)) and read
//! ([`Log::topic`](crate::Log::topic), [`TypedDecoder`] with a [`StreamReader`](crate::StreamReader)).
//!
//! ```
//! use ulog_runtime::{Chars, ULog};
//!
//! #[derive(ULog, Debug, Clone, Copy)]
//! struct EscReport {                    // nested only: no timestamp needed
//!     esc_rpm: i32,
//!     esc_voltage: f32,
//!     #[ulog(padding)]
//!     _pad: [u8; 3],
//! }
//!
//! #[derive(ULog, Debug)]
//! #[ulog(name = "esc_status")]
//! struct EscStatus {
//!     timestamp: u64,
//!     esc_count: u8,
//!     esc: [EscReport; 8],
//!     name: Chars<10>,
//!     temperature: Option<f32>,         // files without it read as None
//! }
//!
//! assert_eq!(
//!     EscStatus::FORMAT.to_format().to_string(),
//!     "esc_status:uint64_t timestamp;uint8_t esc_count;esc_report[8] esc;char[10] name;float temperature;"
//! );
//! ```
//!
//! # Field types
//!
//! | Rust | ULog |
//! |---|---|
//! | `u8` `i8` `u16` `i16` `u32` `i32` `u64` `i64` `f32` `f64` | `uint8_t` ... `int64_t`, `float`, `double` |
//! | `bool` | `bool` (any non-zero byte reads as `true`) |
//! | [`Char`] | `char`: one byte, not text (rare in PX4) |
//! | [`Chars<N>`] | `char[N]`, text without terminator when it fills the array |
//! | `[T; N]` of the above (not `Chars`) or of a nested type | `type[N]` |
//! | a struct deriving `ULog` | the nested format (its own name) |
//! | `Option<T>` of any of these (not of an `Option`: [`RequiredField`]) | the same type; absent from a file → `None`, written as zeros |
//!
//! Anything else (`String`, `Vec`, `usize`, `char`, references, arrays of arrays) does not
//! compile: [`FieldValue`] and [`Element`] are implemented for exactly these types, and the
//! derive has no type table of its own.
//!
//! # Attributes
//!
//! | attribute | on | effect |
//! |---|---|---|
//! | `#[ulog(name = "esc_status")]` | struct | the format name (default: the struct name in snake case) |
//! | `#[ulog(topics("vehicle_attitude", "estimator_attitude"))]` | struct | every topic the type stands for (PX4's `# TOPICS`): [`TypedFormat::topics`]; read and write under any with [`Log::topic_as`](crate::Log::topic_as) and [`Writer::topic_as`](crate::Writer::topic_as) |
//! | `#[ulog(exact)]` | struct | reading requires the file's format to be identical: fields, order, padding |
//! | `#[ulog(widen)]` | struct or field | numeric fields also accept narrower file types they hold every value of (see below) |
//! | `#[ulog(nested)]` | struct | only ever nested, never a topic: no [`Topic`] impl, and a `timestamp` field may have any type |
//! | `#[ulog(crate = "path")]` | struct | where the runtime crate is, for code that renames `ulog-runtime` |
//! | `#[ulog(rename = "type")]` | field | the field's name in the file |
//! | `#[ulog(padding)]` | field (`[u8; N]`) | written as zeros and named `_paddingK` (K counts padding fields); trailing padding is left out of data rows, as PX4 does |
//!
//! Each key may appear once; every mistake of a struct is reported at once, at its span, the
//! field types included (a struct with errors still gets placeholder impls, so code using
//! it shows no follow-on errors). `widen` and `exact` contradict each other.
//! The derive also refuses, at compile time: enums, unions, tuple and unit structs, generics,
//! names the format grammar forbids, two fields with one name after renames, a `timestamp`
//! that is not an unsigned integer, and a struct larger than one data message (65,533 bytes).
//! Using a struct without `timestamp` as a topic does not compile (it is not a [`Topic`]).
//!
//! # The runtime check
//!
//! Reading compares the struct with the file's format of the same name, once, before any row
//! ([`DecodePlan::check`]):
//! - fields match by name, in any order; padding is skipped on both sides but its bytes count;
//! - types and array lengths must be equal, nested types recursively; a `widen` field also
//!   takes a narrower type it can hold every value of ([`widens`]): an unsigned integer
//!   takes unsigned ones of at most its size, a signed integer signed ones of at most its
//!   size and smaller unsigned ones, `f64` takes `float` and integers of up to 32 bits, `f32`
//!   integers of up to 16 bits; never a lossy one (signed into unsigned, `int64_t` into
//!   `f64`), elementwise for arrays of equal length. The plan keeps one loader per widened
//!   field, chosen by the check, so rows convert without branching on types. Writing a
//!   widened type writes its own (wider) format;
//! - fields only the file has are ignored; a struct field the file lacks is an error unless it
//!   is an `Option`;
//! - in exact mode any difference is an error.
//!
//! Every difference is reported in one [`TypedError::Mismatch`], e.g.
//! `esc_status: esc[].esc_rpm is int32_t in the file, f32 in struct EscReport` (several: one
//! per line). A topic the file lacks suggests the closest names it has. After the
//! check, decoding a row is reads at offsets the plan holds: no allocation for fixed-size
//! types, no lookups by name.

mod check;
pub(crate) mod field;
mod view;
mod widen;

pub use check::{DecodePlan, FieldPlan, Mismatch, MismatchKind, TypedDecoder, TypedError};
pub use field::{
    Char, Chars, CharsTooLong, DerivedElement, Element, FieldValue, Padding, RequiredField,
};
pub use view::{TopicRows, TypedRows, TypedTopic};
pub use widen::{common_type, widens};

use crate::schema::{Field, Format, Primitive, TypeRef};

/// A Rust type that maps to a ULog format: a topic (it has a `timestamp`) or a type nested
/// in one. Implemented by `#[derive(ULog)]`.
#[diagnostic::on_unimplemented(
    message = "`{Self}` is not a ULog type",
    label = "does not implement `ULog`",
    note = "add `#[derive(ULog)]` to the definition of `{Self}`"
)]
pub trait ULog: Sized {
    /// The format: name and fields as written to files (padding included).
    const FORMAT: TypedFormat;
    /// Appends the packed little-endian encoding, full size (trailing padding included).
    fn encode(&self, out: &mut Vec<u8>);
    /// Decodes a row (or a nested element) through a plan made by [`DecodePlan::check`].
    fn decode(plan: &DecodePlan, row: &[u8]) -> Self;
}

/// A [`ULog`] type with a `timestamp` field of an unsigned integer type: it can be subscribed,
/// written and read as a topic. `#[derive(ULog)]` implements it for structs with such a field.
#[diagnostic::on_unimplemented(
    message = "`{Self}` has no `timestamp` field, so it cannot be used as a topic",
    label = "not a topic",
    note = "a type without `timestamp: u64` can only be nested in another ULog type"
)]
pub trait Topic: ULog {}

/// What `#[derive(ULog)]` implements for a struct with a `timestamp`; its [`Topic`] impl is
/// this blanket one (see [`DerivedElement`] for why).
#[doc(hidden)]
pub trait DerivedTopic: ULog {}

#[diagnostic::do_not_recommend]
impl<T: DerivedTopic> Topic for T {}

/// The static description of a typed format.
#[derive(Debug)]
pub struct TypedFormat {
    /// The format name: the topic it is read and written as by default.
    pub name: &'static str,
    /// Every topic name the type stands for (`#[ulog(topics(...))]`, PX4's `# TOPICS`), its
    /// own `name` first. [`Log::topic_as`](crate::Log::topic_as) and
    /// [`Writer::topic_as`](crate::Writer::topic_as) take any of them (or any other name
    /// whose format matches).
    pub topics: &'static [&'static str],
    /// The Rust type, for messages.
    pub rust_type: &'static str,
    /// The fields, in declaration order.
    pub fields: &'static [TypedField],
    /// Whether a file's format must be identical (field list, order and padding).
    pub exact: bool,
}

/// One field of a [`TypedFormat`].
#[derive(Debug)]
pub struct TypedField {
    /// The ULog field name.
    pub name: &'static str,
    /// The element type.
    pub kind: TypedKind,
    /// `Some(N)` for arrays.
    pub array_len: Option<u16>,
    /// Whether this is padding (written as zeros, never read).
    pub padding: bool,
    /// Whether the field may be absent from a file (then it decodes as `None`).
    pub optional: bool,
    /// Whether the field accepts narrower file types it can hold every value of
    /// (`#[ulog(widen)]`): `uint8_t` into `u32`, `float` into `f64`...
    pub widen: bool,
    /// The Rust type of the element, for messages (`f32`, `EscReport`).
    pub rust_type: &'static str,
}

/// What a typed field holds.
#[derive(Debug, Clone, Copy)]
pub enum TypedKind {
    /// A basic type.
    Primitive(Primitive),
    /// Another typed format.
    Nested(&'static TypedFormat),
}

impl TypedFormat {
    /// The format as a schema [`Format`].
    pub fn to_format(&self) -> Format {
        self.to_format_as(self.name)
    }

    /// The format under another topic name (the nested formats keep theirs).
    pub fn to_format_as(&self, topic: &str) -> Format {
        Format {
            name: topic.to_owned(),
            fields: self
                .fields
                .iter()
                .map(|f| Field {
                    ty: match f.kind {
                        TypedKind::Primitive(p) => TypeRef::Primitive(p),
                        TypedKind::Nested(n) => TypeRef::Nested(n.name.to_owned()),
                    },
                    array_len: f.array_len,
                    name: f.name.to_owned(),
                })
                .collect(),
        }
    }

    /// This format and every format it nests, each once, nested ones first.
    pub fn formats(&'static self) -> Vec<Format> {
        self.formats_as(self.name)
    }

    /// [`TypedFormat::formats`], the last (this one) under the topic name `topic`.
    pub fn formats_as(&'static self, topic: &str) -> Vec<Format> {
        let mut out: Vec<Format> = Vec::new();
        let mut stack: Vec<(&'static TypedFormat, bool)> = vec![(self, false)];
        while let Some((f, expanded)) = stack.pop() {
            if out.iter().any(|o| o.name == f.name) {
                continue;
            }
            if expanded {
                out.push(if std::ptr::eq(f, self) {
                    f.to_format_as(topic)
                } else {
                    f.to_format()
                });
                continue;
            }
            stack.push((f, true));
            for field in f.fields.iter().rev() {
                if let TypedKind::Nested(n) = field.kind {
                    stack.push((n, false));
                }
            }
        }
        out
    }

    /// Size in bytes without the trailing padding (what rows carry).
    pub const fn payload_size(&self) -> usize {
        let mut end = self.fields.len();
        while end > 0 && self.fields[end - 1].padding {
            end -= 1;
        }
        let mut size = 0;
        let mut i = 0;
        while i < end {
            size += field_size(&self.fields[i]);
            i += 1;
        }
        size
    }

    /// Full size in bytes (the size when nested).
    pub const fn size(&self) -> usize {
        let mut size = 0;
        let mut i = 0;
        while i < self.fields.len() {
            size += field_size(&self.fields[i]);
            i += 1;
        }
        size
    }
}

/// Size of one element of a kind.
pub(crate) const fn kind_size(kind: TypedKind) -> usize {
    match kind {
        TypedKind::Primitive(p) => p.size(),
        TypedKind::Nested(n) => n.size(),
    }
}

const fn field_size(f: &TypedField) -> usize {
    let count = match f.array_len {
        Some(n) => n as usize,
        None => 1,
    };
    kind_size(f.kind) * count
}

/// Appends `value`'s encoding without its trailing padding: a data row as PX4 writes it.
pub fn encode_row<T: ULog>(value: &T, out: &mut Vec<u8>) {
    let start = out.len();
    value.encode(out);
    out.truncate(start + T::FORMAT.payload_size());
}

#[cfg(test)]
mod tests;
