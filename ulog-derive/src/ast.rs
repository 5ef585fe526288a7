//! The derive input as a ULog struct: its shape is checked here (named fields, no generics),
//! its attributes parsed, every error collected.

use proc_macro2::Span;
use syn::spanned::Spanned;
use syn::{Data, DeriveInput, Fields, Ident, Type};

use crate::Errors;
use crate::attr::{self, ContainerAttrs, FieldAttrs};

/// A struct with named fields.
pub(crate) struct Input<'a> {
    pub(crate) ident: &'a Ident,
    pub(crate) attrs: ContainerAttrs,
    pub(crate) fields: Vec<FieldInput<'a>>,
}

/// One field.
pub(crate) struct FieldInput<'a> {
    pub(crate) ident: &'a Ident,
    pub(crate) ty: &'a Type,
    pub(crate) attrs: FieldAttrs,
}

impl FieldInput<'_> {
    /// The Rust name without a raw-identifier prefix.
    pub(crate) fn rust_name(&self) -> String {
        let name = self.ident.to_string();
        name.strip_prefix("r#").map(str::to_owned).unwrap_or(name)
    }

    /// The name in the file (before padding numbering) and where it comes from.
    pub(crate) fn ulog_name(&self) -> (String, Span) {
        match &self.attrs.rename {
            Some(r) => (r.value.clone(), r.span),
            None => (self.rust_name(), self.ident.span()),
        }
    }
}

/// Parses the input; `None` when its shape cannot be a ULog format (errors pushed).
pub(crate) fn parse<'a>(input: &'a DeriveInput, errors: &mut Errors) -> Option<Input<'a>> {
    let attrs = attr::container(&input.attrs, errors);
    let fields = match &input.data {
        Data::Struct(s) => match &s.fields {
            Fields::Named(named) => &named.named,
            Fields::Unnamed(_) => {
                errors.push(syn::Error::new(
                    input.ident.span(),
                    "`#[derive(ULog)]` needs named fields: ULog fields have names; \
                     write `struct Name { field: Type, ... }`",
                ));
                return None;
            }
            Fields::Unit => {
                errors.push(syn::Error::new(
                    input.ident.span(),
                    "`#[derive(ULog)]` needs named fields: a unit struct has nothing to log",
                ));
                return None;
            }
        },
        Data::Enum(e) => {
            errors.push(syn::Error::new(
                e.enum_token.span,
                "`#[derive(ULog)]` supports structs with named fields, not enums: \
                 a ULog format is a fixed list of fields",
            ));
            return None;
        }
        Data::Union(u) => {
            errors.push(syn::Error::new(
                u.union_token.span,
                "`#[derive(ULog)]` supports structs with named fields, not unions",
            ));
            return None;
        }
    };
    if !input.generics.params.is_empty() || input.generics.where_clause.is_some() {
        errors.push(syn::Error::new(
            input.generics.span(),
            "a ULog type cannot be generic: its format has one fixed layout",
        ));
        return None;
    }
    if fields.is_empty() {
        errors.push(syn::Error::new(
            input.ident.span(),
            "`#[derive(ULog)]` needs at least one field: a ULog format cannot be empty",
        ));
        return None;
    }
    let fields = fields
        .iter()
        .map(|f| FieldInput {
            ident: f.ident.as_ref().expect("named fields have names"),
            ty: &f.ty,
            attrs: attr::field(&f.attrs, errors),
        })
        .collect();
    Some(Input {
        ident: &input.ident,
        attrs,
        fields,
    })
}
