//! The build-script generator: Rust types (structs with `#[derive(ULog)]`) from ULog topic
//! definitions. Feature `codegen`.
//!
//! Four kinds of input, mixed freely in one build:
//! - format strings as `F` messages carry them, such as
//!   `vehicle_attitude:uint64_t timestamp;float[4] q;uint8_t[4] _padding0;`
//!   ([`Builder::format`]);
//! - TOML topic files (schema below), with doc text and per-topic options
//!   ([`Builder::toml`]);
//! - the `F` definitions of an existing `.ulg` log, all of them or some topics and the types
//!   they nest ([`Builder::ulog`], [`Builder::ulog_topics`]);
//! - PX4's own `.msg` files, one or a folder (PX4-Autopilot's `msg/`), laid out exactly as
//!   PX4 logs them, with their constants and `# TOPICS` ([`Builder::msg`],
//!   [`Builder::msg_dir`], [`Builder::msg_dir_topics`]; see [`msg`]).
//!
//! Nested types resolve across all inputs. A type used but never defined, a cycle, or two
//! different definitions under one name is an error naming the places involved; with
//! [`Builder::merge`], definitions that differ (the logs of several PX4 versions) become
//! one type that reads them all. The output is one Rust file, formatted, starting with an
//! `@generated` line, rewritten only when its content changes; [`Builder::generate`] prints
//! `cargo:rerun-if-changed` for every input file (and `.msg` folder).
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
//! derives = ["Copy"]                 # optional: extra derives for this type (and the types it nests)
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
//! (`[u8; N]`). Every struct and field gets a doc comment: the TOML doc (or the `.msg`
//! comments), the ULog name and type, and the original format string. A `.msg` file's type
//! keeps the file's name (`VehicleStatus.msg` -> `VehicleStatus`), its constants become
//! associated constants (`VehicleStatus::ARMING_STATE_ARMED: u8`), and its `# TOPICS`
//! names become `#[ulog(topics(...))]`, read with [`Log::topic_as`](crate::Log::topic_as).
//! A single `char` field is [`Char`](crate::Char); a format whose `timestamp` is not an
//! unsigned integer is `#[ulog(nested)]` (never a topic).
//!
//! # One type for many inputs
//!
//! With [`Builder::merge`]`(`[`Merge::Lossless`]`)`, the definitions of one name that differ
//! across inputs (the logs of a fleet of PX4 versions, several `.msg` folders) become one
//! type that reads every one of them: fields present everywhere are plain, fields some lack
//! are `Option`, fields whose types differ get the narrowest type that holds every value of
//! each (`uint8_t` and `int32_t` -> `i32`, `float` and `double` -> `f64`) with
//! `#[ulog(widen)]`, and a field without one (`int64_t` and `uint64_t`, arrays of different
//! lengths) is left out, its doc comment naming the inputs and types; [`Merge::Strict`]
//! makes that an error instead. Padding is left out of merged types; doc comments say which
//! input has which type.
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use ulog_runtime::codegen::{Builder, Merge};
//! Builder::new()
//!     .ulog("logs/2019.ulg")
//!     .ulog("logs/2026.ulg")
//!     .merge(Merge::Lossless)
//!     .generate("fleet.rs")?;
//! # Ok(()) }
//! ```

mod emit;
mod input;
mod merge;
pub mod msg;

use std::path::{Path, PathBuf};

use input::Definition;
pub use input::Place;
pub use merge::Merge;

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
    /// A `.msg` line that does not follow the grammar.
    #[error("{}:{line}: {message}", path.display())]
    Msg {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A topic asked for that no `.msg` file of a folder defines.
    #[error("{}: no .msg file defines topic `{topic}`{}", dir.display(), crate::schema::did_you_mean(.suggestions))]
    TopicNotInMsg {
        /// The folder.
        dir: PathBuf,
        /// The topic.
        topic: String,
        /// The folder's topics closest to it (at most 3, closest first).
        suggestions: Vec<String>,
    },
    /// Merging strictly ([`Merge::Strict`]): a field whose types across the inputs have no
    /// lossless common type.
    #[error("`{format}`: field `{field}` has no type that holds every value of its types: {usage}")]
    Incompatible {
        /// The format.
        format: String,
        /// The field.
        field: String,
        /// Which inputs have which type.
        usage: String,
    },
    /// A log that cannot be read, or too damaged to define the types its formats nest.
    #[error("{}: {error}", path.display())]
    Log {
        /// The log.
        path: PathBuf,
        /// Why.
        error: String,
    },
    /// A topic asked for is not in the log.
    #[error("{}: no format `{topic}` in this log{}", path.display(), crate::schema::did_you_mean(.suggestions))]
    TopicNotInLog {
        /// The log.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// The log's formats closest to it (at most 3, closest first).
        suggestions: Vec<String>,
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
    /// Whether it has an unsigned integer `timestamp` (implements `Topic`).
    pub topic: bool,
    /// Every topic name it stands for, `format` first (PX4's `# TOPICS`).
    pub topics: Vec<String>,
}

#[derive(Debug, Clone)]
enum Input {
    Toml(PathBuf),
    Format(String),
    Log {
        path: PathBuf,
        topics: Option<Vec<String>>,
    },
    Msg(PathBuf),
    MsgDir {
        dir: PathBuf,
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
    merge: Merge,
    exact: bool,
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
            merge: Merge::Never,
            exact: false,
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

    /// Adds one PX4 `.msg` file; the messages it nests must come from another input.
    pub fn msg(&mut self, path: impl AsRef<Path>) -> &mut Builder {
        self.inputs.push(Input::Msg(path.as_ref().to_owned()));
        self
    }

    /// Adds every `.msg` file of a folder (PX4-Autopilot's or px4_msgs' `msg/`): one type
    /// per file, laid out as PX4 logs it (see [`msg`]).
    pub fn msg_dir(&mut self, dir: impl AsRef<Path>) -> &mut Builder {
        self.inputs.push(Input::MsgDir {
            dir: dir.as_ref().to_owned(),
            topics: None,
        });
        self
    }

    /// Adds the `.msg` files of a folder that define these topics (a `# TOPICS` name or a
    /// file's snake-case name), and the files they nest.
    pub fn msg_dir_topics(&mut self, dir: impl AsRef<Path>, topics: &[&str]) -> &mut Builder {
        self.inputs.push(Input::MsgDir {
            dir: dir.as_ref().to_owned(),
            topics: Some(topics.iter().map(|t| (*t).to_owned()).collect()),
        });
        self
    }

    /// What to do with a name that inputs define differently (default [`Merge::Never`]: an
    /// error). [`Merge::Lossless`] makes one type that reads every definition: e.g. the
    /// logs of a fleet of PX4 versions; [`Merge::Widest`] also the versions after them.
    pub fn merge(&mut self, merge: Merge) -> &mut Builder {
        self.merge = merge;
        self
    }

    /// Marks every type `#[ulog(exact)]`: reading requires the file's format to be
    /// identical (default `false`). Not with differing definitions merged.
    pub fn exact(&mut self, exact: bool) -> &mut Builder {
        self.exact = exact;
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
        let resolved = self.resolve()?;
        emit::render(self, &resolved, &self.input_names())
    }

    /// The types the generated file defines, in its order.
    pub fn types(&self) -> Result<Vec<GeneratedType>, CodegenError> {
        let resolved = self.resolve()?;
        let names = emit::names(&resolved.defs);
        Ok(resolved
            .defs
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
                    topic: emit::is_topic(&d.format),
                    topics: std::iter::once(name.clone())
                        .chain(d.topics.iter().cloned())
                        .collect(),
                }
            })
            .collect())
    }

    /// The files and folders [`Builder::generate`] asks cargo to watch
    /// (`cargo:rerun-if-changed`): every TOML file, log and `.msg` file, and every `.msg`
    /// folder as one path (cargo scans a folder for any change of the files in it, added
    /// and removed ones included).
    pub fn watched_files(&self) -> Vec<PathBuf> {
        self.inputs
            .iter()
            .filter_map(|input| match input {
                Input::Toml(path) | Input::Log { path, .. } | Input::Msg(path) => Some(path),
                Input::MsgDir { dir, .. } => Some(dir),
                Input::Format(_) => None,
            })
            .cloned()
            .collect()
    }

    /// Writes the generated file: a relative `file` goes into `OUT_DIR`. The file is rewritten
    /// only if its content changes; `cargo:rerun-if-changed` is printed for every input file.
    /// Returns the path written.
    pub fn generate(&self, file: impl AsRef<Path>) -> Result<PathBuf, CodegenError> {
        for path in self.watched_files() {
            println!("cargo:rerun-if-changed={}", path.display());
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
                Input::Toml(p) | Input::Msg(p) => p.display().to_string(),
                Input::Format(f) => format!("`{f}`"),
                Input::Log { path, .. } => path.display().to_string(),
                Input::MsgDir { dir, .. } => dir.display().to_string(),
            })
            .collect()
    }

    /// Every input read, in input order; `.msg` files laid out last, knowing the sizes of
    /// the other inputs' formats.
    fn read_inputs(&self) -> Result<Vec<Definition>, CodegenError> {
        let mut read: Vec<Vec<Definition>> = Vec::with_capacity(self.inputs.len());
        // The `.msg` files of every input, and per input its files (indices) and topics.
        let mut msg_files = Vec::new();
        let mut msg_inputs: Vec<MsgInput<'_>> = Vec::new();
        let mut format_count = 0;
        for (k, input) in self.inputs.iter().enumerate() {
            read.push(match input {
                Input::Toml(path) => input::read_toml(path)?,
                Input::Format(text) => {
                    format_count += 1;
                    vec![input::read_format(format_count, text)?]
                }
                Input::Log { path, topics } => input::read_log(path, topics.as_deref())?,
                Input::Msg(path) => {
                    msg_inputs.push((k, vec![msg_files.len()], None));
                    msg_files.push(msg::read_file(path)?);
                    Vec::new()
                }
                Input::MsgDir { dir, topics } => {
                    let mut own = Vec::new();
                    for path in msg::files_in(dir)? {
                        own.push(msg_files.len());
                        msg_files.push(msg::read_file(&path)?);
                    }
                    msg_inputs.push((k, own, topics.as_deref().map(|t| (dir.as_path(), t))));
                    Vec::new()
                }
            });
        }
        if !msg_files.is_empty() {
            // Each input's files: all, or those that define its topics and what they nest.
            let mut chosen = vec![false; msg_files.len()];
            let mut per_input = Vec::with_capacity(msg_inputs.len());
            for (k, files, topics) in msg_inputs {
                let selected = match topics {
                    None => files,
                    Some((dir, topics)) => select_msg(&msg_files, &files, dir, topics)?,
                };
                for &i in &selected {
                    chosen[i] = true;
                }
                per_input.push((k, selected));
            }
            let mut others = Schema::new();
            for def in read.iter().flatten() {
                let _ = others.insert(def.format.clone());
            }
            others.resolve_all();
            let size = |name: &str| {
                others
                    .id(name)
                    .and_then(|id| others.resolved(id))
                    .map(|l| l.size)
            };
            // Only the chosen files are laid out: an unused file may nest what no input has.
            let index: Vec<usize> = (0..msg_files.len()).filter(|&i| chosen[i]).collect();
            let files = msg_files
                .into_iter()
                .enumerate()
                .filter(|(i, _)| chosen[*i])
                .map(|(_, f)| f)
                .collect();
            let set = msg::MsgSet::new(files, &size)?;
            for (k, selected) in per_input {
                let in_set: Vec<usize> = selected
                    .iter()
                    .map(|i| index.binary_search(i).expect("chosen"))
                    .collect();
                read[k] = input::msg_definitions(&set, &in_set);
            }
        }
        Ok(read.into_iter().flatten().collect())
    }

    /// Every input read, merged by name, layouts resolved.
    fn resolve(&self) -> Result<Resolved, CodegenError> {
        // Group by name, in order of first appearance.
        let mut groups: Vec<Vec<Definition>> = Vec::new();
        for def in self.read_inputs()? {
            match groups
                .iter_mut()
                .find(|g| g[0].format.name == def.format.name)
            {
                Some(group) => group.push(def),
                None => groups.push(vec![def]),
            }
        }
        let mut defs = Vec::with_capacity(groups.len());
        for group in groups {
            let differing = group.iter().any(|d| d.format != group[0].format);
            if self.merge == Merge::Widest {
                if self.exact {
                    return Err(CodegenError::InvalidOption {
                        what: "exact",
                        value: "true".to_owned(),
                        message: "widened types (`Merge::Widest`) cannot be exact".to_owned(),
                    });
                }
                // Every type widened, whether its inputs agree or not.
                defs.push(merge::merge(group, self.merge)?);
                continue;
            }
            if !differing {
                // The same definition again: keep the first, with any docs the others add.
                let mut rest = group.into_iter();
                let mut first = rest.next().expect("a group has a definition");
                for def in rest {
                    if first.doc.is_none() {
                        first.doc = def.doc;
                    }
                    for (k, v) in def.field_docs {
                        first.field_docs.entry(k).or_insert(v);
                    }
                    first.derives.extend(def.derives);
                    first.exact |= def.exact;
                    for t in def.topics {
                        if !first.topics.contains(&t) {
                            first.topics.push(t);
                        }
                    }
                    if first.constants.is_empty() {
                        first.constants = def.constants;
                    }
                }
                first.exact |= self.exact;
                defs.push(first);
                continue;
            }
            if self.merge == Merge::Never {
                let second = group
                    .iter()
                    .find(|d| d.format != group[0].format)
                    .expect("differing");
                return Err(CodegenError::Redefinition {
                    name: second.format.name.clone(),
                    first: group[0].format.to_string(),
                    first_place: Box::new(group[0].place.clone()),
                    second: second.format.to_string(),
                    second_place: Box::new(second.place.clone()),
                });
            }
            if self.exact {
                return Err(CodegenError::InvalidOption {
                    what: "exact",
                    value: "true".to_owned(),
                    message: format!(
                        "`{}` is defined differently by several inputs, and a merged type \
                         cannot be exact",
                        group[0].format.name
                    ),
                });
            }
            defs.push(merge::merge(group, self.merge)?);
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
        let damage_of = |name: &str| {
            defs.iter()
                .find(|d| d.format.name == name)
                .and_then(|d| d.damage.clone())
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
                } => match (place_of(&format), damage_of(&format)) {
                    // From a damaged log: the damage may have taken the type.
                    (Place::Log(path), Some(damage)) => CodegenError::Log {
                        path,
                        error: format!(
                            "format `{format}` nests `{type_name}` (field `{field}`), which \
                             no input defines: {damage}"
                        ),
                    },
                    (place, _) => CodegenError::UnknownType {
                        place,
                        format,
                        field,
                        type_name,
                    },
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
        Ok(Resolved { defs, schema })
    }
}

/// The definitions to generate, and their formats with layouts resolved.
pub(crate) struct Resolved {
    pub(crate) defs: Vec<Definition>,
    pub(crate) schema: Schema,
}

/// A `.msg` input while reading: its index among the inputs, its files (indices among all
/// `.msg` files read), and the folder and topics it is filtered to.
type MsgInput<'a> = (usize, Vec<usize>, Option<(&'a Path, &'a [String])>);

/// The files of `files` (indices into `all`) that define one of `topics` (a `# TOPICS`
/// name or the snake-case name), and the files they nest, in file order.
fn select_msg(
    all: &[msg::MsgFile],
    files: &[usize],
    dir: &Path,
    topics: &[String],
) -> Result<Vec<usize>, CodegenError> {
    let defines = |i: usize, topic: &str| {
        let f = &all[i];
        f.topics.iter().any(|t| t == topic) || msg::snake_case(&f.type_name) == topic
    };
    let mut wanted = Vec::new();
    for topic in topics {
        let i = files
            .iter()
            .copied()
            .find(|&i| defines(i, topic))
            .ok_or_else(|| {
                let names: Vec<String> = files
                    .iter()
                    .flat_map(|&i| {
                        let f = &all[i];
                        std::iter::once(msg::snake_case(&f.type_name)).chain(f.topics.clone())
                    })
                    .collect();
                CodegenError::TopicNotInMsg {
                    dir: dir.to_owned(),
                    topic: topic.clone(),
                    suggestions: crate::schema::closest_names(
                        topic,
                        names.iter().map(String::as_str),
                    ),
                }
            })?;
        wanted.push(i);
    }
    let mut selected = vec![false; all.len()];
    while let Some(i) = wanted.pop() {
        if std::mem::replace(&mut selected[i], true) {
            continue;
        }
        for field in &all[i].fields {
            if let msg::MsgType::Nested(name) = &field.ty
                && let Some(dep) = all.iter().position(|f| f.type_name == *name)
            {
                wanted.push(dep);
            }
        }
    }
    Ok((0..all.len()).filter(|&i| selected[i]).collect())
}

/// The common case in one call: types for every topic of a TOML file, written to `file` in
/// `OUT_DIR` (see [`Builder::generate`]).
pub fn generate(toml: impl AsRef<Path>, file: impl AsRef<Path>) -> Result<PathBuf, CodegenError> {
    Builder::new().toml(toml).generate(file)
}

#[cfg(test)]
mod tests;
