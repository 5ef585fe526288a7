//! Whole logs to Parquet in one streaming pass each: rows go to a [`Table`] per topic
//! instance as they come, row groups are written when the buffers of all tables together
//! pass the budget (the largest first), and the log's identity and `metadata.json` are
//! written when the pass has hashed the whole file.

use std::collections::HashMap;
use std::fs::File;
use std::io::{self, Read};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use parquet::errors::ParquetError;
use serde::Serialize;
use sha2::Digest;

use super::{AdmitRow, GpsClock, LogIdentity, ParquetOptions, Table, TableWritten};
use crate::columns::ColumnSpec;
use crate::document::{Collected, KEPT_DIAGNOSTICS, LogFacts};
use crate::file_names::FileNames;
use crate::read::{Dropout, LoggedMessage, ParameterChange, Row, Skipped, TopicSummary};
use crate::{Diagnostic, Event, ReadError, StreamReader};

crate::error::debug_as_display!(ConvertError);

/// Why a log could not be converted.
#[derive(thiserror::Error)]
#[non_exhaustive]
pub enum ConvertError {
    /// The log could not be read (not a ULog file, or reading failed).
    #[error("{log}: {source}")]
    Read {
        /// The log.
        log: String,
        /// Why.
        source: ReadError,
    },
    /// A file or folder of the output could not be made or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The path.
        path: PathBuf,
        /// Why.
        source: io::Error,
    },
    /// Parquet refused a table.
    #[error("{}: topic `{topic}` #{multi_id}: {source}", path.display())]
    Parquet {
        /// The file being written.
        path: PathBuf,
        /// Its topic.
        topic: String,
        /// Its instance.
        multi_id: u8,
        /// Why.
        source: ParquetError,
    },
}

/// Converts whole logs to Parquet files in a folder ([module docs](super)).
///
/// ```no_run
/// use ulog_runtime::columns::parquet::{Converter, ParquetOptions};
/// let conversion = Converter::new("out", ParquetOptions::default()).convert_file("flight.ulg".as_ref())?;
/// for file in &conversion.files {
///     println!("{} {} rows", file.path.display(), file.rows);
/// }
/// # Ok::<(), ulog_runtime::columns::parquet::ConvertError>(())
/// ```
#[derive(Clone)]
pub struct Converter {
    pub(super) root: PathBuf,
    pub(super) options: ParquetOptions,
    pub(super) progress: Option<Arc<dyn Fn(u64) + Send + Sync>>,
}

impl std::fmt::Debug for Converter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Converter")
            .field("root", &self.root)
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

/// What a conversion wrote.
#[derive(Debug, Clone)]
pub struct Conversion {
    /// The log's file name.
    pub log: String,
    /// The name of its output folder: its stem (`log=<stem>` in hive layout), made safe and
    /// unique among the logs of one call.
    pub log_dir: String,
    /// Bytes of the log read.
    pub bytes: u64,
    /// Each Parquet file, in the order the topic instances first had rows.
    pub files: Vec<WrittenFile>,
    /// The `metadata.json`.
    pub metadata: PathBuf,
    /// What reading left out.
    pub skipped: Skipped,
    /// Things a user should hear about: names that had to change to stay unique.
    pub notes: Vec<String>,
}

/// One Parquet file of a conversion.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct WrittenFile {
    /// Where.
    pub path: PathBuf,
    /// The topic.
    pub topic: String,
    /// The instance.
    pub multi_id: u8,
    /// Rows written.
    pub rows: usize,
    /// Row groups written.
    pub row_groups: usize,
}

/// Bytes of input between progress calls.
const PROGRESS_STEP: u64 = 8 << 20;

impl Converter {
    /// A converter writing into `root` (made if missing).
    pub fn new(root: impl Into<PathBuf>, options: ParquetOptions) -> Converter {
        Converter {
            root: root.into(),
            options,
            progress: None,
        }
    }

    /// Calls `f` with the bytes read since its last call, every few megabytes of input, from
    /// every log being converted (so the sum over calls is the input read so far).
    pub fn on_progress(mut self, f: impl Fn(u64) + Send + Sync + 'static) -> Converter {
        self.progress = Some(Arc::new(f));
        self
    }

    /// The options.
    pub fn options(&self) -> &ParquetOptions {
        &self.options
    }

    /// Converts the log at `path`; its outputs are named by its stem
    /// ([`log_stem`](crate::file_names::log_stem)).
    pub fn convert_file(&self, path: &Path) -> Result<Conversion, ConvertError> {
        let stem = crate::file_names::log_stem(path);
        self.convert_as(
            path,
            &self.options.layout.log_dir(&mut FileNames::new(), &stem),
        )
    }

    /// [`Converter::convert_file`] into the log folder `log_dir`.
    pub(super) fn convert_as(
        &self,
        path: &Path,
        log_dir: &str,
    ) -> Result<Conversion, ConvertError> {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.display().to_string());
        let file = File::open(path).map_err(|e| ConvertError::Read {
            log: path.display().to_string(),
            source: ReadError::Io(e),
        })?;
        self.convert_reader_as(file, &name, &path.display().to_string(), log_dir)
    }

    /// Converts a log read from `input`, named `file_name` (its outputs by its stem).
    pub fn convert_reader(
        &self,
        input: impl Read,
        file_name: &str,
    ) -> Result<Conversion, ConvertError> {
        let stem = crate::file_names::log_stem(file_name.as_ref());
        let log_dir = self.options.layout.log_dir(&mut FileNames::new(), &stem);
        self.convert_reader_as(input, file_name, file_name, &log_dir)
    }

    /// Converts a log named `file_name` (`label` in errors) into the log folder `log_dir`.
    fn convert_reader_as(
        &self,
        input: impl Read,
        file_name: &str,
        label: &str,
        log_dir: &str,
    ) -> Result<Conversion, ConvertError> {
        let read_error = |source| ConvertError::Read {
            log: label.to_owned(),
            source,
        };
        let mut input = Hashing {
            inner: input,
            sha: sha2::Sha256::new(),
            read: 0,
            unreported: 0,
            progress: self.progress.as_deref(),
        };
        let mut reader = StreamReader::new(&mut input).map_err(read_error)?;
        let mut pass = Pass::new(self, log_dir);
        pass.clock = GpsClock::new(reader.metadata().header().start_timestamp);
        reader
            .for_each_event(|event| pass.event(&event))
            .map_err(read_error)?;
        if let Some(e) = pass.failure.take() {
            pass.discard();
            return Err(e);
        }
        // The digest is of the whole file, whatever the reader stopped at.
        let input = reader.get_mut();
        io::copy(input, &mut io::sink()).map_err(|e| read_error(ReadError::Io(e)))?;
        input.report();
        let (digest, bytes) = (input.sha.clone().finalize(), input.read);
        let identity = LogIdentity::new(reader.metadata(), file_name, &digest, pass.clock.start());
        pass.finish(&identity, reader.metadata(), bytes)
    }
}

/// The input, hashed as it is read, with progress.
struct Hashing<'p, R> {
    inner: R,
    sha: sha2::Sha256,
    read: u64,
    unreported: u64,
    progress: Option<&'p (dyn Fn(u64) + Send + Sync)>,
}

impl<R: Read> Read for Hashing<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.sha.update(&buf[..n]);
        self.read += n as u64;
        self.unreported += n as u64;
        if self.unreported >= PROGRESS_STEP {
            self.report();
        }
        Ok(n)
    }
}

impl<R> Hashing<'_, R> {
    fn report(&mut self) {
        if let Some(f) = self.progress
            && self.unreported > 0
        {
            f(self.unreported);
        }
        self.unreported = 0;
    }
}

/// `by_msg_id` entries: not yet seen, or left out.
const UNSEEN: u32 = 0;
const LEFT_OUT: u32 = u32::MAX;

/// One topic instance being written.
struct Instance {
    topic: String,
    multi_id: u8,
    path: PathBuf,
    partial: PathBuf,
    table: Table<File>,
    /// Memory of its row group in progress, as last measured.
    memory: usize,
}

/// One topic instance's rows and times (all of them, converted or not).
struct Summary {
    topic: TopicSummary,
    /// Where its rows hold `time_utc_usec`, for a GPS topic.
    gps: Option<usize>,
}

/// The state of one conversion pass.
struct Pass<'c> {
    converter: &'c Converter,
    log_dir: String,
    names: FileNames,
    topic_dirs: HashMap<String, String>,
    notes: Vec<String>,
    /// Per `msg_id`: (summary index + 1, instance index + 1), or [`UNSEEN`]/[`LEFT_OUT`].
    by_msg_id: Vec<(u32, u32)>,
    summaries: Vec<Summary>,
    instances: Vec<Instance>,
    /// Sum of the instances' `memory`.
    buffered: usize,
    logged: Vec<LoggedMessage>,
    changes: Vec<ParameterChange>,
    dropouts: Vec<Dropout>,
    diagnostics: Vec<Diagnostic>,
    diagnostics_omitted: u64,
    skipped: Skipped,
    clock: GpsClock,
    failure: Option<ConvertError>,
}

impl<'c> Pass<'c> {
    fn new(converter: &'c Converter, log_dir: &str) -> Pass<'c> {
        Pass {
            converter,
            log_dir: log_dir.to_owned(),
            names: FileNames::new(),
            topic_dirs: HashMap::new(),
            notes: Vec::new(),
            by_msg_id: vec![(UNSEEN, UNSEEN); 1 << 16],
            summaries: Vec::new(),
            instances: Vec::new(),
            buffered: 0,
            logged: Vec::new(),
            changes: Vec::new(),
            dropouts: Vec::new(),
            diagnostics: Vec::new(),
            diagnostics_omitted: 0,
            skipped: Skipped::default(),
            clock: GpsClock::new(0),
            failure: None,
        }
    }

    #[inline]
    fn event(&mut self, event: &Event<'_>) {
        if self.failure.is_some() {
            return;
        }
        match event {
            Event::Row(row) => {
                if let Err(e) = self.row(row) {
                    self.failure = Some(e);
                }
            }
            Event::Logged(m) => self.logged.push(m.clone()),
            Event::ParameterChange(c) => self.changes.push(c.clone()),
            Event::Dropout(d) => self.dropouts.push(*d),
            Event::Diagnostic(d) => {
                self.skipped.add(d);
                if self.diagnostics.len() < KEPT_DIAGNOSTICS {
                    self.diagnostics.push((**d).clone());
                } else {
                    self.diagnostics_omitted += 1;
                }
            }
            Event::Definition { .. } | Event::Subscription(_) | Event::Sync { .. } => {}
        }
    }

    #[inline]
    fn row(&mut self, row: &Row<'_>) -> Result<(), ConvertError> {
        let msg_id = usize::from(row.subscription.msg_id);
        let (mut s, mut i) = self.by_msg_id[msg_id];
        if s == UNSEEN {
            (s, i) = self.first_row(row)?;
            self.by_msg_id[msg_id] = (s, i);
        }
        let summary = &mut self.summaries[s as usize - 1];
        let t = &mut summary.topic;
        t.rows += 1;
        t.first_timestamp.get_or_insert(row.timestamp);
        t.last_timestamp = Some(row.timestamp);
        if let Some(at) = summary.gps
            && self.clock.start().is_none()
        {
            self.clock.watch(row, at);
        }
        if i == LEFT_OUT {
            return Ok(());
        }
        let k = i as usize - 1;
        let inst = &mut self.instances[k];
        match inst.table.admit(row.timestamp) {
            AdmitRow::Take => {}
            AdmitRow::Skip | AdmitRow::Stop => return Ok(()),
        }
        let encoded = inst
            .table
            .push(row.data, row.timestamp)
            .map_err(|e| parquet_error(inst, e))?;
        if encoded {
            self.measure(k);
            self.within_budget()?;
        }
        Ok(())
    }

    /// Re-reads the memory an instance's row group holds.
    fn measure(&mut self, k: usize) {
        let inst = &mut self.instances[k];
        let now = inst.table.memory();
        self.buffered = self.buffered - inst.memory + now;
        inst.memory = now;
    }

    /// Writes out row groups, largest first, until the buffers fit the budget.
    fn within_budget(&mut self) -> Result<(), ConvertError> {
        while self.buffered > self.converter.options.buffer_bytes {
            let Some(k) = (0..self.instances.len()).max_by_key(|&k| self.instances[k].memory)
            else {
                return Ok(());
            };
            let inst = &mut self.instances[k];
            if inst.memory == 0 {
                return Ok(());
            }
            inst.table.flush().map_err(|e| parquet_error(inst, e))?;
            self.measure(k);
        }
        Ok(())
    }

    /// Where the rows of a `msg_id` go, decided at its first row.
    fn first_row(&mut self, row: &Row<'_>) -> Result<(u32, u32), ConvertError> {
        let sub = row.subscription;
        let s = match self
            .summaries
            .iter()
            .position(|x| x.topic.name == sub.name && x.topic.multi_id == sub.multi_id)
        {
            Some(s) => {
                self.summaries[s].topic.msg_ids.push(sub.msg_id);
                s
            }
            None => {
                self.summaries.push(Summary {
                    topic: TopicSummary {
                        name: sub.name.clone(),
                        multi_id: sub.multi_id,
                        msg_ids: vec![sub.msg_id],
                        rows: 0,
                        first_timestamp: None,
                        last_timestamp: None,
                    },
                    gps: GpsClock::field(row.schema(), sub),
                });
                self.summaries.len() - 1
            }
        };
        let s = s as u32 + 1;
        if !self.converter.options.wants(&sub.name) {
            return Ok((s, LEFT_OUT));
        }
        if let Some(k) = self
            .instances
            .iter()
            .position(|x| x.topic == sub.name && x.multi_id == sub.multi_id)
        {
            return Ok((s, k as u32 + 1));
        }
        let Some(spec) = sub.format().and_then(|id| ColumnSpec::of(row.schema(), id)) else {
            return Ok((s, LEFT_OUT));
        };
        let instance = self.open(spec, &sub.name, sub.multi_id)?;
        self.instances.push(instance);
        Ok((s, self.instances.len() as u32))
    }

    /// Makes the file of a new instance.
    fn open(
        &mut self,
        spec: ColumnSpec,
        topic: &str,
        multi_id: u8,
    ) -> Result<Instance, ConvertError> {
        let converter = self.converter;
        let layout = converter.options.layout;
        let (path, collided) = layout.table_path(
            &converter.root,
            &self.log_dir,
            &mut self.names,
            &mut self.topic_dirs,
            topic,
            multi_id,
        );
        if let Some(other) = collided {
            self.notes.push(format!(
                "topics `{other}` and `{topic}` map to one file name; `{topic}` #{multi_id} goes to {}",
                path.display()
            ));
        }
        let io = |path: &Path| {
            let path = path.to_owned();
            move |source| ConvertError::Io { path, source }
        };
        let dir = path.parent().unwrap_or(&converter.root);
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let partial = partial_path(&path);
        let file = File::create(&partial).map_err(io(&partial))?;
        let table =
            Table::new(spec, topic, multi_id, file, &converter.options).map_err(|source| {
                ConvertError::Parquet {
                    path: path.clone(),
                    topic: topic.to_owned(),
                    multi_id,
                    source,
                }
            })?;
        Ok(Instance {
            topic: topic.to_owned(),
            multi_id,
            path,
            partial,
            table,
            memory: 0,
        })
    }

    /// Removes what a failed pass wrote.
    fn discard(self) {
        for inst in self.instances {
            let partial = inst.partial.clone();
            drop(inst);
            let _ = std::fs::remove_file(partial);
        }
    }

    /// Closes every table with the log's identity, and writes `metadata.json`.
    fn finish(
        mut self,
        identity: &LogIdentity,
        meta: &crate::read::Metadata,
        bytes: u64,
    ) -> Result<Conversion, ConvertError> {
        let mut files = Vec::with_capacity(self.instances.len());
        let mut failure = None;
        let instances = std::mem::take(&mut self.instances);
        let mut partials = Vec::new();
        for inst in instances {
            let Instance {
                topic,
                multi_id,
                path,
                partial,
                table,
                ..
            } = inst;
            if failure.is_some() {
                drop(table);
                partials.push(partial);
                continue;
            }
            let closed = table
                .close(identity)
                .map_err(|source| ConvertError::Parquet {
                    path: path.clone(),
                    topic: topic.clone(),
                    multi_id,
                    source,
                });
            let done = closed.and_then(|TableWritten { rows, row_groups }| {
                std::fs::rename(&partial, &path).map_err(|source| ConvertError::Io {
                    path: path.clone(),
                    source,
                })?;
                Ok(WrittenFile {
                    path,
                    topic,
                    multi_id,
                    rows,
                    row_groups,
                })
            });
            match done {
                Ok(f) => files.push(f),
                Err(e) => {
                    failure = Some(e);
                    partials.push(partial);
                }
            }
        }
        if let Some(e) = failure {
            for p in partials {
                let _ = std::fs::remove_file(p);
            }
            return Err(e);
        }
        let mut topics: Vec<TopicSummary> = self.summaries.into_iter().map(|s| s.topic).collect();
        topics.sort_by(|a, b| (&a.name, a.multi_id).cmp(&(&b.name, b.multi_id)));
        let facts = LogFacts::new(
            meta,
            Collected {
                logged: &self.logged,
                changes: &self.changes,
                dropouts: &self.dropouts,
                diagnostics: &self.diagnostics,
                diagnostics_omitted: self.diagnostics_omitted,
                topics: &topics,
                skipped: &self.skipped,
            },
        );
        let root = &self.converter.root;
        let metadata = self
            .converter
            .options
            .layout
            .metadata_path(root, &self.log_dir);
        let document = MetadataJson {
            log: identity,
            facts: &facts,
            files: files
                .iter()
                .map(|f| FileEntry {
                    path: f.path.strip_prefix(root).unwrap_or(&f.path).to_path_buf(),
                    topic: &f.topic,
                    multi_id: f.multi_id,
                    rows: f.rows,
                })
                .collect(),
        };
        write_json(&metadata, &document)?;
        Ok(Conversion {
            log: identity.file_name.clone(),
            log_dir: self.log_dir,
            bytes,
            files,
            metadata,
            skipped: self.skipped,
            notes: self.notes,
        })
    }
}

fn parquet_error(inst: &Instance, source: ParquetError) -> ConvertError {
    ConvertError::Parquet {
        path: inst.path.clone(),
        topic: inst.topic.clone(),
        multi_id: inst.multi_id,
        source,
    }
}

/// Where a file is written before it is complete: a reader globbing `*.parquet` never sees
/// a half-written one.
fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    path.with_file_name(name)
}

/// `metadata.json`: the log's identity, its facts, and the files written.
#[derive(Serialize)]
struct MetadataJson<'a> {
    log: &'a LogIdentity,
    #[serde(flatten)]
    facts: &'a LogFacts,
    files: Vec<FileEntry<'a>>,
}

/// A file of `metadata.json`, its path relative to the output folder.
#[derive(Serialize)]
struct FileEntry<'a> {
    path: PathBuf,
    topic: &'a str,
    multi_id: u8,
    rows: usize,
}

fn write_json(path: &Path, document: &impl Serialize) -> Result<(), ConvertError> {
    let io = |source| ConvertError::Io {
        path: path.to_owned(),
        source,
    };
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(io)?;
    }
    let partial = partial_path(path);
    let mut out = io::BufWriter::new(File::create(&partial).map_err(io)?);
    serde_json::to_writer_pretty(&mut out, document).map_err(|e| io(e.into()))?;
    io::Write::write_all(&mut out, b"\n").map_err(io)?;
    out.into_inner().map_err(|e| io(e.into_error()))?;
    std::fs::rename(&partial, path).map_err(io)
}
