//! What a log says besides its data rows: formats, info, parameters, subscriptions... and the
//! interpreter ([`Metadata::apply`]) that turns each framed message into these records.

use super::message::{FileHeader, FlagBits, KNOWN_VERSION, KeyValue, Message};
use crate::error::{Diagnostic, DiagnosticKind, ReadError};
use crate::schema::{Field, Format, FormatId, Primitive, Schema, TypeRef};
use crate::value::{RowPlan, Value};

/// An `I` message: a typed, named value. Keys are unique; a later `I` replaces the value.
#[derive(Debug, Clone, PartialEq)]
pub struct Info {
    /// The name, e.g. `sys_name` (all of it, even with characters the key grammar does not
    /// allow, such as `Build Date`).
    pub key: String,
    /// The declared type, e.g. `char[3]` or `uint32_t`.
    pub type_name: String,
    /// The value: typed as far as the bytes fit the type ([`Value::Bytes`] where they do
    /// not; a diagnostic says so).
    pub value: Value,
    /// The value's bytes as the file has them.
    pub raw: Vec<u8>,
}

/// All `M` messages of one key: each list is one value and its continuations, in file order.
#[derive(Debug, Clone, PartialEq)]
pub struct MultiInfo {
    /// The name.
    pub key: String,
    /// The declared type of the first part.
    pub type_name: String,
    /// One entry per value; each holds the value's parts (the first and its continuations).
    pub values: Vec<Vec<Value>>,
    /// The bytes of each part as the file has them, in the shape of `values`.
    pub raw: Vec<Vec<Vec<u8>>>,
}

impl MultiInfo {
    /// The `i`-th value's parts joined, as the file has them: e.g. a compressed blob split
    /// over continued messages (PX4's `metadata_events`), joined as pyulog joins it.
    pub fn joined(&self, i: usize) -> Option<Vec<u8>> {
        self.raw.get(i).map(|parts| parts.concat())
    }
}

/// A parameter value: parameters are `int32_t` or `float`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ParamValue {
    /// `int32_t`
    Int32(i32),
    /// `float`
    Float(f32),
}

impl ParamValue {
    /// The value as `f64`.
    pub fn as_f64(self) -> f64 {
        match self {
            ParamValue::Int32(v) => v.into(),
            ParamValue::Float(v) => v.into(),
        }
    }
}

/// As a JSON number: an integer or a `float` (its shortest text).
#[cfg(feature = "serde")]
impl serde::Serialize for ParamValue {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match *self {
            ParamValue::Int32(v) => s.serialize_i32(v),
            ParamValue::Float(v) => s.serialize_f32(v),
        }
    }
}

impl std::fmt::Display for ParamValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamValue::Int32(v) => write!(f, "{v}"),
            ParamValue::Float(v) => write!(f, "{v}"),
        }
    }
}

/// A firmware version, as PX4 packs it into the info `ver_sw_release`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct VersionInfo {
    /// Major version.
    pub major: u8,
    /// Minor version.
    pub minor: u8,
    /// Patch version.
    pub patch: u8,
    /// Below 64: development; 64..128 alpha; 128..192 beta; 192..255 release candidate; 255
    /// release.
    pub kind: u8,
}

/// A `P` message of the definitions section: a parameter's value when logging started.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    /// The name.
    pub name: String,
    /// The value.
    pub value: ParamValue,
}

/// A `P` message of the data section: a parameter changed.
#[derive(Debug, Clone, PartialEq)]
pub struct ParameterChange {
    /// The latest data timestamp seen before the change (as pyulog reports it), in µs.
    pub timestamp: u64,
    /// The name.
    pub name: String,
    /// The new value.
    pub value: ParamValue,
    /// File offset of the message.
    pub offset: u64,
    /// Whether the name was valid UTF-8 (else its invalid bytes are left out, as pyulog
    /// does; [`Log::not_utf8`](crate::Log::not_utf8) lists it).
    pub valid_utf8: bool,
}

/// A `Q` message: a default value of a parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct DefaultParameter {
    /// Bit 0: system-wide default; bit 1: default for the current configuration.
    pub default_types: u8,
    /// The name.
    pub name: String,
    /// The default value.
    pub value: ParamValue,
}

impl DefaultParameter {
    /// Bit 0 of `default_types`.
    pub const SYSTEM: u8 = 1;
    /// Bit 1 of `default_types`.
    pub const CONFIGURATION: u8 = 2;
}

/// Severity of a logged string, as in the Linux kernel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum LogLevel {
    /// `'0'`
    Emergency,
    /// `'1'`
    Alert,
    /// `'2'`
    Critical,
    /// `'3'`
    Error,
    /// `'4'`
    Warning,
    /// `'5'`
    Notice,
    /// `'6'`
    Info,
    /// `'7'`
    Debug,
}

impl LogLevel {
    /// The level of a raw level byte: ASCII `'0'..='7'` (what PX4 writes) or `0..=7`.
    pub fn from_byte(b: u8) -> Option<LogLevel> {
        const LEVELS: [LogLevel; 8] = [
            LogLevel::Emergency,
            LogLevel::Alert,
            LogLevel::Critical,
            LogLevel::Error,
            LogLevel::Warning,
            LogLevel::Notice,
            LogLevel::Info,
            LogLevel::Debug,
        ];
        LEVELS
            .get(usize::from(if b >= b'0' { b - b'0' } else { b }))
            .copied()
    }

    /// The level byte PX4 writes: the ASCII digit `'0'..='7'`.
    pub fn byte(self) -> u8 {
        b'0' + self as u8
    }

    /// The name pyulog prints: `EMERGENCY`, `ALERT`, `CRITICAL`, `ERROR`, `WARNING`, `NOTICE`,
    /// `INFO`, `DEBUG`.
    pub fn name(self) -> &'static str {
        match self {
            LogLevel::Emergency => "EMERGENCY",
            LogLevel::Alert => "ALERT",
            LogLevel::Critical => "CRITICAL",
            LogLevel::Error => "ERROR",
            LogLevel::Warning => "WARNING",
            LogLevel::Notice => "NOTICE",
            LogLevel::Info => "INFO",
            LogLevel::Debug => "DEBUG",
        }
    }
}

/// The byte PX4 writes ([`LogLevel::byte`]): what [`Writer::log`](crate::Writer::log) takes.
impl From<LogLevel> for u8 {
    fn from(level: LogLevel) -> u8 {
        level.byte()
    }
}

/// An `L` or `C` message: a logged string.
#[derive(Debug, Clone, PartialEq)]
pub struct LoggedMessage {
    /// The raw level byte (see [`LoggedMessage::level`]).
    pub level_byte: u8,
    /// The tag of a `C` message; `None` for `L`.
    pub tag: Option<u16>,
    /// Microseconds.
    pub timestamp: u64,
    /// The text; invalid UTF-8 is left out, as pyulog leaves it out.
    pub text: String,
    /// Whether the text was valid UTF-8 (pyulog's tools fail on it without `-i`).
    pub valid_utf8: bool,
    /// File offset of the message.
    pub offset: u64,
}

impl LoggedMessage {
    /// The level, if the byte is a known one.
    pub fn level(&self) -> Option<LogLevel> {
        LogLevel::from_byte(self.level_byte)
    }
}

/// An `O` message: logging lost data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dropout {
    /// The latest data timestamp seen before the dropout (as pyulog reports it), in µs.
    pub timestamp: u64,
    /// How long, in milliseconds.
    pub duration_ms: u16,
    /// File offset of the message.
    pub offset: u64,
}

/// An `A` message: a topic instance and the id its data rows carry.
#[derive(Debug, Clone)]
pub struct Subscription {
    /// Id used by `D` messages.
    pub msg_id: u16,
    /// Instance of the topic (0 for the first).
    pub multi_id: u8,
    /// The topic (format) name.
    pub name: String,
    /// File offset of the `A` message.
    pub offset: u64,
    pub(crate) index: usize,
    pub(crate) format: Option<FormatId>,
    pub(crate) sizes: Option<(usize, usize)>,
    pub(crate) timestamp: Option<(usize, Primitive)>,
    /// Built at the first decoded row, so plan memory is bounded by the data decoded.
    pub(crate) plan: std::sync::OnceLock<RowPlan>,
    clock: Clock,
}

impl Subscription {
    /// Position of this subscription in the log's subscription list.
    pub fn index(&self) -> usize {
        self.index
    }

    /// The format of the rows, if the subscription names a valid one.
    pub fn format(&self) -> Option<FormatId> {
        self.format
    }

    /// Accepted row lengths: without trailing padding up to the full size.
    pub fn payload_sizes(&self) -> Option<(usize, usize)> {
        self.sizes
    }

    /// The dynamic decoding plan of the rows (`schema` is the log's).
    #[inline]
    pub fn plan(&self, schema: &Schema) -> Option<&RowPlan> {
        let id = self.format?;
        // `format` is set only for formats `RowPlan::check` accepted.
        Some(self.plan.get_or_init(|| RowPlan::from_checked(schema, id)))
    }

    /// Type of the `timestamp` field, if there is one.
    pub fn timestamp_type(&self) -> Option<Primitive> {
        self.timestamp.map(|(_, p)| p)
    }
}

/// Unwraps version-0 timestamps of `uint32_t`, `uint16_t` or `uint8_t` (ms) into a
/// monotonically increasing `u64` µs timeline, counting a wrap whenever the raw value goes
/// back, and whole extra periods when dropouts since the last row last longer than that.
#[derive(Debug, Clone, Copy, Default)]
struct Clock {
    last: Option<u64>,
    base: u64,
    dropout_mark: u64,
}

impl Clock {
    fn unwrap(&mut self, primitive: Primitive, raw: u64, dropouts_us: u64) -> u64 {
        let (modulus, scale) = match primitive {
            Primitive::UInt64 => return raw,
            Primitive::UInt32 => (1u64 << 32, 1),
            Primitive::UInt16 => (1 << 16, 1),
            _ => (1 << 8, 1000),
        };
        let period = modulus * scale;
        let mut t = self.base + raw * scale;
        if let Some(last) = self.last {
            if t < last {
                self.base += period;
                t += period;
            }
            let lost = dropouts_us - self.dropout_mark;
            while t + period <= last + lost {
                self.base += period;
                t += period;
            }
        }
        self.last = Some(t);
        self.dropout_mark = dropouts_us;
        t
    }
}

/// What one message changed, for the reader driving [`Metadata::apply`].
#[derive(Debug)]
pub(crate) enum Applied {
    Nothing,
    /// A subscription was added; `sizes` are its accepted row lengths if it can be decoded.
    /// `diagnostic` is what stops it being read or timed; `duplicate` says its msg_id was
    /// subscribed before (both can be said of one subscription).
    Subscribed {
        msg_id: u16,
        sizes: Option<(usize, usize)>,
        diagnostic: Option<Diagnostic>,
        /// Boxed: rare, and it would double the size of every `Applied`.
        duplicate: Option<Box<Diagnostic>>,
    },
    Row {
        sub: usize,
        timestamp: u64,
    },
    Logged(LoggedMessage),
    Dropout(Dropout),
    ParameterChange(ParameterChange),
    Sync,
    /// The message was applied all the same, with a note on what is odd about it (a format
    /// outside the grammar, a value kept as far as it goes).
    Noted(Diagnostic),
    /// The message was left out, and why.
    Diagnostic(Diagnostic),
}

/// Everything but data rows, accumulated message by message.
#[derive(Debug, Clone)]
pub struct Metadata {
    pub(crate) header: FileHeader,
    pub(crate) flag_bits: Option<FlagBits>,
    pub(crate) schema: Schema,
    pub(crate) info: Vec<Info>,
    pub(crate) multi_info: Vec<MultiInfo>,
    pub(crate) initial_parameters: Vec<Parameter>,
    /// Position of each initial parameter in `initial_parameters`.
    parameter_index: std::collections::HashMap<String, usize>,
    pub(crate) default_parameters: Vec<DefaultParameter>,
    pub(crate) subscriptions: Vec<Subscription>,
    /// Subscription index + 1 per `msg_id` (0: none), a flat table for the per-row lookup.
    by_msg_id: Vec<u32>,
    /// For `msg_id`s subscribed more than once: `(msg_id, offset of the A, subscription)`, in
    /// file order, so the subscription a row belongs to can be found from its offset.
    resubscriptions: Vec<(u16, u64, u32)>,
    /// One bit per `msg_id`: whether it is in `resubscriptions`.
    resubscribed: Vec<u64>,
    in_data_section: bool,
    last_timestamp: u64,
    dropouts_us: u64,
    pub(crate) sync_count: u64,
}

impl Metadata {
    pub(crate) fn new(header: FileHeader) -> Metadata {
        Metadata {
            header,
            flag_bits: None,
            schema: Schema::new(),
            info: Vec::new(),
            multi_info: Vec::new(),
            initial_parameters: Vec::new(),
            parameter_index: std::collections::HashMap::new(),
            default_parameters: Vec::new(),
            subscriptions: Vec::new(),
            by_msg_id: vec![0; 1 << 16],
            resubscriptions: Vec::new(),
            resubscribed: vec![0; (1 << 16) / 64],
            in_data_section: false,
            last_timestamp: header.start_timestamp,
            dropouts_us: 0,
            sync_count: 0,
        }
    }

    /// A diagnostic for the header itself, if any.
    pub(crate) fn header_diagnostic(&self) -> Option<Diagnostic> {
        (self.header.version > KNOWN_VERSION).then_some(Diagnostic {
            offset: 7,
            kind: DiagnosticKind::UnknownVersion(self.header.version),
        })
    }

    /// The file header.
    pub fn header(&self) -> FileHeader {
        self.header
    }

    /// The flag bits, for files that have them (version 1).
    pub fn flag_bits(&self) -> Option<&FlagBits> {
        self.flag_bits.as_ref()
    }

    /// All formats, with their layouts.
    pub fn schema(&self) -> &Schema {
        &self.schema
    }

    /// Info values, in order of first appearance.
    pub fn info(&self) -> &[Info] {
        &self.info
    }

    /// The info value of this key.
    pub fn info_value(&self, key: &str) -> Option<&Value> {
        self.info.iter().find(|i| i.key == key).map(|i| &i.value)
    }

    /// Multi info values by key, in order of first appearance.
    pub fn multi_info(&self) -> &[MultiInfo] {
        &self.multi_info
    }

    /// Parameters as logging started (the definitions section), in order of first appearance.
    pub fn initial_parameters(&self) -> &[Parameter] {
        &self.initial_parameters
    }

    /// The value of a parameter as logging started.
    ///
    /// ```no_run
    /// # let log = ulog_runtime::Log::open("flight.ulg")?;
    /// if let Some(v) = log.metadata().parameter("MPC_XY_VEL_MAX") {
    ///     println!("max horizontal speed {} m/s", v.as_f64());
    /// }
    /// # Ok::<(), ulog_runtime::ReadError>(())
    /// ```
    pub fn parameter(&self, name: &str) -> Option<ParamValue> {
        let &i = self.parameter_index.get(name)?;
        Some(self.initial_parameters[i].value)
    }

    /// The firmware version PX4 writes in the info `ver_sw_release` (`0xMMmmpptt`).
    pub fn version_info(&self) -> Option<VersionInfo> {
        let v = self.info_value("ver_sw_release")?.as_scalar()?.as_i128()?;
        let v = u32::try_from(v).ok()?;
        let [major, minor, patch, kind] = v.to_be_bytes();
        Some(VersionInfo {
            major,
            minor,
            patch,
            kind,
        })
    }

    /// The firmware version as pyulog's `get_version_info_str` gives it: `v1.15.1`, with
    /// ` (alpha)`, ` (beta)` or ` (RC)` for those; `None` for a development build or a log
    /// without `ver_sw_release`.
    pub fn software_version(&self) -> Option<String> {
        let v = self.version_info()?;
        let kind = match v.kind {
            0..64 => return None,
            64..128 => " (alpha)",
            128..192 => " (beta)",
            192..255 => " (RC)",
            255 => "",
        };
        Some(format!("v{}.{}.{}{kind}", v.major, v.minor, v.patch))
    }

    /// Default parameters, in file order.
    pub fn default_parameters(&self) -> &[DefaultParameter] {
        &self.default_parameters
    }

    /// Whether a message of the data section has been read.
    pub(crate) fn in_data_section(&self) -> bool {
        self.in_data_section
    }

    /// Subscriptions, in file order (including ones that never get data).
    pub fn subscriptions(&self) -> &[Subscription] {
        &self.subscriptions
    }

    /// Number of `S` sync messages read.
    pub fn sync_count(&self) -> u64 {
        self.sync_count
    }

    /// The latest data timestamp seen so far (starting at the header's), in µs.
    pub fn last_timestamp(&self) -> u64 {
        self.last_timestamp
    }

    /// Takes in what a part of the file read by a worker found: its latest timestamp, sync
    /// messages and dropouts, and whether it entered the data section (a logged string or
    /// a dropout there: a parameter after it is a change) (see the parallel whole-file
    /// reader).
    pub(crate) fn absorb(
        &mut self,
        last_timestamp: u64,
        syncs: u64,
        dropouts_ms: u64,
        in_data_section: bool,
    ) {
        self.in_data_section |= in_data_section;
        self.last_timestamp = self.last_timestamp.max(last_timestamp);
        self.sync_count += syncs;
        self.dropouts_us += dropouts_ms * 1000;
    }

    /// Interprets one framed message.
    pub(crate) fn apply(&mut self, offset: u64, msg: Message<'_>) -> Result<Applied, ReadError> {
        let diag = |kind| Ok(Applied::Diagnostic(Diagnostic { offset, kind }));
        let noted = |kind| Ok(Applied::Noted(Diagnostic { offset, kind }));
        match msg {
            Message::FlagBits(bits) => {
                if offset != super::message::HEADER_LEN as u64 || self.flag_bits.is_some() {
                    return diag(DiagnosticKind::FlagBitsNotFirst);
                }
                if let Some((byte, bit)) = bits.unknown_incompat_bit() {
                    return Err(ReadError::IncompatibleFlags { byte, bit });
                }
                self.flag_bits = Some(bits);
                Ok(Applied::Nothing)
            }
            Message::Format(bytes) => {
                // As pyulog reads it: invalid UTF-8 left out, names outside the grammar kept.
                let (text, valid) = text_of(bytes);
                let strict = Format::parse(&text).map(|f| (f, Vec::new()));
                let (format, mut notes) = match strict.or_else(|_| Format::parse_lax(&text)) {
                    Ok(x) => x,
                    Err(error) => return diag(DiagnosticKind::InvalidFormat { text, error }),
                };
                if !valid {
                    notes.insert(0, "not UTF-8 (the invalid bytes are left out)".to_owned());
                }
                if let Err(e) = self.schema.insert(format) {
                    return diag(DiagnosticKind::Redefinition(e));
                }
                if notes.is_empty() {
                    Ok(Applied::Nothing)
                } else {
                    noted(DiagnosticKind::OddFormat {
                        text,
                        notes: notes.join("; "),
                        not_utf8: !valid,
                    })
                }
            }
            Message::Info(kv) => {
                let d = decode_key_value(kv);
                let problem = d.problem();
                match self.info.iter_mut().find(|i| i.key == d.name) {
                    Some(existing) => {
                        existing.type_name = d.type_name;
                        existing.value = d.value;
                        existing.raw = d.raw;
                    }
                    None => self.info.push(Info {
                        key: d.name,
                        type_name: d.type_name,
                        value: d.value,
                        raw: d.raw,
                    }),
                }
                problem.map_or(Ok(Applied::Nothing), noted)
            }
            Message::MultiInfo { continued, entry } => {
                let d = decode_key_value(entry);
                let problem = d.problem();
                match self.multi_info.iter_mut().find(|m| m.key == d.name) {
                    Some(m) => match (m.values.last_mut(), m.raw.last_mut()) {
                        (Some(last), Some(raw)) if continued => {
                            last.push(d.value);
                            raw.push(d.raw);
                        }
                        _ => {
                            m.values.push(vec![d.value]);
                            m.raw.push(vec![d.raw]);
                        }
                    },
                    None => self.multi_info.push(MultiInfo {
                        key: d.name,
                        type_name: d.type_name,
                        values: vec![vec![d.value]],
                        raw: vec![vec![d.raw]],
                    }),
                }
                problem.map_or(Ok(Applied::Nothing), noted)
            }
            Message::Parameter(kv) => {
                let (name, value, problem) = match param_value(kv) {
                    Ok(x) => x,
                    Err(kind) => return diag(kind),
                };
                if self.in_data_section {
                    return Ok(Applied::ParameterChange(ParameterChange {
                        timestamp: self.last_timestamp,
                        name,
                        value,
                        offset,
                        valid_utf8: !matches!(
                            problem,
                            Some(DiagnosticKind::KeptValue { not_utf8: true, .. })
                        ),
                    }));
                }
                // Logs hold thousands of parameters: found by name through an index.
                match self.parameter_index.get(&name) {
                    Some(&i) => self.initial_parameters[i].value = value,
                    None => {
                        self.parameter_index
                            .insert(name.clone(), self.initial_parameters.len());
                        self.initial_parameters.push(Parameter { name, value });
                    }
                }
                problem.map_or(Ok(Applied::Nothing), noted)
            }
            Message::DefaultParameter {
                default_types,
                entry,
            } => {
                let (name, value, _) = match param_value(entry) {
                    Ok(x) => x,
                    Err(kind) => return diag(kind),
                };
                self.default_parameters.push(DefaultParameter {
                    default_types,
                    name,
                    value,
                });
                Ok(Applied::Nothing)
            }
            Message::Subscribe {
                multi_id,
                msg_id,
                name,
            } => {
                self.in_data_section = true;
                self.subscribe(offset, multi_id, msg_id, name)
            }
            Message::Unsubscribe { .. } => {
                self.in_data_section = true;
                Ok(Applied::Nothing)
            }
            Message::Data { msg_id, data } => {
                self.in_data_section = true;
                self.data(offset, msg_id, data)
            }
            Message::Logging {
                level,
                tag,
                timestamp,
                text,
            } => {
                self.in_data_section = true;
                let (text, valid) = text_of(text);
                Ok(Applied::Logged(LoggedMessage {
                    level_byte: level,
                    tag,
                    timestamp,
                    text,
                    valid_utf8: valid,
                    offset,
                }))
            }
            Message::Sync => {
                self.sync_count += 1;
                Ok(Applied::Sync)
            }
            Message::Dropout { duration_ms } => {
                self.in_data_section = true;
                self.dropouts_us += u64::from(duration_ms) * 1000;
                Ok(Applied::Dropout(Dropout {
                    timestamp: self.last_timestamp,
                    duration_ms,
                    offset,
                }))
            }
            Message::Unknown { ty, payload } => diag(DiagnosticKind::UnknownMessageType {
                ty,
                size: payload.len() as u16,
            }),
        }
    }

    fn subscribe(
        &mut self,
        offset: u64,
        multi_id: u8,
        msg_id: u16,
        name: &[u8],
    ) -> Result<Applied, ReadError> {
        // As the format's name: invalid UTF-8 left out (reported when the format was read).
        let (name, _) = text_of(name);
        let mut sub = Subscription {
            msg_id,
            multi_id,
            name,
            offset,
            index: self.subscriptions.len(),
            format: None,
            sizes: None,
            timestamp: None,
            plan: std::sync::OnceLock::new(),
            clock: Clock::default(),
        };
        let mut problem = None;
        match self.schema.id(&sub.name) {
            None => {
                problem = Some(DiagnosticKind::BadSubscription {
                    topic: sub.name.clone(),
                    msg_id,
                    error: crate::schema::LayoutError::UnknownFormat(sub.name.clone()).into(),
                });
            }
            Some(id) => match RowPlan::check(&mut self.schema, id) {
                Err(error) => {
                    problem = Some(DiagnosticKind::BadSubscription {
                        topic: sub.name.clone(),
                        msg_id,
                        error,
                    });
                }
                Ok(layout) => {
                    sub.format = Some(id);
                    sub.sizes = Some((layout.payload_size, layout.size));
                    sub.timestamp = layout.field("timestamp").and_then(|f| match f.kind {
                        crate::schema::FieldKind::Primitive(p)
                            if p.is_unsigned_integer() && f.array_len.is_none() =>
                        {
                            Some((f.offset, p))
                        }
                        _ => None,
                    });
                    if sub.timestamp.is_none() {
                        problem = Some(DiagnosticKind::MissingTimestamp {
                            topic: sub.name.clone(),
                        });
                    }
                }
            },
        }
        let mut duplicate = None;
        if let Some(previous) = self.by_msg_id[usize::from(msg_id)].checked_sub(1) {
            if !self.is_resubscribed(msg_id) {
                // Its first subscription joins the list, and rows of this id now look up
                // which subscription they follow.
                let first = &self.subscriptions[previous as usize];
                self.resubscriptions.push((msg_id, first.offset, previous));
                self.resubscribed[usize::from(msg_id / 64)] |= 1 << (msg_id % 64);
            }
            self.resubscriptions
                .push((msg_id, offset, self.subscriptions.len() as u32));
            let previous = previous as usize;
            duplicate = Some(DiagnosticKind::DuplicateMsgId {
                msg_id,
                previous: self.subscriptions[previous].name.clone(),
                topic: sub.name.clone(),
            });
        }
        let sizes = sub.sizes;
        self.by_msg_id[usize::from(msg_id)] = self.subscriptions.len() as u32 + 1;
        self.subscriptions.push(sub);
        Ok(Applied::Subscribed {
            msg_id,
            sizes,
            diagnostic: problem.map(|kind| Diagnostic { offset, kind }),
            duplicate: duplicate.map(|kind| Box::new(Diagnostic { offset, kind })),
        })
    }

    /// Whether `msg_id` has been subscribed more than once (it is in `resubscriptions`).
    #[inline]
    fn is_resubscribed(&self, msg_id: u16) -> bool {
        self.resubscribed[usize::from(msg_id / 64)] & (1 << (msg_id % 64)) != 0
    }

    /// The subscription a row of `msg_id` at file offset `offset` belongs to: the last one
    /// of that id before the row.
    #[inline]
    pub(crate) fn subscription_at(&self, msg_id: u16, offset: u64) -> Option<usize> {
        if !self.is_resubscribed(msg_id) {
            return self.by_msg_id[usize::from(msg_id)]
                .checked_sub(1)
                .map(|i| i as usize);
        }
        self.resubscriptions
            .iter()
            .rev()
            .find(|r| r.0 == msg_id && r.1 < offset)
            .map(|r| r.2 as usize)
    }

    /// The fast path's part of [`Metadata::apply`] for a row the framer took: the latest
    /// timestamp seen.
    #[inline]
    pub(crate) fn saw_timestamp(&mut self, timestamp: u64) {
        if timestamp > self.last_timestamp {
            self.last_timestamp = timestamp;
        }
    }

    fn data(&mut self, offset: u64, msg_id: u16, data: &[u8]) -> Result<Applied, ReadError> {
        let Some(index) = self.by_msg_id[usize::from(msg_id)]
            .checked_sub(1)
            .map(|i| i as usize)
        else {
            return Ok(Applied::Diagnostic(Diagnostic {
                offset,
                kind: DiagnosticKind::UnknownMsgId { msg_id },
            }));
        };
        let sub = &mut self.subscriptions[index];
        let Some((min, max)) = sub.sizes else {
            // The subscription was already reported as undecodable.
            return Ok(Applied::Nothing);
        };
        if !(min..=max).contains(&data.len()) {
            return Ok(Applied::Diagnostic(Diagnostic {
                offset,
                kind: DiagnosticKind::PayloadSize {
                    topic: sub.name.clone(),
                    multi_id: sub.multi_id,
                    msg_id,
                    len: data.len(),
                    min,
                    max,
                },
            }));
        }
        let timestamp = match sub.timestamp {
            None => 0,
            Some((at, p)) => {
                let raw = crate::value::Scalar::decode(p, &data[at..])
                    .and_then(|s| s.as_i128())
                    .unwrap_or(0) as u64;
                sub.clock.unwrap(p, raw, self.dropouts_us)
            }
        };
        if timestamp > self.last_timestamp {
            self.last_timestamp = timestamp;
        }
        Ok(Applied::Row {
            sub: index,
            timestamp,
        })
    }
}

/// Text as pyulog decodes it (`errors='ignore'`): invalid UTF-8 sequences left out; `false`
/// if there were any.
pub(crate) fn text_of(bytes: &[u8]) -> (String, bool) {
    match std::str::from_utf8(bytes) {
        Ok(t) => (t.to_owned(), true),
        Err(_) => (bytes.utf8_chunks().map(|c| c.valid()).collect(), false),
    }
}

/// The key and value of an `I`/`M`/`P`/`Q` message, decoded as far as they can be.
struct Decoded {
    name: String,
    type_name: String,
    value: Value,
    raw: Vec<u8>,
    key_text: String,
    problems: Vec<String>,
    not_utf8: bool,
}

impl Decoded {
    /// A diagnostic if anything was odd (the value is kept either way).
    fn problem(&self) -> Option<DiagnosticKind> {
        (!self.problems.is_empty()).then(|| DiagnosticKind::KeptValue {
            key: self.key_text.clone(),
            reason: self.problems.join("; "),
            not_utf8: self.not_utf8,
        })
    }
}

/// The name of the key of an `I`/`M`/`P`/`Q` message, as [`Info::key`] gives it (a key
/// outside the grammar keeps its whole name).
pub(crate) fn key_name(kv: KeyValue<'_>) -> String {
    decode_key_value(kv).name
}

/// Decodes the key and value of an `I`/`M`/`P`/`Q` message, keeping what is there: a key
/// outside the grammar keeps its whole name, a value that does not fit its type is typed
/// as far as it fits (or kept as bytes), and each oddity is noted.
fn decode_key_value(kv: KeyValue<'_>) -> Decoded {
    let (key_text, key_valid) = text_of(kv.key);
    let mut not_utf8 = !key_valid;
    let mut problems = Vec::new();
    if !key_valid {
        problems.push("the key is not UTF-8 (the invalid bytes are left out)".to_owned());
    }
    let raw = kv.value.to_vec();
    // The type, if basic, and the element count; the name.
    let (type_name, name, ty) = match Field::parse_key(&key_text) {
        Ok(field) => (field_type_name(&field), field.name.clone(), basic(&field)),
        Err(_) => match key_text.split_once(' ') {
            Some((ty, name)) if !name.is_empty() => {
                problems.push(format!(
                    "the name `{name}` is outside the key grammar (kept whole)"
                ));
                let ty_field = Field::parse_key(&format!("{ty} k")).ok();
                (
                    ty.to_owned(),
                    name.to_owned(),
                    ty_field.as_ref().and_then(basic),
                )
            }
            _ => {
                problems.push("the key has no type".to_owned());
                (String::new(), key_text.clone(), None)
            }
        },
    };
    let value = match ty {
        None => {
            if !type_name.is_empty() {
                problems.push(format!(
                    "`{type_name}` is not a basic type; the value is kept as bytes"
                ));
            }
            Value::Bytes(raw.clone())
        }
        Some((Primitive::Char, Some(_))) => {
            // The text is the whole value, whatever length the key declares (as pyulog reads it).
            let (text, valid) = text_of(&raw);
            if !valid {
                not_utf8 = true;
                problems.push("the text is not UTF-8 (the invalid bytes are left out)".to_owned());
            }
            Value::String(text)
        }
        Some((p, count)) => {
            let expected = count.unwrap_or(1) * p.size();
            if raw.len() != expected {
                problems.push(format!(
                    "{} value bytes, the type needs {expected}; kept as they are",
                    raw.len()
                ));
            }
            let whole = raw.len() / p.size();
            let decoded = match count {
                None if whole >= 1 => Value::decode_primitive(p, None, &raw, false),
                None => None,
                Some(_) => Value::decode_primitive(p, Some(whole), &raw, false),
            };
            decoded.unwrap_or_else(|| Value::Bytes(raw.clone()))
        }
    };
    Decoded {
        name,
        type_name,
        value,
        raw,
        key_text,
        problems,
        not_utf8,
    }
}

/// `char[3]`, `uint32_t`: the type part of a key.
fn field_type_name(field: &Field) -> String {
    match field.array_len {
        Some(n) => format!("{}[{n}]", field.ty),
        None => field.ty.to_string(),
    }
}

/// The basic type and array length of a key's field, if its type is basic.
fn basic(field: &Field) -> Option<(Primitive, Option<usize>)> {
    match field.ty {
        TypeRef::Primitive(p) => Some((p, field.array_len.map(usize::from))),
        TypeRef::Nested(_) => None,
    }
}

/// A parameter's name and value, and what was odd about them (reported for initial
/// parameters; a change says whether its name was UTF-8).
fn param_value(
    kv: KeyValue<'_>,
) -> Result<(String, ParamValue, Option<DiagnosticKind>), DiagnosticKind> {
    let d = decode_key_value(kv);
    let value = match d.value {
        Value::Scalar(crate::value::Scalar::Int32(v)) => ParamValue::Int32(v),
        Value::Scalar(crate::value::Scalar::Float(v)) => ParamValue::Float(v),
        _ => {
            return Err(DiagnosticKind::InvalidValue {
                key: d.key_text,
                reason: "parameters are int32_t or float".to_owned(),
            });
        }
    };
    let problem = d.problem();
    Ok((d.name, value, problem))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clock_unwraps_small_timestamps() {
        let mut c = Clock::default();
        let seq: Vec<u64> = [65_000u64, 65_500, 200, 900, 100]
            .into_iter()
            .map(|raw| c.unwrap(Primitive::UInt16, raw, 0))
            .collect();
        assert_eq!(seq, [65_000, 65_500, 65_736, 66_436, 131_172]);
        // uint8_t counts milliseconds.
        let mut ms = Clock::default();
        assert_eq!(ms.unwrap(Primitive::UInt8, 250, 0), 250_000);
        assert_eq!(ms.unwrap(Primitive::UInt8, 5, 0), 261_000);
        // A dropout longer than a whole period adds that period.
        let mut d = Clock::default();
        assert_eq!(d.unwrap(Primitive::UInt16, 1_000, 0), 1_000);
        assert_eq!(d.unwrap(Primitive::UInt16, 2_000, 70_000), 2_000 + 65_536);
        assert_eq!(
            Clock::default().unwrap(Primitive::UInt64, u64::MAX, 0),
            u64::MAX
        );
    }

    #[test]
    fn log_levels() {
        assert_eq!(LogLevel::from_byte(b'6'), Some(LogLevel::Info));
        assert_eq!(LogLevel::from_byte(3), Some(LogLevel::Error));
        assert_eq!(LogLevel::from_byte(b'9'), None);
        assert_eq!(LogLevel::Emergency.name(), "EMERGENCY");
    }
}
