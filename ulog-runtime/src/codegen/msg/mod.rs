//! PX4's own topic definitions, `.msg` files, as the generator's fourth input: parsed
//! ([`parse`]), laid out as PX4's generator lays them out so that each topic's format is the
//! string PX4's logger writes ([`MsgSet`]), and compared with a log's formats
//! ([`MsgSet::check`], what `ulog check-msg` prints).
//!
//! The layout (checked against logs of three PX4 versions): fields sorted by the size of
//! their basic type, largest first, file order kept among equal sizes, nested messages last;
//! `uint8_t[k] _paddingN` inserted before each nested field and at the end wherever the size
//! so far is not a multiple of 8 (N counts from 0 in each message); a nested message's size
//! includes its own end padding. Nested types are named in snake case (`EscReport` ->
//! `esc_report`); each name of a `# TOPICS` line is a topic with the message's layout, and a
//! file without one defines the topic of its snake-case name.

mod layout;
mod parse;

use std::path::{Path, PathBuf};

pub use layout::snake_case;
pub use parse::{ConstValue, Constant, MsgField, MsgFile, MsgType, builtin};

use super::CodegenError;
use super::input::Place;
use crate::schema::{Difference, Format, Primitive, Schema, diff};
use layout::LayoutProblem;

/// The `.msg` name of a built-in type (`uint8`, `float32`).
pub fn msg_type_name(p: Primitive) -> &'static str {
    match p {
        Primitive::Bool => "bool",
        Primitive::Char => "char",
        Primitive::Int8 => "int8",
        Primitive::UInt8 => "uint8",
        Primitive::Int16 => "int16",
        Primitive::UInt16 => "uint16",
        Primitive::Int32 => "int32",
        Primitive::UInt32 => "uint32",
        Primitive::Int64 => "int64",
        Primitive::UInt64 => "uint64",
        Primitive::Float => "float32",
        Primitive::Double => "float64",
    }
}

/// Parses one `.msg` file (errors name the file and line).
pub fn read_file(path: &Path) -> Result<MsgFile, CodegenError> {
    let text = std::fs::read_to_string(path).map_err(|source| CodegenError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse(path, &text)
}

/// Parses the text of a `.msg` file; `path` names it (its stem is the message type name).
pub fn parse(path: &Path, text: &str) -> Result<MsgFile, CodegenError> {
    parse::parse(path, text).map_err(|e| CodegenError::Msg {
        path: path.to_owned(),
        line: e.line,
        message: e.message,
    })
}

/// Every `*.msg` file of a folder (not its subfolders), sorted by name.
pub fn files_in(dir: &Path) -> Result<Vec<PathBuf>, CodegenError> {
    let io = |source| CodegenError::Io {
        path: dir.to_owned(),
        source,
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let path = entry.map_err(io)?.path();
        if path.extension().is_some_and(|e| e == "msg") && path.is_file() {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

/// A set of `.msg` files laid out as PX4 lays them out.
///
/// ```no_run
/// use ulog_runtime::codegen::msg::MsgSet;
/// let set = MsgSet::read_dir("PX4-Autopilot/msg".as_ref())?;
/// let attitude = set.format("estimator_attitude").unwrap();
/// println!("{attitude}"); // estimator_attitude:uint64_t timestamp;uint64_t timestamp_sample;...
/// # Ok::<(), ulog_runtime::codegen::CodegenError>(())
/// ```
#[derive(Debug, Clone)]
pub struct MsgSet {
    files: Vec<MsgFile>,
    formats: Vec<Format>,
}

impl MsgSet {
    /// Reads and lays out every `.msg` file of a folder; nested types must be in it.
    pub fn read_dir(dir: &Path) -> Result<MsgSet, CodegenError> {
        let files = files_in(dir)?
            .iter()
            .map(|p| read_file(p))
            .collect::<Result<Vec<_>, _>>()?;
        MsgSet::new(files, &|_| None)
    }

    /// Lays out parsed files; `external` gives the size of a nested format no file defines
    /// (by its snake-case name), from the build's other inputs.
    pub(crate) fn new(
        files: Vec<MsgFile>,
        external: &dyn Fn(&str) -> Option<usize>,
    ) -> Result<MsgSet, CodegenError> {
        let formats = layout::layout_all(&files, external).map_err(|problem| match problem {
            LayoutProblem::Unknown { file, field } => {
                let (f, fd) = (&files[file], &files[file].fields[field]);
                CodegenError::UnknownType {
                    format: snake_case(&f.type_name),
                    place: Place::Msg {
                        path: f.path.clone(),
                        line: fd.line,
                    },
                    field: fd.name.clone(),
                    type_name: match &fd.ty {
                        MsgType::Nested(n) => n.clone(),
                        MsgType::Primitive(p) => msg_type_name(*p).to_owned(),
                    },
                }
            }
            LayoutProblem::Cycle(members) => CodegenError::Cycle {
                cycle: members
                    .into_iter()
                    .map(|(file, field)| {
                        let f = &files[file];
                        (
                            snake_case(&f.type_name),
                            Place::Msg {
                                path: f.path.clone(),
                                line: f.fields[field].line,
                            },
                        )
                    })
                    .collect(),
            },
        })?;
        Ok(MsgSet { files, formats })
    }

    /// The files, in the order read.
    pub fn files(&self) -> &[MsgFile] {
        &self.files
    }

    /// Each file's format (named in snake case), in the order of [`MsgSet::files`].
    pub fn formats(&self) -> &[Format] {
        &self.formats
    }

    /// The topic names of the `i`-th file: its `# TOPICS` names, or its snake-case name.
    pub fn topics(&self, i: usize) -> Vec<String> {
        let file = &self.files[i];
        if file.topics.is_empty() {
            vec![snake_case(&file.type_name)]
        } else {
            file.topics.clone()
        }
    }

    /// The file that defines a format of this name: as one of its topics, or as its
    /// snake-case (nested) name.
    pub fn defining(&self, name: &str) -> Option<usize> {
        (0..self.files.len())
            .find(|&i| self.topics(i).iter().any(|t| t == name))
            .or_else(|| self.formats.iter().position(|f| f.name == name))
    }

    /// The format PX4 logs under `name` (a topic, or a nested type's name).
    pub fn format(&self, name: &str) -> Option<Format> {
        self.defining(name).map(|i| Format {
            name: name.to_owned(),
            fields: self.formats[i].fields.clone(),
        })
    }

    /// Compares every format of a log's schema (topics and nested types) with the format
    /// these files make under its name.
    pub fn check(&self, log: &Schema) -> MsgCheck {
        let formats = log
            .formats()
            .iter()
            .map(|f| {
                let result = match self.defining(&f.name) {
                    None => FormatCheck::NotDefined,
                    Some(i) => {
                        let ours = self.format(&f.name).expect("defined");
                        if ours == *f {
                            FormatCheck::Identical { file: i }
                        } else {
                            FormatCheck::Differs {
                                file: i,
                                expected: ours.to_string(),
                                differences: diff(f, &ours),
                            }
                        }
                    }
                };
                (f.name.clone(), result)
            })
            .collect();
        MsgCheck { formats }
    }
}

/// What [`MsgSet::check`] found, per format of the log, in the log's order.
#[derive(Debug, Clone)]
pub struct MsgCheck {
    /// Each format's name and result.
    pub formats: Vec<(String, FormatCheck)>,
}

/// How one format of a log compares with the `.msg` files.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FormatCheck {
    /// The files make exactly the log's `F` string (file index in the set).
    Identical {
        /// The defining file.
        file: usize,
    },
    /// The files make another format under this name.
    Differs {
        /// The defining file.
        file: usize,
        /// The format the files make, printed.
        expected: String,
        /// How the log's format (first) differs from it (second).
        differences: Vec<Difference>,
    },
    /// No file defines this name.
    NotDefined,
}

impl MsgCheck {
    /// Formats the files make exactly.
    pub fn identical(&self) -> usize {
        self.formats
            .iter()
            .filter(|(_, r)| matches!(r, FormatCheck::Identical { .. }))
            .count()
    }

    /// Formats of the log the files define.
    pub fn defined(&self) -> usize {
        self.formats
            .iter()
            .filter(|(_, r)| !matches!(r, FormatCheck::NotDefined))
            .count()
    }

    /// Whether every format the files define is identical, and there is at least one.
    pub fn all_identical(&self) -> bool {
        self.defined() > 0 && self.identical() == self.defined()
    }
}
