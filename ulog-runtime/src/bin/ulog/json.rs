//! `ulog json`: rows as JSON Lines, or one document with the metadata and every row.
//!
//! Values keep their types: integers as integers (parameters too), `float` values in their
//! shortest text, `char` arrays as text. JSON has no NaN or infinity: those are written as
//! `null`.

use std::io::Write;
use std::path::PathBuf;

use serde::Serialize;
use serde::ser::{SerializeMap, SerializeSeq};
use ulog_runtime::read::{ParamValue, Subscription};
use ulog_runtime::{Log, Value};

use crate::Failure;
use crate::csv::selected;

/// `ulog json FILE [-m a,b] [--document]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log.
    file: PathBuf,
    /// Only these topics (comma-separated).
    #[arg(short, long, value_delimiter = ',')]
    messages: Vec<String>,
    /// One document: header, info, multi info, parameters (initial, changes, defaults),
    /// logged strings, dropouts, diagnostics and every topic's rows. NaN and infinities are
    /// written as null.
    #[arg(long)]
    document: bool,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    let log = crate::open(&args.file)?;
    crate::check_topics(&log, &args.file, &args.messages)?;
    if args.document {
        serde_json::to_writer_pretty(&mut *out, &Document::new(&log, &args.messages))?;
        out.write_all(b"\n")?;
        return Ok(());
    }
    let wanted = |s: &Subscription| args.messages.is_empty() || args.messages.contains(&s.name);
    for row in log.data() {
        if !wanted(row.subscription) {
            continue;
        }
        let line = RowLine {
            topic: &row.subscription.name,
            multi_id: row.subscription.multi_id,
            timestamp: row.timestamp,
            data: row.value(),
        };
        serde_json::to_writer(&mut *out, &line)?;
        out.write_all(b"\n")?;
    }
    Ok(())
}

/// One row of the JSON Lines output.
#[derive(Serialize)]
struct RowLine<'a> {
    topic: &'a str,
    multi_id: u8,
    timestamp: u64,
    data: Option<Value>,
}

/// Pairs serialized as a map, in their order (a log's order, not sorted).
struct Ordered<'a, V>(Vec<(&'a str, V)>);

impl<V: Serialize> Serialize for Ordered<'_, V> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

#[derive(Serialize)]
struct Document<'a> {
    version: u8,
    start_timestamp: u64,
    software_version: Option<String>,
    info: Ordered<'a, &'a Value>,
    /// Per key: every value, each as its parts (a value and its continuations).
    multi_info: Ordered<'a, &'a [Vec<Value>]>,
    parameters: Ordered<'a, ParamValue>,
    parameter_changes: Vec<Change<'a>>,
    default_parameters: Vec<Default<'a>>,
    logged_messages: Vec<Logged<'a>>,
    dropouts: Vec<Dropout>,
    diagnostics: Vec<String>,
    topics: Vec<Topic<'a>>,
}

#[derive(Serialize)]
struct Change<'a> {
    timestamp: u64,
    name: &'a str,
    value: ParamValue,
}

#[derive(Serialize)]
struct Default<'a> {
    name: &'a str,
    value: ParamValue,
    /// Bit 0: the system default; bit 1: the current setup's.
    default_types: u8,
}

#[derive(Serialize)]
struct Logged<'a> {
    timestamp: u64,
    level: Option<&'static str>,
    tag: Option<u16>,
    text: &'a str,
}

#[derive(Serialize)]
struct Dropout {
    timestamp: u64,
    duration_ms: u16,
}

#[derive(Serialize)]
struct Topic<'a> {
    topic: &'a str,
    multi_id: u8,
    format: String,
    rows: Rows<'a>,
}

/// A topic instance's rows, decoded as they are written (never all in memory at once).
struct Rows<'a> {
    log: &'a Log<'a>,
    subs: Vec<&'a Subscription>,
}

impl Serialize for Rows<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Row {
            timestamp: u64,
            data: Option<Value>,
        }
        let len = self.subs.iter().map(|sub| self.log.rows(sub).len()).sum();
        let mut seq = s.serialize_seq(Some(len))?;
        for sub in &self.subs {
            for r in self.log.rows(sub) {
                seq.serialize_element(&Row {
                    timestamp: r.timestamp,
                    data: r.value(),
                })?;
            }
        }
        seq.end()
    }
}

impl<'a> Document<'a> {
    fn new(log: &'a Log<'a>, topics: &[String]) -> Document<'a> {
        let meta = log.metadata();
        Document {
            version: log.header().version,
            start_timestamp: log.header().start_timestamp,
            software_version: meta.software_version(),
            info: Ordered(
                meta.info()
                    .iter()
                    .map(|i| (i.key.as_str(), &i.value))
                    .collect(),
            ),
            multi_info: Ordered(
                meta.multi_info()
                    .iter()
                    .map(|m| (m.key.as_str(), m.values.as_slice()))
                    .collect(),
            ),
            parameters: Ordered(
                meta.initial_parameters()
                    .iter()
                    .map(|p| (p.name.as_str(), p.value))
                    .collect(),
            ),
            parameter_changes: log
                .parameter_changes()
                .iter()
                .map(|c| Change {
                    timestamp: c.timestamp,
                    name: &c.name,
                    value: c.value,
                })
                .collect(),
            default_parameters: meta
                .default_parameters()
                .iter()
                .map(|d| Default {
                    name: &d.name,
                    value: d.value,
                    default_types: d.default_types,
                })
                .collect(),
            logged_messages: log
                .logged_messages()
                .iter()
                .map(|m| Logged {
                    timestamp: m.timestamp,
                    level: m.level().map(|l| l.name()),
                    tag: m.tag,
                    text: &m.text,
                })
                .collect(),
            dropouts: log
                .dropouts()
                .iter()
                .map(|d| Dropout {
                    timestamp: d.timestamp,
                    duration_ms: d.duration_ms,
                })
                .collect(),
            diagnostics: log.diagnostics().iter().map(ToString::to_string).collect(),
            topics: selected(log, topics)
                .into_iter()
                .map(|group| Topic {
                    topic: &group[0].name,
                    multi_id: group[0].multi_id,
                    format: meta
                        .schema()
                        .format(
                            group[0]
                                .format()
                                .expect("selected subscriptions have formats"),
                        )
                        .to_string(),
                    rows: Rows { log, subs: group },
                })
                .collect(),
        }
    }
}
