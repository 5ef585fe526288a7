//! One type from several definitions of a format (the logs of a fleet, several `.msg`
//! folders): the type that reads every one of them. Fields present everywhere are plain,
//! fields missing somewhere become `Option`, types that differ get the narrowest common
//! type every one widens into (`#[ulog(widen)]`), and a field without one is left out (or,
//! strictly, an error). Padding is left out: a merged type writes its own layout.

use std::collections::HashMap;

use super::CodegenError;
use super::input::Definition;
use crate::schema::{Field, Format, Primitive, TypeRef};
use crate::typed::common_type;

/// What to do when inputs define one name differently ([`Builder::merge`](super::Builder::merge)).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Merge {
    /// An error naming both places (the default: one input, one truth).
    #[default]
    Never,
    /// One type that reads every definition; a field whose types have no lossless common
    /// type is left out, and the type's docs say so.
    Lossless,
    /// As [`Merge::Lossless`], but such a field is an error.
    Strict,
    /// As [`Merge::Lossless`], and then every number is made the widest type of its kind,
    /// even where all inputs agree: unsigned integers `u64`, signed ones `i64`, floats
    /// `f64` (`bool` and `char` stay), all `#[ulog(widen)]`. The types then also read
    /// versions newer than their inputs that widened a field (PX4 made
    /// `vehicle_status.onboard_control_sensors_*` `uint64_t` after years of `uint32_t`).
    /// What it costs: every number takes 8 bytes in memory (a `uint8_t[16]` becomes
    /// `[u64; 16]`), the types write their own, wider formats (not the firmware's), and a
    /// field that changes signedness toward unsigned (`int8_t` to `uint8_t`) still has no
    /// common type. It applies to every type of the builder, merged or not.
    Widest,
}

/// How one field appears across the definitions.
struct Seen<'a> {
    name: &'a str,
    /// Per definition: the field there, if it has it.
    per_input: Vec<Option<&'a Field>>,
}

/// Merges definitions of one name (at least two, not all equal).
pub(crate) fn merge(group: Vec<Definition>, mode: Merge) -> Result<Definition, CodegenError> {
    let name = group[0].format.name.clone();
    let places: Vec<String> = group
        .iter()
        .map(|d| format!("`{}`", d.place.doc_text()))
        .collect();
    // Union of the data fields, in order of first appearance.
    let mut seen: Vec<Seen<'_>> = Vec::new();
    for (i, def) in group.iter().enumerate() {
        for field in def.format.fields.iter().filter(|f| !f.is_padding()) {
            let slot = match seen.iter().position(|s| s.name == field.name) {
                Some(k) => k,
                None => {
                    seen.push(Seen {
                        name: &field.name,
                        per_input: vec![None; group.len()],
                    });
                    seen.len() - 1
                }
            };
            seen[slot].per_input[i] = Some(field);
        }
    }
    let mut fields = Vec::new();
    let mut optional = std::collections::HashSet::new();
    let mut widen = std::collections::HashSet::new();
    let mut field_docs: HashMap<String, String> = HashMap::new();
    let mut left_out = Vec::new();
    for s in &seen {
        let usage = usage(s, &places);
        let common = common(s).map(|(field, widens)| match mode {
            Merge::Widest => widest(field, widens),
            _ => (field, widens),
        });
        match common {
            Some((field, widens)) => {
                if s.per_input.iter().any(Option::is_none) {
                    optional.insert(field.name.clone());
                }
                if widens {
                    widen.insert(field.name.clone());
                }
                let mut doc = group
                    .iter()
                    .find_map(|d| d.field_docs.get(s.name).cloned())
                    .map(|d| format!("{d}\n\n"))
                    .unwrap_or_default();
                doc.push_str(&usage);
                field_docs.insert(field.name.clone(), doc);
                fields.push(field);
            }
            None if mode == Merge::Strict => {
                return Err(CodegenError::Incompatible {
                    format: name,
                    field: s.name.to_owned(),
                    usage,
                });
            }
            None => left_out.push(format!("`{}`: {usage}", s.name)),
        }
    }
    let first = group.into_iter().next().expect("a group has a definition");
    let mut doc = first
        .doc
        .clone()
        .map(|d| format!("{d}\n\n"))
        .unwrap_or_default();
    if places.len() > 1 {
        doc.push_str(&format!(
            "One type for the {} definitions of `{name}` in {}: fields some lack are `Option`, \
             types that differ are widened to one that holds every value.",
            places.len(),
            places.join(", ")
        ));
    }
    if mode == Merge::Widest {
        if places.len() > 1 {
            doc.push(' ');
        }
        doc.push_str(
            "Every number is the widest type of its kind (`Merge::Widest`), so that the type \
             also reads versions that widened a field.",
        );
    }
    for line in &left_out {
        doc.push_str(&format!(
            "\n\nLeft out (no Rust type holds every value of its types): {line}"
        ));
    }
    Ok(Definition {
        format: Format { name, fields },
        doc: Some(doc),
        field_docs,
        optional,
        widen,
        merged: places.len(),
        ..first
    })
}

/// The field every definition's version of it reads into, and whether it widens; `None`
/// if there is none.
fn common(s: &Seen<'_>) -> Option<(Field, bool)> {
    let present: Vec<&Field> = s.per_input.iter().flatten().copied().collect();
    let first = present[0];
    if present.iter().any(|f| f.array_len != first.array_len) {
        return None;
    }
    if present.iter().all(|f| f.ty == first.ty) {
        return Some((first.clone(), false));
    }
    let primitives: Option<Vec<Primitive>> = present
        .iter()
        .map(|f| match f.ty {
            TypeRef::Primitive(p) => Some(p),
            TypeRef::Nested(_) => None,
        })
        .collect();
    let wide = common_type(&primitives?)?;
    // Text stays text: `char` arrays do not widen.
    if wide == Primitive::Char {
        return None;
    }
    Some((
        Field {
            ty: TypeRef::Primitive(wide),
            ..first.clone()
        },
        true,
    ))
}

/// The widest type of a field's kind ([`Merge::Widest`]), and whether it widens.
fn widest(field: Field, widens: bool) -> (Field, bool) {
    let wide = match field.ty {
        TypeRef::Primitive(p) if p.is_unsigned_integer() => Primitive::UInt64,
        TypeRef::Primitive(
            Primitive::Int8 | Primitive::Int16 | Primitive::Int32 | Primitive::Int64,
        ) => Primitive::Int64,
        TypeRef::Primitive(Primitive::Float | Primitive::Double) => Primitive::Double,
        _ => return (field, widens),
    };
    let changed = field.ty != TypeRef::Primitive(wide);
    (
        Field {
            ty: TypeRef::Primitive(wide),
            ..field
        },
        widens || changed,
    )
}

/// `float` in a.ulg, b.ulg; `double` in c.ulg; absent from d.ulg.
fn usage(s: &Seen<'_>, places: &[String]) -> String {
    let mut by_type: Vec<(String, Vec<&str>)> = Vec::new();
    let mut absent = Vec::new();
    for (field, place) in s.per_input.iter().zip(places) {
        match field {
            Some(f) => {
                let ty = match f.array_len {
                    Some(n) => format!("{}[{n}]", f.ty),
                    None => f.ty.to_string(),
                };
                match by_type.iter_mut().find(|(t, _)| *t == ty) {
                    Some((_, at)) => at.push(place),
                    None => by_type.push((ty, vec![place])),
                }
            }
            None => absent.push(place.as_str()),
        }
    }
    if let ([(ty, _)], []) = (by_type.as_slice(), absent.as_slice()) {
        return format!("`{ty}` in every input");
    }
    let mut parts: Vec<String> = by_type
        .iter()
        .map(|(ty, at)| format!("`{ty}` in {}", at.join(", ")))
        .collect();
    if !absent.is_empty() {
        parts.push(format!("absent from {}", absent.join(", ")));
    }
    parts.join("; ")
}
