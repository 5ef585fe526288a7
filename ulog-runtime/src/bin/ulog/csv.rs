//! `ulog csv`: one file per topic instance, as pyulog's `ulog2csv` writes them.

use std::io::Write;
use std::path::{Path, PathBuf};

use ulog_runtime::read::Subscription;
use ulog_runtime::schema::{FieldKind, FormatId, Primitive, Schema};
use ulog_runtime::{Log, Scalar};

use crate::number::{f32_text, f64_text};
use crate::{Failure, Progress};

/// `ulog csv FILE [-m a,b] [-o DIR] [-d ;] [--start S --end S]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log.
    file: PathBuf,
    /// Only these topics (comma-separated).
    #[arg(short, long, value_delimiter = ',')]
    messages: Vec<String>,
    /// Output directory (default: beside the log).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Field separator.
    #[arg(short, long, default_value = ",")]
    delimiter: String,
    /// Only rows from this time on, in seconds (pyulog's `-ts`, `--time_s`).
    #[arg(long, alias = "time_s")]
    start: Option<f64>,
    /// Only rows before this time, in seconds (pyulog's `-te`, `--time_e`).
    #[arg(long, alias = "time_e")]
    end: Option<f64>,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    let log = crate::open(&args.file)?;
    crate::check_topics(&log, &args.file, &args.messages)?;
    let options = Options {
        topics: args.messages.clone(),
        output: args.output.clone(),
        delimiter: args.delimiter.clone(),
        start_us: args.start.map(|s| s * 1e6),
        end_us: args.end.map(|s| s * 1e6),
    };
    let mut progress = Progress::new(log.row_count(), log.bytes().len());
    let written = write_all(&log, &args.file, &options, &mut progress)?;
    progress.done();
    for (path, rows) in &written {
        writeln!(out, "{} ({rows} rows)", path.display())?;
    }
    report_skipped(&log, &args.file, &args.messages, written.is_empty());
    Ok(())
}

/// Says on stderr what the export left out, so that nothing is skipped silently.
fn report_skipped(log: &Log<'_>, file: &Path, topics: &[String], nothing_written: bool) {
    let wanted = |t: &str| topics.is_empty() || topics.iter().any(|w| w == t);
    let skipped = log.skipped();
    let say = |what: String| eprintln!("ulog: {}: {what}", file.display());
    for (topic, msg_id, why) in skipped.unreadable_topics.iter().filter(|t| wanted(&t.0)) {
        say(format!("skipped topic `{topic}` (msg_id {msg_id}): {why}"));
    }
    for (topic, multi_id, rows) in skipped.misfit_rows.iter().filter(|t| wanted(&t.0)) {
        say(format!(
            "skipped {rows} row{} of `{topic}` #{multi_id} whose size does not fit the format",
            if *rows == 1 { "" } else { "s" }
        ));
    }
    if skipped.orphan_rows > 0 && topics.is_empty() {
        say(format!(
            "skipped {} row{} of msg_ids no subscription declares",
            skipped.orphan_rows,
            if skipped.orphan_rows == 1 { "" } else { "s" }
        ));
    }
    if skipped.damaged_bytes > 0 {
        say(format!(
            "{} damaged bytes skipped (`ulog info -v` lists where)",
            skipped.damaged_bytes
        ));
    }
    if nothing_written {
        say("no CSV file written: no topic has rows that can be read".to_owned());
    }
}

struct Options {
    topics: Vec<String>,
    output: Option<PathBuf>,
    delimiter: String,
    start_us: Option<f64>,
    end_us: Option<f64>,
}

/// One CSV column: a number at an offset, or a `char` array as text.
enum Column {
    Number {
        name: String,
        primitive: Primitive,
        offset: usize,
    },
    Text {
        name: String,
        offset: usize,
        len: usize,
    },
}

impl Column {
    fn name(&self) -> &str {
        match self {
            Column::Number { name, .. } | Column::Text { name, .. } => name,
        }
    }
}

/// pyulog's columns: every leaf in format order (`q[0]`, `esc[3].esc_rpm`), top-level
/// `_padding*` fields left out (padding inside nested types kept, as pyulog keeps it),
/// `char` arrays as one text column, `timestamp` first.
fn columns(schema: &Schema, id: FormatId) -> Vec<Column> {
    let mut out = Vec::new();
    flatten(schema, id, 0, "", true, &mut out);
    if let Some(i) = out.iter().position(|c| c.name() == "timestamp") {
        let ts = out.remove(i);
        out.insert(0, ts);
    }
    out
}

fn flatten(
    schema: &Schema,
    id: FormatId,
    base: usize,
    prefix: &str,
    top: bool,
    out: &mut Vec<Column>,
) {
    let Some(layout) = schema.resolved(id) else {
        return;
    };
    for f in &layout.fields {
        if top && f.name.starts_with("_padding") {
            continue;
        }
        let start = base + f.offset;
        match (f.kind, f.array_len) {
            (FieldKind::Primitive(Primitive::Char), Some(n)) => out.push(Column::Text {
                name: format!("{prefix}{}", f.name),
                offset: start,
                len: usize::from(n),
            }),
            (kind, len) => {
                for i in 0..len.map_or(1, usize::from) {
                    let name = match len {
                        Some(_) => format!("{prefix}{}[{i}]", f.name),
                        None => format!("{prefix}{}", f.name),
                    };
                    let offset = start + i * f.elem_size;
                    match kind {
                        FieldKind::Primitive(primitive) => out.push(Column::Number {
                            name,
                            primitive,
                            offset,
                        }),
                        FieldKind::Nested(nested) => {
                            flatten(schema, nested, offset, &format!("{name}."), false, out);
                        }
                    }
                }
            }
        }
    }
}

/// A value as pyulog writes it: integers in decimal, `bool` and `char` as their signed byte
/// (pyulog reads both as `int8`), floats as numpy prints them (parsing gives back the stored
/// value).
fn write_number(out: &mut String, p: Primitive, b: &[u8]) {
    use std::fmt::Write as _;
    match Scalar::decode(p, b) {
        Some(Scalar::Float(x)) => out.push_str(&f32_text(x)),
        Some(Scalar::Double(x)) => out.push_str(&f64_text(x)),
        // The raw byte: a `bool` of 0x41 is 65 for pyulog, not 1.
        Some(Scalar::Bool(_)) => {
            let _ = write!(out, "{}", b[0] as i8);
        }
        Some(other) => {
            let _ = write!(out, "{other}");
        }
        None => {}
    }
}

/// Text up to the first zero byte, each byte one character (as pyulog's `chr`).
fn write_text(out: &mut String, bytes: &[u8]) {
    out.extend(
        bytes
            .iter()
            .take_while(|&&b| b != 0)
            .map(|&b| char::from(b)),
    );
}

/// The subscriptions to export, grouped by (name, multi_id), in file order.
pub(crate) fn selected<'a>(log: &'a Log<'_>, topics: &[String]) -> Vec<Vec<&'a Subscription>> {
    let mut groups: Vec<Vec<&Subscription>> = Vec::new();
    for sub in log.subscriptions() {
        if sub.format().is_none() || (!topics.is_empty() && !topics.contains(&sub.name)) {
            continue;
        }
        match groups
            .iter_mut()
            .find(|g| g[0].name == sub.name && g[0].multi_id == sub.multi_id)
        {
            Some(g) => g.push(sub),
            None => groups.push(vec![sub]),
        }
    }
    groups.retain(|g| g.iter().any(|s| log.rows(s).len() > 0));
    groups
}

/// Writes one CSV per topic instance with rows; returns the files and their row counts.
fn write_all(
    log: &Log<'_>,
    file: &Path,
    options: &Options,
    progress: &mut Progress,
) -> Result<Vec<(PathBuf, usize)>, Failure> {
    let stem = file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = stem
        .strip_suffix(".ulg")
        .or_else(|| stem.strip_suffix(".ULG"))
        .unwrap_or(&stem)
        .to_owned();
    let dir = match &options.output {
        Some(d) => {
            std::fs::create_dir_all(d).map_err(|e| Failure::at(d, e))?;
            d.clone()
        }
        None => file.parent().map(Path::to_owned).unwrap_or_default(),
    };
    let schema = log.metadata().schema();
    let mut written = Vec::new();
    let mut names = ulog_runtime::file_names::FileNames::new();
    let prefix = format!("{stem}_");
    for group in selected(log, &options.topics) {
        let sub = group[0];
        let id = sub.format().expect("selected subscriptions have formats");
        let cols = columns(schema, id);
        let name = names.unique(&prefix, &sub.name, &format!("_{}.csv", sub.multi_id));
        let path = dir.join(&name.file_name);
        if let Some(other) = name.collided_with {
            eprintln!(
                "ulog: {}: topics `{other}` and `{}` map to one file name; `{}` #{} goes to {}",
                file.display(),
                sub.name,
                sub.name,
                sub.multi_id,
                path.display()
            );
        }
        let io = |e| Failure::at(&path, e);
        let mut out = std::io::BufWriter::new(std::fs::File::create(&path).map_err(io)?);
        let header: Vec<&str> = cols.iter().map(Column::name).collect();
        writeln!(out, "{}", header.join(&options.delimiter)).map_err(io)?;
        let mut line = String::new();
        let mut count = 0;
        let rows = group.iter().flat_map(|s| log.rows(s));
        // As ulog2csv: from the first row at or after the start, up to the first row at or
        // after the end.
        let mut started = options.start_us.is_none();
        for row in rows {
            progress.add(1);
            let t = row.timestamp as f64;
            if !started {
                started = options.start_us.is_some_and(|s| t >= s);
                if !started {
                    continue;
                }
            }
            if options.end_us.is_some_and(|e| t >= e) {
                break;
            }
            line.clear();
            for (k, c) in cols.iter().enumerate() {
                if k > 0 {
                    line.push_str(&options.delimiter);
                }
                match c {
                    Column::Number {
                        primitive, offset, ..
                    } => {
                        // Past a row shortened by its trailing padding there is nothing to show.
                        if let Some(b) = row.data.get(*offset..*offset + primitive.size()) {
                            write_number(&mut line, *primitive, b);
                        }
                    }
                    Column::Text { offset, len, .. } => {
                        let end = (*offset + *len).min(row.data.len());
                        write_text(&mut line, row.data.get(*offset..end).unwrap_or_default());
                    }
                }
            }
            line.push('\n');
            out.write_all(line.as_bytes()).map_err(io)?;
            count += 1;
        }
        out.flush().map_err(io)?;
        written.push((path, count));
    }
    Ok(written)
}
