//! Writing ULog files (format version 1): header and flag bits, formats (each once), info,
//! multi info, parameters and defaults, subscriptions, data rows, logged and tagged strings,
//! sync and dropout messages, and appending to an existing file.
//!
//! Every call checks its input before writing a byte, so misuse is an error value and the file
//! stays valid; every message is written with one `write_all`, so a file cut by a crash reads
//! back up to its last complete message.

use std::io::{self, Write};

use crate::read::ParamValue;
use crate::read::{
    FLAG_BITS_LEN, FileHeader, FlagBits, HEADER_LEN, KeyValue, Message, MessageTooLarge,
};
use crate::schema::{Format, FormatError, FormatId, LayoutError, Primitive, Redefinition, Schema};
use crate::typed::{Topic, ULog, encode_row};
use crate::value::{Scalar, Value};

#[cfg(test)]
mod tests;

crate::error::debug_as_display!(WriteError);

/// Why a write was refused (nothing was written) or failed.
#[derive(thiserror::Error)]
#[non_exhaustive]
pub enum WriteError {
    /// Writing to the output failed.
    #[error("I/O error: {0}")]
    Io(#[from] io::Error),
    /// A format string that does not follow the grammar.
    #[error("invalid format `{text}`: {error}")]
    InvalidFormat {
        /// The format string.
        text: String,
        /// Why.
        error: FormatError,
    },
    /// A second, different format under a name already written.
    #[error(transparent)]
    Redefinition(#[from] Redefinition),
    /// A subscription to a format that was never written.
    #[error("no format named `{0}` was written; write it (and the formats it nests) first")]
    UnknownFormat(String),
    /// A subscription to a format whose layout cannot be resolved (a nested type missing...).
    #[error("format `{format}` cannot be subscribed: {error}")]
    Layout {
        /// The format.
        format: String,
        /// Why.
        error: LayoutError,
    },
    /// Data for a subscription this writer did not make.
    #[error("no subscription with msg_id {0}")]
    NotSubscribed(u16),
    /// A data row whose length does not fit its format.
    #[error("{}", row_size_text(.topic, *.len, *.min, *.max))]
    RowSize {
        /// The topic.
        topic: String,
        /// The row's length.
        len: usize,
        /// Size without trailing padding.
        min: usize,
        /// Full size.
        max: usize,
    },
    /// A new format after the data section began (at the first row, logged string or other
    /// data message): pyulog and PX4 tools would not see it.
    #[error(
        "format `{0}` comes too late: formats must be written before the first data row or \
         logged string (readers ignore them in the data section); declare every topic \
         (`Writer::topic`) or type (`Writer::define`) before writing rows"
    )]
    DefinitionsClosed(String),
    /// A sync or dropout before any subscription or logged string: readers take the data
    /// section to begin with one of those (pyulog skips a sync or dropout before it).
    #[error(
        "{0} belongs to the data section, which begins with the first subscription or logged \
         string: subscribe a topic or log a string first (readers skip it before one)"
    )]
    NoDataSection(&'static str),
    /// A second subscription of a topic instance already subscribed (and not unsubscribed):
    /// readers would not know which rows are the instance's.
    #[error(
        "`{topic}` instance {multi_id} is already subscribed (msg_id {msg_id}); write its rows \
         through that subscription, or give this one another multi_id"
    )]
    AlreadySubscribed {
        /// The topic.
        topic: String,
        /// The instance.
        multi_id: u8,
        /// The subscription it has.
        msg_id: u16,
    },
    /// All 65,536 `msg_id`s are used.
    #[error("all 65536 msg_ids are used")]
    TooManySubscriptions,
    /// A message or key too large for its length field.
    #[error(transparent)]
    TooLarge(#[from] MessageTooLarge),
    /// A key or value that cannot be written.
    #[error("invalid `{key}`: {reason}")]
    InvalidValue {
        /// The key.
        key: String,
        /// Why.
        reason: String,
    },
    /// A default parameter in a file whose flag bits do not announce them.
    #[error(
        "default parameters need `WriterOptions::default_parameters` (the flag bits announce them)"
    )]
    DefaultParametersNotDeclared,
    /// Appending to a file that cannot take appended data.
    #[error("cannot append: {0}")]
    CannotAppend(String),
}

/// `` `battery` rows are 31 bytes, got 3 ``, or `36 to 40 bytes` where the format's
/// trailing padding may be left out.
fn row_size_text(topic: &str, len: usize, min: usize, max: usize) -> String {
    if min == max {
        format!("`{topic}` rows are {max} bytes, got {len}")
    } else {
        format!(
            "`{topic}` rows are {min} to {max} bytes (the trailing padding may be left out), got {len}"
        )
    }
}

/// How a new file starts.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WriterOptions {
    /// Start of logging, in microseconds (the header's timestamp).
    pub start_timestamp: u64,
    /// Whether the file will hold default parameters (`Q`): sets the compat flag bit.
    pub default_parameters: bool,
}

/// A subscription made by [`Writer::subscribe`]: the `msg_id` its rows carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SubscriptionId(pub u16);

/// A subscription of a typed topic made by [`Writer::topic`]; [`Writer::write`] takes rows of
/// type `T` for it.
pub struct TypedSubscription<T> {
    id: SubscriptionId,
    multi_id: u8,
    _type: std::marker::PhantomData<fn(&T)>,
}

impl<T> TypedSubscription<T> {
    /// The `msg_id` its rows carry.
    pub fn id(&self) -> SubscriptionId {
        self.id
    }

    /// The instance number.
    pub fn multi_id(&self) -> u8 {
        self.multi_id
    }
}

impl<T> Clone for TypedSubscription<T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for TypedSubscription<T> {}

impl<T> std::fmt::Debug for TypedSubscription<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TypedSubscription")
            .field("id", &self.id)
            .field("multi_id", &self.multi_id)
            .finish()
    }
}

#[derive(Debug, Clone)]
struct Subscribed {
    topic: String,
    min: usize,
    max: usize,
}

/// Writes a ULog file to any `io::Write` (wrap files in `io::BufWriter`).
///
/// A file has two sections: the definitions (formats, info, initial parameters) and the data
/// (subscriptions, rows, logged strings, parameter changes). Subscriptions made while the
/// definitions are open wait to be written until the data begins (the first row, logged
/// string, parameter change, dropout, sync or unsubscription, or [`Writer::flush`]), so
/// several topics can be declared, in any order, before the first row.
///
/// ```
/// use ulog_runtime::write::{Writer, WriterOptions};
/// let mut w = Writer::new(Vec::new(), WriterOptions { start_timestamp: 1_000, ..Default::default() })?;
/// w.format("t:uint64_t timestamp;float x;")?;
/// w.info("sys_name", &ulog_runtime::Value::String("rover".into()))?;
/// let t = w.subscribe("t", 0)?;
/// let mut row = 2_000u64.to_le_bytes().to_vec();
/// row.extend_from_slice(&1.5f32.to_le_bytes());
/// w.data(t, &row)?;
/// let bytes = w.into_inner();
/// let log = ulog_runtime::Log::from_slice(&bytes).unwrap();
/// assert_eq!(log.row_count(), 1);
/// # Ok::<(), ulog_runtime::write::WriteError>(())
/// ```
#[derive(Debug)]
pub struct Writer<W: Write> {
    /// Always `Some` but in `into_inner` (taken there, so that `Drop` finds nothing to do).
    out: Option<W>,
    schema: Schema,
    subscriptions: Vec<Option<Subscribed>>,
    /// The topic instances subscribed by this writer and not unsubscribed, and their
    /// `msg_id`s: a second subscription of one is refused.
    active: std::collections::HashMap<(String, u8), u16>,
    next_msg_id: u32,
    default_parameters: bool,
    /// Whether the data section has begun (the file has an `A`, `L` or `C`, or a row):
    /// formats can no longer be written.
    data_section: bool,
    /// Subscriptions made while the definitions were open, written when the data begins.
    pending: Vec<(SubscriptionId, u8)>,
    buf: Vec<u8>,
    row: Vec<u8>,
}

impl<W: Write> Writer<W> {
    /// Starts a file: the 16-byte header (version 1) and the flag bits.
    pub fn new(out: W, options: WriterOptions) -> Result<Writer<W>, WriteError> {
        let mut w = Writer {
            out: Some(out),
            schema: Schema::new(),
            subscriptions: Vec::new(),
            active: std::collections::HashMap::new(),
            next_msg_id: 0,
            default_parameters: options.default_parameters,
            data_section: false,
            pending: Vec::new(),
            buf: Vec::with_capacity(256),
            row: Vec::with_capacity(256),
        };
        let header = FileHeader {
            version: 1,
            start_timestamp: options.start_timestamp,
        };
        w.out().write_all(&header.to_bytes())?;
        let mut bits = FlagBits::default();
        if options.default_parameters {
            bits.compat[0] |= FlagBits::COMPAT_DEFAULT_PARAMETERS;
        }
        w.put(Message::FlagBits(bits))?;
        Ok(w)
    }

    fn out(&mut self) -> &mut W {
        self.out
            .as_mut()
            .expect("the output is taken only by into_inner")
    }

    /// The output.
    pub fn get_ref(&self) -> &W {
        self.out
            .as_ref()
            .expect("the output is taken only by into_inner")
    }

    /// Writes the subscriptions still waiting (see [`Writer`]), flushes, and returns the
    /// output. Errors are ignored here; call [`Writer::flush`] first to see them.
    pub fn into_inner(mut self) -> W {
        let _ = self.flush();
        self.out.take().expect("the output is taken only here")
    }

    /// Writes the subscriptions still waiting (see [`Writer`]) and flushes the output.
    /// Without any, the definitions stay open.
    pub fn flush(&mut self) -> Result<(), WriteError> {
        if !self.pending.is_empty() {
            self.begin_data()?;
        }
        Ok(self.out().flush()?)
    }

    /// The formats written so far.
    pub fn schema(&self) -> &Schema {
        &self.schema
    }

    fn put(&mut self, m: Message<'_>) -> Result<(), WriteError> {
        self.buf.clear();
        m.encode(&mut self.buf)?;
        let Writer { out, buf, .. } = self;
        out.as_mut()
            .expect("the output is taken only by into_inner")
            .write_all(buf)?;
        Ok(())
    }

    /// Ends the definitions section: the waiting subscriptions go out, in `msg_id` order.
    fn begin_data(&mut self) -> Result<(), WriteError> {
        self.data_section = true;
        for (id, multi_id) in std::mem::take(&mut self.pending) {
            let topic = self.subscriptions[usize::from(id.0)]
                .as_ref()
                .expect("pending subscriptions are registered")
                .topic
                .clone();
            self.put(Message::Subscribe {
                multi_id,
                msg_id: id.0,
                name: topic.as_bytes(),
            })?;
        }
        Ok(())
    }

    /// Writes a format definition (`F`) from its string, e.g.
    /// `vehicle_attitude:uint64_t timestamp;float[4] q;`. A format already written with the
    /// same definition is not written again; a different one under the same name is refused.
    /// Formats belong to the definitions section: a new one once the data has begun (see
    /// [`Writer`]) is refused ([`WriteError::DefinitionsClosed`]).
    pub fn format(&mut self, text: &str) -> Result<FormatId, WriteError> {
        let format = Format::parse(text).map_err(|error| WriteError::InvalidFormat {
            text: text.to_owned(),
            error,
        })?;
        self.write_format(format)
    }

    /// Writes a format definition (`F`); see [`Writer::format`].
    pub fn write_format(&mut self, format: Format) -> Result<FormatId, WriteError> {
        if let Some(id) = self.schema.id(&format.name) {
            if *self.schema.format(id) == format {
                return Ok(id);
            }
        } else if self.data_section {
            return Err(WriteError::DefinitionsClosed(format.name));
        }
        let text = format.to_string();
        let id = self.schema.insert(format)?;
        self.put(Message::Format(text.as_bytes()))?;
        Ok(id)
    }

    /// Writes an info value (`I`): text as `char[N]`, a scalar as its type, an array of one
    /// basic type as `type[N]`. Keys are unique in a file; a later value replaces the earlier.
    pub fn info(&mut self, key: &str, value: &Value) -> Result<(), WriteError> {
        let (key_text, bytes) = key_value(key, value)?;
        self.put(Message::Info(KeyValue {
            key: key_text.as_bytes(),
            value: &bytes,
        }))
    }

    /// Writes one part of a multi info value (`M`); `continued` appends it to the previous
    /// part of the same key.
    pub fn multi_info(
        &mut self,
        key: &str,
        value: &Value,
        continued: bool,
    ) -> Result<(), WriteError> {
        let (key_text, bytes) = key_value(key, value)?;
        self.put(Message::MultiInfo {
            continued,
            entry: KeyValue {
                key: key_text.as_bytes(),
                value: &bytes,
            },
        })
    }

    /// Writes a parameter (`P`): its initial value before the first subscription, a change
    /// after (a change begins the data section, see [`Writer`]).
    pub fn parameter(&mut self, name: &str, value: ParamValue) -> Result<(), WriteError> {
        let (key_text, bytes) = param_key_value(name, value)?;
        let m = Message::Parameter(KeyValue {
            key: key_text.as_bytes(),
            value: &bytes,
        });
        if self.pending.is_empty() {
            self.put(m)
        } else {
            self.put_in_data(m)
        }
    }

    /// Writes a default parameter (`Q`); `default_types` bit 0: system default, bit 1: default
    /// of the current configuration (at least one set). The file must have been started with
    /// [`WriterOptions::default_parameters`].
    pub fn default_parameter(
        &mut self,
        name: &str,
        value: ParamValue,
        default_types: u8,
    ) -> Result<(), WriteError> {
        if !self.default_parameters {
            return Err(WriteError::DefaultParametersNotDeclared);
        }
        if !(1..=3).contains(&default_types) {
            return Err(WriteError::InvalidValue {
                key: name.to_owned(),
                reason: format!("default_types {default_types} must set bit 0, bit 1 or both"),
            });
        }
        let (key_text, bytes) = param_key_value(name, value)?;
        self.put(Message::DefaultParameter {
            default_types,
            entry: KeyValue {
                key: key_text.as_bytes(),
                value: &bytes,
            },
        })
    }

    /// Subscribes a written format (`A`) as instance `multi_id`; the format and the formats it
    /// nests must have been written. `msg_id`s are given in increasing order from 0. While
    /// the definitions are open the subscription waits, and goes out when the data begins
    /// (see [`Writer`]). A topic instance already subscribed, and not unsubscribed, is
    /// refused ([`WriteError::AlreadySubscribed`]): pyulog would read its rows as two
    /// datasets of one name and `multi_id`.
    pub fn subscribe(&mut self, format: &str, multi_id: u8) -> Result<SubscriptionId, WriteError> {
        let id = self
            .schema
            .id(format)
            .ok_or_else(|| WriteError::UnknownFormat(format.to_owned()))?;
        let layout = self.schema.layout(id).map_err(|error| WriteError::Layout {
            format: format.to_owned(),
            error,
        })?;
        let (min, max) = (layout.payload_size, layout.size);
        if let Some(&msg_id) = self.active.get(&(format.to_owned(), multi_id)) {
            return Err(WriteError::AlreadySubscribed {
                topic: format.to_owned(),
                multi_id,
                msg_id,
            });
        }
        let msg_id =
            u16::try_from(self.next_msg_id).map_err(|_| WriteError::TooManySubscriptions)?;
        if self.data_section {
            self.put(Message::Subscribe {
                multi_id,
                msg_id,
                name: format.as_bytes(),
            })?;
        } else {
            self.pending.push((SubscriptionId(msg_id), multi_id));
        }
        self.next_msg_id += 1;
        self.active.insert((format.to_owned(), multi_id), msg_id);
        self.subscriptions.push(Some(Subscribed {
            topic: format.to_owned(),
            min,
            max,
        }));
        Ok(SubscriptionId(msg_id))
    }

    /// Writes the formats of a [`ULog`] type (nested ones first, each once) without
    /// subscribing it. [`Writer::topic`] does this itself; formats must all be written
    /// before the data begins (the first row or logged string).
    ///
    /// ```
    /// # use ulog_runtime::{ULog, Writer, WriterOptions};
    /// # #[derive(ULog)] struct Gps { timestamp: u64, alt: f32 }
    /// let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
    /// w.define::<Gps>()?;
    /// let gps = w.topic::<Gps>(0)?;
    /// # Ok::<(), ulog_runtime::WriteError>(())
    /// ```
    pub fn define<T: ULog>(&mut self) -> Result<FormatId, WriteError> {
        self.define_as::<T>(T::FORMAT.name)
    }

    /// [`Writer::define`] with `T`'s format under the topic name `topic` (its nested formats
    /// keep their names): one type for topics that share a layout.
    pub fn define_as<T: ULog>(&mut self, topic: &str) -> Result<FormatId, WriteError> {
        let mut last = None;
        for format in T::FORMAT.formats_as(topic) {
            last = Some(self.write_format(format)?);
        }
        Ok(last.expect("a format lists itself"))
    }

    /// Subscribes a typed topic as instance `multi_id`, writing its formats first (nested ones
    /// included, each once per file). Several topics can be declared before the first row:
    /// their formats go out at once, their subscriptions when the data begins. A different
    /// format already written under one of its names is refused, and so is a new format
    /// once the data has begun ([`WriteError::DefinitionsClosed`]).
    ///
    /// ```
    /// use ulog_runtime::{Chars, ULog, Writer, WriterOptions};
    ///
    /// #[derive(ULog, Clone, Copy)]
    /// struct Cell { voltage: f32, #[ulog(padding)] _pad: [u8; 4] }
    ///
    /// #[derive(ULog)]
    /// #[ulog(name = "battery_status")]
    /// struct Battery { timestamp: u64, cells: [Cell; 2], id: Chars<4> }
    ///
    /// #[derive(ULog)]
    /// struct Gps { timestamp: u64, alt: f32 }
    ///
    /// let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
    /// let first = w.topic::<Battery>(0)?;
    /// let second = w.topic::<Battery>(1)?;
    /// let gps = w.topic::<Gps>(0)?;
    /// let cells = [Cell { voltage: 3.9, _pad: [0; 4] }; 2];
    /// w.write(&first, &Battery { timestamp: 1, cells, id: Chars::new("A").unwrap() })?;
    /// w.write(&second, &Battery { timestamp: 2, cells, id: Chars::new("B").unwrap() })?;
    /// w.write(&gps, &Gps { timestamp: 3, alt: 488.0 })?;
    /// let log = ulog_runtime::Log::from_vec(w.into_inner())?;
    /// let f = log.metadata().schema().get("battery_status").unwrap();
    /// assert_eq!(f.to_string(), "battery_status:uint64_t timestamp;cell[2] cells;char[4] id;");
    /// assert_eq!(log.topic::<Battery>()?.multi_ids(), [0, 1]);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn topic<T: Topic>(&mut self, multi_id: u8) -> Result<TypedSubscription<T>, WriteError> {
        self.topic_as::<T>(T::FORMAT.name, multi_id)
    }

    /// [`Writer::topic`] under the topic name `topic`: `T`'s layout written and subscribed
    /// as that topic (PX4 logs one layout under several names, e.g. `vehicle_attitude` and
    /// `estimator_attitude`; see [`Log::topic_as`](crate::Log::topic_as)).
    pub fn topic_as<T: Topic>(
        &mut self,
        topic: &str,
        multi_id: u8,
    ) -> Result<TypedSubscription<T>, WriteError> {
        self.define_as::<T>(topic)?;
        let id = self.subscribe(topic, multi_id)?;
        Ok(TypedSubscription {
            id,
            multi_id,
            _type: std::marker::PhantomData,
        })
    }

    /// Writes one typed data row (`D`), without its trailing padding as PX4 writes it.
    pub fn write<T: Topic>(
        &mut self,
        sub: &TypedSubscription<T>,
        value: &T,
    ) -> Result<(), WriteError> {
        let mut row = std::mem::take(&mut self.row);
        row.clear();
        encode_row(value, &mut row);
        let result = self.data(sub.id, &row);
        self.row = row;
        result
    }

    /// Marks a subscription as no longer logged (`R`); its topic instance can be subscribed
    /// again.
    pub fn unsubscribe(&mut self, id: SubscriptionId) -> Result<(), WriteError> {
        self.subscription(id)?;
        self.begin_data()?;
        self.put(Message::Unsubscribe { msg_id: id.0 })?;
        self.active.retain(|_, msg_id| *msg_id != id.0);
        Ok(())
    }

    fn subscription(&self, id: SubscriptionId) -> Result<&Subscribed, WriteError> {
        self.subscriptions
            .get(usize::from(id.0))
            .and_then(Option::as_ref)
            .ok_or(WriteError::NotSubscribed(id.0))
    }

    /// Writes a data row (`D`): the packed little-endian fields, with or without the trailing
    /// padding.
    pub fn data(&mut self, id: SubscriptionId, row: &[u8]) -> Result<(), WriteError> {
        let sub = self.subscription(id)?;
        if !(sub.min..=sub.max).contains(&row.len()) {
            return Err(WriteError::RowSize {
                topic: sub.topic.clone(),
                len: row.len(),
                min: sub.min,
                max: sub.max,
            });
        }
        if !self.data_section {
            self.begin_data()?;
        }
        self.put(Message::Data {
            msg_id: id.0,
            data: row,
        })
    }

    /// Writes a logged string (`L`): `level` a [`LogLevel`](crate::read::LogLevel), written
    /// as the ASCII digit PX4 writes (`LogLevel::Info` is `b'6'`), or the raw byte of another
    /// writer's level.
    ///
    /// ```
    /// use ulog_runtime::{LogLevel, Writer, WriterOptions};
    /// let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
    /// w.log(LogLevel::Warning, 1_000, "low battery")?;
    /// w.log(b'6', 2_000, "a raw level byte")?;
    /// let log = ulog_runtime::Log::from_vec(w.into_inner())?;
    /// let levels: Vec<_> = log.logged_messages().iter().map(|m| m.level()).collect();
    /// assert_eq!(levels, [Some(LogLevel::Warning), Some(LogLevel::Info)]);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn log(
        &mut self,
        level: impl Into<u8>,
        timestamp: u64,
        text: &str,
    ) -> Result<(), WriteError> {
        self.put_in_data(Message::Logging {
            level: level.into(),
            tag: None,
            timestamp,
            text: text.as_bytes(),
        })
    }

    /// Writes a tagged logged string (`C`); `level` as for [`Writer::log`].
    pub fn log_tagged(
        &mut self,
        level: impl Into<u8>,
        tag: u16,
        timestamp: u64,
        text: &str,
    ) -> Result<(), WriteError> {
        self.put_in_data(Message::Logging {
            level: level.into(),
            tag: Some(tag),
            timestamp,
            text: text.as_bytes(),
        })
    }

    /// Writes a sync message (`S`), which lets readers recover from corruption. It belongs
    /// to the data section: before any subscription or logged string it is refused
    /// ([`WriteError::NoDataSection`]).
    pub fn sync(&mut self) -> Result<(), WriteError> {
        self.data_section_for("a sync message")?;
        self.put_in_data(Message::Sync)
    }

    /// Writes a dropout (`O`) of `duration_ms` milliseconds. It belongs to the data section:
    /// before any subscription or logged string it is refused
    /// ([`WriteError::NoDataSection`]).
    pub fn dropout(&mut self, duration_ms: u16) -> Result<(), WriteError> {
        self.data_section_for("a dropout")?;
        self.put_in_data(Message::Dropout { duration_ms })
    }

    /// Refuses a message that cannot begin the data section for readers before it has begun.
    fn data_section_for(&self, what: &'static str) -> Result<(), WriteError> {
        if !self.data_section && self.pending.is_empty() {
            return Err(WriteError::NoDataSection(what));
        }
        Ok(())
    }

    /// Writes a message of the data section, beginning it if needed; a message that cannot
    /// be encoded is refused before anything is written.
    fn put_in_data(&mut self, m: Message<'_>) -> Result<(), WriteError> {
        if self.pending.is_empty() {
            // Refused (too large) before anything is written, and before the definitions
            // close.
            self.put(m)?;
            self.data_section = true;
            return Ok(());
        }
        let mut bytes = Vec::new();
        m.encode(&mut bytes)?;
        self.begin_data()?;
        self.out().write_all(&bytes)?;
        Ok(())
    }
}

/// The key text and value bytes of an info value.
pub(crate) fn key_value(key: &str, value: &Value) -> Result<(String, Vec<u8>), WriteError> {
    let invalid = |reason: &str| WriteError::InvalidValue {
        key: key.to_owned(),
        reason: reason.to_owned(),
    };
    if key.is_empty() || !key.bytes().all(|c| c.is_ascii_graphic()) {
        return Err(invalid("keys are visible ASCII characters, at least one"));
    }
    let mut bytes = Vec::new();
    let ty = match value {
        Value::String(s) => {
            bytes.extend_from_slice(s.as_bytes());
            format!("char[{}]", s.len())
        }
        Value::Scalar(s) => {
            push_scalar(&mut bytes, *s);
            s.primitive().to_string()
        }
        Value::Array(items) => {
            let mut primitive = None;
            for item in items {
                let Value::Scalar(s) = item else {
                    return Err(invalid("array values must be basic values"));
                };
                if *primitive.get_or_insert(s.primitive()) != s.primitive() {
                    return Err(invalid("array values must all have one type"));
                }
                push_scalar(&mut bytes, *s);
            }
            format!("{}[{}]", primitive.unwrap_or(Primitive::UInt8), items.len())
        }
        Value::Bytes(raw) => {
            bytes.extend_from_slice(raw);
            format!("uint8_t[{}]", raw.len())
        }
        Value::Struct(_) => return Err(invalid("info values are basic values, arrays or text")),
    };
    Ok((format!("{ty} {key}"), bytes))
}

fn param_key_value(name: &str, value: ParamValue) -> Result<(String, Vec<u8>), WriteError> {
    let scalar = match value {
        ParamValue::Int32(v) => Scalar::Int32(v),
        ParamValue::Float(v) => Scalar::Float(v),
    };
    key_value(name, &Value::Scalar(scalar))
}

/// Appends a scalar's little-endian bytes.
pub(crate) fn push_scalar(out: &mut Vec<u8>, s: Scalar) {
    match s {
        Scalar::Int8(v) => out.extend_from_slice(&v.to_le_bytes()),
        Scalar::UInt8(v) => out.push(v),
        Scalar::Int16(v) => out.extend_from_slice(&v.to_le_bytes()),
        Scalar::UInt16(v) => out.extend_from_slice(&v.to_le_bytes()),
        Scalar::Int32(v) => out.extend_from_slice(&v.to_le_bytes()),
        Scalar::UInt32(v) => out.extend_from_slice(&v.to_le_bytes()),
        Scalar::Int64(v) => out.extend_from_slice(&v.to_le_bytes()),
        Scalar::UInt64(v) => out.extend_from_slice(&v.to_le_bytes()),
        Scalar::Float(v) => out.extend_from_slice(&v.to_le_bytes()),
        Scalar::Double(v) => out.extend_from_slice(&v.to_le_bytes()),
        Scalar::Bool(v) => out.push(u8::from(v)),
        Scalar::Char(v) => out.push(v),
    }
}

/// Writes the subscriptions still waiting (see [`Writer`]) and flushes, ignoring errors, as
/// `io::BufWriter` does; call [`Writer::flush`] to see them.
impl<W: Write> Drop for Writer<W> {
    fn drop(&mut self) {
        if self.out.is_some() {
            let _ = self.flush();
        }
    }
}

impl Writer<io::BufWriter<std::fs::File>> {
    /// Creates (or truncates) a file and starts it; see [`Writer::new`]. Call
    /// [`Writer::flush`] (or drop the writer) when done.
    pub fn create(
        path: impl AsRef<std::path::Path>,
        options: WriterOptions,
    ) -> Result<Writer<io::BufWriter<std::fs::File>>, WriteError> {
        Writer::new(io::BufWriter::new(std::fs::File::create(path)?), options)
    }
}

impl Writer<std::fs::File> {
    /// Opens an existing version-1 log to append data to it: sets the DATA_APPENDED flag and
    /// the next free appended offset (the current end of the file), then continues with the
    /// file's formats and subscriptions (new ones get the next `msg_id`s; an instance the
    /// file has is continued by subscribing it again, its rows read as one instance).
    pub fn append(path: impl AsRef<std::path::Path>) -> Result<Writer<std::fs::File>, WriteError> {
        use std::io::{Read, Seek, SeekFrom};
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)?;
        let mut bytes = Vec::new();
        file.read_to_end(&mut bytes)?;
        let log =
            crate::Log::from_slice(&bytes).map_err(|e| WriteError::CannotAppend(e.to_string()))?;
        let mut bits = *log.flag_bits().ok_or_else(|| {
            WriteError::CannotAppend("the file has no flag bits message (version 0)".into())
        })?;
        let slot = bits
            .appended_offsets
            .iter()
            .position(|&o| o == 0)
            .ok_or_else(|| WriteError::CannotAppend("all 3 appended offsets are used".into()))?;
        bits.incompat[0] |= FlagBits::INCOMPAT_DATA_APPENDED;
        bits.appended_offsets[slot] = bytes.len() as u64;
        file.seek(SeekFrom::Start((HEADER_LEN + 3) as u64))?;
        file.write_all(&bits.to_bytes()[..FLAG_BITS_LEN])?;
        file.seek(SeekFrom::End(0))?;
        let mut schema = Schema::new();
        for f in log.metadata().schema().formats() {
            schema.insert(f.clone())?;
        }
        let mut subscriptions: Vec<Option<Subscribed>> = Vec::new();
        for s in log.subscriptions() {
            let i = usize::from(s.msg_id);
            if subscriptions.len() <= i {
                subscriptions.resize(i + 1, None);
            }
            subscriptions[i] = s.payload_sizes().map(|(min, max)| Subscribed {
                topic: s.name.clone(),
                min,
                max,
            });
        }
        let next_msg_id = subscriptions.len() as u32;
        Ok(Writer {
            out: Some(file),
            schema,
            subscriptions,
            // The file's own subscriptions are not counted: an instance it has is continued
            // by subscribing it again (its rows read as one instance).
            active: std::collections::HashMap::new(),
            next_msg_id,
            default_parameters: bits.has_default_parameters(),
            data_section: true,
            pending: Vec::new(),
            buf: Vec::with_capacity(256),
            row: Vec::with_capacity(256),
        })
    }
}
