//! The inputs of the generator: TOML topic files, format strings, logs and `.msg` files,
//! read into one list of definitions that remember where each came from.

use std::collections::{HashMap, HashSet};
use std::fmt;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::CodegenError;
use crate::schema::{Format, TypeRef};

/// Where a definition comes from, for error messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Place {
    /// A TOML topics file, at a line (1-based).
    Toml {
        /// The file.
        path: PathBuf,
        /// The line of the topic's name.
        line: usize,
    },
    /// The `n`-th format string given to the builder (1-based).
    FormatString(usize),
    /// The `F` messages of a log.
    Log(PathBuf),
    /// A PX4 `.msg` file, at a line (1-based).
    Msg {
        /// The file.
        path: PathBuf,
        /// The line.
        line: usize,
    },
}

impl Place {
    /// The place for a doc comment: a file without its line for `.msg` files (the whole
    /// file is the definition), as [`Display`](fmt::Display) otherwise.
    pub(crate) fn doc_text(&self) -> String {
        match self {
            Place::Msg { path, .. } => path.display().to_string(),
            other => other.to_string(),
        }
    }
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Place::Toml { path, line } | Place::Msg { path, line } => {
                write!(f, "{}:{line}", path.display())
            }
            Place::FormatString(n) => write!(f, "format string #{n}"),
            Place::Log(path) => write!(f, "{}", path.display()),
        }
    }
}

/// One format to generate a type for, with what the inputs say about it.
#[derive(Debug, Clone)]
pub(crate) struct Definition {
    pub(crate) format: Format,
    pub(crate) place: Place,
    pub(crate) doc: Option<String>,
    pub(crate) field_docs: HashMap<String, String>,
    pub(crate) derives: Vec<String>,
    pub(crate) exact: bool,
    /// Topic names beyond the format's own (PX4's `# TOPICS`), in order.
    pub(crate) topics: Vec<String>,
    /// Constants of a `.msg` file.
    pub(crate) constants: Vec<crate::codegen::msg::Constant>,
    /// The Rust type name an input asks for (a `.msg` file's name).
    pub(crate) rust_name: Option<String>,
    /// Fields a merged type may lack (`Option`).
    pub(crate) optional: HashSet<String>,
    /// Fields that widen (`#[ulog(widen)]`).
    pub(crate) widen: HashSet<String>,
    /// Docs that are plain text from a file (`.msg` comments), escaped for rustdoc.
    pub(crate) plain_docs: bool,
    /// How many differing definitions were merged into this one (0: none).
    pub(crate) merged: usize,
    /// Its input is a damaged log: what the reader said (the first problem), for an error
    /// about a type it nests and no input defines (the damage may have taken it).
    pub(crate) damage: Option<String>,
}

impl Definition {
    pub(crate) fn plain(format: Format, place: Place) -> Definition {
        Definition {
            format,
            place,
            doc: None,
            field_docs: HashMap::new(),
            derives: Vec::new(),
            exact: false,
            topics: Vec::new(),
            constants: Vec::new(),
            rust_name: None,
            optional: HashSet::new(),
            widen: HashSet::new(),
            plain_docs: false,
            merged: 0,
            damage: None,
        }
    }
}

/// A TOML topics file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TopicsFile {
    #[serde(default)]
    topic: Vec<TomlTopic>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TomlTopic {
    name: toml::Spanned<String>,
    #[serde(default)]
    doc: Option<String>,
    #[serde(default)]
    derives: Vec<String>,
    #[serde(default)]
    exact: bool,
    fields: Vec<TomlField>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TomlField {
    name: toml::Spanned<String>,
    #[serde(rename = "type")]
    ty: toml::Spanned<String>,
    #[serde(default)]
    len: Option<toml::Spanned<u32>>,
    #[serde(default)]
    doc: Option<String>,
}

/// 1-based line of a byte offset.
fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

/// Reads a TOML topics file.
pub(crate) fn read_toml(path: &Path) -> Result<Vec<Definition>, CodegenError> {
    let text = std::fs::read_to_string(path).map_err(|source| CodegenError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse_toml(path, &text)
}

pub(crate) fn parse_toml(path: &Path, text: &str) -> Result<Vec<Definition>, CodegenError> {
    let file: TopicsFile = toml::from_str(text).map_err(|e| {
        let line = e.span().map_or(0, |s| line_of(text, s.start));
        CodegenError::Toml {
            path: path.to_owned(),
            line,
            message: e.message().to_owned(),
        }
    })?;
    let mut out = Vec::new();
    for topic in file.topic {
        let line = line_of(text, topic.name.span().start);
        let place = Place::Toml {
            path: path.to_owned(),
            line,
        };
        let mut spec = format!("{}:", topic.name.get_ref());
        let mut field_docs = HashMap::new();
        for field in &topic.fields {
            let at = |span: std::ops::Range<usize>| Place::Toml {
                path: path.to_owned(),
                line: line_of(text, span.start),
            };
            let ty = field.ty.get_ref();
            if ty.contains(['[', ']', ';', ' ']) {
                return Err(CodegenError::Topic {
                    place: at(field.ty.span()),
                    message: format!(
                        "field `{}`: type `{ty}` must be a bare type name; give the array \
                         length as `len`",
                        field.name.get_ref()
                    ),
                });
            }
            match &field.len {
                Some(len) if *len.get_ref() == 0 || *len.get_ref() > u32::from(u16::MAX) => {
                    return Err(CodegenError::Topic {
                        place: at(len.span()),
                        message: format!(
                            "field `{}`: `len` must be 1..=65535, not {}",
                            field.name.get_ref(),
                            len.get_ref()
                        ),
                    });
                }
                Some(len) => spec.push_str(&format!(
                    "{ty}[{}] {};",
                    len.get_ref(),
                    field.name.get_ref()
                )),
                None => spec.push_str(&format!("{ty} {};", field.name.get_ref())),
            }
            if let Some(doc) = &field.doc {
                field_docs.insert(field.name.get_ref().clone(), doc.clone());
            }
        }
        let format = Format::parse(&spec).map_err(|error| CodegenError::Topic {
            place: place.clone(),
            message: format!("`{spec}` is not a valid format: {error}"),
        })?;
        out.push(Definition {
            doc: topic.doc,
            field_docs,
            derives: topic.derives,
            exact: topic.exact,
            ..Definition::plain(format, place)
        });
    }
    Ok(out)
}

/// A format string.
pub(crate) fn read_format(n: usize, text: &str) -> Result<Definition, CodegenError> {
    let place = Place::FormatString(n);
    let format = Format::parse(text).map_err(|error| CodegenError::Topic {
        place: place.clone(),
        message: format!("`{text}` is not a valid format: {error}"),
    })?;
    Ok(Definition::plain(format, place))
}

/// The formats of a log: all of them, or the listed topics and the types they nest.
pub(crate) fn read_log(
    path: &Path,
    topics: Option<&[String]>,
) -> Result<Vec<Definition>, CodegenError> {
    let log = crate::Log::read(path).map_err(|error| CodegenError::Log {
        path: path.to_owned(),
        error: error.to_string(),
    })?;
    let schema = log.metadata().schema();
    let place = Place::Log(path.to_owned());
    // A damaged log (cut short, say) may lack formats its formats nest: if no other input
    // defines them either, the error says the log is damaged.
    let damage = log.diagnostics().first().map(|first| {
        format!(
            "the log is damaged ({} problem(s), the first {first})",
            log.diagnostics().len()
        )
    });
    let definition = |f: &Format| Definition {
        damage: damage.clone(),
        ..Definition::plain(f.clone(), place.clone())
    };
    // A log may hold formats outside the grammar (the reader keeps them, lax): no Rust
    // type can be named after them.
    let in_grammar = |f: &Format| -> Result<(), CodegenError> {
        match f.to_string().parse::<Format>() {
            Ok(_) => Ok(()),
            Err(e) => Err(CodegenError::Unsupported {
                format: f.name.clone(),
                place: place.clone(),
                message: format!(
                    "its definition `{f}` is outside the format grammar ({e}), so no Rust type can be named after it; pick other topics with `ulog_topics`"
                ),
            }),
        }
    };
    let Some(topics) = topics else {
        return schema
            .formats()
            .iter()
            .map(|f| in_grammar(f).map(|()| definition(f)))
            .collect();
    };
    let mut wanted: Vec<&Format> = Vec::new();
    let mut stack: Vec<String> = Vec::new();
    for topic in topics {
        if schema.get(topic).is_none() {
            return Err(CodegenError::TopicNotInLog {
                path: path.to_owned(),
                topic: topic.clone(),
                suggestions: schema.suggest(topic),
            });
        }
        stack.push(topic.clone());
    }
    while let Some(name) = stack.pop() {
        let Some(format) = schema.get(&name) else {
            continue; // reported as an unknown type once all inputs are merged
        };
        if wanted.iter().any(|w| w.name == name) {
            continue;
        }
        for field in &format.fields {
            if let TypeRef::Nested(n) = &field.ty {
                stack.push(n.clone());
            }
        }
        wanted.push(format);
    }
    // In the log's order, for stable output.
    schema
        .formats()
        .iter()
        .filter(|f| wanted.iter().any(|w| w.name == f.name))
        .map(|f| in_grammar(f).map(|()| definition(f)))
        .collect()
}

/// Definitions from laid-out `.msg` files: the files selected by `topics` (all of them when
/// `None`) and every file they nest, in the set's order.
pub(crate) fn msg_definitions(
    set: &crate::codegen::msg::MsgSet,
    selected: &[usize],
) -> Vec<Definition> {
    selected
        .iter()
        .map(|&i| {
            let file = &set.files()[i];
            let format = set.formats()[i].clone();
            let own = format.name.clone();
            let field_docs = file
                .fields
                .iter()
                .filter_map(|f| f.doc.clone().map(|d| (f.name.clone(), d)))
                .collect();
            let line = file.fields.first().map_or(1, |f| f.line);
            let valid_ident = file.type_name.starts_with(|c: char| c.is_ascii_uppercase())
                && file.type_name.chars().all(|c| c.is_ascii_alphanumeric());
            Definition {
                doc: file.doc.clone(),
                field_docs,
                topics: set.topics(i).into_iter().filter(|t| *t != own).collect(),
                constants: file.constants.clone(),
                rust_name: valid_ident.then(|| file.type_name.clone()),
                plain_docs: true,
                ..Definition::plain(
                    format,
                    Place::Msg {
                        path: file.path.clone(),
                        line,
                    },
                )
            }
        })
        .collect()
}
