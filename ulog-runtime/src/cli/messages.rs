//! `ulog messages`: logged strings and PX4 events as pyulog's `ulog_messages` prints them,
//! over `events::messages` (`events::all_messages` with `--tagged`).

use std::io::Write;
use std::path::PathBuf;

use crate::events::{MessageKind, MessageLine, all_messages, messages};
use serde::Serialize;

use crate::cli::Failure;

/// `ulog messages FILE [-i] [--json] [--tagged]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log.
    file: PathBuf,
    /// Drop bytes of text that are not UTF-8 (pyulog's `-i`); without it such text is an
    /// error.
    #[arg(short, long)]
    ignore: bool,
    /// JSON Lines, one object per message with every field (pyulog's warnings go to stderr
    /// as `ulog: warning: FILE: ...`).
    #[arg(long)]
    json: bool,
    /// Also the tagged strings (`C` messages), as `[tag N] text` among the others, which
    /// `ulog_messages` leaves out.
    #[arg(long)]
    tagged: bool,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    let log = crate::cli::open(&args.file)?;
    crate::cli::check_utf8(&log, &args.file, args.ignore, "-i")?;
    crate::cli::report_damage(&log, &args.file);
    let m = if args.tagged {
        all_messages(&log)
    } else {
        messages(&log)
    };
    for note in &m.notes {
        eprintln!("ulog: {}: {note}", args.file.display());
    }
    if args.json {
        // pyulog prints its warnings among the messages; beside JSON on stdout they go to
        // stderr, marked as warnings (the exit code stays 0, as pyulog's).
        for w in &m.warnings {
            eprintln!("ulog: warning: {}: {w}", args.file.display());
        }
        for line in &m.lines {
            serde_json::to_writer(&mut *out, &JsonLine::of(line))?;
            out.write_all(b"\n")?;
        }
        return Ok(());
    }
    for w in &m.warnings {
        writeln!(out, "{w}")?;
    }
    for line in &m.lines {
        writeln!(out, "{}", line.pyulog_line())?;
    }
    Ok(())
}

/// One message of `--json`.
#[derive(Serialize)]
struct JsonLine<'a> {
    timestamp: u64,
    level: &'static str,
    text: &'a str,
    kind: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    tag: Option<u16>,
    #[serde(skip_serializing_if = "Option::is_none")]
    event: Option<JsonEvent<'a>>,
}

#[derive(Serialize)]
struct JsonEvent<'a> {
    id: u32,
    name: Option<&'a str>,
    external_level: u8,
    sequence: Option<u16>,
    arguments: Vec<JsonArg<'a>>,
    description: Option<&'a str>,
}

#[derive(Serialize)]
struct JsonArg<'a> {
    name: &'a str,
    value: &'a str,
}

impl<'a> JsonLine<'a> {
    fn of(line: &'a MessageLine) -> JsonLine<'a> {
        let (kind, tag, event) = match &line.kind {
            MessageKind::Logged => ("logged", None, None),
            MessageKind::Tagged(t) => ("tagged", Some(*t), None),
            MessageKind::Event {
                id,
                name,
                external_level,
                sequence,
                arguments,
                description,
            } => (
                "event",
                None,
                Some(JsonEvent {
                    id: *id,
                    name: name.as_deref(),
                    external_level: *external_level,
                    sequence: *sequence,
                    arguments: arguments
                        .iter()
                        .map(|(name, value)| JsonArg { name, value })
                        .collect(),
                    description: description.as_deref(),
                }),
            ),
        };
        JsonLine {
            timestamp: line.timestamp,
            level: line.level,
            text: &line.text,
            kind,
            tag,
            event,
        }
    }
}
