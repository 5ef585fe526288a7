//! PX4 events (feature `events`, default): the rows of the `event` topic (an id, log levels
//! and packed arguments) decoded with the events metadata the log embeds, as PX4's
//! libevents and pyulog decode them.
//!
//! - [`EventsMetadata::of`]: the metadata of a log (multi info `metadata_events`, xz, checked
//!   against `metadata_events_sha256`), as [`EventDefinitions`].
//! - [`EventRow`]: an `event` row as it is logged, read through an [`EventLayout`] found from
//!   the log's own format (available whatever the metadata).
//! - [`decode`]: a row with the definitions: name, namespace, group, typed arguments, the
//!   message and description as libevents formats them ([`format`](mod@format)).
//! - [`Log::events`]: all of a log's events at once; [`messages`]: the lines of pyulog's
//!   `ulog_messages`, logged strings and events merged.
//!
//! ```no_run
//! let log = ulog_runtime::Log::open("flight.ulg")?;
//! let events = log.events();
//! let metadata = events.metadata.as_ref().expect("the log embeds its events metadata");
//! for row in &events.rows {
//!     match ulog_runtime::events::decode(row, &metadata.definitions) {
//!         Ok(e) => println!("{} {} {}", row.timestamp, e.name, e.message.unwrap_or_default()),
//!         Err(why) => println!("{} {why}", row.timestamp),
//!     }
//! }
//! # Ok::<(), ulog_runtime::ReadError>(())
//! ```
//!
//! Streaming: make an [`EventLayout`] from the `event` subscription's format when it comes
//! ([`Event::Subscription`](crate::Event::Subscription)), take [`EventsMetadata::of`] the
//! reader's metadata then (the metadata is in the definitions section, before any
//! subscription), and read each of its rows with [`EventLayout::read`].

pub mod definitions;
pub mod format;
mod messages;
pub mod metadata;
#[cfg(test)]
mod tests;

pub use definitions::{ArgDef, DefinitionsError, EnumDef, EventDef, EventDefinitions};
pub use format::{ArgValue, FormatError, format_message};
pub use messages::{MessageKind, MessageLine, Messages, all_messages, messages};
pub use metadata::{EventsMetadata, MetadataError, Verification};

use crate::read::{Log, Row};
use crate::schema::{FieldKind, FormatId, Primitive, Schema};

/// The topic PX4 logs events in.
pub const TOPIC: &str = "event";
/// The profile PX4's tools format messages for.
pub const PROFILE: &str = "dev";

/// A log level of an event: 0 `EMERGENCY` to 7 `DEBUG`, 8 `PROTOCOL`, 9 `DISABLED`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct EventLevel(pub u8);

impl EventLevel {
    /// The name PX4's tools give it, `UNKNOWN` above 9.
    pub fn name(self) -> &'static str {
        const NAMES: [&str; 10] = [
            "EMERGENCY",
            "ALERT",
            "CRITICAL",
            "ERROR",
            "WARNING",
            "NOTICE",
            "INFO",
            "DEBUG",
            "PROTOCOL",
            "DISABLED",
        ];
        NAMES.get(usize::from(self.0)).copied().unwrap_or("UNKNOWN")
    }
}

/// An `event` row as it is logged.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EventRow {
    /// µs.
    pub timestamp: u64,
    /// The event id: component in the top 8 bits, sub-id below.
    pub id: u32,
    /// The sequence number (it wraps), if the format has it.
    pub sequence: Option<u16>,
    /// The packed arguments, as logged (unused bytes included).
    pub arguments: Vec<u8>,
    /// The log levels: internal in the top 4 bits, external in the low 4.
    pub log_levels: u8,
    /// The row's file offset.
    pub offset: u64,
}

impl EventRow {
    /// The internal log level (what PX4's tools show, and filter on: 8 and above are not
    /// shown).
    pub fn internal_level(&self) -> EventLevel {
        EventLevel(self.log_levels >> 4)
    }

    /// The external log level (what a ground station is told).
    pub fn external_level(&self) -> EventLevel {
        EventLevel(self.log_levels & 0xf)
    }
}

/// Where the fields of an `event` row are, from the log's own format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EventLayout {
    id: usize,
    log_levels: usize,
    sequence: Option<usize>,
    arguments: (usize, usize),
}

/// Why a format cannot be read as events.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("format `{format}` is not an event format: {why}")]
pub struct LayoutError {
    /// The format's name.
    pub format: String,
    /// What it lacks.
    pub why: String,
}

impl EventLayout {
    /// The layout of format `id` of `schema`: it needs `uint32_t id`, `uint8_t log_levels`
    /// and `uint8_t[N] arguments`; `uint16_t event_sequence` is read if present.
    pub fn of(schema: &Schema, id: FormatId) -> Result<EventLayout, LayoutError> {
        let name = schema.format(id).name.clone();
        let error = |why: &str| LayoutError {
            format: name.clone(),
            why: why.to_owned(),
        };
        let layout = schema
            .resolved(id)
            .ok_or_else(|| error("its layout does not resolve"))?;
        let field = |field: &str, p: Primitive, array: bool| {
            layout
                .fields
                .iter()
                .find(|f| {
                    f.name == field
                        && f.kind == FieldKind::Primitive(p)
                        && f.array_len.is_some() == array
                })
                .map(|f| (f.offset, f.array_len.map_or(1, usize::from)))
        };
        Ok(EventLayout {
            id: field("id", Primitive::UInt32, false)
                .ok_or_else(|| error("no `uint32_t id`"))?
                .0,
            log_levels: field("log_levels", Primitive::UInt8, false)
                .ok_or_else(|| error("no `uint8_t log_levels`"))?
                .0,
            sequence: field("event_sequence", Primitive::UInt16, false).map(|f| f.0),
            arguments: field("arguments", Primitive::UInt8, true)
                .ok_or_else(|| error("no `uint8_t[N] arguments`"))?,
        })
    }

    /// The event of a row of that format; `None` if the row is too short.
    pub fn read(&self, row: &Row<'_>) -> Option<EventRow> {
        let d = row.data;
        let u32_at = |at: usize| Some(u32::from_le_bytes(d.get(at..at + 4)?.try_into().ok()?));
        let (at, n) = self.arguments;
        Some(EventRow {
            timestamp: row.timestamp,
            id: u32_at(self.id)?,
            sequence: match self.sequence {
                Some(at) => Some(u16::from_le_bytes(d.get(at..at + 2)?.try_into().ok()?)),
                None => None,
            },
            arguments: d.get(at..at + n)?.to_vec(),
            log_levels: *d.get(self.log_levels)?,
            offset: row.offset,
        })
    }
}

/// An event decoded with its definition.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedEvent {
    /// Its name.
    pub name: String,
    /// Its component's namespace (`px4`).
    pub namespace: String,
    /// Its group (`default`; PX4's tools show only those).
    pub group: String,
    /// Its type, if the definition has one.
    pub kind: Option<String>,
    /// Its arguments: name, value, and the value as a placeholder shows it (enum text).
    pub arguments: Vec<(String, ArgValue, Result<String, FormatError>)>,
    /// The message, formatted.
    pub message: Result<String, FormatError>,
    /// The description, formatted, if the event has one.
    pub description: Option<Result<String, FormatError>>,
}

/// Why a row could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum EventError {
    /// The metadata has no event of this id.
    #[error("[Unknown event with ID {0}]")]
    UnknownId(u32),
    /// An argument's type is neither basic nor an enum of the metadata.
    #[error(
        "event `{event}`: argument `{arg}` has type `{ty}`, which the metadata does not define"
    )]
    UnknownType {
        /// The event.
        event: String,
        /// The argument.
        arg: String,
        /// Its type.
        ty: String,
    },
    /// The arguments need more bytes than the row has.
    #[error("event `{event}`: its arguments need {need} bytes, the row has {have}")]
    ShortArguments {
        /// The event.
        event: String,
        /// Bytes needed.
        need: usize,
        /// Bytes logged.
        have: usize,
    },
}

/// Decodes a row with `definitions`, formatting for the `dev` profile.
pub fn decode(row: &EventRow, definitions: &EventDefinitions) -> Result<DecodedEvent, EventError> {
    let found = definitions
        .find(row.id)
        .ok_or(EventError::UnknownId(row.id))?;
    let def = found.event;
    let namespace = &found.component.namespace;
    let mut args = Vec::with_capacity(def.arguments.len());
    let mut offset = 0;
    for a in &def.arguments {
        let (base, e) = if ArgValue::size_of(&a.ty).is_some() {
            (a.ty.as_str(), None)
        } else {
            let e = definitions
                .enum_of(&a.ty, namespace)
                .filter(|e| ArgValue::size_of(&e.base).is_some())
                .ok_or_else(|| EventError::UnknownType {
                    event: def.name.clone(),
                    arg: a.name.clone(),
                    ty: a.ty.clone(),
                })?;
            (e.base.as_str(), Some(e.as_ref()))
        };
        let size = ArgValue::size_of(base).expect("a basic type");
        let value = row
            .arguments
            .get(offset..)
            .and_then(|b| ArgValue::read(base, b))
            .ok_or_else(|| EventError::ShortArguments {
                event: def.name.clone(),
                need: offset + size,
                have: row.arguments.len(),
            })?;
        offset += size;
        args.push((value, e));
    }
    Ok(DecodedEvent {
        name: def.name.clone(),
        namespace: namespace.clone(),
        group: found.group.to_owned(),
        kind: def.kind.clone(),
        arguments: def
            .arguments
            .iter()
            .zip(&args)
            .map(|(a, &(v, e))| (a.name.clone(), v, format::display_value(v, e)))
            .collect(),
        message: format_message(&def.message, &args, PROFILE),
        description: def
            .description
            .as_deref()
            .map(|d| format_message(d, &args, PROFILE)),
    })
}

/// A log's events: the `event` rows of instance 0 in file order, and its metadata.
#[derive(Debug)]
pub struct Events {
    /// The rows (empty if the log has no `event` topic).
    pub rows: Vec<EventRow>,
    /// The metadata, or why there is none to use.
    pub metadata: Result<EventsMetadata, MetadataError>,
    /// Why the `event` topic's rows could not be read, if it could not.
    pub layout_error: Option<LayoutError>,
}

impl Log<'_> {
    /// The log's events: every `event` row of instance 0 in file order, and the embedded
    /// metadata to decode them with ([`decode`]).
    pub fn events(&self) -> Events {
        // The subscriptions of a topic share its one format, so one layout reads them all.
        let subs = self.instance(TOPIC, 0);
        let (rows, layout_error) = match subs.first().and_then(|s| s.format()) {
            None => (Vec::new(), None),
            Some(id) => match EventLayout::of(self.metadata().schema(), id) {
                Ok(layout) => (
                    self.instance_rows(&subs)
                        .filter_map(|r| layout.read(&r))
                        .collect(),
                    None,
                ),
                Err(e) => (Vec::new(), Some(e)),
            },
        };
        Events {
            rows,
            metadata: EventsMetadata::of(self.metadata()),
            layout_error,
        }
    }
}
