//! Whole logs to Parquet in one streaming pass each: rows are collected per topic instance
//! as they come and handed in batches to the [`Encoder`], which makes them columns and row
//! groups beside the read (on other cores) while the pass feeds the flight analysis; the
//! file is hashed on a thread of its own when there are cores to spare, else by the
//! encoder's threads from copies of what was read (or as it is read, with no encoder
//! thread); the tables' footers and `metadata.json` are written once the digest is known.

use std::collections::HashMap;
use std::fs::File;
use std::io::{self, Read};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use parquet::errors::ParquetError;
use serde::Serialize;
use sha2::Digest;

use super::encode::{Encoder, Output, TableWork};
use super::fleet::TablePlace;
use super::{Admission, AdmitRow, LogIdentity, ParquetOptions, Table, TableWritten};
use crate::analysis::{Analysis, Analyzer, ColumnStats};
use crate::columns::{ColumnBudget, ColumnSpec, RowBatch};
use crate::document::{Collected, KEPT_DIAGNOSTICS, LogFacts};
use crate::file_names::FileNames;
use crate::read::GpsClock;
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
    /// Not converted: the conversion was told to stop before this log was started
    /// ([`Converter::convert_files_until`]).
    #[error("{log}: not converted (the conversion was stopped before this log)")]
    Stopped {
        /// The log.
        log: String,
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
    /// Hive layout: each topic's folder, one for all logs this converter writes.
    pub(super) topic_dirs: Arc<std::sync::Mutex<super::fleet::TopicDirs>>,
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
#[non_exhaustive]
pub struct Conversion {
    /// The log's file name.
    pub log: String,
    /// The name of its output folder: its stem (`log=<stem>` in hive layout), made safe;
    /// `<stem>~2`, `~3`... when that folder holds another log (see
    /// [`Converter::convert_file`]).
    pub log_dir: String,
    /// Bytes of the log read.
    pub bytes: u64,
    /// Each Parquet file, in the order the topic instances first had rows.
    pub files: Vec<WrittenFile>,
    /// The `metadata.json`.
    pub metadata: PathBuf,
    /// What reading left out.
    pub skipped: Skipped,
    /// Things a user should hear about: names that had to change to stay unique (a topic's
    /// file, the log's folder).
    pub notes: Vec<String>,
    /// The earliest first and the latest last timestamp (µs) of the topic instances
    /// converted (those asked for, or all, whose rows can be read: each instance's first
    /// and last row in file order), in the window or not; `None` when they have no row.
    pub row_span_us: Option<(u64, u64)>,
}

impl Conversion {
    /// What `ulog parquet` says of this log on stderr, a line each: its notes, what reading
    /// left out ([`Skipped::lines`] of `topics`), and when no file was written, that no
    /// topic (of `topics`) has rows (in `window`, the conversion's:
    /// [`Window::nothing_written`](crate::columns::Window::nothing_written)), with the time
    /// span of their rows when a window left them all out.
    pub fn lines(&self, topics: &[String], window: &crate::columns::Window) -> Vec<String> {
        let mut out = self.notes.clone();
        out.extend(self.skipped.lines(topics));
        if self.files.is_empty() {
            let mut line = window.nothing_written("Parquet file", topics);
            if let Some((first, last)) = self.row_span_us.filter(|_| window.is_bounded()) {
                line.push_str(&crate::columns::span_in_words(first, last));
            }
            out.push(line);
        }
        out
    }
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
            topic_dirs: Arc::default(),
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
    /// ([`log_stem`](crate::file_names::log_stem)): its folder is the first of `<stem>`,
    /// `<stem>~2`... that holds this same log (same SHA-256 in its `metadata.json`: replaced)
    /// or nothing, never another log's ([`Conversion::log_dir`], [`Conversion::notes`]).
    pub fn convert_file(&self, path: &Path) -> Result<Conversion, ConvertError> {
        self.convert_as(path, &crate::file_names::log_stem(path), self.encoders(1))
    }

    /// [`Converter::convert_file`], its outputs named by `stem`, with `encoders` threads
    /// beside the reading one.
    pub(super) fn convert_as(
        &self,
        path: &Path,
        stem: &str,
        encoders: usize,
    ) -> Result<Conversion, ConvertError> {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.display().to_string());
        let read_error = |e| ConvertError::Read {
            log: path.display().to_string(),
            source: ReadError::Io(e),
        };
        let file = crate::read::open_file(path).map_err(read_error)?;
        let source = Source {
            file_name: &name,
            label: &path.display().to_string(),
            stem,
            // With two encoders or more, the file is hashed on a thread of its own; with
            // one (2 cores, both busy), from what is read: one read of the file instead of
            // two costs less (11 runs each, three times: 2 to 11% less CPU, wall 8% less to
            // 1.5% more), and hashing copies of it on the encoder's thread rather than on
            // the reading one took 15% less wall time for the same CPU (15 runs).
            hash_file: (encoders > 1).then_some(path),
        };
        self.convert_source(file, &source, encoders)
    }

    /// Converts a log read from `input`, named `file_name` (its outputs by its stem, as
    /// [`Converter::convert_file`] names them).
    pub fn convert_reader(
        &self,
        input: impl Read,
        file_name: &str,
    ) -> Result<Conversion, ConvertError> {
        let stem = crate::file_names::log_stem(file_name.as_ref());
        let source = Source {
            file_name,
            label: file_name,
            stem: &stem,
            hash_file: None,
        };
        self.convert_source(input, &source, self.encoders(1))
    }

    /// Encoder threads for one log of `logs` converted at once: the option's, or every
    /// core but the reading one's for a single log, none for several.
    pub(super) fn encoders(&self, logs: usize) -> usize {
        self.options.encoders.unwrap_or_else(|| {
            if logs > 1 {
                0
            } else {
                std::thread::available_parallelism().map_or(1, std::num::NonZero::get) - 1
            }
        })
    }

    /// Converts the log read from `input`: the pass, the encoders beside it, the digest;
    /// then the tables closed and `metadata.json` written.
    fn convert_source(
        &self,
        input: impl Read,
        source: &Source<'_>,
        encoders: usize,
    ) -> Result<Conversion, ConvertError> {
        // A file where the output folder should be is refused before the log is read.
        crate::file_names::prepare_folder(&self.root).map_err(|source| ConvertError::Io {
            path: self.root.clone(),
            source,
        })?;
        let encoder = if encoders == 0 {
            Encoder::inline(self.options.buffer_bytes)
        } else {
            Encoder::pool(self.options.buffer_bytes, encoders)
        };
        let label = source.label;
        let (pass, digest) = std::thread::scope(|s| {
            for _ in 0..encoder.threads() {
                s.spawn(|| encoder.work());
            }
            let hashing = source.hash_file.map(|p| s.spawn(move || hash_file(p)));
            let hash = match (&hashing, encoder.threads()) {
                (Some(_), _) => HashBy::Elsewhere,
                (None, 0) => HashBy::Reader,
                (None, _) => HashBy::Encoder,
            };
            let pass = self.pass(input, source, &encoder, hash);
            // The workers stop once the batches are encoded, failed or not; this thread
            // helps them with the last ones.
            encoder.finish();
            if encoder.threads() > 0 {
                encoder.work();
            }
            let digest = hashing.map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)));
            (pass, digest)
        });
        let (pass, meta, read) = pass?;
        let tables = encoder
            .take_tables()
            .map_err(|(t, e)| pass.table_error(t, e))?;
        let (digest, bytes) = match (digest, read) {
            (Some(d), _) => d.map_err(|e| ConvertError::Read {
                log: label.to_owned(),
                source: ReadError::Io(e),
            })?,
            (None, (Some(sha), bytes)) => (sha.finalize().to_vec(), bytes),
            (None, (None, bytes)) => (encoder.take_hash().finalize().to_vec(), bytes),
        };
        let identity = LogIdentity::new(&meta, source.file_name, &digest, pass.clock.start());
        pass.finish(tables, &identity, &meta, bytes, encoders + 1)
    }

    /// The reading pass: every event to the pass, batches to the encoder; the metadata,
    /// the hash when hashed as read ([`HashBy::Reader`]), and the file's length.
    #[allow(clippy::type_complexity)]
    fn pass<'c>(
        &'c self,
        input: impl Read,
        source: &Source<'_>,
        encoder: &'c Encoder<Reopening>,
        hash: HashBy,
    ) -> Result<(Pass<'c>, crate::read::Metadata, (Option<sha2::Sha256>, u64)), ConvertError> {
        let read_error = |e| ConvertError::Read {
            log: source.label.to_owned(),
            source: e,
        };
        let mut input = Hashing {
            inner: input,
            sha: matches!(hash, HashBy::Reader).then(sha2::Sha256::new),
            encoder: matches!(hash, HashBy::Encoder).then_some(encoder),
            read: 0,
            unreported: 0,
            progress: self.progress.as_deref(),
        };
        let mut reader = StreamReader::new(&mut input).map_err(read_error)?;
        let mut pass = Pass::new(self, source.stem, encoder);
        pass.clock = GpsClock::new(reader.metadata().header().start_timestamp);
        let result = reader.for_each_message(|meta, event, _| {
            pass.event(meta, &event);
            Ok::<(), ReadError>(())
        });
        result.map_err(read_error)?;
        pass.send_all();
        if let Some(e) = pass.failure.take() {
            // The guard removes what was written.
            return Err(e);
        }
        let meta = reader.metadata().clone();
        let input = reader.get_mut();
        // The digest is of the whole file, whatever the reader stopped at.
        io::copy(input, &mut io::sink()).map_err(|e| read_error(ReadError::Io(e)))?;
        input.report();
        Ok((pass, meta, (input.sha.take(), input.read)))
    }
}

/// Where the file's SHA-256 is taken.
#[derive(Debug, Clone, Copy)]
enum HashBy {
    /// By the reading thread, as it reads (no encoder thread).
    Reader,
    /// By the encoder's threads, from copies of what was read ([`Encoder::hash`]): for a
    /// file with one encoder thread (two cores), where the reading thread sets the pace
    /// and hashing took it two fifths of its time, and for any other input with encoder
    /// threads (nothing to read again).
    Encoder,
    /// On a thread of its own, reading the file again ([`Source::hash_file`]).
    Elsewhere,
}

/// Where a log comes from and how its outputs are named.
pub(super) struct Source<'a> {
    file_name: &'a str,
    /// Errors say this.
    label: &'a str,
    stem: &'a str,
    /// The file to hash on a thread of its own (else it is hashed from what is read).
    hash_file: Option<&'a Path>,
}

/// SHA-256 of a whole file, and its length.
fn hash_file(path: &Path) -> io::Result<(Vec<u8>, u64)> {
    let mut file = File::open(path)?;
    let mut sha = sha2::Sha256::new();
    let mut buf = vec![0u8; 1 << 20];
    let mut len = 0u64;
    loop {
        let n = match file.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        sha.update(&buf[..n]);
        len += n as u64;
    }
    Ok((sha.finalize().to_vec(), len))
}

/// The input, hashed as it is read or its bytes given to the encoder to hash (unless
/// hashed elsewhere), with progress.
struct Hashing<'p, R> {
    inner: R,
    sha: Option<sha2::Sha256>,
    encoder: Option<&'p Encoder<Reopening>>,
    read: u64,
    unreported: u64,
    progress: Option<&'p (dyn Fn(u64) + Send + Sync)>,
}

impl<R: Read> Read for Hashing<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        if let Some(sha) = &mut self.sha {
            sha.update(&buf[..n]);
        }
        if let Some(encoder) = self.encoder
            && n > 0
            && encoder.hash(&buf[..n]).is_err()
        {
            // A table failed: the conversion fails with it, and no digest is asked for.
            self.encoder = None;
        }
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

/// `by_sub` entries: not yet seen, or left out.
const UNSEEN: u32 = 0;
const LEFT_OUT: u32 = u32::MAX;

/// A file that is open only while a row group or the footer is written to it (so a
/// conversion of hundreds of tables holds no file handles between row groups); made empty
/// on its first write.
struct Reopening {
    path: PathBuf,
    file: Option<File>,
    begun: bool,
}

impl Reopening {
    fn new(path: PathBuf) -> Reopening {
        Reopening {
            path,
            file: None,
            begun: false,
        }
    }

    /// Closes the handle (after the writer has flushed to it).
    fn release(&mut self) {
        self.file = None;
    }

    fn file(&mut self) -> io::Result<&mut File> {
        if self.file.is_none() {
            if !self.begun
                && let Some(dir) = self.path.parent()
            {
                std::fs::create_dir_all(dir)?;
            }
            let file = if self.begun {
                std::fs::OpenOptions::new().append(true).open(&self.path)?
            } else {
                File::create(&self.path)?
            };
            self.begun = true;
            self.file = Some(file);
        }
        Ok(self.file.as_mut().expect("just opened"))
    }
}

impl Output for Reopening {
    fn release(&mut self) {
        Reopening::release(self);
    }
}

impl io::Write for Reopening {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.file()?.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        match &mut self.file {
            Some(f) => f.flush(),
            None => Ok(()),
        }
    }
}

/// The files a conversion has made; removed when it is dropped unless it succeeded (so a
/// failed conversion leaves nothing, and no half-written file is ever under its name).
#[derive(Default)]
struct Outputs {
    paths: Vec<PathBuf>,
    kept: bool,
}

impl Drop for Outputs {
    fn drop(&mut self) {
        if !self.kept {
            for p in &self.paths {
                let _ = std::fs::remove_file(p);
            }
        }
    }
}

/// One topic instance being written.
struct Instance {
    topic: String,
    multi_id: u8,
    /// Where its file goes in whichever folder the log takes.
    place: TablePlace,
    /// Its path in the first choice of folder (errors say it).
    path: PathBuf,
    /// Where it is written until the pass is done.
    partial: PathBuf,
    window: Admission,
    /// Its table in the encoder.
    table: usize,
    /// The rows of its next batch.
    batch: RowBatch,
    batch_rows: usize,
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
    encoder: &'c Encoder<Reopening>,
    /// The log's stem.
    stem: String,
    /// The first choice of the log's folder: the files are written there (as `.partial`)
    /// until the log's digest says which folder it takes.
    log_dir: String,
    names: FileNames,
    notes: Vec<String>,
    /// Per subscription (by index): (summary index + 1, instance index + 1), or
    /// [`UNSEEN`]/[`LEFT_OUT`].
    by_sub: Vec<(u32, u32)>,
    summaries: Vec<Summary>,
    instances: Vec<Instance>,
    /// Each instance's index by topic and `multi_id`.
    instance_index: HashMap<(String, u8), usize>,
    /// The columns of each format an instance was bound to (`None`: it has none).
    specs: HashMap<crate::schema::FormatId, Option<Arc<ColumnSpec>>>,
    /// The columns of the tables open ([`ParquetOptions::max_columns`]), and the instances
    /// left out.
    budget: ColumnBudget,
    logged: Vec<LoggedMessage>,
    changes: Vec<ParameterChange>,
    dropouts: Vec<Dropout>,
    diagnostics: Vec<Diagnostic>,
    diagnostics_omitted: u64,
    skipped: Skipped,
    clock: GpsClock,
    /// The flight analysis, if asked for.
    analyzer: Option<Analyzer>,
    /// Whether the tables take the per-field statistics from their columns (every row of
    /// every topic converted), not the analyzer.
    stats_from_columns: bool,
    failure: Option<ConvertError>,
    /// A table failed: the encoder says which.
    stopped: bool,
    outputs: Outputs,
}

impl<'c> Pass<'c> {
    fn new(converter: &'c Converter, stem: &str, encoder: &'c Encoder<Reopening>) -> Pass<'c> {
        let options = &converter.options;
        let stats_from_columns = options.analysis
            && options.topics.is_empty()
            && options.window == crate::columns::Window::default();
        Pass {
            converter,
            encoder,
            stem: stem.to_owned(),
            log_dir: options.layout.log_dir(stem, 1),
            names: FileNames::new(),
            notes: Vec::new(),
            by_sub: Vec::new(),
            summaries: Vec::new(),
            instances: Vec::new(),
            instance_index: HashMap::new(),
            specs: HashMap::new(),
            budget: ColumnBudget::default(),
            logged: Vec::new(),
            changes: Vec::new(),
            dropouts: Vec::new(),
            diagnostics: Vec::new(),
            diagnostics_omitted: 0,
            skipped: Skipped::default(),
            clock: GpsClock::new(0),
            analyzer: options.analysis.then(|| {
                if stats_from_columns {
                    Analyzer::without_field_stats()
                } else {
                    Analyzer::new()
                }
            }),
            stats_from_columns,
            failure: None,
            stopped: false,
            outputs: Outputs::default(),
        }
    }

    #[inline]
    fn event(&mut self, meta: &crate::read::Metadata, event: &Event<'_>) {
        if self.failure.is_some() || self.stopped {
            return;
        }
        match event {
            Event::Row(row) => self.take_row(meta, row),
            Event::Logged(m) => self.logged.push(m.clone()),
            Event::ParameterChange(c) => self.changes.push(c.clone()),
            Event::Dropout(d) => self.dropouts.push(*d),
            Event::Diagnostic(d) => self.diagnostic(d),
            Event::Subscription(_) | Event::Definition { .. } | Event::Sync { .. } => {}
        }
    }

    /// A row, to the analysis and its table.
    #[inline]
    fn take_row(&mut self, meta: &crate::read::Metadata, row: &Row<'_>) {
        if let Some(a) = &mut self.analyzer {
            a.row(meta, row);
        }
        self.row(row);
    }

    fn diagnostic(&mut self, d: &Diagnostic) {
        if let Some(a) = &mut self.analyzer {
            a.diagnostic(d);
        }
        self.skipped.add(d);
        if self.diagnostics.len() < KEPT_DIAGNOSTICS {
            self.diagnostics.push(d.clone());
        } else {
            self.diagnostics_omitted += 1;
        }
    }

    #[inline]
    fn row(&mut self, row: &Row<'_>) {
        let (s, i) = match self.by_sub.get(row.subscription.index()) {
            Some(&(s, i)) if s != UNSEEN => (s, i),
            _ => self.first_row(row),
        };
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
            return;
        }
        let k = i as usize - 1;
        let inst = &mut self.instances[k];
        match inst.window.admit(row.timestamp) {
            AdmitRow::Take => {}
            AdmitRow::Skip | AdmitRow::Stop => return,
        }
        if inst.batch.push(row.data, row.timestamp) && inst.batch.rows() >= inst.batch_rows {
            self.send(k);
        }
    }

    /// Hands instance `k`'s batch to the encoder.
    #[inline(never)]
    fn send(&mut self, k: usize) {
        let inst = &mut self.instances[k];
        if inst.batch.rows() == 0 {
            return;
        }
        let spec = inst.batch.spec().clone();
        let batch = std::mem::replace(
            &mut inst.batch,
            RowBatch::with_capacity(spec, inst.batch_rows),
        );
        if self.encoder.push(inst.table, batch).is_err() {
            self.stopped = true;
        }
    }

    /// Hands every instance's last batch to the encoder.
    fn send_all(&mut self) {
        for k in 0..self.instances.len() {
            if !self.stopped {
                self.send(k);
            }
        }
    }

    /// The error of table `t` (as the encoder numbers them: in instance order).
    fn table_error(&self, t: usize, source: ParquetError) -> ConvertError {
        let inst = &self.instances[t];
        ConvertError::Parquet {
            path: inst.path.clone(),
            topic: inst.topic.clone(),
            multi_id: inst.multi_id,
            source,
        }
    }

    /// Where the rows of a subscription go, decided at its first row.
    #[cold]
    #[inline(never)]
    fn first_row(&mut self, row: &Row<'_>) -> (u32, u32) {
        let place = self.place(row);
        let sub = row.subscription.index();
        if self.by_sub.len() <= sub {
            self.by_sub.resize(sub + 1, (UNSEEN, UNSEEN));
        }
        self.by_sub[sub] = place;
        place
    }

    /// Where the rows of `row`'s subscription go: its summary and its instance (new ones
    /// made for it).
    fn place(&mut self, row: &Row<'_>) -> (u32, u32) {
        let sub = row.subscription;
        let s = match self
            .summaries
            .iter()
            .position(|x| x.topic.name == sub.name && x.topic.multi_id == sub.multi_id)
        {
            Some(s) => {
                if !self.summaries[s].topic.msg_ids.contains(&sub.msg_id) {
                    self.summaries[s].topic.msg_ids.push(sub.msg_id);
                }
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
            return (s, LEFT_OUT);
        }
        let key = (sub.name.clone(), sub.multi_id);
        if let Some(&k) = self.instance_index.get(&key) {
            return (s, k as u32 + 1);
        }
        let Some(id) = sub.format() else {
            return (s, LEFT_OUT);
        };
        // Counted before any column is made: an instance past the budget costs nothing.
        let columns = crate::columns::column_count(row.schema(), id);
        let limit = self.converter.options.max_columns;
        if !self.budget.admit(limit, &sub.name, sub.multi_id, columns) {
            return (s, LEFT_OUT);
        }
        // Made once per format, not once per instance.
        let spec = self
            .specs
            .entry(id)
            .or_insert_with(|| ColumnSpec::of(row.schema(), id).map(Arc::new))
            .clone();
        let Some(spec) = spec else {
            return (s, LEFT_OUT);
        };
        let instance = self.instance(spec, &sub.name, sub.multi_id);
        self.instance_index.insert(key, self.instances.len());
        self.instances.push(instance);
        (s, self.instances.len() as u32)
    }

    /// A new instance: its file's name (the file is made with its first row group).
    fn instance(&mut self, spec: Arc<ColumnSpec>, topic: &str, multi_id: u8) -> Instance {
        let converter = self.converter;
        let (place, collided) = converter.options.layout.table_place(
            &mut self.names,
            &converter.topic_dirs,
            topic,
            multi_id,
        );
        let path = place.path(&converter.root, &self.log_dir);
        if let Some(other) = collided {
            self.notes.push(format!(
                "topics `{other}` and `{topic}` map to one file name; `{topic}` #{multi_id} goes to {}",
                path.display()
            ));
        }
        let partial = crate::file_names::partial_path(&path);
        // Removed if the conversion fails (if it was made at all).
        self.outputs.paths.push(partial.clone());
        let options = &converter.options;
        let table = Table::new(
            &spec,
            topic,
            multi_id,
            Reopening::new(partial.clone()),
            options,
        );
        let batch_rows = options
            .batch_rows(spec.stored_row_size())
            .min(options.row_group_rows.max(1));
        let stats = self
            .stats_from_columns
            .then(|| ColumnStats::new(topic, multi_id, spec.clone()));
        let table = self.encoder.add(TableWork { table, stats });
        debug_assert_eq!(table, self.instances.len(), "tables in instance order");
        Instance {
            topic: topic.to_owned(),
            multi_id,
            place,
            path,
            partial,
            window: Admission::new(options.window),
            table,
            batch: RowBatch::with_capacity(spec, batch_rows),
            batch_rows,
        }
    }

    /// Closes every table with the log's identity (on `threads` threads), chooses the log's
    /// folder ([`Converter::claim_log_dir`]), writes `metadata.json` (with the analysis),
    /// then gives every file its name, and removes the files of an earlier conversion of
    /// this log that this one did not write.
    fn finish(
        mut self,
        tables: Vec<TableWork<Reopening>>,
        identity: &LogIdentity,
        meta: &crate::read::Metadata,
        bytes: u64,
        threads: usize,
    ) -> Result<Conversion, ConvertError> {
        // The instances left out for their columns, said once in the notes and, where the
        // field statistics come from the tables, in the analysis.
        let too_wide = self.budget.said(&format!(
            "{} open at once (--max-columns, ParquetOptions::max_columns)",
            self.converter.options.max_columns
        ));
        if let Some(text) = &too_wide {
            let stats = if self.stats_from_columns && self.analyzer.is_some() {
                " and in no field statistics"
            } else {
                ""
            };
            self.notes
                .push(format!("{text}; their rows are in no file{stats}"));
        }
        let root = self.converter.root.clone();
        let (log_dir, moved) = self.converter.claim_log_dir(&self.stem, &identity.sha256)?;
        if moved {
            self.notes.push(format!(
                "`{}` holds another log (another sha256); this one goes to `{log_dir}`",
                self.log_dir
            ));
        }
        let mut stats = Vec::new();
        let mut closing = Vec::with_capacity(tables.len());
        for work in tables {
            stats.extend(work.stats);
            closing.push(work.table);
        }
        let closed = close_all(closing, identity, threads);
        let analysis: Option<Analysis> = self.analyzer.take().map(|a| {
            if self.stats_from_columns {
                let mut analysis = a.finish_with_columns(meta, stats);
                if let Some(text) = too_wide {
                    analysis.missing.push(crate::analysis::Missing {
                        fact: "field_stats".to_owned(),
                        reason: text,
                    });
                }
                analysis
            } else {
                a.finish(meta)
            }
        });
        // Of the instances converted: topics asked for, with rows that can be read.
        let instances = &self.instances;
        let row_span_us = self
            .summaries
            .iter()
            .filter(|s| {
                instances
                    .iter()
                    .any(|i| i.topic == s.topic.name && i.multi_id == s.topic.multi_id)
            })
            .filter_map(|s| Some((s.topic.first_timestamp?, s.topic.last_timestamp?)))
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)));
        let mut files = Vec::with_capacity(self.instances.len());
        let mut renames = Vec::new();
        let mut written_tables = Vec::with_capacity(closed.len());
        for (t, result) in closed.into_iter().enumerate() {
            written_tables.push(result.map_err(|source| self.table_error(t, source))?);
        }
        for (inst, (written, TableWritten { rows, row_groups })) in
            std::mem::take(&mut self.instances)
                .into_iter()
                .zip(written_tables)
        {
            let Instance {
                topic,
                multi_id,
                place,
                partial,
                ..
            } = inst;
            let path = place.path(&root, &log_dir);
            if !written {
                // No row in the window: no file.
                continue;
            }
            renames.push((partial, path.clone()));
            files.push(WrittenFile {
                path,
                topic,
                multi_id,
                rows,
                row_groups,
            });
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
                gps_utc_start: self.clock.start(),
            },
        );
        let metadata = self.converter.options.layout.metadata_path(&root, &log_dir);
        let earlier = earlier_files(&root, &metadata);
        let window = self.converter.options.window;
        let document = MetadataJson {
            log: identity,
            window: window.is_bounded().then_some(WindowFact {
                start_s: window.start_us.map(|us| us / 1e6),
                end_s: window.end_us.map(|us| us / 1e6),
            }),
            facts: &facts,
            analysis: analysis.as_ref(),
            files: files
                .iter()
                .map(|f| FileEntry {
                    path: f.path.strip_prefix(&root).unwrap_or(&f.path).to_path_buf(),
                    topic: &f.topic,
                    multi_id: f.multi_id,
                    rows: f.rows,
                })
                .collect(),
        };
        let metadata_partial = crate::file_names::partial_path(&metadata);
        self.outputs.paths.push(metadata_partial.clone());
        write_json(&metadata_partial, &document)?;
        renames.push((metadata_partial, metadata.clone()));
        for (from, to) in &renames {
            let io = |source| ConvertError::Io {
                path: to.clone(),
                source,
            };
            // Written in the first choice of folder; the log may have taken another.
            if let Some(dir) = to.parent()
                && from.parent() != Some(dir)
            {
                std::fs::create_dir_all(dir).map_err(io)?;
            }
            std::fs::rename(from, to).map_err(io)?;
            self.outputs.paths.push(to.clone());
        }
        self.outputs.kept = true;
        for old in earlier {
            if !files.iter().any(|f| f.path == old) {
                let _ = std::fs::remove_file(&old);
            }
        }
        Ok(Conversion {
            log: identity.file_name.clone(),
            log_dir,
            bytes,
            files,
            metadata,
            skipped: std::mem::take(&mut self.skipped),
            notes: std::mem::take(&mut self.notes),
            row_span_us,
        })
    }
}

/// A closed table: whether a file was written, and what it holds.
type Closed = Result<(bool, TableWritten), ParquetError>;

/// Closes every table (its last row group and footer, with the log's identity) on up to
/// `threads` threads; the results in the tables' order.
fn close_all(tables: Vec<Table<Reopening>>, identity: &LogIdentity, threads: usize) -> Vec<Closed> {
    // The tables holding most first, so that no large one is left to one thread at the end.
    let mut order: Vec<usize> = (0..tables.len()).collect();
    order.sort_by_key(|&k| std::cmp::Reverse(tables[k].memory()));
    let slots: Vec<std::sync::Mutex<Option<Table<Reopening>>>> = tables
        .into_iter()
        .map(|t| std::sync::Mutex::new(Some(t)))
        .collect();
    let results: Vec<std::sync::Mutex<Option<Closed>>> =
        slots.iter().map(|_| std::sync::Mutex::new(None)).collect();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let work = || {
        loop {
            let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let Some(&k) = order.get(i) else { break };
            let slot = &slots[k];
            let table = slot
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .take()
                .expect("each table closed once");
            let result = table.close(identity, false);
            *results[k]
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(result);
        }
    };
    std::thread::scope(|s| {
        for _ in 1..threads.clamp(1, slots.len().max(1)) {
            s.spawn(work);
        }
        work();
    });
    results
        .into_iter()
        .map(|r| {
            r.into_inner()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .expect("every table closed")
        })
        .collect()
}

/// The Parquet files an earlier conversion listed in its `metadata.json` (inside `root`,
/// named `*.parquet`), to remove those the new one does not write.
fn earlier_files(root: &Path, metadata: &Path) -> Vec<PathBuf> {
    let Ok(text) = std::fs::read(metadata) else {
        return Vec::new();
    };
    let Ok(doc) = serde_json::from_slice::<serde_json::Value>(&text) else {
        return Vec::new();
    };
    let Some(files) = doc.get("files").and_then(|f| f.as_array()) else {
        return Vec::new();
    };
    files
        .iter()
        .filter_map(|f| f.get("path")?.as_str())
        .map(Path::new)
        .filter(|p| {
            p.components()
                .all(|c| matches!(c, std::path::Component::Normal(_)))
                && p.extension().is_some_and(|e| e == "parquet")
        })
        .map(|p| root.join(p))
        .collect()
}

/// `metadata.json`: the log's identity, its facts, and the files written.
#[derive(Serialize)]
struct MetadataJson<'a> {
    log: &'a LogIdentity,
    /// The window the files' rows were taken from, when one was asked for (the facts'
    /// per-topic row counts are the whole log's).
    #[serde(skip_serializing_if = "Option::is_none")]
    window: Option<WindowFact>,
    #[serde(flatten)]
    facts: &'a LogFacts,
    /// The flight analysis ([`crate::analysis`]), unless left out.
    #[serde(skip_serializing_if = "Option::is_none")]
    analysis: Option<&'a Analysis>,
    files: Vec<FileEntry<'a>>,
}

/// `metadata.json`'s `window`: its bounds in seconds of log time (`null`: none).
#[derive(Serialize)]
struct WindowFact {
    start_s: Option<f64>,
    end_s: Option<f64>,
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
    let mut out = io::BufWriter::new(File::create(path).map_err(io)?);
    serde_json::to_writer_pretty(&mut out, document).map_err(|e| io(e.into()))?;
    io::Write::write_all(&mut out, b"\n").map_err(io)?;
    out.into_inner().map_err(|e| io(e.into_error()))?;
    Ok(())
}
