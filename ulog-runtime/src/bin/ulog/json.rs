//! `ulog json`: rows as JSON Lines, or one document with the metadata and every row.

use std::io::Write;
use std::path::PathBuf;

use ulog_runtime::Log;
use ulog_runtime::read::Subscription;

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
    /// One document with the metadata and every topic's rows.
    #[arg(long)]
    document: bool,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    let log = crate::open(&args.file)?;
    crate::check_topics(&log, &args.file, &args.messages)?;
    json(&log, &args.messages, args.document, out)
}

/// `ulog json`: JSON Lines (`{"topic", "multi_id", "timestamp", "data"}` per row, file order)
/// or one document with the metadata and every instance's rows.
fn json(
    log: &Log<'_>,
    topics: &[String],
    document: bool,
    out: &mut impl Write,
) -> Result<(), Failure> {
    use serde_json::{Map, Value as Json, json};
    let wanted = |s: &Subscription| topics.is_empty() || topics.contains(&s.name);
    if !document {
        for row in log.data() {
            if !wanted(row.subscription) {
                continue;
            }
            let line = json!({
                "topic": row.subscription.name,
                "multi_id": row.subscription.multi_id,
                "timestamp": row.timestamp,
                "data": row.value(),
            });
            serde_json::to_writer(&mut *out, &line)?;
            out.write_all(b"\n")?;
        }
        return Ok(());
    }
    let meta = log.metadata();
    let mut info = Map::new();
    for i in meta.info() {
        info.insert(i.key.clone(), serde_json::to_value(&i.value)?);
    }
    let mut params = Map::new();
    for p in meta.initial_parameters() {
        params.insert(p.name.clone(), json!(p.value.as_f64()));
    }
    let mut instances = Vec::new();
    for group in selected(log, topics) {
        let rows: Vec<Json> = group
            .iter()
            .flat_map(|s| log.rows(s))
            .map(|r| json!({"timestamp": r.timestamp, "data": r.value()}))
            .collect();
        instances.push(json!({
            "topic": group[0].name,
            "multi_id": group[0].multi_id,
            "format": meta.schema().format(group[0].format().expect("selected")).to_string(),
            "rows": rows,
        }));
    }
    let doc = json!({
        "version": log.header().version,
        "start_timestamp": log.header().start_timestamp,
        "info": info,
        "parameters": params,
        "logged_messages": log.logged_messages().iter().map(|m| json!({
            "timestamp": m.timestamp,
            "level": m.level().map(|l| l.name()),
            "tag": m.tag,
            "text": m.text,
        })).collect::<Vec<_>>(),
        "topics": instances,
    });
    serde_json::to_writer_pretty(&mut *out, &doc)?;
    out.write_all(b"\n")?;
    Ok(())
}
