//! What pyulog 1.3.0's `ulog_messages` prints for a log, line for line:

use super::{EventError, decode};
use crate::Value;
use crate::read::{Log, LoggedMessage};

/// What a line shows.
#[derive(Debug, Clone, PartialEq)]
pub enum MessageKind {
    /// A logged string (`L`).
    Logged,
    /// A tagged logged string (`C`).
    Tagged(u16),
    /// An event.
    Event {
        /// Its id.
        id: u32,
        /// Its name, if the metadata has it.
        name: Option<String>,
        /// Its external log level.
        external_level: u8,
        /// Its sequence number.
        sequence: Option<u16>,
        /// Its arguments as shown (name and text), if decoded.
        arguments: Vec<(String, String)>,
        /// Its description, formatted, if it has one.
        description: Option<String>,
    },
}

/// One line of the messages.
#[derive(Debug, Clone, PartialEq)]
pub struct MessageLine {
    /// µs.
    pub timestamp: u64,
    /// The level's name (`INFO`); for events the internal level.
    pub level: &'static str,
    /// The text.
    pub text: String,
    /// What it is.
    pub kind: MessageKind,
}

impl MessageLine {
    /// The line as `ulog_messages` prints it: `h:mm:ss.mmm LEVEL: text` (hours not padded).
    pub fn pyulog_line(&self) -> String {
        // pyulog: int(t / 1000), then divmod.
        let total_ms = (self.timestamp as f64 / 1000.0) as u64;
        let s = total_ms / 1000;
        let tag = match self.kind {
            MessageKind::Tagged(t) => format!("[tag {t}] "),
            _ => String::new(),
        };
        format!(
            "{}:{:02}:{:02}.{:03} {}: {tag}{}",
            s / 3600,
            s / 60 % 60,
            s % 60,
            total_ms % 1000,
            self.level,
            self.text
        )
    }
}

/// What `ulog_messages` prints: see [`messages`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Messages {
    /// Lines pyulog prints before the messages (its warnings while reading).
    pub warnings: Vec<String>,
    /// The messages.
    pub lines: Vec<MessageLine>,
    /// What was left out and why, for a note on stderr (pyulog says nothing).
    pub notes: Vec<String>,
}

/// A logged string's level name as pyulog gives it: ASCII `'0'..'7'` only.
fn level_name(m: &LoggedMessage) -> &'static str {
    match m.level_byte {
        b'0'..=b'7' => {
            crate::read::LogLevel::from_byte(m.level_byte).map_or("UNKNOWN", |l| l.name())
        }
        _ => "UNKNOWN",
    }
}

/// The lines of pyulog's `ulog_messages` for `log`.
///
/// What pyulog 1.3.0's `ulog_messages` prints for a log, line for line:
///
/// 1. the warnings pyulog prints while it reads the file (a file version above 1,
///    `Warning: no subscription found for message id N. Continuing, but file is most likely
///    corrupt` once per `msg_id` no subscription declares), and `Failed to get event parser: ...` when a PX4 log has events but no
///    usable metadata;
/// 2. the messages, `h:mm:ss.mmm LEVEL: text`. For a log whose `sys_name` is `PX4`: its
///    events of internal level below 8 in the `default` group (an id the metadata lacks as
///    `[Unknown event with ID N]`), then its logged strings except those ending in a tab
///    (PX4 logs those beside an event that says the same), sorted by time, events first at
///    equal times. For other logs: the logged strings in file order.
///
/// Where pyulog stops listing events (an event whose message cannot be formatted, or whose
/// argument type the metadata lacks, ends the list there), so does this, and
/// [`Messages::notes`] says why. One difference, where pyulog cannot go on: an event whose
/// arguments are cut short ends the list with a note (pyulog stops with a Python error).
/// And one where pyulog reaches out: for a PX4 log with events but no events metadata of
/// its own, pyulog downloads PX4's current definitions from the network (and prints its
/// download error without one); this reader never does, and says the log has none.
///
/// When the events cannot be shown (no usable metadata or event rows), the logged strings
/// ending in a tab, left out as pyulog leaves them out, show nowhere: [`Messages::notes`]
/// says how many.
///
/// Tagged strings (`C` messages) are not among them, as pyulog leaves them out:
/// [`all_messages`] lists them too.
pub fn messages(log: &Log<'_>) -> Messages {
    listed(log, false)
}

/// [`messages`] and, among the logged strings, the tagged ones (`C` messages, which
/// `ulog_messages` leaves out), each as `[tag N] text` ([`MessageKind::Tagged`]).
pub fn all_messages(log: &Log<'_>) -> Messages {
    listed(log, true)
}

fn listed(log: &Log<'_>, tagged: bool) -> Messages {
    let mut out = Messages {
        warnings: crate::tools::pyulog_warnings(log),
        ..Messages::default()
    };
    let meta = log.metadata();
    let strings = log.logged_messages().iter();
    let strings = strings.filter(|m| tagged || m.tag.is_none());
    let strings = strings.map(|m| MessageLine {
        timestamp: m.timestamp,
        level: level_name(m),
        text: m.text.clone(),
        kind: match m.tag {
            Some(t) => MessageKind::Tagged(t),
            None => MessageKind::Logged,
        },
    });
    let strings: Vec<MessageLine> = strings.collect();
    let px4 = matches!(meta.info_value("sys_name"), Some(Value::String(s)) if s == "PX4");
    if !px4 {
        out.lines = strings;
        return out;
    }
    let shown = px4_events(log, &mut out);
    let undecoded = shown.is_none();
    let mut lines = shown.unwrap_or_default();
    let (copies, strings): (Vec<MessageLine>, Vec<MessageLine>) =
        strings.into_iter().partition(|m| m.text.ends_with('\t'));
    if undecoded && !copies.is_empty() {
        out.notes.push(format!(
            "{} logged string{} ending in a tab left out, as pyulog leaves them out (PX4 logs \
             each beside an event that says the same), though the events could not be shown; \
             `ulog json --document` lists them",
            copies.len(),
            if copies.len() == 1 { "" } else { "s" }
        ));
    }
    lines.extend(strings);
    // Stable: events before strings at equal times, each in its order.
    lines.sort_by_key(|m| m.timestamp);
    out.lines = lines;
    out
}

/// The events `ulog_messages` shows, in file order; `None` when they cannot be shown (the
/// event rows unreadable, or no usable metadata for them).
fn px4_events(log: &Log<'_>, out: &mut Messages) -> Option<Vec<MessageLine>> {
    let events = log.events();
    if let Some(e) = &events.layout_error {
        out.notes.push(format!("events not shown: {e}"));
        return None;
    }
    if events.rows.is_empty() {
        return Some(Vec::new());
    }
    let definitions = match &events.metadata {
        Ok(m) => {
            if let super::Verification::Mismatch { expected, actual } = &m.verification {
                out.notes.push(format!(
                    "the events metadata's sha256 is {actual}, the log says {expected}: decoded anyway, as pyulog does"
                ));
            }
            &m.definitions
        }
        Err(e) => {
            out.warnings
                .push(format!("Failed to get event parser: {e}"));
            return None;
        }
    };
    let mut lines = Vec::new();
    let total = events.rows.len();
    for (i, row) in events.rows.iter().enumerate() {
        let level = row.internal_level();
        if level.0 >= 8 {
            continue;
        }
        let line = |text: String, kind| MessageLine {
            timestamp: row.timestamp,
            level: level.name(),
            text,
            kind,
        };
        let stop = |why: String, out: &mut Messages| {
            out.notes.push(format!(
                "events from row {i} of {total} (at {} µs) on not shown, as pyulog stops there: {why}",
                row.timestamp
            ));
        };
        match decode(row, definitions) {
            Err(EventError::UnknownId(id)) => lines.push(line(
                format!("[Unknown event with ID {id}]"),
                MessageKind::Event {
                    id,
                    name: None,
                    external_level: row.external_level().0,
                    sequence: row.sequence,
                    arguments: Vec::new(),
                    description: None,
                },
            )),
            Err(e) => {
                stop(e.to_string(), out);
                break;
            }
            Ok(e) if e.group != "default" => {}
            Ok(e) => match e.message {
                Ok(text) => lines.push(line(
                    text,
                    MessageKind::Event {
                        id: row.id,
                        name: Some(e.name.clone()),
                        external_level: row.external_level().0,
                        sequence: row.sequence,
                        arguments: e
                            .arguments
                            .iter()
                            .map(|(n, v, shown)| {
                                (n.clone(), shown.clone().unwrap_or_else(|_| v.to_string()))
                            })
                            .collect(),
                        description: e.description.and_then(Result::ok),
                    },
                )),
                Err(why) => {
                    stop(format!("event `{}`: {why}", e.name), out);
                    break;
                }
            },
        }
    }
    Some(lines)
}
