//! Typed topics: Rust structs that map to ULog formats ([`ULog`]), the field types they may
//! use ([`FieldValue`]), and the runtime check that compares a struct with a file's own format
//! once and yields a [`DecodePlan`], after which decoding a row is offset reads only.
//!
//! `#[derive(ULog)]` writes the [`ULog`] (and, for structs with a `timestamp`, [`Topic`])
//! impls; [`Log::topic`](crate::Log::topic) and [`Writer::topic`](crate::Writer::topic) use
//! them.

mod check;
pub(crate) mod field;
mod view;

pub use check::{DecodePlan, FieldPlan, Mismatch, MismatchKind, TypedDecoder, TypedError};
pub use field::{Chars, Element, FieldValue, Padding};
pub use view::{TopicRows, TypedRows, TypedTopic};

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

/// The static description of a typed format.
#[derive(Debug)]
pub struct TypedFormat {
    /// The format name.
    pub name: &'static str,
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
        Format {
            name: self.name.to_owned(),
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
        let mut out: Vec<Format> = Vec::new();
        let mut stack: Vec<(&'static TypedFormat, bool)> = vec![(self, false)];
        while let Some((f, expanded)) = stack.pop() {
            if out.iter().any(|o| o.name == f.name) {
                continue;
            }
            if expanded {
                out.push(f.to_format());
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
