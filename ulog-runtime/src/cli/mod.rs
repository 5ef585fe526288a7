//! The `ulog` command-line tool (feature `cli`): inspect, export and generate from PX4 ULog
//! files, with pyulog's tools' options and output. [`main`] runs it on a list of arguments
//! (the `ulog` binary and the Python package's `ulog` command are a line or two over it,
//! [`handle_signals`] first). One
//! file per verb, each a thin layer over library calls; this file holds what they share:
//! opening logs, checking topic names, errors, progress. The verbs' doc comments are
//! clap's help text.

use std::ffi::OsString;
use std::io::{self, IsTerminal, Write};
use std::path::{Path, PathBuf};

use crate::Log;
use clap::{Parser, Subcommand};

mod analyze;
mod anonymize;
mod check_msg;
mod codegen;
mod csv;
mod cut;
mod gps_dump;
mod info;
mod json;
mod kml;
mod messages;
mod params;
mod parquet;
mod report;
mod signals;

pub use signals::handle_signals;

/// Inspect, export and generate code from PX4 ULog (.ulg) flight logs.
#[derive(Parser)]
#[command(name = "ulog", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Header, flag bits, info, subscriptions with rates, dropouts and damage.
    Info(info::Args),
    /// Parameters as pyulog's `ulog_params` writes them: `NAME,initial[,change...]`.
    Params(params::Args),
    /// Logged strings and PX4 events as pyulog's `ulog_messages` prints them (tagged strings
    /// with `--tagged`).
    Messages(messages::Args),
    /// One CSV per subscription, `<stem>_<topic>_<multi_id>.csv`, as pyulog's `ulog2csv`.
    Csv(csv::Args),
    /// A KML track of the GPS topic, colored by flight mode, as pyulog's `ulog2kml`.
    Kml(kml::Args),
    /// The raw GPS byte streams of the gps_dump topic, as pyulog's `ulog_extract_gps_dump`.
    GpsDump(gps_dump::Args),
    /// Per-topic Parquet files and a metadata.json per log, many logs in parallel
    /// (`DIR/<stem>/<topic>_<multi_id>.parquet`, or hive partitions with `--layout hive`).
    ///
    /// On Unix, Ctrl-C (or SIGTERM) starts no more logs and finishes those under way, then
    /// exits 130 (143); a second one ends the tool at once.
    Parquet(parquet::Args),
    /// Rows as JSON Lines (one object per row), or one JSON document.
    Json(json::Args),
    /// Rust types for a log's formats (several logs: one type per topic that reads them
    /// all), or for a folder of PX4 `.msg` files, as `ulog_runtime::codegen` makes them.
    Codegen(codegen::Args),
    /// Whether the `.msg` files of a folder make exactly a log's formats, and where not.
    CheckMsg(check_msg::Args),
    /// A new log of a time window and some topics (`--start`, `--end`, `-m`, `--exclude`).
    Cut(cut::Args),
    /// A new log with positions moved, times shifted and identifiers removed.
    Anonymize(anonymize::Args),
    /// The flight analysis: modes, statistics, battery, GPS, vibration, diagnostics.
    Analyze(analyze::Args),
    /// A flight report: one self-contained HTML file of plots and tables.
    Report(report::Args),
}

/// An error for the one line `ulog` prints: `ulog: PATH: message`.
pub(crate) struct Failure {
    /// The file concerned, printed before the message (once).
    path: Option<PathBuf>,
    message: String,
    /// The reader of our output went away (`ulog csv ... | head`): not an error.
    broken_pipe: bool,
    /// The exit code (1 unless a verb says otherwise).
    code: u8,
}

impl<E: std::fmt::Display + 'static> From<E> for Failure {
    fn from(e: E) -> Failure {
        let any = &e as &dyn std::any::Any;
        let kind = match any.downcast_ref::<io::Error>() {
            Some(io) => Some(io.kind()),
            None => any
                .downcast_ref::<serde_json::Error>()
                .and_then(serde_json::Error::io_error_kind),
        };
        Failure {
            path: None,
            message: e.to_string(),
            broken_pipe: kind == Some(io::ErrorKind::BrokenPipe),
            code: 1,
        }
    }
}

impl Failure {
    /// `FILE: message`, or the message: what `ulog: ` is followed by on stderr.
    pub(crate) fn text(&self) -> String {
        match &self.path {
            Some(path) => format!("{}: {}", path.display(), self.message),
            None => self.message.clone(),
        }
    }

    /// A failure about one file.
    pub(crate) fn at(path: &Path, message: impl std::fmt::Display) -> Failure {
        Failure {
            path: Some(path.to_owned()),
            ..Failure::from(message.to_string())
        }
    }

    /// A failure that is not about one file, with an exit code.
    pub(crate) fn exit(code: u8, message: impl std::fmt::Display) -> Failure {
        Failure {
            code,
            ..Failure::from(message.to_string())
        }
    }
}

/// pyulog's spellings of options that clap cannot take as they are: `-ts`/`-te` (ulog2csv's
/// time window) become `--start`/`--end`.
fn pyulog_aliases(args: impl Iterator<Item = OsString>) -> Vec<OsString> {
    args.map(|a| match a.to_str() {
        Some("-ts") => "--start".into(),
        Some("-te") => "--end".into(),
        _ => a,
    })
    .collect()
}

/// Runs `ulog` with `args` (the first is the program's name, as `std::env::args_os` gives
/// it): its output on stdout, errors on stderr; returns the exit code (0 success, 1 a
/// failure, 2 a usage error, 128 + a signal's number when [`handle_signals`] let the signal
/// stop `ulog parquet`; `--help` and `--version` print and return 0). Never exits the
/// process, and sets no signal handler.
pub fn main(args: impl IntoIterator<Item = impl Into<OsString>>) -> u8 {
    let args = pyulog_aliases(args.into_iter().map(Into::into));
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return code;
        }
    };
    let stdout = io::stdout();
    let mut out = io::BufWriter::new(stdout.lock());
    let result = run(cli.command, &mut out).and_then(|()| out.flush().map_err(Failure::from));
    match result {
        Ok(())
        | Err(Failure {
            broken_pipe: true, ..
        }) => 0,
        Err(failure) => {
            eprintln!("ulog: {}", failure.text());
            failure.code
        }
    }
}

fn run(command: Command, out: &mut impl Write) -> Result<(), Failure> {
    match command {
        Command::Info(args) => info::run(&args, out),
        Command::Params(args) => params::run(&args, out),
        Command::Messages(args) => messages::run(&args, out),
        Command::Csv(args) => csv::run(&args, out),
        Command::Json(args) => json::run(&args, out),
        Command::Parquet(args) => parquet::run(&args, out),
        Command::Kml(args) => kml::run(&args, out),
        Command::GpsDump(args) => gps_dump::run(&args, out),
        Command::Codegen(args) => codegen::run(&args, out),
        Command::CheckMsg(args) => check_msg::run(&args, out),
        Command::Cut(args) => cut::run(&args, out),
        Command::Anonymize(args) => anonymize::run(&args, out),
        Command::Analyze(args) => analyze::run(&args, out),
        Command::Report(args) => report::run(&args, out),
    }
}

/// A rewrite's failure as the CLI says it: about the output file (its path in the message),
/// or about the input `input` (its path first).
pub(crate) fn rewrite_failure(input: &Path, e: crate::rewrite::RewriteError) -> Failure {
    match e {
        // These name their path already.
        crate::rewrite::RewriteError::Output { .. } | crate::rewrite::RewriteError::SameFile(_) => {
            Failure::from(e.to_string())
        }
        other => Failure::at(input, other),
    }
}

/// What `ulog cut` and `ulog anonymize` print: the new log, then the report.
pub(crate) fn report_rewrite(
    report: &crate::rewrite::Report,
    output: &Path,
    out: &mut impl Write,
) -> Result<(), Failure> {
    writeln!(out, "{}", output.display())?;
    write!(out, "{report}")?;
    Ok(())
}

/// Says on stderr that rows were asked for in a window and none lay in it (the output has
/// no rows), with the time span of those topics' rows when it is known (first and last row,
/// µs), so that an empty output is never silent.
pub(crate) fn report_empty_window(
    file: &Path,
    window: &crate::columns::Window,
    span_us: Option<(u64, u64)>,
) {
    let span = span_us.map_or(String::new(), |(a, b)| crate::columns::span_in_words(a, b));
    eprintln!(
        "ulog: {}: no row of the topics asked for lies in the window {window}{span}",
        file.display()
    );
}

/// The window of `--start`/`--end`, or exit 2 saying why it cannot be one.
pub(crate) fn window(
    start: Option<f64>,
    end: Option<f64>,
) -> Result<crate::columns::Window, Failure> {
    crate::columns::Window::seconds(start, end)
        .map_err(|e| Failure::exit(2, format!("--start/--end: {e}")))
}

/// Opens a log, with plain messages for paths that are not readable files.
pub(crate) fn open(path: &Path) -> Result<Log<'static>, Failure> {
    check_path(path, false)?;
    Log::open(path).map_err(|e| match e {
        crate::ReadError::Io(io) => Failure::at(path, plain_io(&io, false)),
        other => Failure::at(path, other),
    })
}

/// The log file at `path`, memory-mapped (for a verb that walks it without a row index),
/// with [`open`]'s messages.
pub(crate) fn open_mapped(path: &Path) -> Result<crate::read::MappedFile, Failure> {
    check_path(path, false)?;
    crate::read::MappedFile::open(path).map_err(|e| match e {
        crate::ReadError::Io(io) => Failure::at(path, plain_io(&io, false)),
        other => Failure::at(path, other),
    })
}

/// Makes ready the one file a verb writes ([`crate::file_names::prepare_file`]: a folder
/// there is refused, missing parent folders made), with plain messages.
pub(crate) fn output_file(path: &Path) -> Result<(), Failure> {
    crate::file_names::prepare_file(path).map_err(|e| Failure::at(path, plain_io(&e, false)))
}

/// Makes ready the folder a verb writes files into ([`crate::file_names::prepare_folder`]: a
/// file there is refused, the folder made), with plain messages.
pub(crate) fn output_folder(path: &Path) -> Result<(), Failure> {
    crate::file_names::prepare_folder(path).map_err(|e| Failure::at(path, plain_io(&e, true)))
}

/// A failure to write the output file `path`, in plain words.
pub(crate) fn write_failure(path: &Path, e: &io::Error) -> Failure {
    Failure::at(path, plain_io(e, false))
}

/// A plain message when `path` is not what a verb needs: a file (`folder` false) or a
/// folder (`folder` true).
pub(crate) fn check_path(path: &Path, folder: bool) -> Result<(), Failure> {
    match std::fs::metadata(path) {
        Err(e) => Err(Failure::at(path, plain_io(&e, folder))),
        Ok(m) if folder && !m.is_dir() => Err(Failure::at(path, "is not a folder")),
        Ok(m) if !folder => match crate::read::not_a_log_file(&m) {
            Some(e) => Err(Failure::at(path, e)),
            None => Ok(()),
        },
        Ok(_) => Ok(()),
    }
}

fn plain_io(e: &io::Error, folder: bool) -> String {
    match e.kind() {
        io::ErrorKind::NotFound if folder => "no such folder".to_owned(),
        io::ErrorKind::NotFound => "no such file".to_owned(),
        io::ErrorKind::PermissionDenied => "permission denied".to_owned(),
        _ => e.to_string(),
    }
}

/// Prints what pyulog prints while it reads (its warnings), as the verbs that mirror a
/// pyulog tool do before their output.
pub(crate) fn pyulog_warnings(log: &Log<'_>, out: &mut impl Write) -> Result<(), Failure> {
    for w in crate::tools::pyulog_warnings(log) {
        writeln!(out, "{w}")?;
    }
    Ok(())
}

/// Says on stderr the damage the reader skipped, for the verbs that mirror a pyulog tool:
/// their output is what this reader recovers, and a damaged log is never silent.
pub(crate) fn report_damage(log: &Log<'_>, file: &Path) {
    for line in log.skipped().damage_lines() {
        eprintln!("ulog: {}: {line}", file.display());
    }
}

/// As pyulog's tools without `-i`: text that is not UTF-8 anywhere in the log is an error.
/// `flag` is the verb's spelling of the option that allows it (`-i`, `-x`, `--ignore`),
/// named in the error.
pub(crate) fn check_utf8(
    log: &Log<'_>,
    path: &Path,
    ignore: bool,
    flag: &str,
) -> Result<(), Failure> {
    match log.not_utf8().first() {
        Some(at) if !ignore => Err(Failure::at(
            path,
            format!(
                "at byte {at}: text that is not valid UTF-8 ({flag} leaves out the invalid \
                 bytes, as pyulog's {flag} does)"
            ),
        )),
        _ => Ok(()),
    }
}

/// The names of a `-m` list (`-m a,b`) without the spaces around them (`-m "a, b"`), and
/// without empty ones: as for pyulog's tools, `-m ""` names no topic, so every topic is
/// taken, and a comma too many (`-m a,`) adds none.
pub(crate) fn topic_list(names: &[String]) -> Vec<String> {
    names
        .iter()
        .map(|n| n.trim())
        .filter(|n| !n.is_empty())
        .map(str::to_owned)
        .collect()
}

/// Checks that every topic of a `-m` list is one the log defines; the error names the
/// closest it has.
pub(crate) fn check_topics(log: &Log<'_>, path: &Path, topics: &[String]) -> Result<(), Failure> {
    let schema = log.metadata().schema();
    match topics.iter().find(|t| schema.get(t).is_none()) {
        Some(topic) => Err(Failure::at(
            path,
            format!(
                "no topic `{topic}` in this log{}",
                did_you_mean(&schema.suggest(topic))
            ),
        )),
        None => Ok(()),
    }
}

/// Before any conversion ([`crate::read::check_topics`]): a `-m` topic that no log
/// defines is an error (naming the closest topics), as for every verb; one that only some
/// logs lack is said on stderr for each of them (a fleet's logs need not share topics).
/// Logs that cannot be read are left to the conversion to report.
pub(crate) fn check_topics_in_files(files: &[PathBuf], topics: &[String]) -> Result<(), Failure> {
    let check = crate::read::check_topics(files, topics);
    // Each topic in order: the logs lacking one said until a topic no log defines.
    for missing in &check.missing {
        if missing.in_none {
            break;
        }
        for path in &missing.lacking {
            eprintln!(
                "ulog: {}: no topic `{}` in this log",
                path.display(),
                missing.topic
            );
        }
    }
    match check.refusal(files.len()) {
        None => Ok(()),
        Some((missing, text)) => {
            // No close name: where to see the topics.
            let text = if missing.suggestions.is_empty() {
                format!("{text}{}", did_you_mean(&[]))
            } else {
                text
            };
            Err(match files {
                [path] => Failure::at(path, text),
                _ => Failure::exit(1, text),
            })
        }
    }
}

/// `; did you mean `a` or `b`?`, or where to see the topics when no name is close.
pub(crate) fn did_you_mean(names: &[String]) -> String {
    if names.is_empty() {
        return " (`ulog info FILE` lists its topics)".to_owned();
    }
    crate::schema::did_you_mean(names)
}

/// Says on stderr what the export left out, so that nothing is skipped silently.
pub(crate) fn report_skipped(
    skipped: &crate::read::Skipped,
    file: &Path,
    topics: &[String],
    nothing_written: Option<&str>,
    window: &crate::columns::Window,
) {
    let say = |what: String| eprintln!("ulog: {}: {what}", file.display());
    for line in skipped.lines(topics) {
        say(line);
    }
    if let Some(kind) = nothing_written {
        say(window.nothing_written(&format!("{kind} file"), topics));
    }
}

/// A percentage on stderr while long exports run, only when stderr is a terminal and the
/// file is large.
pub(crate) struct Progress {
    total: usize,
    done: usize,
    shown: usize,
    active: bool,
}

impl Progress {
    pub(crate) fn new(total: usize, file_size: usize) -> Progress {
        Progress {
            total: total.max(1),
            done: 0,
            shown: 0,
            active: file_size > 64 << 20 && io::stderr().is_terminal(),
        }
    }

    pub(crate) fn add(&mut self, rows: usize) {
        self.done += rows;
        let pct = self.done * 100 / self.total;
        if self.active && pct != self.shown {
            self.shown = pct;
            eprint!("\r{pct:3}% of {} rows", self.total);
        }
    }

    pub(crate) fn done(&self) {
        if self.active {
            eprintln!();
        }
    }
}
