//! Rust code for the resolved definitions: one struct per format, `#[derive(ULog)]` doing the
//! rest. Built as tokens, formatted with prettyplease.

use std::collections::{HashMap, HashSet};

use proc_macro2::{Ident, Span, TokenStream};
use quote::{format_ident, quote};

use super::input::Definition;
use super::msg::{ConstValue, Constant};
use super::{Builder, CodegenError, Resolved};
use crate::schema::{Field, Format, Primitive, Schema, TypeRef, is_padding_name};

/// Words Rust reserves: fields named so get a `_` suffix (and keep their ULog name).
const KEYWORDS: &[&str] = &[
    "as", "async", "await", "break", "const", "continue", "crate", "dyn", "else", "enum", "extern",
    "false", "fn", "for", "gen", "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut",
    "pub", "ref", "return", "self", "static", "struct", "super", "trait", "true", "try", "type",
    "unsafe", "use", "where", "while", "abstract", "become", "box", "do", "final", "macro",
    "override", "priv", "typeof", "unsized", "virtual", "yield",
];

/// `vehicle_attitude` -> `VehicleAttitude`, `GPS-data/raw` -> `GpsDataRaw`.
pub(crate) fn type_name(name: &str) -> String {
    let mut out = String::new();
    for part in name.split(|c: char| !c.is_ascii_alphanumeric()) {
        let mut chars = part.chars();
        if let Some(first) = chars.next() {
            out.push(first.to_ascii_uppercase());
            out.extend(chars.map(|c| c.to_ascii_lowercase()));
        }
    }
    if out.is_empty() || out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert(0, 'T');
    }
    if out == "Self" {
        out.push('_');
    }
    out
}

/// `airspeedSp` -> `airspeed_sp`, `R_body` -> `r_body`, `type` -> `type_`, `5v` -> `f_5v`.
pub(crate) fn field_name(name: &str) -> String {
    let chars: Vec<char> = name.chars().collect();
    let mut out = String::with_capacity(name.len() + 4);
    for (i, &c) in chars.iter().enumerate() {
        if c.is_ascii_uppercase() && i > 0 {
            let prev = chars[i - 1];
            let next_lower = chars.get(i + 1).is_some_and(char::is_ascii_lowercase);
            if prev.is_ascii_lowercase() || (prev.is_ascii_uppercase() && next_lower) {
                out.push('_');
            }
        }
        out.push(c.to_ascii_lowercase());
    }
    if out.is_empty() || out == "_" || out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert_str(0, "f_");
    }
    if KEYWORDS.contains(&out.as_str()) {
        out.push('_');
    }
    out
}

/// Unique names: a second `name` becomes `name_2`, and so on.
fn unique(name: String, taken: &mut HashSet<String>) -> String {
    let mut candidate = name.clone();
    let mut n = 2;
    while !taken.insert(candidate.clone()) {
        candidate = format!("{name}_{n}");
        n += 1;
    }
    candidate
}

fn rust_primitive(p: Primitive) -> &'static str {
    match p {
        Primitive::Int8 => "i8",
        Primitive::UInt8 => "u8",
        Primitive::Int16 => "i16",
        Primitive::UInt16 => "u16",
        Primitive::Int32 => "i32",
        Primitive::UInt32 => "u32",
        Primitive::Int64 => "i64",
        Primitive::UInt64 => "u64",
        Primitive::Float => "f32",
        Primitive::Double => "f64",
        Primitive::Bool => "bool",
        Primitive::Char => "u8",
    }
}

fn parse<T: syn::parse::Parse>(what: &'static str, value: &str) -> Result<T, CodegenError> {
    syn::parse_str(value).map_err(|e| CodegenError::InvalidOption {
        what,
        value: value.to_owned(),
        message: e.to_string(),
    })
}

/// Where generated code finds a type of another definition.
pub(crate) struct Names {
    /// Rust type name by format name.
    pub(crate) types: HashMap<String, String>,
    /// Module name (module-per-topic mode) by format name.
    pub(crate) modules: HashMap<String, String>,
}

/// Whether a format is a topic: it has a `timestamp` of an unsigned integer type (the
/// derive then implements `Topic`).
pub(crate) fn is_topic(format: &Format) -> bool {
    format.fields.iter().any(|f| {
        f.name == "timestamp"
            && f.array_len.is_none()
            && matches!(f.ty, TypeRef::Primitive(p) if p.is_unsigned_integer())
    })
}

/// Unique Rust names for the definitions, in order.
pub(crate) fn names(defs: &[Definition]) -> Names {
    let mut taken_types = HashSet::new();
    let mut taken_modules = HashSet::new();
    let mut names = Names {
        types: HashMap::new(),
        modules: HashMap::new(),
    };
    for def in defs {
        let name = &def.format.name;
        let wanted = def.rust_name.clone().unwrap_or_else(|| type_name(name));
        names
            .types
            .insert(name.clone(), unique(wanted, &mut taken_types));
        names
            .modules
            .insert(name.clone(), unique(field_name(name), &mut taken_modules));
    }
    names
}

pub(crate) fn render(
    builder: &Builder,
    resolved: &Resolved,
    inputs: &[String],
) -> Result<String, CodegenError> {
    let defs = &resolved.defs;
    let krate: syn::Path = parse("runtime crate path", &builder.runtime_crate)?;
    let vis: syn::Visibility = parse("visibility", &builder.visibility)?;
    let mut global_derives = Vec::new();
    for d in &builder.derives {
        global_derives.push(parse::<syn::Path>("derive", d)?);
    }
    let names = names(defs);
    let derives = inherited_derives(defs);
    let mut items = Vec::new();
    for def in defs {
        let item = one_type(
            builder,
            def,
            &resolved.schema,
            &names,
            &krate,
            &vis,
            (&derives[def.format.name.as_str()], &global_derives),
        )?;
        if builder.module_per_topic {
            let module = format_ident!("{}", names.modules[&def.format.name]);
            let doc = format!(" The `{}` format.", def.format.name);
            items.push(quote! {
                #[doc = #doc]
                #vis mod #module {
                    #item
                }
            });
        } else {
            items.push(item);
        }
    }
    let file: syn::File =
        syn::parse2(quote!(#(#items)*)).map_err(|e| CodegenError::InvalidOption {
            what: "generated code",
            value: String::new(),
            message: e.to_string(),
        })?;
    let mut out = format!(
        "// @generated by ulog_runtime::codegen from {}. Do not edit.\n\n",
        inputs.join(", ")
    );
    // A blank line between items, as rustfmt leaves them.
    let code = prettyplease::unparse(&file).replace("\n}\n", "\n}\n\n");
    out.push_str(code.trim_end());
    out.push('\n');
    Ok(out)
}

/// Each type's extra derives: its own, and those of every type that nests it, however
/// deep (a derive such as `Copy` or `Eq` holds only if the fields' types have it too).
fn inherited_derives(defs: &[Definition]) -> HashMap<&str, Vec<String>> {
    let mut derives: HashMap<&str, Vec<String>> = defs
        .iter()
        .map(|d| (d.format.name.as_str(), d.derives.clone()))
        .collect();
    // Handed down one level a round, until no type gains one (each round adds at least one
    // derive to a type, so the rounds are bounded by the types times their derives).
    loop {
        let mut changed = false;
        for def in defs {
            let from = derives[def.format.name.as_str()].clone();
            for field in &def.format.fields {
                let TypeRef::Nested(inner) = &field.ty else {
                    continue;
                };
                if let Some(to) = derives.get_mut(inner.as_str()) {
                    for d in &from {
                        if !to.contains(d) {
                            to.push(d.clone());
                            changed = true;
                        }
                    }
                }
            }
        }
        if !changed {
            return derives;
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn one_type(
    builder: &Builder,
    def: &Definition,
    schema: &Schema,
    names: &Names,
    krate: &syn::Path,
    vis: &syn::Visibility,
    (own_derives, global_derives): (&[String], &[syn::Path]),
) -> Result<TokenStream, CodegenError> {
    let format = &def.format;
    let ident = Ident::new(&names.types[&format.name], Span::call_site());
    let mut doc = Vec::new();
    if let Some(text) = &def.doc {
        doc.extend(doc_text(text, def.plain_docs));
        doc.push(String::new());
    }
    if def.merged > 0 {
        doc.push(format!("`ULog` format `{}`, merged:", format.name));
    } else {
        doc.push(format!(
            "`ULog` format `{}`, from `{}`:",
            format.name,
            def.place.doc_text()
        ));
    }
    doc.push(format!("`{format}`"));
    if !def.topics.is_empty() {
        doc.push(String::new());
        let all: Vec<String> = std::iter::once(&format.name)
            .chain(&def.topics)
            .map(|t| format!("`{t}`"))
            .collect();
        doc.push(format!(
            "Topics with this layout: {} (read others with `Log::topic_as`).",
            all.join(", ")
        ));
    }
    let name = &format.name;
    let exact = def.exact.then(|| quote!(exact,));
    let topics = (!def.topics.is_empty()).then(|| {
        let all = std::iter::once(name).chain(&def.topics);
        quote!(topics(#(#all),*),)
    });
    // A `timestamp` that is not an unsigned integer cannot be a topic's clock.
    let nested =
        (!is_topic(format) && format.field("timestamp").is_some()).then(|| quote!(nested,));
    let krate_text = quote!(#krate).to_string().replace(' ', "");
    // Extra derives, each once, and not again the ones every type gets.
    let mut derives: Vec<syn::Path> = Vec::new();
    let mut seen: Vec<String> = ["Debug", "Clone", "PartialEq"].map(String::from).to_vec();
    let mut extra = Vec::new();
    for d in own_derives {
        extra.push(parse::<syn::Path>("derive", d)?);
    }
    for path in extra.into_iter().chain(global_derives.iter().cloned()) {
        let text = quote!(#path).to_string().replace(' ', "");
        if !seen.contains(&text) {
            seen.push(text);
            derives.push(path);
        }
    }

    let mut taken = HashSet::new();
    let mut fields = Vec::new();
    let mut bools = 0;
    let mut underscore = false;
    for field in &format.fields {
        fields.push(one_field(
            &FieldContext {
                def,
                schema,
                names,
                krate,
                vis,
                builder,
            },
            field,
            &mut taken,
            &mut bools,
            &mut underscore,
        )?);
    }
    let mut allows = Vec::new();
    if bools > 3 {
        allows.push(quote!(clippy::struct_excessive_bools));
    }
    if underscore {
        allows.push(quote!(clippy::pub_underscore_fields));
    }
    // Comments of `.msg` files are prose with C names in it, not Markdown.
    let prose = def.plain_docs && (def.doc.is_some() || !def.field_docs.is_empty());
    if prose {
        allows.push(quote!(clippy::doc_markdown));
    }
    let allow = (!allows.is_empty()).then(|| quote!(#[allow(#(#allows),*)]));
    let doc = doc_lines(&doc);
    let constants = constants(def, &ident, krate, vis, def.plain_docs);
    Ok(quote! {
        #(#[doc = #doc])*
        #[derive(#krate::ULog, Debug, Clone, PartialEq #(, #derives)*)]
        #[ulog(name = #name, #topics #exact #nested crate = #krate_text)]
        #allow
        #vis struct #ident {
            #(#fields)*
        }

        #constants
    })
}

/// The constants of a `.msg` file, as associated constants.
fn constants(
    def: &Definition,
    ident: &Ident,
    krate: &syn::Path,
    vis: &syn::Visibility,
    prose: bool,
) -> Option<TokenStream> {
    if def.constants.is_empty() {
        return None;
    }
    let items = def.constants.iter().map(|c| {
        let name = format_ident!("{}", const_ident(&c.name));
        let (ty, value) = const_tokens(c, krate);
        let mut doc = vec![format!(
            "`{} {} = {}`",
            super::msg::msg_type_name(c.ty),
            c.name,
            c.text
        )];
        if let Some(text) = &c.doc {
            doc.push(String::new());
            doc.extend(doc_text(text, true));
        }
        let doc = doc_lines(&doc);
        let allow = (c.name.chars().any(|ch| ch.is_ascii_lowercase()))
            .then(|| quote!(#[allow(non_upper_case_globals)]));
        quote! {
            #(#[doc = #doc])*
            #allow
            #vis const #name: #ty = #value;
        }
    });
    let doc = format!(" The constants of `{}`.", def.place.doc_text());
    // The values are the file's, whatever they look like, and so are the comments.
    let prose = prose.then(|| quote!(, clippy::doc_markdown));
    Some(quote! {
        #[doc = #doc]
        #[allow(clippy::unreadable_literal, clippy::approx_constant #prose)]
        impl #ident {
            #(#items)*
        }
    })
}

/// A constant's name as an identifier (`Self` and keywords get a `_` suffix).
fn const_ident(name: &str) -> String {
    if KEYWORDS.contains(&name) || name == "Self" {
        format!("{name}_")
    } else {
        name.to_owned()
    }
}

/// A constant's Rust type and value.
fn const_tokens(c: &Constant, krate: &syn::Path) -> (TokenStream, TokenStream) {
    use proc_macro2::Literal;
    let ty = match c.ty {
        Primitive::Char => quote!(#krate::Char),
        p => {
            let t = format_ident!("{}", rust_primitive(p));
            quote!(#t)
        }
    };
    let value = match (c.ty, c.value) {
        (_, ConstValue::Bool(b)) => quote!(#b),
        (Primitive::Float, ConstValue::Float(v)) => {
            // The shortest text that gives the same f32: no excessive precision.
            #[allow(clippy::cast_possible_truncation)]
            let lit: TokenStream = format!("{:?}", v as f32).parse().expect("a float literal");
            lit
        }
        (_, ConstValue::Float(v)) => {
            let lit: TokenStream = format!("{v:?}").parse().expect("a float literal");
            lit
        }
        (Primitive::Char, ConstValue::Int(v)) => {
            let b = Literal::u8_unsuffixed(u8::try_from(v).expect("checked to fit"));
            quote!(#krate::Char(#b))
        }
        (_, ConstValue::Int(v)) => {
            let lit = Literal::i128_unsuffixed(v.abs());
            if v < 0 { quote!(-#lit) } else { quote!(#lit) }
        }
    };
    (ty, value)
}

/// What one field's code needs to know.
struct FieldContext<'a> {
    def: &'a Definition,
    schema: &'a Schema,
    names: &'a Names,
    krate: &'a syn::Path,
    vis: &'a syn::Visibility,
    builder: &'a Builder,
}

fn one_field(
    cx: &FieldContext<'_>,
    field: &Field,
    taken: &mut HashSet<String>,
    bools: &mut usize,
    underscore: &mut bool,
) -> Result<TokenStream, CodegenError> {
    let FieldContext {
        def,
        schema,
        names,
        krate,
        vis,
        builder,
    } = cx;
    let len = field.array_len.map(usize::from);
    if is_padding_name(&field.name) {
        // Padding is bytes whatever its declared type: its size is what counts.
        let elem = match &field.ty {
            TypeRef::Primitive(p) => p.size(),
            TypeRef::Nested(n) => schema
                .id(n)
                .and_then(|id| schema.resolved(id))
                .map(|l| l.size)
                .expect("layouts are resolved before emitting"),
        };
        let size = elem * len.unwrap_or(1);
        let ident = format_ident!("{}", unique(field.name.clone(), taken));
        let size = proc_macro2::Literal::usize_unsuffixed(size);
        *underscore = true;
        let doc = format!(" Padding: `{field}`.");
        return Ok(quote! {
            #[doc = #doc]
            #[ulog(padding)]
            #vis #ident: [u8; #size],
        });
    }
    let element: TokenStream = match &field.ty {
        TypeRef::Primitive(Primitive::Char) => match len {
            Some(n) => {
                let n = proc_macro2::Literal::usize_unsuffixed(n);
                return Ok(field_tokens(cx, field, quote!(#krate::Chars<#n>), taken));
            }
            None => quote!(#krate::Char),
        },
        TypeRef::Primitive(p) => {
            if *p == Primitive::Bool && len.is_none() && !def.optional.contains(&field.name) {
                *bools += 1;
            }
            let ty = format_ident!("{}", rust_primitive(*p));
            quote!(#ty)
        }
        TypeRef::Nested(n) => {
            let ty = format_ident!("{}", names.types[n]);
            if builder.module_per_topic {
                let module = format_ident!("{}", names.modules[n]);
                quote!(super::#module::#ty)
            } else {
                quote!(#ty)
            }
        }
    };
    let ty = match len {
        Some(n) => {
            let n = proc_macro2::Literal::usize_unsuffixed(n);
            quote!([#element; #n])
        }
        None => element,
    };
    Ok(field_tokens(cx, field, ty, taken))
}

fn field_tokens(
    cx: &FieldContext<'_>,
    field: &Field,
    ty: TokenStream,
    taken: &mut HashSet<String>,
) -> TokenStream {
    let (def, vis) = (cx.def, cx.vis);
    let rust = unique(field_name(&field.name), taken);
    let ident = format_ident!("{rust}");
    let mut doc = Vec::new();
    if let Some(text) = def.field_docs.get(&field.name) {
        doc.extend(doc_text(text, def.plain_docs));
        doc.push(String::new());
    }
    doc.push(format!("`{field}`"));
    let doc = doc_lines(&doc);
    let rename = (rust != field.name).then(|| {
        let name = &field.name;
        quote!(#[ulog(rename = #name)])
    });
    let widen = def
        .widen
        .contains(&field.name)
        .then(|| quote!(#[ulog(widen)]));
    let ty = if def.optional.contains(&field.name) {
        quote!(::core::option::Option<#ty>)
    } else {
        ty
    };
    quote! {
        #(#[doc = #doc])*
        #rename
        #widen
        #vis #ident: #ty,
    }
}

/// The lines of a doc text; plain text from a file (`.msg` comments, merge notes) is
/// escaped so that rustdoc shows it as written: brackets and angle brackets are not links
/// or HTML, bare URLs are links.
fn doc_text(text: &str, plain: bool) -> Vec<String> {
    text.lines()
        .map(|line| {
            if !plain {
                return line.to_owned();
            }
            // Tabs align columns in `.msg` comments; rustdoc wants spaces.
            let line = &line.replace('\t', "    ");
            let mut out = String::with_capacity(line.len());
            for word in line.split_inclusive(' ') {
                let (w, space) = match word.strip_suffix(' ') {
                    Some(w) => (w, " "),
                    None => (word, ""),
                };
                if w.starts_with("http://") || w.starts_with("https://") {
                    out.push('<');
                    out.push_str(w);
                    out.push('>');
                } else {
                    for c in w.chars() {
                        if matches!(c, '[' | ']' | '<' | '>' | '*' | '\\') {
                            out.push('\\');
                        }
                        out.push(c);
                    }
                }
                out.push_str(space);
            }
            // Not a heading, list item or quote.
            if out.starts_with(['#', '-', '+', '>', '=']) {
                out.insert(0, '\\');
            }
            out
        })
        .collect()
}

/// Doc lines as `///` comments print them: a space after the slashes.
fn doc_lines(lines: &[String]) -> Vec<String> {
    lines
        .iter()
        .map(|l| {
            if l.is_empty() {
                String::new()
            } else {
                format!(" {l}")
            }
        })
        .collect()
}
