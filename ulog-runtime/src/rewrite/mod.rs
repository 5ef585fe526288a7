//! Rewriting logs: the messages of a [`StreamReader`] written again as a new version-1 file,
//! every message as it was unless a rule changes it ([`Rewrite`]): cut to a time window,
//! topics kept or dropped, info values dropped or replaced, rows transformed (by field name
//! or as a typed struct), positions, times and identifiers anonymized ([`Anonymize`]).
//!
//! One pass, in bounded memory: the definitions section (formats, info, parameters: tens to
//! hundreds of kilobytes) is held until the data begins, or until the window opens when the
//! cut moves the parameters in force at its start into the initial parameters; everything
//! else goes out as it comes. What the reader skipped in a damaged log is said in the
//! [`Report`]; the output holds every message the reader recovered.
//!
//! ```
//! use ulog_runtime::rewrite::Rewrite;
//! use ulog_runtime::columns::Window;
//! use ulog_runtime::{Log, ULog, Writer, WriterOptions};
//!
//! #[derive(ULog)]
//! struct Battery { timestamp: u64, voltage_v: f32 }
//!
//! let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
//! let sub = w.topic::<Battery>(0)?;
//! for s in 0..10u64 {
//!     w.write(&sub, &Battery { timestamp: s * 1_000_000, voltage_v: 16.0 - s as f32 / 10.0 })?;
//! }
//! let input = w.into_inner();
//!
//! let mut cut = Vec::new();
//! let report = Rewrite::new()
//!     .window(Window::seconds(Some(2.0), Some(5.0))?)
//!     .run(&input[..], &mut cut)?;
//! assert_eq!(report.topics[0].rows_out, 3);
//! let log = Log::from_vec(cut)?;
//! let times = log.columns("battery", 0)?;
//! assert_eq!(times.get("timestamp").unwrap().as_uint64(), Some(&[2_000_000, 3_000_000, 4_000_000][..]));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod anonymize;
mod fields;
#[cfg(test)]
mod tests;

use std::io::{self, Read, Write};
use std::path::Path;

pub use anonymize::{Anonymize, Target};
pub use fields::{FieldError, RowFields};

use crate::columns::FieldIndex;
use crate::columns::{Admit, Window};
use crate::read::FileHeader;
use crate::read::{
    FlagBits, KeyValue, Message, MessageTooLarge, RawMessage, Skipped, Subscription,
};
use crate::schema::{Schema, TypeRef};
use crate::typed::{Topic, TypedDecoder, TypedError, encode_row};
use crate::value::Value;
use crate::{Event, ReadError, StreamReader};

crate::error::debug_as_display!(RewriteError);

/// Why a rewrite stopped (what was written until then is not a whole log).
#[derive(thiserror::Error)]
#[non_exhaustive]
pub enum RewriteError {
    /// The input could not be read (not a ULog file, or reading failed).
    #[error("reading: {0}")]
    Read(#[from] ReadError),
    /// Writing the output failed.
    #[error("writing: {0}")]
    Write(#[source] io::Error),
    /// The output file could not be made or named ([`Rewrite::run_file`]): a folder in its
    /// place, a folder that cannot be made, no permission.
    #[error("{}: {source}", path.display())]
    Output {
        /// The output file.
        path: std::path::PathBuf,
        /// Why.
        source: io::Error,
    },
    /// A typed row transform's struct does not fit the topic's format.
    #[error(transparent)]
    Typed(#[from] TypedError),
    /// A typed row transform of a type with widened fields: its values cannot be written
    /// back into a file whose type may be narrower.
    #[error(
        "`map::<{rust_type}>`: a type with `#[ulog(widen)]` fields cannot be written back (the \
         file's type may be narrower); use a type with the file's own field types"
    )]
    Widened {
        /// The struct.
        rust_type: &'static str,
    },
    /// A replacement info value that cannot be written.
    #[error("info `{key}`: {reason}")]
    InvalidInfo {
        /// The key.
        key: String,
        /// Why.
        reason: String,
    },
    /// A message that no longer fits its length field (a replaced value too long).
    #[error(transparent)]
    TooLarge(#[from] MessageTooLarge),
    /// The output is the input.
    #[error("{}: the output is the input file; write the rewritten log elsewhere", .0.display())]
    SameFile(std::path::PathBuf),
}

/// A row transform of one topic's rows.
type FieldsFn = Box<dyn FnMut(&mut RowFields<'_>)>;

/// What transforms the rows of some subscriptions ([`Rewrite::map_rows`], [`Rewrite::map`],
/// [`Anonymize`]).
trait RowTransform {
    /// Prepares for the rows of a subscription (its format checked): a slot to give
    /// [`RowTransform::apply`], or `None` if its rows are left as they are.
    fn prepare(
        &mut self,
        schema: &Schema,
        sub: &Subscription,
    ) -> Result<Option<usize>, RewriteError>;
    /// Changes a row of the subscription prepared as `slot`.
    fn apply(&mut self, slot: usize, row: &mut [u8], timestamp: u64);
}

/// [`Rewrite::map_rows`]: a closure over a row's fields by name.
struct FieldsMap {
    topic: String,
    f: FieldsFn,
    indices: Vec<FieldIndex>,
}

impl RowTransform for FieldsMap {
    fn prepare(
        &mut self,
        schema: &Schema,
        sub: &Subscription,
    ) -> Result<Option<usize>, RewriteError> {
        if sub.name != self.topic {
            return Ok(None);
        }
        let Some(index) = sub.format().and_then(|id| FieldIndex::of(schema, id)) else {
            return Ok(None);
        };
        self.indices.push(index);
        Ok(Some(self.indices.len() - 1))
    }

    fn apply(&mut self, slot: usize, row: &mut [u8], timestamp: u64) {
        (self.f)(&mut RowFields {
            row,
            index: &self.indices[slot],
            timestamp,
        });
    }
}

/// [`Rewrite::map`]: rows decoded into `T`, changed, written back into the file's layout.
struct TypedMap<T: Topic, F> {
    topic: String,
    f: F,
    decoders: Vec<TypedDecoder<T>>,
    encoded: Vec<u8>,
}

impl<T: Topic, F: FnMut(&mut T)> RowTransform for TypedMap<T, F> {
    fn prepare(
        &mut self,
        schema: &Schema,
        sub: &Subscription,
    ) -> Result<Option<usize>, RewriteError> {
        if sub.name != self.topic {
            return Ok(None);
        }
        if fields::widens(&T::FORMAT) {
            return Err(RewriteError::Widened {
                rust_type: T::FORMAT.rust_type,
            });
        }
        self.decoders
            .push(TypedDecoder::new_as(schema, &self.topic)?);
        Ok(Some(self.decoders.len() - 1))
    }

    fn apply(&mut self, slot: usize, row: &mut [u8], _: u64) {
        let decoder = &self.decoders[slot];
        let Some(mut value) = decoder.decode(row) else {
            return;
        };
        (self.f)(&mut value);
        self.encoded.clear();
        encode_row(&value, &mut self.encoded);
        fields::scatter(&T::FORMAT, decoder.plan(), &self.encoded, row);
    }
}

/// The rules of a rewrite, then [`Rewrite::run`] (module docs).
#[derive(Default)]
pub struct Rewrite {
    window: Window,
    keep: Vec<String>,
    exclude: Vec<String>,
    drop_info: Vec<String>,
    replace_info: Vec<(String, Value)>,
    transforms: Vec<Box<dyn RowTransform>>,
    anonymize: Option<anonymize::Anonymizer>,
}

impl std::fmt::Debug for Rewrite {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Rewrite")
            .field("window", &self.window)
            .field("keep", &self.keep)
            .field("exclude", &self.exclude)
            .field("drop_info", &self.drop_info)
            .field("transforms", &self.transforms.len())
            .field("anonymize", &self.anonymize.is_some())
            .finish_non_exhaustive()
    }
}

/// What one topic instance lost and kept.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TopicReport {
    /// The topic.
    pub name: String,
    /// The instance.
    pub multi_id: u8,
    /// Rows read.
    pub rows_in: usize,
    /// The smallest and the largest timestamp of the rows read (µs), when any was.
    pub span_in: Option<(u64, u64)>,
    /// Rows written.
    pub rows_out: usize,
    /// Rows written changed by a transform (anonymized rows included).
    pub rows_changed: usize,
    /// Whether the rules keep the instance (its rows in the window are written): false for a
    /// topic left out by [`Rewrite::topics`], [`Rewrite::exclude`] or anonymizing, or one
    /// whose format cannot be read.
    pub kept: bool,
}

/// What a rewrite did.
#[derive(Debug, Clone, Default, PartialEq)]
#[non_exhaustive]
pub struct Report {
    /// Bytes read.
    pub bytes_in: u64,
    /// Bytes written.
    pub bytes_out: u64,
    /// Every topic instance with rows, in order of first row.
    pub topics: Vec<TopicReport>,
    /// Subscriptions not written (a topic dropped, no row left in the window, or a format
    /// the log does not define): topic, instance.
    pub subscriptions_dropped: Vec<(String, u8)>,
    /// Formats not written (their topics dropped, and nothing kept nests them).
    pub formats_dropped: Vec<String>,
    /// Info and multi info keys not written.
    pub info_dropped: Vec<String>,
    /// Info keys whose values were replaced.
    pub info_replaced: Vec<String>,
    /// Logged strings written, and left out (outside the window).
    pub logged: (usize, usize),
    /// Logged strings whose text was changed (anonymized).
    pub logged_changed: usize,
    /// Parameter changes written, moved into the initial parameters (before the window, or
    /// before any message of the output's data section: a subscription, row, logged string
    /// or dropout, which the reader takes a `P` message after to be a change), and left out
    /// (after the window).
    pub parameter_changes: (usize, usize, usize),
    /// Dropouts and syncs left out (outside the window).
    pub dropouts_and_syncs_dropped: usize,
    /// What anonymizing changed (see [`Anonymize`]).
    pub anonymized: Option<anonymize::Anonymized>,
    /// What the reader skipped of the input (damage, unknown messages): not in the output.
    pub skipped: Skipped,
    /// The window asked for (unbounded: every row).
    pub window: Window,
}

/// The output: messages encoded into one buffer, written whole.
struct Output<W: Write> {
    out: io::BufWriter<W>,
    buf: Vec<u8>,
    bytes: u64,
    /// Whether a message of the data section has been written: a parameter message reads
    /// as a change only after one.
    in_data: bool,
}

impl<W: Write> Output<W> {
    fn raw(&mut self, ty: u8, payload: &[u8]) -> Result<(), RewriteError> {
        let size = u16::try_from(payload.len()).map_err(|_| MessageTooLarge {
            ty,
            what: "payload",
            size: payload.len(),
            limit: usize::from(u16::MAX),
        })?;
        let mut header = [0u8; 3];
        header[..2].copy_from_slice(&size.to_le_bytes());
        header[2] = ty;
        self.entered(ty);
        self.write(&header)?;
        self.write(payload)
    }

    /// Notes a message of type `ty` written: the messages the reader starts the data
    /// section at.
    fn entered(&mut self, ty: u8) {
        self.in_data |= matches!(ty, b'A' | b'R' | b'D' | b'L' | b'C' | b'O');
    }

    fn message(&mut self, m: &Message<'_>) -> Result<(), RewriteError> {
        self.buf.clear();
        m.encode(&mut self.buf)?;
        if let Some(&ty) = self.buf.get(2) {
            self.entered(ty);
        }
        let Output {
            out, buf, bytes, ..
        } = self;
        out.write_all(buf).map_err(RewriteError::Write)?;
        *bytes += buf.len() as u64;
        Ok(())
    }

    fn row(&mut self, msg_id: u16, data: &[u8]) -> Result<(), RewriteError> {
        let size = u16::try_from(data.len() + 2).map_err(|_| MessageTooLarge {
            ty: b'D',
            what: "payload",
            size: data.len() + 2,
            limit: usize::from(u16::MAX),
        })?;
        let mut header = [0u8; 5];
        header[..2].copy_from_slice(&size.to_le_bytes());
        header[2] = b'D';
        header[3..].copy_from_slice(&msg_id.to_le_bytes());
        self.in_data = true;
        self.write(&header)?;
        self.write(data)
    }

    #[inline]
    fn write(&mut self, bytes: &[u8]) -> Result<(), RewriteError> {
        self.bytes += bytes.len() as u64;
        self.out.write_all(bytes).map_err(RewriteError::Write)
    }
}

/// A message held until the definitions are written.
struct Held {
    ty: u8,
    payload: Vec<u8>,
}

/// A subscription's state in the pass.
struct SubState {
    kept: bool,
    written: bool,
    /// Index into `Pass::topics`.
    topic: usize,
    /// Transforms that apply: (transform, slot).
    transforms: Vec<(usize, usize)>,
}

/// A topic instance's window admission and counts.
struct Instance {
    report: TopicReport,
    started: bool,
    stopped: bool,
}

/// The state of one rewrite.
struct Pass<'r, W: Write> {
    rules: &'r mut Rewrite,
    out: Output<W>,
    report: Report,
    /// The definitions section (and data-section info before the output's data began).
    held: Vec<Held>,
    /// Whether the definitions were written: the output's data section has begun.
    flushed: bool,
    /// Whether the flag bits were written.
    flag_bits: bool,
    /// Parameter changes before the window, by name: the latest `P` payload.
    folded: Vec<(String, Vec<u8>)>,
    subs: Vec<Option<SubState>>,
    instances: Vec<Instance>,
    /// Per `msg_id`: whether its current subscription was written.
    written_ids: Vec<bool>,
    /// Per `msg_id` the output has subscribed: the topic instance of its last subscription.
    out_subscribed: std::collections::HashMap<u16, (String, u8)>,
    scratch: Vec<u8>,
}

/// Counts bytes read.
struct Counting<R> {
    inner: R,
    read: u64,
}

impl<R: Read> Read for Counting<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read += n as u64;
        Ok(n)
    }
}

impl Rewrite {
    /// No rules: a rewrite that copies every message the reader reads (a clean version-1
    /// log comes out byte for byte; appended data comes out as one data section).
    pub fn new() -> Rewrite {
        Rewrite::default()
    }

    /// Only what lies in this time window (log time, as [`Window`] and `ulog csv` take it):
    /// each topic instance's rows from its first row at or after the start to the last
    /// before its first row at or after the end; logged strings, parameter changes,
    /// dropouts and syncs whose time is in `[start, end)`. The parameters in force at the
    /// start (the initial ones, changed by every change before it) become the initial
    /// parameters, and a subscription none of whose rows is left is not written.
    pub fn window(mut self, window: Window) -> Rewrite {
        self.window = window;
        self
    }

    /// Only these topics (all if empty); their formats and the formats they nest are kept,
    /// other formats dropped.
    pub fn topics(mut self, topics: &[impl AsRef<str>]) -> Rewrite {
        self.keep = topics.iter().map(|t| t.as_ref().to_owned()).collect();
        self
    }

    /// Not these topics: their subscriptions and rows are dropped, and their formats unless
    /// a kept format nests them. The types they nest stay (a topic of that name, which this
    /// does not exclude, may be subscribed later in the log).
    pub fn exclude(mut self, topics: &[impl AsRef<str>]) -> Rewrite {
        self.exclude
            .extend(topics.iter().map(|t| t.as_ref().to_owned()));
        self
    }

    /// Leaves out the info (`I`) and multi info (`M`) values of this key (its name, as
    /// `sys_uuid`).
    pub fn drop_info(mut self, key: &str) -> Rewrite {
        self.drop_info.push(key.to_owned());
        self
    }

    /// Writes this value for the info key instead of the log's (text as `char[N]`, a
    /// number as its type), where the log has the key.
    pub fn replace_info(mut self, key: &str, value: Value) -> Rewrite {
        self.replace_info.push((key.to_owned(), value));
        self
    }

    /// Transforms every row of `topic` (all instances) through its fields by name
    /// ([`RowFields`]).
    pub fn map_rows(mut self, topic: &str, f: impl FnMut(&mut RowFields<'_>) + 'static) -> Rewrite {
        self.transforms.push(Box::new(FieldsMap {
            topic: topic.to_owned(),
            f: Box::new(f),
            indices: Vec::new(),
        }));
        self
    }

    /// Transforms every row of `T`'s topic as a `T` (a derived or generated struct): each
    /// row decoded through the runtime check against the file's format (as reading is),
    /// changed by `f`, and its fields written back where the file's layout has them (what
    /// `T` leaves out stays as it was). A type that does not fit the format is an error at
    /// the topic's first row.
    ///
    /// ```
    /// use ulog_runtime::rewrite::Rewrite;
    /// use ulog_runtime::{Log, ULog, Writer, WriterOptions};
    ///
    /// #[derive(ULog)]
    /// #[ulog(name = "vehicle_local_position")]
    /// struct Local { timestamp: u64, x: f32, y: f32, z: f32, vx: f32 }
    ///
    /// // Only the fields the transform needs: the others stay as the file has them.
    /// #[derive(ULog)]
    /// #[ulog(name = "vehicle_local_position")]
    /// struct Altitude { timestamp: u64, z: f32 }
    ///
    /// let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
    /// let sub = w.topic::<Local>(0)?;
    /// w.write(&sub, &Local { timestamp: 1, x: 1.0, y: 2.0, z: -10.0, vx: 0.5 })?;
    /// let input = w.into_inner();
    ///
    /// let mut out = Vec::new();
    /// Rewrite::new().map(|row: &mut Altitude| row.z -= 5.0).run(&input[..], &mut out)?;
    /// let log = Log::from_vec(out)?;
    /// let row = log.topic::<Local>()?.instance(0)?.next().unwrap();
    /// assert_eq!((row.x, row.y, row.z, row.vx), (1.0, 2.0, -15.0, 0.5));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn map<T: Topic + 'static>(self, f: impl FnMut(&mut T) + 'static) -> Rewrite {
        self.map_as(T::FORMAT.name, f)
    }

    /// [`Rewrite::map`] of the topic named `topic`, read as `T` (one type for topics that
    /// share a layout).
    pub fn map_as<T: Topic + 'static>(
        mut self,
        topic: &str,
        f: impl FnMut(&mut T) + 'static,
    ) -> Rewrite {
        self.transforms.push(Box::new(TypedMap {
            topic: topic.to_owned(),
            f,
            decoders: Vec::new(),
            encoded: Vec::new(),
        }));
        self
    }

    /// Anonymizes the log (see [`Anonymize`] for every field, time and identifier it
    /// changes).
    pub fn anonymize(mut self, anonymize: Anonymize) -> Rewrite {
        self.anonymize = Some(anonymize::Anonymizer::new(anonymize));
        self
    }

    /// Rewrites the log read from `input` into `output`.
    pub fn run(&mut self, input: impl Read, output: impl Write) -> Result<Report, RewriteError> {
        let mut input = Counting {
            inner: input,
            read: 0,
        };
        let mut reader = StreamReader::new(&mut input)?;
        let header = reader.metadata().header();
        if let Some(a) = &mut self.anonymize {
            a.start(reader.metadata());
        }
        let start_timestamp = self.anonymize.as_ref().map_or(header.start_timestamp, |a| {
            a.header_start(header.start_timestamp)
        });
        let window = self.window;
        let mut pass = Pass {
            rules: self,
            out: Output {
                out: io::BufWriter::with_capacity(256 << 10, output),
                buf: Vec::with_capacity(256),
                bytes: 0,
                in_data: false,
            },
            report: Report {
                window,
                ..Report::default()
            },
            held: Vec::new(),
            flushed: false,
            flag_bits: false,
            folded: Vec::new(),
            subs: Vec::new(),
            instances: Vec::new(),
            written_ids: vec![false; 1 << 16],
            out_subscribed: std::collections::HashMap::new(),
            scratch: Vec::new(),
        };
        pass.out.write(
            &FileHeader {
                version: 1,
                start_timestamp,
            }
            .to_bytes(),
        )?;
        reader.for_each_message(|meta, event, raw| {
            let raw = || raw.expect("an event of a message");
            match &event {
                Event::Row(row) => pass.row(row),
                Event::Diagnostic(d) => {
                    pass.report.skipped.add(d);
                    Ok(())
                }
                Event::Subscription(sub) => pass.subscription(sub, meta.schema()),
                Event::Definition { .. } => {
                    let m = raw();
                    pass.definition(m.ty, m.payload, meta.in_data_section())
                }
                Event::Logged(l) => pass.timed(l.timestamp, Timed::Logged, raw(), meta),
                Event::ParameterChange(c) => {
                    pass.timed(c.timestamp, Timed::Change(c.name.clone()), raw(), meta)
                }
                Event::Dropout(d) => pass.timed(d.timestamp, Timed::Dropout, raw(), meta),
                // A sync's time: the latest row's.
                Event::Sync { .. } => pass.timed(meta.last_timestamp(), Timed::Sync, raw(), meta),
            }
        })?;
        pass.flush()?;
        let mut report = pass.finish()?;
        report.bytes_in = input.read;
        Ok(report)
    }

    /// Rewrites the log at `input` into a new file `output` (written whole, then named: a
    /// failure leaves nothing), refusing to write over the input. The folder `output` goes
    /// in is made if it does not exist; a folder at `output` itself is an error
    /// ([`RewriteError::Output`]), as is a file that cannot be made there.
    pub fn run_file(&mut self, input: &Path, output: &Path) -> Result<Report, RewriteError> {
        if same_file(input, output) {
            return Err(RewriteError::SameFile(output.to_owned()));
        }
        let out_error = |source| RewriteError::Output {
            path: output.to_owned(),
            source,
        };
        // Read as it is: the stream reader reads in chunks of its own.
        let file = std::fs::File::open(input).map_err(|e| RewriteError::Read(e.into()))?;
        crate::file_names::prepare_file(output).map_err(out_error)?;
        let partial = crate::file_names::partial_path(output);
        let out = std::fs::File::create(&partial).map_err(out_error)?;
        let result =
            self.run(file, out)
                .and_then(|report| match std::fs::rename(&partial, output) {
                    Ok(()) => Ok(report),
                    Err(e) => Err(out_error(e)),
                });
        if result.is_err() {
            let _ = std::fs::remove_file(&partial);
        }
        result
    }
}

/// Whether two paths name one file (the same file through another path or a hard link
/// included).
fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        ma.dev() == mb.dev() && ma.ino() == mb.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (ma, mb);
        std::fs::canonicalize(a).ok() == std::fs::canonicalize(b).ok()
    }
}

/// A data-section message with a time.
enum Timed {
    Logged,
    Change(String),
    Dropout,
    Sync,
}

impl<W: Write> Pass<'_, W> {
    /// Writes the flag bits (the input's, or default ones) if not yet written.
    fn flag_bits(&mut self, input: Option<&[u8]>) -> Result<(), RewriteError> {
        if self.flag_bits {
            return Ok(());
        }
        self.flag_bits = true;
        let mut bits = match input.map(|p| Message::parse(b'B', p)) {
            Some(Ok(Message::FlagBits(bits))) => bits,
            _ => FlagBits::default(),
        };
        // Appended data comes out as one data section.
        bits.incompat[0] &= !FlagBits::INCOMPAT_DATA_APPENDED;
        bits.appended_offsets = [0; 3];
        self.out.message(&Message::FlagBits(bits))
    }

    fn definition(&mut self, ty: u8, payload: &[u8], in_data: bool) -> Result<(), RewriteError> {
        if ty == b'B' {
            return self.flag_bits(Some(payload));
        }
        self.flag_bits(None)?;
        if ty == b'R' {
            // Unsubscribing a subscription that was written.
            let msg_id = u16::from_le_bytes([payload[0], payload[1]]);
            if self.flushed && self.written_ids[usize::from(msg_id)] {
                self.written_ids[usize::from(msg_id)] = false;
                self.out.raw(ty, payload)?;
            }
            return Ok(());
        }
        if !self.flushed {
            self.held.push(Held {
                ty,
                payload: payload.to_vec(),
            });
            // Without a window to wait for, the data-section info is where the output's
            // data begins.
            if in_data && self.rules.window.start_us.is_none() {
                self.flush()?;
            }
            return Ok(());
        }
        self.kept_message(ty, payload)
    }

    /// Writes an info, multi info, format or parameter message as the rules say.
    fn kept_message(&mut self, ty: u8, payload: &[u8]) -> Result<(), RewriteError> {
        if matches!(ty, b'P' | b'Q') {
            return self.parameter(ty, payload);
        }
        if matches!(ty, b'I' | b'M') {
            let entry = match Message::parse(ty, payload) {
                Ok(Message::Info(kv)) => Some(kv),
                Ok(Message::MultiInfo { entry, .. }) => Some(entry),
                _ => None,
            };
            if let Some(kv) = entry {
                let name = crate::read::key_name(kv);
                if let Some(a) = &mut self.rules.anonymize
                    && ty == b'I'
                {
                    a.observe_info(&name, kv);
                }
                let dropped = self.rules.drop_info.contains(&name)
                    || self
                        .rules
                        .anonymize
                        .as_ref()
                        .is_some_and(|a| a.drops_info(&name, ty));
                if dropped {
                    if !self.report.info_dropped.contains(&name) {
                        self.report.info_dropped.push(name);
                    }
                    return Ok(());
                }
                if ty == b'I'
                    && let Some((key, value)) = self.replacement(&name, kv)?
                {
                    self.report.info_replaced.push(name);
                    return self.out.message(&Message::Info(KeyValue {
                        key: key.as_bytes(),
                        value: &value,
                    }));
                }
            }
        }
        self.out.raw(ty, payload)
    }

    /// Writes a parameter (`P`) or default parameter (`Q`) message, anonymized if the rules
    /// say so.
    fn parameter(&mut self, ty: u8, payload: &[u8]) -> Result<(), RewriteError> {
        match self
            .rules
            .anonymize
            .as_mut()
            .and_then(|a| a.parameter(ty, payload))
        {
            Some(changed) => self.out.raw(ty, &changed),
            None => self.out.raw(ty, payload),
        }
    }

    /// The key text and value to write for an info value a rule replaces.
    fn replacement(
        &mut self,
        name: &str,
        kv: KeyValue<'_>,
    ) -> Result<Option<(String, Vec<u8>)>, RewriteError> {
        let value = match self.rules.replace_info.iter().find(|(k, _)| k == name) {
            Some((_, v)) => v.clone(),
            None => match self.rules.anonymize.as_mut().and_then(|a| a.info(name, kv)) {
                Some(v) => v,
                None => return Ok(None),
            },
        };
        crate::write::key_value(name, &value)
            .map(Some)
            .map_err(|e| RewriteError::InvalidInfo {
                key: name.to_owned(),
                reason: e.to_string(),
            })
    }

    /// Writes the definitions held (the formats the rules keep, the parameters in force at
    /// the window's start) and the info held after them.
    fn flush(&mut self) -> Result<(), RewriteError> {
        if self.flushed {
            return Ok(());
        }
        self.flag_bits(None)?;
        self.flushed = true;
        let held = std::mem::take(&mut self.held);
        let dropped_formats = self.dropped_formats(&held);
        let mut folded = std::mem::take(&mut self.folded);
        let last_param = held.iter().rposition(|h| h.ty == b'P');
        for (i, h) in held.iter().enumerate() {
            match h.ty {
                b'F' => {
                    let name = format_name(&h.payload);
                    if dropped_formats.contains(&name) {
                        continue;
                    }
                    self.out.raw(h.ty, &h.payload)?;
                }
                b'P' => {
                    let name = param_name(&h.payload);
                    match folded.iter().position(|(n, _)| *n == name) {
                        Some(k) => {
                            let (_, payload) = folded.remove(k);
                            self.parameter(b'P', &payload)?;
                        }
                        None => self.parameter(b'P', &h.payload)?,
                    }
                }
                ty => self.kept_message(ty, &h.payload)?,
            }
            // Parameters only changes before the window set: after the initial ones.
            if Some(i) == last_param || (last_param.is_none() && i + 1 == held.len()) {
                for (_, payload) in std::mem::take(&mut folded) {
                    self.parameter(b'P', &payload)?;
                }
            }
        }
        for (_, payload) in folded {
            self.parameter(b'P', &payload)?;
        }
        self.report.formats_dropped = dropped_formats;
        Ok(())
    }

    /// The formats of the held definitions the topic rules drop: those of topics not kept,
    /// unless a kept format nests them. A type that only dropped topics nest stays when the
    /// rules would keep a topic of its name (`exclude` does not name it): a subscription of
    /// that name may come later in the stream, and without its format it could not be read.
    fn dropped_formats(&self, held: &[Held]) -> Vec<String> {
        let formats: Vec<crate::schema::Format> = held
            .iter()
            .filter(|h| h.ty == b'F')
            .filter_map(|h| {
                crate::schema::Format::parse_lax(&String::from_utf8_lossy(&h.payload))
                    .ok()
                    .map(|(f, _)| f)
            })
            .collect();
        // Topics (and unused formats) the rules keep; then everything they nest.
        let mut kept: Vec<&str> = formats
            .iter()
            .map(|f| f.name.as_str())
            .filter(|n| self.topic_kept(n))
            .collect();
        // Everything a kept format nests, transitively.
        let mut i = 0;
        while i < kept.len() {
            let name = kept[i];
            if let Some(f) = formats.iter().find(|f| f.name == name) {
                for field in &f.fields {
                    if let TypeRef::Nested(n) = &field.ty
                        && !kept.contains(&n.as_str())
                    {
                        kept.push(n);
                    }
                }
            }
            i += 1;
        }
        formats
            .iter()
            .map(|f| f.name.clone())
            .filter(|n| !kept.contains(&n.as_str()))
            .collect()
    }

    /// Whether the topic rules keep `name`.
    fn topic_kept(&self, name: &str) -> bool {
        (self.rules.keep.is_empty() || self.rules.keep.iter().any(|k| k == name))
            && !self.rules.exclude.iter().any(|k| k == name)
            && !self
                .rules
                .anonymize
                .as_ref()
                .is_some_and(|a| a.drops_topic(name))
    }

    fn subscription(&mut self, sub: &Subscription, schema: &Schema) -> Result<(), RewriteError> {
        self.flag_bits(None)?;
        // A subscription of a format the log does not define (or cannot lay out) has no row
        // a reader can read: written again, it would make the output invalid. Dropped, and
        // said in the report as a dropped subscription.
        let kept = self.topic_kept(&sub.name) && sub.format().is_some();
        let topic = match self
            .instances
            .iter()
            .position(|i| i.report.name == sub.name && i.report.multi_id == sub.multi_id)
        {
            Some(k) => k,
            None => {
                self.instances.push(Instance {
                    report: TopicReport {
                        name: sub.name.clone(),
                        multi_id: sub.multi_id,
                        ..TopicReport::default()
                    },
                    started: false,
                    stopped: false,
                });
                self.instances.len() - 1
            }
        };
        self.instances[topic].report.kept |= kept;
        let mut transforms = Vec::new();
        if kept {
            for (t, transform) in self.rules.transforms.iter_mut().enumerate() {
                if let Some(slot) = transform.prepare(schema, sub)? {
                    transforms.push((t, slot));
                }
            }
            if let Some(a) = &mut self.rules.anonymize
                && let Some(slot) = a.prepare(schema, sub)?
            {
                transforms.push((usize::MAX, slot));
            }
        }
        if self.subs.len() <= sub.index {
            self.subs.resize_with(sub.index + 1, || None);
        }
        self.subs[sub.index] = Some(SubState {
            kept,
            written: false,
            topic,
            transforms,
        });
        // A new subscription of the msg_id: its earlier one is no longer what rows mean.
        self.written_ids[usize::from(sub.msg_id)] = false;
        if kept && self.rules.window.start_us.is_none() && self.rules.window.end_us.is_none() {
            self.flush()?;
            self.write_subscription(sub.index, sub)?;
        }
        Ok(())
    }

    fn write_subscription(&mut self, index: usize, sub: &Subscription) -> Result<(), RewriteError> {
        let state = self.subs[index].as_mut().expect("registered");
        if state.written {
            return Ok(());
        }
        state.written = true;
        self.written_ids[usize::from(sub.msg_id)] = true;
        // The input subscribing a msg_id again to the same topic instance (a damaged or
        // spliced file) reads as damage; in the output its rows follow the first one, which
        // means the same. (Another topic on a used msg_id is written as the input has it.)
        let instance = (sub.name.clone(), sub.multi_id);
        if self.out_subscribed.get(&sub.msg_id) == Some(&instance) {
            return Ok(());
        }
        self.out_subscribed.insert(sub.msg_id, instance);
        self.out.message(&Message::Subscribe {
            multi_id: sub.multi_id,
            msg_id: sub.msg_id,
            name: sub.name.as_bytes(),
        })
    }

    #[inline]
    fn row(&mut self, row: &crate::Row<'_>) -> Result<(), RewriteError> {
        let Some(Some(state)) = self.subs.get(row.subscription.index) else {
            return Ok(());
        };
        let (kept, topic) = (state.kept, state.topic);
        let inst = &mut self.instances[topic];
        inst.report.rows_in += 1;
        let t = row.timestamp;
        inst.report.span_in = Some(
            inst.report
                .span_in
                .map_or((t, t), |(a, b)| (a.min(t), b.max(t))),
        );
        if !kept {
            return Ok(());
        }
        if inst.stopped {
            return Ok(());
        }
        match self.rules.window.admit(row.timestamp, inst.started) {
            Admit::Skip => return Ok(()),
            Admit::Stop => {
                inst.stopped = true;
                return Ok(());
            }
            Admit::Take => inst.started = true,
        }
        inst.report.rows_out += 1;
        if !self.flushed {
            self.flush()?;
        }
        let state = self.subs[row.subscription.index].as_ref().expect("checked");
        if !state.written {
            self.write_subscription(row.subscription.index, row.subscription)?;
        }
        let state = self.subs[row.subscription.index].as_ref().expect("checked");
        if state.transforms.is_empty() {
            return self.out.row(row.subscription.msg_id, row.data);
        }
        self.scratch.clear();
        self.scratch.extend_from_slice(row.data);
        for &(t, slot) in &state.transforms {
            match t {
                usize::MAX => self.rules.anonymize.as_mut().expect("prepared").apply(
                    slot,
                    &mut self.scratch,
                    row.timestamp,
                ),
                t => self.rules.transforms[t].apply(slot, &mut self.scratch, row.timestamp),
            }
        }
        if self.scratch[..] != *row.data {
            self.instances[topic].report.rows_changed += 1;
        }
        let Pass { out, scratch, .. } = self;
        out.row(row.subscription.msg_id, scratch)
    }

    /// Whether time `t` is in the window.
    fn in_window(&self, t: u64) -> bool {
        let t = t as f64;
        self.rules.window.start_us.is_none_or(|s| t >= s)
            && self.rules.window.end_us.is_none_or(|e| t < e)
    }

    fn timed(
        &mut self,
        t: u64,
        what: Timed,
        raw: RawMessage<'_>,
        meta: &crate::read::Metadata,
    ) -> Result<(), RewriteError> {
        let (ty, payload, in_data) = (raw.ty, raw.payload, meta.in_data_section());
        self.flag_bits(None)?;
        let before = self.rules.window.start_us.is_some_and(|s| (t as f64) < s);
        match what {
            Timed::Change(name) if before => {
                match self.folded.iter_mut().find(|(n, _)| *n == name) {
                    Some((_, p)) => *p = payload.to_vec(),
                    None => self.folded.push((name, payload.to_vec())),
                }
                self.report.parameter_changes.1 += 1;
                return Ok(());
            }
            Timed::Sync if !in_data && !self.flushed => {
                // A sync among the definitions, where the input has it.
                if self.rules.window.start_us.is_none() {
                    self.held.push(Held {
                        ty,
                        payload: payload.to_vec(),
                    });
                }
                return Ok(());
            }
            _ => {}
        }
        if !self.in_window(t) {
            match what {
                Timed::Logged => self.report.logged.1 += 1,
                Timed::Change(_) => self.report.parameter_changes.2 += 1,
                Timed::Dropout | Timed::Sync => self.report.dropouts_and_syncs_dropped += 1,
            }
            return Ok(());
        }
        self.flush()?;
        match what {
            Timed::Logged => {
                self.report.logged.0 += 1;
                if let Some(a) = &mut self.rules.anonymize
                    && let Some(changed) = a.logged(ty, payload)
                {
                    self.report.logged_changed += 1;
                    return self.out.raw(ty, &changed);
                }
            }
            // Before the output's data section, a parameter message is an initial
            // parameter to a reader (the input's data section began with something not
            // written, such as rows of no subscription): said so.
            Timed::Change(_) if !self.out.in_data => {
                self.report.parameter_changes.1 += 1;
                return self.parameter(ty, payload);
            }
            Timed::Change(_) => {
                self.report.parameter_changes.0 += 1;
                return self.parameter(ty, payload);
            }
            Timed::Dropout | Timed::Sync => {}
        }
        self.out.raw(ty, payload)
    }

    fn finish(mut self) -> Result<Report, RewriteError> {
        self.out.out.flush().map_err(RewriteError::Write)?;
        let mut report = self.report;
        report.bytes_out = self.out.bytes;
        for inst in &self.instances {
            if inst.report.rows_in > 0 {
                report.topics.push(inst.report.clone());
            }
        }
        for state in self.subs.iter().flatten() {
            if !state.written {
                let r = &self.instances[state.topic].report;
                report
                    .subscriptions_dropped
                    .push((r.name.clone(), r.multi_id));
            }
        }
        report.anonymized = self.rules.anonymize.as_ref().map(|a| a.report());
        Ok(report)
    }
}

/// The name of a format message (`name:...`).
fn format_name(payload: &[u8]) -> String {
    let end = payload
        .iter()
        .position(|&c| c == b':')
        .unwrap_or(payload.len());
    String::from_utf8_lossy(&payload[..end]).into_owned()
}

/// The name of a parameter message.
fn param_name(payload: &[u8]) -> String {
    match Message::parse(b'P', payload) {
        Ok(Message::Parameter(kv)) => crate::read::key_name(kv),
        _ => String::new(),
    }
}

impl Report {
    /// Rows read and rows written, over every topic instance.
    pub fn rows(&self) -> (usize, usize) {
        self.topics
            .iter()
            .fold((0, 0), |(a, b), t| (a + t.rows_in, b + t.rows_out))
    }

    /// When the window left out every row of the topics kept, though they have rows: where
    /// those rows lie, their smallest and largest timestamp (µs). A window given in the
    /// wrong clock (seconds since boot for a log whose timestamps are dates) shows here.
    pub fn window_missed(&self) -> Option<(u64, u64)> {
        let kept = self.topics.iter().filter(|t| t.kept);
        let (rows_in, rows_out) = kept
            .clone()
            .fold((0, 0), |(a, b), t| (a + t.rows_in, b + t.rows_out));
        if !self.window.is_bounded() || rows_in == 0 || rows_out > 0 {
            return None;
        }
        let spans = kept.filter_map(|t| t.span_in);
        let first = spans.clone().map(|(a, _)| a).min()?;
        let last = spans.map(|(_, b)| b).max()?;
        Some((first, last))
    }
}

/// What a rewrite did, in lines for people: the bytes, every topic instance that lost or
/// changed rows, what was left out, and what anonymizing changed.
impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let list = |items: &[String]| items.join(", ");
        writeln!(
            f,
            "{} bytes read, {} written",
            self.bytes_in, self.bytes_out
        )?;
        let (rows_in, rows_out) = self.rows();
        writeln!(
            f,
            "rows: {rows_out} of {rows_in} written, {} topic instances",
            self.topics.len()
        )?;
        if let Some((first, last)) = self.window_missed() {
            writeln!(
                f,
                "  no row of the topics kept lies in the window {}: their rows run from {} s \
                 to {} s",
                self.window,
                first as f64 / 1e6,
                last as f64 / 1e6
            )?;
        }
        // One line per instance partly written or changed; those left out whole are
        // counted in one line (and named under "subscriptions not written").
        let (mut none, mut none_rows) = (0, 0);
        for t in self
            .topics
            .iter()
            .filter(|t| t.rows_out == 0 && t.rows_in > 0)
        {
            none += 1;
            none_rows += t.rows_in;
        }
        for t in self
            .topics
            .iter()
            .filter(|t| (t.rows_out > 0 && t.rows_out != t.rows_in) || t.rows_changed > 0)
        {
            write!(
                f,
                "  {} #{}: {} of {} rows",
                t.name, t.multi_id, t.rows_out, t.rows_in
            )?;
            if t.rows_changed > 0 {
                write!(f, ", {} changed", t.rows_changed)?;
            }
            writeln!(f)?;
        }
        if none > 0 {
            writeln!(
                f,
                "  {none} topic instance{} left out whole ({none_rows} rows)",
                if none == 1 { "" } else { "s" }
            )?;
        }
        // Subscriptions and formats: the first few by name, then how many more (a window
        // before every row drops them all).
        let named = |items: Vec<String>| {
            const NAMED: usize = 8;
            let more = items.len().saturating_sub(NAMED);
            let mut text = list(&items[..items.len().min(NAMED)]);
            if more > 0 {
                text += &format!(" and {more} more");
            }
            text
        };
        if !self.subscriptions_dropped.is_empty() {
            let subs = self
                .subscriptions_dropped
                .iter()
                .map(|(t, m)| format!("{t} #{m}"))
                .collect();
            writeln!(f, "subscriptions not written: {}", named(subs))?;
        }
        if !self.formats_dropped.is_empty() {
            writeln!(
                f,
                "formats not written: {}",
                named(self.formats_dropped.clone())
            )?;
        }
        if !self.info_dropped.is_empty() {
            writeln!(f, "info left out: {}", list(&self.info_dropped))?;
        }
        if !self.info_replaced.is_empty() {
            writeln!(f, "info replaced: {}", list(&self.info_replaced))?;
        }
        let (kept, left) = self.logged;
        write!(f, "logged strings: {kept} written, {left} left out")?;
        if self.logged_changed > 0 {
            write!(
                f,
                ", {} with dates or times made zeros",
                self.logged_changed
            )?;
        }
        writeln!(f)?;
        let (kept, moved, left) = self.parameter_changes;
        writeln!(
            f,
            "parameter changes: {kept} written, {moved} moved into the initial parameters, {left} left out"
        )?;
        if self.dropouts_and_syncs_dropped > 0 {
            writeln!(
                f,
                "dropouts and syncs outside the window: {} left out",
                self.dropouts_and_syncs_dropped
            )?;
        }
        if let Some(a) = &self.anonymized {
            match a.target {
                Some((lat, lon)) => write!(f, "anonymized: positions moved to {lat:.6}, {lon:.6}")?,
                None => write!(f, "anonymized: no position found")?,
            }
            writeln!(
                f,
                " (altitudes {:+} m, times {:+.3} days)",
                a.altitude_offset_m,
                a.time_offset_us as f64 / 86_400e6
            )?;
            for (topic, field, rows) in &a.fields {
                writeln!(f, "  {topic} {field}: {rows} rows")?;
            }
        }
        if !self.skipped.is_empty() {
            let s = &self.skipped;
            writeln!(
                f,
                "skipped in the input (not in the output): {} damaged bytes, {} rows that do not fit their format, {} rows of no subscription, {} unusable messages",
                s.damaged_bytes,
                s.misfit_rows.iter().map(|m| m.2).sum::<usize>(),
                s.orphan_rows,
                s.unusable_messages
            )?;
            for (topic, msg_id, why) in &s.unreadable_topics {
                writeln!(
                    f,
                    "  `{topic}` (msg_id {msg_id}) cannot be read, left out with its rows: {why}"
                )?;
            }
        }
        Ok(())
    }
}
