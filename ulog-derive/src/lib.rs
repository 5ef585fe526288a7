//! `#[derive(ULog)]`: a Rust struct as a typed ULog format, with its encoder and decoder.
//!
//! Use it through `ulog_runtime`, which re-exports it next to the `ULog` trait; the
//! attributes and field types are documented there (`ulog_runtime::ULog`).
//!
//! The pipeline: `ast` and `attr` parse the input and collect every error, `check` applies
//! the naming and shape rules one per function, `expand` generates the impls.

mod ast;
mod attr;
mod check;
mod expand;

use proc_macro::TokenStream;
use syn::{DeriveInput, parse_macro_input};

/// Errors collected over a whole input, reported together.
pub(crate) type Errors = Vec<syn::Error>;

/// Implements `ulog_runtime::ULog` (and `ulog_runtime::Topic` for a struct with a `timestamp`)
/// for a struct with named fields. See `ulog_runtime::ULog` for the attributes.
#[proc_macro_derive(ULog, attributes(ulog))]
pub fn derive_ulog(input: TokenStream) -> TokenStream {
    let input = parse_macro_input!(input as DeriveInput);
    let mut errors = Errors::new();
    let Some(parsed) = ast::parse(&input, &mut errors) else {
        return compile_errors(errors).into();
    };
    let topic = parsed.attrs.name.as_ref().map_or_else(
        || expand::snake_case(&parsed.ident.to_string()),
        |n| n.value.clone(),
    );
    check::all(&parsed, &topic, &mut errors);
    if errors.is_empty() {
        expand::expand(&parsed, &topic).into()
    } else {
        // Beside the errors: the field-type checks, and impls that keep code using the type
        // from failing again.
        let mut tokens = compile_errors(errors);
        tokens.extend(expand::fallback(&parsed));
        tokens.into()
    }
}

fn compile_errors(errors: Errors) -> proc_macro2::TokenStream {
    errors.into_iter().map(|e| e.to_compile_error()).collect()
}
