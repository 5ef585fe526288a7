//! `ulog`: inspect, export and generate from PX4 ULog files, in the spirit of pyulog's
//! `ulog_info`, `ulog_params`, `ulog_messages` and `ulog2csv`.

use std::io::{self, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use ulog_runtime::Log;

mod csv;
mod info;
mod number;

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
    Info {
        /// The log.
        file: PathBuf,
        /// Also perf_* info, multi info values and every diagnostic.
        #[arg(short, long)]
        verbose: bool,
    },
    /// Parameters as pyulog's `ulog_params` writes them: `NAME,initial[,change...]`.
    Params {
        /// The log.
        file: PathBuf,
        /// Only the initial values (no changes).
        #[arg(short, long)]
        initial: bool,
        /// Only the parameters that changed during the log.
        #[arg(short, long)]
        changed: bool,
        /// After each parameter, a line with the change timestamps.
        #[arg(short, long)]
        timestamps: bool,
        /// Separator between name and values.
        #[arg(short = 'l', long, default_value = ",")]
        delimiter: String,
        /// Print default parameters instead: `system` or `current_setup`.
        #[arg(short, long, value_parser = ["system", "current_setup"])]
        default: Option<String>,
    },
    /// Logged and tagged strings with time and level.
    Messages {
        /// The log.
        file: PathBuf,
    },
    /// One CSV per subscription, `<stem>_<topic>_<multi_id>.csv`, as pyulog's `ulog2csv`.
    Csv {
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
        /// Only rows from this time on, in seconds.
        #[arg(long)]
        start: Option<f64>,
        /// Only rows before this time, in seconds.
        #[arg(long)]
        end: Option<f64>,
    },
    /// Rows as JSON Lines (one object per row), or one JSON document.
    Json {
        /// The log.
        file: PathBuf,
        /// Only these topics (comma-separated).
        #[arg(short, long, value_delimiter = ',')]
        messages: Vec<String>,
        /// One document with the metadata and every topic's rows.
        #[arg(long)]
        document: bool,
    },
    /// The Rust types `ulog_runtime::codegen` makes for this log's formats.
    Codegen {
        /// The log.
        file: PathBuf,
        /// Only these topics (comma-separated) and the types they nest.
        #[arg(short, long, value_delimiter = ',')]
        messages: Vec<String>,
    },
}

/// An error for the one line `ulog` prints.
struct Failure {
    message: String,
    /// The reader of our output went away (`ulog csv ... | head`): not an error.
    broken_pipe: bool,
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
            message: e.to_string(),
            broken_pipe: kind == Some(io::ErrorKind::BrokenPipe),
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let file = match &cli.command {
        Command::Info { file, .. }
        | Command::Params { file, .. }
        | Command::Messages { file }
        | Command::Csv { file, .. }
        | Command::Json { file, .. }
        | Command::Codegen { file, .. } => file.clone(),
    };
    let stdout = io::stdout();
    let mut out = io::BufWriter::new(stdout.lock());
    let result = run(cli.command, &mut out).and_then(|()| out.flush().map_err(Failure::from));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure {
            broken_pipe: true, ..
        }) => ExitCode::SUCCESS,
        Err(Failure { message, .. }) => {
            eprintln!("ulog: {}: {message}", file.display());
            ExitCode::FAILURE
        }
    }
}

fn open(file: &Path) -> Result<Log<'static>, Failure> {
    Ok(Log::open(file)?)
}

fn run(command: Command, out: &mut impl Write) -> Result<(), Failure> {
    match command {
        Command::Info { file, verbose } => info::info(&open(&file)?, &file, verbose, out),
        Command::Params {
            file,
            initial,
            changed,
            timestamps,
            delimiter,
            default,
        } => info::params(
            &open(&file)?,
            initial,
            changed,
            timestamps,
            &delimiter,
            default.as_deref(),
            out,
        ),
        Command::Messages { file } => info::messages(&open(&file)?, out),
        Command::Csv {
            file,
            messages,
            output,
            delimiter,
            start,
            end,
        } => {
            let log = open(&file)?;
            let options = csv::Options {
                topics: messages,
                output,
                delimiter,
                start_us: start.map(|s| s * 1e6),
                end_us: end.map(|s| s * 1e6),
            };
            let mut progress = Progress::new(log.row_count(), log.bytes().len());
            for (path, rows) in csv::write_all(&log, &file, &options, &mut progress)? {
                writeln!(out, "{} ({rows} rows)", path.display())?;
            }
            progress.done();
            Ok(())
        }
        Command::Json {
            file,
            messages,
            document,
        } => csv::json(&open(&file)?, &messages, document, out),
        Command::Codegen { file, messages } => {
            let mut builder = ulog_runtime::codegen::Builder::new();
            if messages.is_empty() {
                builder.ulog(&file);
            } else {
                let topics: Vec<&str> = messages.iter().map(String::as_str).collect();
                builder.ulog_topics(&file, &topics);
            }
            out.write_all(builder.render()?.as_bytes())?;
            Ok(())
        }
    }
}

/// A percentage on stderr while long exports run, only when stderr is a terminal and the
/// file is large.
struct Progress {
    total: usize,
    done: usize,
    shown: usize,
    active: bool,
}

impl Progress {
    fn new(total: usize, file_size: usize) -> Progress {
        Progress {
            total: total.max(1),
            done: 0,
            shown: 0,
            active: file_size > 64 << 20 && io::stderr().is_terminal(),
        }
    }

    fn add(&mut self, rows: usize) {
        self.done += rows;
        let pct = self.done * 100 / self.total;
        if self.active && pct != self.shown {
            self.shown = pct;
            eprint!("\r{pct:3}% of {} rows", self.total);
        }
    }

    fn done(&self) {
        if self.active {
            eprintln!();
        }
    }
}
