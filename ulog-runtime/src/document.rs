//! What a log says besides its rows, as one serializable document (feature `serde`): the
//! `metadata.json` of a Parquet conversion and the head of `ulog json --document`. Values
//! keep their types (integer parameters as integers, `float` values in their shortest
//! text); JSON has no NaN or infinity, so serde_json writes those as `null`.

use serde::Serialize;
use serde::ser::SerializeMap;

use crate::read::{
    DefaultParameter, Dropout, FlagBits, Log, LoggedMessage, Metadata, ParamValue, ParameterChange,
    Skipped, TopicSummary,
};
use crate::{Diagnostic, Value};

/// A log's facts, owned, ready to serialize.
#[derive(Debug, Clone, Serialize)]
pub struct LogFacts {
    /// The format version of the file.
    pub version: u8,
    /// The header's start time, µs.
    pub start_timestamp: u64,
    /// The start time as a UTC date: the header's when it holds an absolute time, else from
    /// the first GPS fix ([`crate::read::GpsClock`]), else none. The same date as the
    /// Parquet files' `ulog.start_utc` and `metadata.json`'s `log.start_utc`.
    pub start_utc: Option<String>,
    /// The firmware version as pyulog gives it (`v1.15.1`), if a release.
    pub software_version: Option<String>,
    /// The flag bits, for files that have them.
    pub flag_bits: Option<FlagBitsFact>,
    /// Info values, in file order.
    pub info: Ordered<Value>,
    /// Multi info values: per key, each value as its parts.
    pub multi_info: Ordered<Vec<Vec<Value>>>,
    /// Parameters as logging started.
    pub parameters: Ordered<ParamValue>,
    /// Parameter changes, in file order.
    pub parameter_changes: Vec<ParameterChangeFact>,
    /// Default parameters, in file order.
    pub default_parameters: Vec<DefaultParameterFact>,
    /// Logged strings (`L`, and `C` with their tag), in file order.
    pub logged_messages: Vec<LoggedFact>,
    /// Dropouts, in file order.
    pub dropouts: Vec<DropoutFact>,
    /// Per topic instance with rows: rows and time range.
    pub topics: Vec<TopicFact>,
    /// What reading left out.
    pub skipped: SkippedFacts,
    /// The diagnostics, as text, in file order (a stream keeps the first
    /// [`KEPT_DIAGNOSTICS`]).
    pub diagnostics: Vec<String>,
    /// Diagnostics not listed (beyond the first [`KEPT_DIAGNOSTICS`] of a stream; what they
    /// report is counted in `skipped`).
    pub diagnostics_omitted: u64,
}

/// Diagnostics a streaming pass keeps as text; the rest are counted (a damaged file can
/// have one per message).
pub const KEPT_DIAGNOSTICS: usize = 1000;

/// Pairs serialized as a JSON object, in their order (a log's order, not sorted).
#[derive(Debug, Clone, Default)]
pub struct Ordered<V>(pub Vec<(String, V)>);

impl<V: Serialize> Serialize for Ordered<V> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

/// The flag bits.
#[derive(Debug, Clone, Serialize)]
pub struct FlagBitsFact {
    /// Compatible flags.
    pub compat: [u8; 8],
    /// Incompatible flags.
    pub incompat: [u8; 8],
    /// Offsets of appended data (non-zero ones).
    pub appended_offsets: Vec<u64>,
}

/// A parameter change.
#[derive(Debug, Clone, Serialize)]
pub struct ParameterChangeFact {
    /// The latest data timestamp before it (as pyulog dates it), µs.
    pub timestamp: u64,
    /// The parameter.
    pub name: String,
    /// Its new value.
    pub value: ParamValue,
}

/// A default parameter.
#[derive(Debug, Clone, Serialize)]
pub struct DefaultParameterFact {
    /// The parameter.
    pub name: String,
    /// Its default.
    pub value: ParamValue,
    /// Bit 0: the system default; bit 1: the current setup's.
    pub default_types: u8,
}

/// A logged string.
#[derive(Debug, Clone, Serialize)]
pub struct LoggedFact {
    /// µs.
    pub timestamp: u64,
    /// `ERROR`, `INFO`...; `None` for a byte that is no level.
    pub level: Option<&'static str>,
    /// The tag of a tagged string.
    pub tag: Option<u16>,
    /// The text.
    pub text: String,
}

/// A dropout.
#[derive(Debug, Clone, Serialize)]
pub struct DropoutFact {
    /// The latest data timestamp before it, µs.
    pub timestamp: u64,
    /// How long, ms.
    pub duration_ms: u16,
}

/// A topic instance with rows.
#[derive(Debug, Clone, Serialize)]
pub struct TopicFact {
    /// The topic.
    pub topic: String,
    /// The instance.
    pub multi_id: u8,
    /// Its format, as the `F` message has it.
    pub format: String,
    /// Rows.
    pub rows: usize,
    /// First row's timestamp, µs.
    pub first_timestamp: Option<u64>,
    /// Last row's timestamp, µs.
    pub last_timestamp: Option<u64>,
}

/// What reading left out ([`Skipped`]).
#[derive(Debug, Clone, Serialize)]
pub struct SkippedFacts {
    /// Subscriptions whose rows cannot be decoded.
    pub unreadable_topics: Vec<UnreadableTopic>,
    /// Rows whose size does not fit their format, per instance.
    pub misfit_rows: Vec<MisfitRows>,
    /// Rows of a `msg_id` no subscription declares.
    pub orphan_rows: usize,
    /// Messages that could not be used (unknown types, malformed).
    pub unusable_messages: usize,
    /// Bytes skipped as damaged.
    pub damaged_bytes: u64,
    /// Appended-data offsets of the flag bits that were ignored as impossible (the data
    /// appended there, if any, is not read).
    pub ignored_appended_offsets: Vec<u64>,
}

/// A subscription whose rows cannot be decoded.
#[derive(Debug, Clone, Serialize)]
pub struct UnreadableTopic {
    /// The topic.
    pub topic: String,
    /// Its `msg_id`.
    pub msg_id: u16,
    /// Why.
    pub reason: String,
}

/// Rows of one instance whose size does not fit its format.
#[derive(Debug, Clone, Serialize)]
pub struct MisfitRows {
    /// The topic.
    pub topic: String,
    /// The instance.
    pub multi_id: u8,
    /// How many.
    pub rows: usize,
}

/// What a reading pass collected besides the metadata: the parts of [`LogFacts`] that come
/// from the data section.
#[derive(Debug, Clone, Copy)]
pub struct Collected<'a> {
    /// Logged strings.
    pub logged: &'a [LoggedMessage],
    /// Parameter changes.
    pub changes: &'a [ParameterChange],
    /// Dropouts.
    pub dropouts: &'a [Dropout],
    /// Diagnostics (the first ones of a stream).
    pub diagnostics: &'a [Diagnostic],
    /// Diagnostics left out of `diagnostics`.
    pub diagnostics_omitted: u64,
    /// Topic instances with rows.
    pub topics: &'a [TopicSummary],
    /// What was left out.
    pub skipped: &'a Skipped,
    /// The log's start in UTC from its first GPS fix (µs since 1970), if one was seen
    /// ([`crate::read::GpsClock`]): the date when the header holds none.
    pub gps_utc_start: Option<u64>,
}

impl LogFacts {
    /// The facts of a whole-file log.
    pub fn of_log(log: &Log<'_>) -> LogFacts {
        let topics = log.topics();
        let skipped = log.skipped();
        LogFacts::new(
            log.metadata(),
            Collected {
                logged: log.logged_messages(),
                changes: log.parameter_changes(),
                dropouts: log.dropouts(),
                diagnostics: log.diagnostics(),
                diagnostics_omitted: 0,
                topics: &topics,
                skipped: &skipped,
                gps_utc_start: crate::read::GpsClock::of_log(log),
            },
        )
    }

    /// The facts of a log read some other way (a stream): its metadata and what the pass
    /// collected.
    pub fn new(meta: &Metadata, c: Collected<'_>) -> LogFacts {
        let header = meta.header();
        let format_of = |t: &TopicSummary| {
            meta.schema()
                .get(&t.name)
                .map(ToString::to_string)
                .unwrap_or_default()
        };
        LogFacts {
            version: header.version,
            start_timestamp: header.start_timestamp,
            start_utc: crate::read::GpsClock::date(header, c.gps_utc_start).map(|t| t.to_string()),
            software_version: meta.software_version(),
            flag_bits: meta.flag_bits().map(|b: &FlagBits| FlagBitsFact {
                compat: b.compat,
                incompat: b.incompat,
                appended_offsets: b.appended().collect(),
            }),
            info: Ordered(
                meta.info()
                    .iter()
                    .map(|i| (i.key.clone(), i.value.clone()))
                    .collect(),
            ),
            multi_info: Ordered(
                meta.multi_info()
                    .iter()
                    .map(|m| (m.key.clone(), m.values.clone()))
                    .collect(),
            ),
            parameters: Ordered(
                meta.initial_parameters()
                    .iter()
                    .map(|p| (p.name.clone(), p.value))
                    .collect(),
            ),
            parameter_changes: c
                .changes
                .iter()
                .map(|p| ParameterChangeFact {
                    timestamp: p.timestamp,
                    name: p.name.clone(),
                    value: p.value,
                })
                .collect(),
            default_parameters: meta
                .default_parameters()
                .iter()
                .map(|d: &DefaultParameter| DefaultParameterFact {
                    name: d.name.clone(),
                    value: d.value,
                    default_types: d.default_types,
                })
                .collect(),
            logged_messages: c
                .logged
                .iter()
                .map(|m| LoggedFact {
                    timestamp: m.timestamp,
                    level: m.level().map(|l| l.name()),
                    tag: m.tag,
                    text: m.text.clone(),
                })
                .collect(),
            dropouts: c
                .dropouts
                .iter()
                .map(|d| DropoutFact {
                    timestamp: d.timestamp,
                    duration_ms: d.duration_ms,
                })
                .collect(),
            topics: c
                .topics
                .iter()
                .map(|t| TopicFact {
                    topic: t.name.clone(),
                    multi_id: t.multi_id,
                    format: format_of(t),
                    rows: t.rows,
                    first_timestamp: t.first_timestamp,
                    last_timestamp: t.last_timestamp,
                })
                .collect(),
            skipped: SkippedFacts {
                unreadable_topics: c
                    .skipped
                    .unreadable_topics
                    .iter()
                    .map(|(topic, msg_id, reason)| UnreadableTopic {
                        topic: topic.clone(),
                        msg_id: *msg_id,
                        reason: reason.clone(),
                    })
                    .collect(),
                misfit_rows: c
                    .skipped
                    .misfit_rows
                    .iter()
                    .map(|(topic, multi_id, rows)| MisfitRows {
                        topic: topic.clone(),
                        multi_id: *multi_id,
                        rows: *rows,
                    })
                    .collect(),
                orphan_rows: c.skipped.orphan_rows,
                unusable_messages: c.skipped.unusable_messages,
                damaged_bytes: c.skipped.damaged_bytes,
                ignored_appended_offsets: c.skipped.ignored_appended_offsets.clone(),
            },
            diagnostics: c.diagnostics.iter().map(ToString::to_string).collect(),
            diagnostics_omitted: c.diagnostics_omitted,
        }
    }
}
