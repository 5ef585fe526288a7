//! The build-script generator: Rust types (structs with `#[derive(ULog)]`) from ULog topic
//! definitions. Feature `codegen`.
//!
//! Three kinds of input, mixed freely in one build:
//! - format strings as `F` messages carry them:
//!   `vehicle_attitude:uint64_t timestamp;float[4] q;uint8_t[4] _padding0;`;
//! - TOML topic files (schema below), with doc text and per-topic options;
//! - the `F` definitions of an existing `.ulg` log, all of them or some topics (and the
//!   types they nest).
//!
//! Nested types resolve across all inputs. A type used but never defined, a cycle, or two
//! different definitions under one name is an error naming the places involved. The output
//! is one Rust file, formatted, starting with an `@generated` line, rewritten only when its
//! content changes; [`Builder::generate`] prints `cargo:rerun-if-changed` for every input file.
//!
//! ```no_run
//! // build.rs
//! fn main() -> Result<(), Box<dyn std::error::Error>> {
//!     ulog_runtime::codegen::Builder::new()
//!         .toml("topics.toml")
//!         .format("vehicle_attitude:uint64_t timestamp;float[4] q;")
//!         .ulog_topics("logs/flight.ulg", &["esc_status"])
//!         .derive("serde::Serialize")
//!         .generate("topics.rs")?; // into OUT_DIR
//!     Ok(())
//! }
//! // src/lib.rs: include!(concat!(env!("OUT_DIR"), "/topics.rs"));
//! ```
//! For the common case, [`generate`] does the same from one TOML file.
//!
//! # TOML topics files
//!
//! ```toml
//! # One [[topic]] table per format; nested types are topics too (without `timestamp`).
//! [[topic]]
//! name = "esc_status"                # the format name
//! doc = "Status of the ESCs."        # optional: doc comment of the struct
//! derives = ["PartialEq"]            # optional: extra derives for this type
//! exact = false                      # optional: #[ulog(exact)]
//! fields = [
//!   { name = "timestamp", type = "uint64_t", doc = "Microseconds since boot." },
//!   { name = "esc_count", type = "uint8_t" },
//!   { name = "_padding0", type = "uint8_t", len = 7 },   # padding stays padding
//!   { name = "esc", type = "esc_report", len = 8 },      # defined below, or in another input
//! ]
//!
//! [[topic]]
//! name = "esc_report"
//! fields = [
//!   { name = "esc_rpm", type = "int32_t" },
//!   { name = "esc_voltage", type = "float" },
//! ]
//! ```
//! Field keys: `name`, `type` (one of the 12 basic types of the format, or another topic's
//! name), `len` (array length, 1..=65535), `doc`. Unknown keys, a missing key or a value of
//! the wrong kind are errors with the file and line.
//!
//! # Rust names
//!
//! Topic `vehicle_attitude` becomes `VehicleAttitude`. Field names that are Rust keywords
//! (`type`) or not snake case (`airspeedSp`, `R_body`) become `type_`, `airspeed_sp`, `r_body`
//! and keep their ULog name through `#[ulog(rename = "...")]`; padding fields stay padding
//! (`[u8; N]`). Every struct and field gets a doc comment: the TOML doc, the ULog name and
//! type, and the original format string.

mod emit;
mod input;

use std::path::{Path, PathBuf};

use input::Definition;
pub use input::Place;

use crate::schema::{LayoutError, Schema};

crate::error::debug_as_display!(CodegenError);

/// Why generation failed.
#[derive(thiserror::Error)]
#[non_exhaustive]
pub enum CodegenError {
    /// An input or output file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A TOML file that is not a valid topics file.
    #[error("{}:{line}: {message}", path.display())]
    Toml {
        /// The file.
        path: PathBuf,
        /// 1-based line (0 if unknown).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A topic definition that is not valid.
    #[error("{place}: {message}")]
    Topic {
        /// Where.
        place: Place,
        /// What is wrong.
        message: String,
    },
    /// A log that cannot be read.
    #[error("{}: {error}", path.display())]
    Log {
        /// The log.
        path: PathBuf,
        /// Why.
        error: String,
    },
    /// A topic asked for is not in the log.
    #[error("{}: no format `{topic}` in this log", path.display())]
    TopicNotInLog {
        /// The log.
        path: PathBuf,
        /// The topic.
        topic: String,
    },
    /// Two different definitions under one name.
    #[error(
        "`{name}` is defined twice, differently: `{first}` ({first_place}) and `{second}` ({second_place})"
    )]
    Redefinition {
        /// The name.
        name: String,
        /// The first definition.
        first: String,
        /// Where.
        first_place: Box<Place>,
        /// The second definition.
        second: String,
        /// Where.
        second_place: Box<Place>,
    },
    /// A nested type no input defines.
    #[error("`{format}` ({place}): field `{field}` has type `{type_name}`, which no input defines")]
    UnknownType {
        /// The format using it.
        format: String,
        /// Where that format comes from.
        place: Place,
        /// The field.
        field: String,
        /// The undefined type.
        type_name: String,
    },
    /// Formats that nest each other.
    #[error("nested types form a cycle: {}", cycle.iter().map(|(n, p)| format!("`{n}` ({p})")).collect::<Vec<_>>().join(" -> "))]
    Cycle {
        /// The formats of the cycle and where each comes from.
        cycle: Vec<(String, Place)>,
    },
    /// A format this generator cannot express as a Rust type.
    #[error("`{format}` ({place}): {message}")]
    Unsupported {
        /// The format.
        format: String,
        /// Where it comes from.
        place: Place,
        /// Why.
        message: String,
    },
    /// A builder option that is not valid Rust.
    #[error("invalid {what} `{value}`: {message}")]
    InvalidOption {
        /// Which option.
        what: &'static str,
        /// Its value.
        value: String,
        /// Why.
        message: String,
    },
    /// No place to write to.
    #[error("OUT_DIR is not set: call `generate` from a build script, or give it an absolute path")]
    NoOutDir,
}

/// A type the generator defines ([`Builder::types`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GeneratedType {
    /// The ULog format name.
    pub format: String,
    /// The Rust path within the generated file: `EscStatus`, or `esc_status::EscStatus`
    /// with a module per topic.
    pub path: String,
    /// Whether it has a `timestamp` (implements `Topic`).
    pub topic: bool,
}

#[derive(Debug, Clone)]
enum Input {
    Toml(PathBuf),
    Format(String),
    Log {
        path: PathBuf,
        topics: Option<Vec<String>>,
    },
}

/// Generates Rust types from topic definitions; see the [module docs](self).
#[derive(Debug, Clone)]
pub struct Builder {
    inputs: Vec<Input>,
    derives: Vec<String>,
    visibility: String,
    module_per_topic: bool,
    runtime_crate: String,
}

impl Default for Builder {
    fn default() -> Builder {
        Builder::new()
    }
}

impl Builder {
    /// No inputs yet; `pub` types deriving `Debug`, `Clone` and `PartialEq`, in one flat file,
    /// using the runtime as `::ulog_runtime`.
    pub fn new() -> Builder {
        Builder {
            inputs: Vec::new(),
            derives: Vec::new(),
            visibility: "pub".to_owned(),
            module_per_topic: false,
            runtime_crate: "::ulog_runtime".to_owned(),
        }
    }

    /// Adds a TOML topics file.
    pub fn toml(&mut self, path: impl AsRef<Path>) -> &mut Builder {
        self.inputs.push(Input::Toml(path.as_ref().to_owned()));
        self
    }

    /// Adds a format string, as in an `F` message.
    pub fn format(&mut self, text: &str) -> &mut Builder {
        self.inputs.push(Input::Format(text.to_owned()));
        self
    }

    /// Adds every format defined in a log.
    pub fn ulog(&mut self, path: impl AsRef<Path>) -> &mut Builder {
        self.inputs.push(Input::Log {
            path: path.as_ref().to_owned(),
            topics: None,
        });
        self
    }

    /// Adds some topics of a log, and the types they nest.
    pub fn ulog_topics(&mut self, path: impl AsRef<Path>, topics: &[&str]) -> &mut Builder {
        self.inputs.push(Input::Log {
            path: path.as_ref().to_owned(),
            topics: Some(topics.iter().map(|t| (*t).to_owned()).collect()),
        });
        self
    }

    /// Adds a derive to every type, e.g. `serde::Serialize` or `Copy`.
    pub fn derive(&mut self, path: &str) -> &mut Builder {
        self.derives.push(path.to_owned());
        self
    }

    /// The visibility of the types and their fields (default `pub`), e.g. `pub(crate)`.
    pub fn visibility(&mut self, visibility: &str) -> &mut Builder {
        visibility.clone_into(&mut self.visibility);
        self
    }

    /// Puts each type in a module named after its format (default: one flat file).
    pub fn module_per_topic(&mut self, yes: bool) -> &mut Builder {
        self.module_per_topic = yes;
        self
    }

    /// The path of the runtime crate in generated code (default `::ulog_runtime`), for a
    /// renamed dependency.
    pub fn runtime_crate(&mut self, path: &str) -> &mut Builder {
        path.clone_into(&mut self.runtime_crate);
        self
    }

    /// The generated file's content.
    pub fn render(&self) -> Result<String, CodegenError> {
        let definitions = self.resolve()?;
        emit::render(self, &definitions, &self.input_names())
    }

    /// The types the generated file defines, in its order.
    pub fn types(&self) -> Result<Vec<GeneratedType>, CodegenError> {
        let definitions = self.resolve()?;
        let names = emit::names(&definitions);
        Ok(definitions
            .iter()
            .map(|d| {
                let name = &d.format.name;
                let ty = &names.types[name];
                GeneratedType {
                    format: name.clone(),
                    path: if self.module_per_topic {
                        format!("{}::{ty}", names.modules[name])
                    } else {
                        ty.clone()
                    },
                    topic: d.format.fields.iter().any(|f| {
                        f.name == "timestamp"
                            && f.array_len.is_none()
                            && matches!(f.ty, crate::schema::TypeRef::Primitive(p) if p.is_unsigned_integer())
                    }),
                }
            })
            .collect())
    }

    /// Writes the generated file: a relative `file` goes into `OUT_DIR`. The file is rewritten
    /// only if its content changes; `cargo:rerun-if-changed` is printed for every input file.
    /// Returns the path written.
    pub fn generate(&self, file: impl AsRef<Path>) -> Result<PathBuf, CodegenError> {
        for input in &self.inputs {
            match input {
                Input::Toml(path) | Input::Log { path, .. } => {
                    println!("cargo:rerun-if-changed={}", path.display());
                }
                Input::Format(_) => {}
            }
        }
        let content = self.render()?;
        let file = file.as_ref();
        let path = if file.is_absolute() {
            file.to_owned()
        } else {
            PathBuf::from(std::env::var_os("OUT_DIR").ok_or(CodegenError::NoOutDir)?).join(file)
        };
        let io = |source| CodegenError::Io {
            path: path.clone(),
            source,
        };
        if std::fs::read_to_string(&path).ok().as_deref() != Some(content.as_str()) {
            if let Some(dir) = path.parent() {
                std::fs::create_dir_all(dir).map_err(io)?;
            }
            std::fs::write(&path, content).map_err(io)?;
        }
        Ok(path)
    }

    fn input_names(&self) -> Vec<String> {
        self.inputs
            .iter()
            .map(|i| match i {
                Input::Toml(p) => p.display().to_string(),
                Input::Format(f) => format!("`{f}`"),
                Input::Log { path, .. } => path.display().to_string(),
            })
            .collect()
    }

    /// Every input read, merged by name, layouts resolved.
    fn resolve(&self) -> Result<Vec<Definition>, CodegenError> {
        let mut defs: Vec<Definition> = Vec::new();
        let mut format_count = 0;
        for input in &self.inputs {
            let read = match input {
                Input::Toml(path) => input::read_toml(path)?,
                Input::Format(text) => {
                    format_count += 1;
                    vec![input::read_format(format_count, text)?]
                }
                Input::Log { path, topics } => input::read_log(path, topics.as_deref())?,
            };
            for def in read {
                match defs.iter_mut().find(|d| d.format.name == def.format.name) {
                    Some(first) if first.format != def.format => {
                        return Err(CodegenError::Redefinition {
                            name: def.format.name.clone(),
                            first: first.format.to_string(),
                            first_place: Box::new(first.place.clone()),
                            second: def.format.to_string(),
                            second_place: Box::new(def.place),
                        });
                    }
                    // The same definition again: keep the first, with any docs the second adds.
                    Some(first) => {
                        if first.doc.is_none() {
                            first.doc = def.doc;
                        }
                        for (k, v) in def.field_docs {
                            first.field_docs.entry(k).or_insert(v);
                        }
                        first.derives.extend(def.derives);
                        first.exact |= def.exact;
                    }
                    None => defs.push(def),
                }
            }
        }
        let mut schema = Schema::new();
        for def in &defs {
            schema
                .insert(def.format.clone())
                .expect("names are unique after merging");
        }
        let place_of = |name: &str| {
            defs.iter()
                .find(|d| d.format.name == name)
                .map(|d| d.place.clone())
                .expect("a known format")
        };
        // The first error of a format itself; a nested type's own error is reported under
        // its own name, so `InvalidNested` adds nothing.
        let first = schema
            .resolve_all()
            .into_iter()
            .find(|(_, e)| !matches!(e, LayoutError::InvalidNested { .. }));
        if let Some((name, error)) = first {
            return Err(match error {
                LayoutError::UnknownType {
                    format,
                    field,
                    type_name,
                } => CodegenError::UnknownType {
                    place: place_of(&format),
                    format,
                    field,
                    type_name,
                },
                LayoutError::Cycle(names) => CodegenError::Cycle {
                    cycle: names.iter().map(|n| (n.clone(), place_of(n))).collect(),
                },
                other => CodegenError::Unsupported {
                    place: place_of(&name),
                    format: name,
                    message: other.to_string(),
                },
            });
        }
        Ok(defs)
    }
}

/// The common case in one call: types for every topic of a TOML file, written to `file` in
/// `OUT_DIR` (see [`Builder::generate`]).
pub fn generate(toml: impl AsRef<Path>, file: impl AsRef<Path>) -> Result<PathBuf, CodegenError> {
    Builder::new().toml(toml).generate(file)
}

#[cfg(test)]
mod tests;
