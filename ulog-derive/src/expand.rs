//! Code generation: the `ULog` impl (format constant, encode, decode), the `Topic` impl for
//! structs with a `timestamp`, and the size assertion. Every type mapping is a reference to a
//! trait constant of the runtime, so the derive has no type table.

use proc_macro2::TokenStream;
use quote::{ToTokens, quote, quote_spanned};
use syn::Path;
use syn::spanned::Spanned;

use crate::ast::Input;

/// `EscStatus` -> `esc_status`, `GPSPosition` -> `gps_position`.
pub(crate) fn snake_case(name: &str) -> String {
    let chars: Vec<char> = name.chars().collect();
    let mut out = String::with_capacity(name.len() + 4);
    for (i, &c) in chars.iter().enumerate() {
        if c.is_uppercase() && i > 0 {
            let prev = chars[i - 1];
            let next_lower = chars.get(i + 1).is_some_and(|n| n.is_lowercase());
            if prev.is_lowercase() || prev.is_ascii_digit() || (prev.is_uppercase() && next_lower) {
                out.push('_');
            }
        }
        out.extend(c.to_lowercase());
    }
    out
}

/// A type as people write it: `[f32; 4]`, `Option<Chars<8>>`.
fn type_text(ty: &syn::Type) -> String {
    let mut s = ty.to_token_stream().to_string();
    for (from, to) in [
        (" ;", ";"),
        ("[ ", "["),
        (" ]", "]"),
        (" <", "<"),
        ("< ", "<"),
        (" >", ">"),
        (" ,", ","),
        (" :: ", "::"),
        (":: ", "::"),
        ("& ", "&"),
    ] {
        s = s.replace(from, to);
    }
    s
}

/// The path of the runtime's hidden module, `::ulog_runtime::__private` by default.
fn private_path(input: &Input<'_>) -> TokenStream {
    let krate: Path = input
        .attrs
        .krate
        .clone()
        .unwrap_or_else(|| syn::parse_quote!(::ulog_runtime));
    quote!(#krate::__private)
}

/// Every topic name: the format's own first, then the others of `topics(...)`.
fn topic_names(input: &Input<'_>, topic: &str) -> Vec<String> {
    let mut names = vec![topic.to_owned()];
    for lit in input.attrs.topics.iter().flatten() {
        let name = lit.value();
        if !names.contains(&name) {
            names.push(name);
        }
    }
    names
}

/// What is emitted beside the errors of an input that has some: the checks of the field
/// types (so one build shows them too) and impls that satisfy the traits without doing
/// anything, so code using the type does not fail again for lack of them.
pub(crate) fn fallback(input: &Input<'_>) -> TokenStream {
    let ident = input.ident;
    let p = private_path(input);
    let rust_type = ident.to_string();
    // The types the checks refused are not checked again (one error each).
    let checks = input
        .fields
        .iter()
        .filter(|f| !crate::check::type_refused(f))
        .map(|field| {
            let ty = field.ty;
            if field.attrs.padding.is_some() {
                quote_spanned!(ty.span()=> __ulog_padding::<#ty>();)
            } else {
                quote_spanned!(ty.span()=> __ulog_field::<#ty>();)
            }
        });
    let timestamp = input.attrs.nested.is_none()
        && input
            .fields
            .iter()
            .any(|f| f.attrs.padding.is_none() && f.ulog_name().0 == "timestamp");
    let topic_impl = timestamp.then(|| quote! { impl #p::DerivedTopic for #ident {} });
    quote! {
        #[doc(hidden)]
        #[allow(non_upper_case_globals, unused_qualifications, dead_code, clippy::all, clippy::pedantic)]
        const _: () = {
            fn __ulog_field<T: #p::FieldValue>() {}
            fn __ulog_padding<T: #p::Padding>() {}
            fn __ulog_field_types() {
                #(#checks)*
            }

            impl #p::ULog for #ident {
                const FORMAT: #p::TypedFormat = #p::TypedFormat {
                    name: "",
                    topics: &[],
                    rust_type: #rust_type,
                    fields: &[],
                    exact: false,
                };
                fn encode(&self, _: &mut #p::Vec<u8>) {
                    ::core::unreachable!("the derive failed")
                }
                fn decode(_: &#p::DecodePlan, _: &[u8]) -> Self {
                    ::core::unreachable!("the derive failed")
                }
            }

            impl #p::DerivedElement for #ident {}

            #topic_impl
        };
    }
}

pub(crate) fn expand(input: &Input<'_>, topic: &str) -> TokenStream {
    let ident = input.ident;
    let p = private_path(input);
    let rust_type = ident.to_string();
    let exact = input.attrs.exact.is_some();
    let topics = topic_names(input, topic);

    let mut descriptors = Vec::new();
    let mut encodes = Vec::new();
    let mut decodes = Vec::new();
    let mut padding_index = 0usize;
    let mut has_timestamp = false;
    for (i, field) in input.fields.iter().enumerate() {
        let ty = field.ty;
        let member = field.ident;
        let text = type_text(ty);
        if field.attrs.padding.is_some() {
            let name = format!("_padding{padding_index}");
            padding_index += 1;
            let pad = quote_spanned!(ty.span()=> <#ty as #p::Padding>);
            descriptors.push(quote! {
                #p::TypedField {
                    name: #name,
                    kind: #p::TypedKind::Primitive(#p::Primitive::UInt8),
                    array_len: ::core::option::Option::Some(#pad::LEN),
                    padding: true,
                    optional: false,
                    widen: false,
                    rust_type: #text,
                }
            });
            encodes.push(quote! { #p::encode_padding(#pad::LEN, out); });
            decodes.push(quote! { #member: #pad::ZERO });
            continue;
        }
        let (name, _) = field.ulog_name();
        has_timestamp |= name == "timestamp";
        let widen = input.attrs.widen.is_some() || field.attrs.widen.is_some();
        let value = quote_spanned!(ty.span()=> <#ty as #p::FieldValue>);
        descriptors.push(quote! {
            #p::TypedField {
                name: #name,
                kind: #value::KIND,
                array_len: #value::ARRAY_LEN,
                padding: false,
                optional: #value::OPTIONAL,
                widen: #widen,
                rust_type: #text,
            }
        });
        encodes.push(quote! { #value::encode_field(&self.#member, out); });
        let decode = if widen {
            quote!(decode_field_widened)
        } else {
            quote!(decode_field)
        };
        decodes.push(quote! { #member: #value::#decode(plan.field(#i), row) });
    }

    let topic_impl = (has_timestamp && input.attrs.nested.is_none())
        .then(|| quote! { impl #p::DerivedTopic for #ident {} });
    let too_large = format!(
        "`{rust_type}` is too large for ULog: one data message carries at most 65533 bytes"
    );
    let size_assert = quote_spanned! {ident.span()=>
        const _: () = ::core::assert!(
            <#ident as #p::ULog>::FORMAT.size() <= #p::MAX_DATA_SIZE,
            #too_large
        );
    };

    quote! {
        #[doc(hidden)]
        #[allow(non_upper_case_globals, unused_qualifications, clippy::all, clippy::pedantic)]
        const _: () = {
            #[automatically_derived]
            impl #p::ULog for #ident {
                const FORMAT: #p::TypedFormat = #p::TypedFormat {
                    name: #topic,
                    topics: &[#(#topics),*],
                    rust_type: #rust_type,
                    fields: &[#(#descriptors),*],
                    exact: #exact,
                };

                #[inline]
                fn encode(&self, out: &mut #p::Vec<u8>) {
                    #(#encodes)*
                }

                #[inline]
                fn decode(plan: &#p::DecodePlan, row: &[u8]) -> Self {
                    Self { #(#decodes),* }
                }
            }

            #[automatically_derived]
            impl #p::DerivedElement for #ident {}

            #topic_impl

            #size_assert
        };
    }
}
