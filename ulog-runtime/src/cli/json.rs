//! `ulog json`: rows as JSON Lines, or one document with the metadata and every row.
//!
//! Values keep their types: integers as integers (parameters too), `float` values in their
//! shortest text, `char` arrays as text. JSON has no NaN or infinity: those are written as
//! `null`.

use std::io::Write;
use std::path::PathBuf;

use crate::document::LogFacts;
use crate::read::Subscription;
use crate::{Log, Value};
use serde::Serialize;
use serde::ser::SerializeSeq;

use crate::cli::Failure;

/// `ulog json FILE [-m a,b] [--document]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log.
    file: PathBuf,
    /// Only these topics (comma-separated).
    #[arg(short, long, value_delimiter = ',')]
    messages: Vec<String>,
    /// One document: the log's facts as `ulog parquet` writes them to metadata.json (header,
    /// flag bits, info, multi info, parameters, changes and defaults, logged strings,
    /// dropouts, per-topic row counts, what was skipped, diagnostics) and, under `data`,
    /// every topic instance's rows. NaN and infinities are written as null.
    #[arg(long)]
    document: bool,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    let messages = crate::cli::topic_list(&args.messages);
    let log = crate::cli::open(&args.file)?;
    crate::cli::check_topics(&log, &args.file, &messages)?;
    if args.document {
        serde_json::to_writer_pretty(&mut *out, &Document::new(&log, &messages))?;
        out.write_all(b"\n")?;
        report_skipped(&log, args, &messages);
        return Ok(());
    }
    let wanted = |s: &Subscription| messages.is_empty() || messages.contains(&s.name);
    let mut lines = 0usize;
    for row in log.data() {
        if !wanted(row.subscription) {
            continue;
        }
        lines += 1;
        let line = RowLine {
            topic: &row.subscription.name,
            multi_id: row.subscription.multi_id,
            timestamp: row.timestamp,
            data: row.value(),
        };
        serde_json::to_writer(&mut *out, &line)?;
        out.write_all(b"\n")?;
    }
    report_skipped(&log, args, &messages);
    if lines == 0 {
        // An empty output is a valid JSON Lines file: say why it is empty.
        eprintln!(
            "ulog: {}: {}",
            args.file.display(),
            crate::columns::Window::default().nothing_written("row", &messages)
        );
    }
    Ok(())
}

/// What the output lacks of the file (damage, unreadable topics, rows that do not fit), on
/// stderr as the other exports say it; the document also holds it under `skipped`.
fn report_skipped(log: &Log<'_>, args: &Args, messages: &[String]) {
    crate::cli::report_skipped(
        &log.skipped(),
        &args.file,
        messages,
        None,
        &crate::columns::Window::default(),
    );
}

/// One row of the JSON Lines output.
#[derive(Serialize)]
struct RowLine<'a> {
    topic: &'a str,
    multi_id: u8,
    timestamp: u64,
    data: Option<Value>,
}

/// `--document`: the log's facts (as a Parquet conversion's metadata.json has them) and
/// every selected topic instance's rows.
#[derive(Serialize)]
struct Document<'a> {
    #[serde(flatten)]
    facts: LogFacts,
    data: Vec<Topic<'a>>,
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
        // In file order: a resubscribed instance's rows interleave as the file has them.
        for r in self.log.instance_rows(&self.subs) {
            seq.serialize_element(&Row {
                timestamp: r.timestamp,
                data: r.value(),
            })?;
        }
        seq.end()
    }
}

impl<'a> Document<'a> {
    fn new(log: &'a Log<'a>, topics: &[String]) -> Document<'a> {
        let schema = log.metadata().schema();
        Document {
            facts: LogFacts::of_log(log),
            data: log
                .instances(topics)
                .into_iter()
                .map(|group| Topic {
                    topic: &group[0].name,
                    multi_id: group[0].multi_id,
                    format: group[0]
                        .format()
                        .map(|id| schema.format(id).to_string())
                        .unwrap_or_default(),
                    rows: Rows { log, subs: group },
                })
                .collect(),
        }
    }
}
