//! The rules a ULog struct must follow that the type system cannot check, one per function.
//! Field types are checked by the runtime's trait impls, not here.

use std::collections::HashMap;

use syn::{LitStr, Type, TypeArray};

use crate::Errors;
use crate::ast::{FieldInput, Input};

/// Prefix the format grammar reserves for padding fields.
const PADDING_PREFIX: &str = "_padding";

/// The basic type names of the format grammar, which a format name may not take.
const BASIC_TYPE_NAMES: [&str; 12] = [
    "int8_t", "uint8_t", "int16_t", "uint16_t", "int32_t", "uint32_t", "int64_t", "uint64_t",
    "float", "double", "bool", "char",
];

pub(crate) fn all(input: &Input<'_>, topic: &str, errors: &mut Errors) {
    let span = input
        .attrs
        .name
        .as_ref()
        .map_or(input.ident.span(), |n| n.span);
    topic_name(topic, span, errors);
    topics(input, errors);
    widen_not_exact(input, errors);
    for field in &input.fields {
        field_name(field, errors);
        padding_field(field, errors);
        array_dimensions(field.ty, errors);
        if input.attrs.nested.is_none() {
            timestamp_type(field, errors);
        }
    }
    nested_not_topic(input, errors);
    unique_names(input, errors);
}

/// Every name of `topics(...)` is a valid topic name, listed once.
fn topics(input: &Input<'_>, errors: &mut Errors) {
    let Some(topics) = &input.attrs.topics else {
        return;
    };
    if topics.is_empty() {
        errors.push(syn::Error::new(
            input.ident.span(),
            "`topics(...)` needs at least one topic name",
        ));
    }
    let mut seen = Vec::new();
    for lit in topics {
        let name = lit.value();
        topic_name(&name, lit.span(), errors);
        if seen.contains(&name) {
            errors.push(syn::Error::new(
                lit.span(),
                format!("topic `{name}` is listed twice in `topics(...)`"),
            ));
        }
        seen.push(name);
    }
}

/// A type only ever nested has no topic names.
fn nested_not_topic(input: &Input<'_>, errors: &mut Errors) {
    if let (Some(_), Some(topics)) = (input.attrs.nested, &input.attrs.topics) {
        errors.push(syn::Error::new(
            topics.first().map_or(input.ident.span(), LitStr::span),
            "a `nested` type is never a topic, so it has no `topics(...)`",
        ));
    }
}

/// Exact mode requires identical types, so widening contradicts it.
fn widen_not_exact(input: &Input<'_>, errors: &mut Errors) {
    if input.attrs.exact.is_none() {
        return;
    }
    let widen = input
        .attrs
        .widen
        .into_iter()
        .chain(input.fields.iter().filter_map(|f| f.attrs.widen));
    for span in widen {
        errors.push(syn::Error::new(
            span,
            "`widen` contradicts `exact` (exact mode requires the file's types to be identical); \
             remove one of them",
        ));
    }
}

/// A topic name follows the format grammar: `a-z A-Z 0-9 _ - /`, not a basic type name.
fn topic_name(topic: &str, span: proc_macro2::Span, errors: &mut Errors) {
    let bad = topic
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '/')));
    let message = if topic.is_empty() {
        "a ULog topic name cannot be empty".to_owned()
    } else if let Some(c) = bad {
        format!(
            "invalid ULog topic name `{topic}`: {c:?} is not allowed \
             (allowed: a-z A-Z 0-9 _ - /)"
        )
    } else if BASIC_TYPE_NAMES.contains(&topic) {
        format!("invalid ULog topic name `{topic}`: it is a basic type name")
    } else {
        return;
    };
    errors.push(syn::Error::new(span, message));
}

/// A field name follows the format grammar (`a-z A-Z 0-9 _`), and only padding fields use the
/// padding prefix.
fn field_name(field: &FieldInput<'_>, errors: &mut Errors) {
    if field.attrs.padding.is_some() {
        return;
    }
    let (name, span) = field.ulog_name();
    if name.is_empty() {
        errors.push(syn::Error::new(span, "a ULog field name cannot be empty"));
    } else if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || *c == '_'))
    {
        errors.push(syn::Error::new(
            span,
            format!(
                "invalid ULog field name `{name}`: {c:?} is not allowed (allowed: a-z A-Z 0-9 _); \
                 use `#[ulog(rename = \"...\")]`"
            ),
        ));
    } else if name.starts_with(PADDING_PREFIX) {
        errors.push(syn::Error::new(
            span,
            format!(
                "`{name}`: names starting with `{PADDING_PREFIX}` are padding in ULog; \
                 mark the field `#[ulog(padding)]` or rename it"
            ),
        ));
    }
}

/// Padding is a byte array and has no name of its own.
fn padding_field(field: &FieldInput<'_>, errors: &mut Errors) {
    if field.attrs.padding.is_none() {
        return;
    }
    if !is_byte_array(field.ty) {
        errors.push(syn::Error::new_spanned(
            field.ty,
            "a `#[ulog(padding)]` field must be a byte array `[u8; N]`",
        ));
    }
    if let Some(rename) = &field.attrs.rename {
        errors.push(syn::Error::new(
            rename.span,
            "padding fields are named `_paddingN` in the file; remove `rename`",
        ));
    }
    if let Some(widen) = field.attrs.widen {
        errors.push(syn::Error::new(
            widen,
            "padding is never read, so it cannot widen; remove `widen`",
        ));
    }
}

fn is_byte_array(ty: &Type) -> bool {
    match ty {
        Type::Array(TypeArray { elem, .. }) => {
            matches!(&**elem, Type::Path(p) if p.qself.is_none() && p.path.is_ident("u8"))
        }
        Type::Group(g) => is_byte_array(&g.elem),
        Type::Paren(p) => is_byte_array(&p.elem),
        _ => false,
    }
}

/// Whether a field's type is one the checks above already refused (a padding field that
/// is not bytes, an array of arrays): the trait bound on its type is left out of the
/// fallback, so that it is said once.
pub(crate) fn type_refused(field: &FieldInput<'_>) -> bool {
    (field.attrs.padding.is_some() && !is_byte_array(field.ty)) || is_multi_dimensional(field.ty)
}

fn is_multi_dimensional(ty: &Type) -> bool {
    /// The type inside invisible groups (a `macro_rules!` `$t:ty`) and parentheses.
    fn bare(ty: &Type) -> &Type {
        match ty {
            Type::Group(g) => bare(&g.elem),
            Type::Paren(p) => bare(&p.elem),
            other => other,
        }
    }
    matches!(bare(ty), Type::Array(outer) if matches!(bare(&outer.elem), Type::Array(_)))
}

/// ULog arrays have one dimension.
fn array_dimensions(ty: &Type, errors: &mut Errors) {
    if is_multi_dimensional(ty) {
        errors.push(syn::Error::new_spanned(
            ty,
            "multi-dimensional arrays do not exist in ULog: use one `[T; N]` \
             (flattened), or an array of a nested struct",
        ));
    }
}

/// The topic clock: `timestamp` holds microseconds in an unsigned integer.
fn timestamp_type(field: &FieldInput<'_>, errors: &mut Errors) {
    if field.attrs.padding.is_some() || field.ulog_name().0 != "timestamp" {
        return;
    }
    let unsigned = ["u64", "u32", "u16", "u8"];
    let ok = matches!(field.ty, Type::Path(p) if p.qself.is_none()
        && unsigned.iter().any(|u| p.path.is_ident(u)));
    if !ok {
        errors.push(syn::Error::new_spanned(
            field.ty,
            "`timestamp` must be an unsigned integer of microseconds: `u64` \
             (version-0 logs also used u32, u16, u8); a type that is only nested can say \
             `#[ulog(nested)]`",
        ));
    }
}

/// No two fields share a name in the file.
fn unique_names(input: &Input<'_>, errors: &mut Errors) {
    let mut seen: HashMap<String, &FieldInput<'_>> = HashMap::new();
    for field in input.fields.iter().filter(|f| f.attrs.padding.is_none()) {
        let (name, span) = field.ulog_name();
        if let Some(first) = seen.get(&name) {
            errors.push(syn::Error::new(
                span,
                format!(
                    "duplicate ULog field name `{name}`: field `{}` already has it",
                    first.rust_name()
                ),
            ));
        } else {
            seen.insert(name, field);
        }
    }
}
