//! `#[ulog(...)]` attributes: every key spelled once here, every error collected.

use proc_macro2::Span;
use syn::spanned::Spanned;
use syn::{Attribute, LitStr, Path};

use crate::Errors;

/// The attribute's name.
pub(crate) const ULOG: &str = "ulog";
/// Container: the topic (format) name.
const NAME: &str = "name";
/// Container: the file's format must be identical.
const EXACT: &str = "exact";
/// Container: path of the runtime crate.
const CRATE: &str = "crate";
/// Field: the name in the file.
const RENAME: &str = "rename";
/// Field: a padding field.
const PADDING: &str = "padding";
/// Container or field: accept narrower file types (lossless widening).
const WIDEN: &str = "widen";
/// Container: every topic name the type stands for.
const TOPICS: &str = "topics";
/// Container: only ever nested, never a topic (its `timestamp` may have any type).
const NESTED: &str = "nested";

/// A value with the span of the attribute that set it.
pub(crate) struct WithSpan<T> {
    pub(crate) value: T,
    pub(crate) span: Span,
}

/// Options of the struct.
#[derive(Default)]
pub(crate) struct ContainerAttrs {
    pub(crate) name: Option<WithSpan<String>>,
    pub(crate) exact: Option<Span>,
    pub(crate) krate: Option<Path>,
    pub(crate) widen: Option<Span>,
    pub(crate) topics: Option<Vec<LitStr>>,
    pub(crate) nested: Option<Span>,
}

/// Options of one field.
#[derive(Default)]
pub(crate) struct FieldAttrs {
    pub(crate) rename: Option<WithSpan<String>>,
    pub(crate) padding: Option<Span>,
    pub(crate) widen: Option<Span>,
}

/// Sets `slot` once; a second setting is an error at its key.
fn set_once<T>(slot: &mut Option<T>, value: T, key: &syn::Path, errors: &mut Errors) {
    if slot.is_some() {
        let name = key.get_ident().map(ToString::to_string).unwrap_or_default();
        errors.push(syn::Error::new_spanned(
            key,
            format!("duplicate `{name}` in `#[ulog(...)]`: set it once"),
        ));
    } else {
        *slot = Some(value);
    }
}

fn unknown(meta: &syn::meta::ParseNestedMeta<'_>, allowed: &[&str]) -> syn::Error {
    let key = meta
        .path
        .get_ident()
        .map(ToString::to_string)
        .unwrap_or_else(|| "this".to_owned());
    let allowed: Vec<String> = allowed.iter().map(|k| format!("`{k}`")).collect();
    meta.error(format!(
        "unknown ulog attribute `{key}`; expected one of {}",
        allowed.join(", ")
    ))
}

/// The `#[ulog(...)]` attributes among `attrs`.
fn ulog_attrs(attrs: &[Attribute]) -> impl Iterator<Item = &Attribute> {
    attrs.iter().filter(|a| a.path().is_ident(ULOG))
}

pub(crate) fn container(attrs: &[Attribute], errors: &mut Errors) -> ContainerAttrs {
    let mut out = ContainerAttrs::default();
    for attr in ulog_attrs(attrs) {
        let parsed = attr.parse_nested_meta(|meta| {
            if meta.path.is_ident(NAME) {
                let lit: LitStr = meta.value()?.parse()?;
                let value = WithSpan {
                    value: lit.value(),
                    span: lit.span(),
                };
                set_once(&mut out.name, value, &meta.path, errors);
            } else if meta.path.is_ident(EXACT) {
                set_once(&mut out.exact, meta.path.span(), &meta.path, errors);
            } else if meta.path.is_ident(CRATE) {
                let lit: LitStr = meta.value()?.parse()?;
                let path: Path = lit.parse()?;
                set_once(&mut out.krate, path, &meta.path, errors);
            } else if meta.path.is_ident(WIDEN) {
                set_once(&mut out.widen, meta.path.span(), &meta.path, errors);
            } else if meta.path.is_ident(NESTED) {
                set_once(&mut out.nested, meta.path.span(), &meta.path, errors);
            } else if meta.path.is_ident(TOPICS) {
                let content;
                syn::parenthesized!(content in meta.input);
                let names = content
                    .parse_terminated(<LitStr as syn::parse::Parse>::parse, syn::Token![,])?;
                set_once(
                    &mut out.topics,
                    names.into_iter().collect(),
                    &meta.path,
                    errors,
                );
            } else if meta.path.is_ident(RENAME) || meta.path.is_ident(PADDING) {
                return Err(meta.error(format!(
                    "`{}` is a field attribute; put it on a field",
                    meta.path.get_ident().expect("checked")
                )));
            } else {
                return Err(unknown(&meta, &[NAME, EXACT, CRATE, WIDEN, TOPICS, NESTED]));
            }
            Ok(())
        });
        if let Err(e) = parsed {
            errors.push(e);
        }
    }
    out
}

pub(crate) fn field(attrs: &[Attribute], errors: &mut Errors) -> FieldAttrs {
    let mut out = FieldAttrs::default();
    for attr in ulog_attrs(attrs) {
        let parsed = attr.parse_nested_meta(|meta| {
            if meta.path.is_ident(RENAME) {
                let lit: LitStr = meta.value()?.parse()?;
                let value = WithSpan {
                    value: lit.value(),
                    span: lit.span(),
                };
                set_once(&mut out.rename, value, &meta.path, errors);
            } else if meta.path.is_ident(PADDING) {
                set_once(&mut out.padding, meta.path.span(), &meta.path, errors);
            } else if meta.path.is_ident(WIDEN) {
                set_once(&mut out.widen, meta.path.span(), &meta.path, errors);
            } else if meta.path.is_ident(NAME)
                || meta.path.is_ident(EXACT)
                || meta.path.is_ident(CRATE)
                || meta.path.is_ident(TOPICS)
                || meta.path.is_ident(NESTED)
            {
                return Err(meta.error(format!(
                    "`{}` is a struct attribute; put it on the struct",
                    meta.path.get_ident().expect("checked")
                )));
            } else {
                return Err(unknown(&meta, &[RENAME, PADDING, WIDEN]));
            }
            Ok(())
        });
        if let Err(e) = parsed {
            errors.push(e);
        }
    }
    out
}
