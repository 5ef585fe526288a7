//! `ulog parquet`: logs to per-topic Parquet files and a metadata.json each, over
//! `columns::parquet::Converter`.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::columns::parquet::{ConvertError, Converter, Layout, ParquetOptions};

use crate::cli::Failure;

/// `ulog parquet FILE... -o DIR [-m a,b] [--start S --end S] [--layout hive] [-j N]
/// [--no-analysis] [--buffer-mb N] [--max-columns N]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The logs.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// Output folder.
    #[arg(short, long)]
    output: PathBuf,
    /// Only these topics (comma-separated).
    #[arg(short, long, value_delimiter = ',')]
    messages: Vec<String>,
    /// Only rows from this time on, in seconds (pyulog's `-ts`, `--time_s`).
    #[arg(long, alias = "time_s", allow_negative_numbers = true)]
    start: Option<f64>,
    /// Only rows before this time, in seconds (pyulog's `-te`, `--time_e`).
    #[arg(long, alias = "time_e", allow_negative_numbers = true)]
    end: Option<f64>,
    /// `per-log`: DIR/<stem>/<topic>_<multi_id>.parquet; `hive`:
    /// DIR/topic=<topic>/log=<stem>/multi_id=<m>/data.parquet.
    #[arg(long, value_enum, default_value = "per-log")]
    layout: LayoutArg,
    /// Threads: logs converted at once, and a single log encodes on the N-1 others
    /// (default: one per core).
    #[arg(short, long, value_parser = at_least_one)]
    jobs: Option<usize>,
    /// ZSTD compression level.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    zstd_level: i32,
    /// Leave the flight analysis out of metadata.json.
    #[arg(long)]
    no_analysis: bool,
    /// Memory for rows waiting for their row group, MiB per log (more: fewer, larger row
    /// groups).
    #[arg(long, default_value_t = 16, value_parser = at_least_one)]
    buffer_mb: usize,
    /// Most columns of one log's tables open at once (each costs about 1 to 4 KiB until
    /// its file closes): a topic instance past it is left out, with a note.
    #[arg(long, default_value_t = 100_000, value_parser = at_least_one)]
    max_columns: usize,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum LayoutArg {
    PerLog,
    Hive,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    let messages = crate::cli::topic_list(&args.messages);
    let window = crate::cli::window(args.start, args.end)?;
    let options = ParquetOptions {
        zstd_level: args.zstd_level,
        topics: messages.clone(),
        window,
        layout: match args.layout {
            LayoutArg::PerLog => Layout::PerLog,
            LayoutArg::Hive => Layout::Hive,
        },
        analysis: !args.no_analysis,
        buffer_bytes: args.buffer_mb.saturating_mul(1 << 20),
        max_columns: args.max_columns,
        ..ParquetOptions::default()
    };
    // Refused here rather than once per log.
    options
        .properties(Vec::new())
        .map_err(|e| Failure::exit(2, format!("--zstd-level {}: {e}", args.zstd_level)))?;
    crate::cli::check_topics_in_files(&args.files, &messages)?;
    crate::cli::output_folder(&args.output)?;
    let total: u64 = args
        .files
        .iter()
        .filter_map(|p| std::fs::metadata(p).ok())
        .map(|m| m.len())
        .sum();
    let mut converter = Converter::new(&args.output, options);
    let progress = std::io::stderr().is_terminal() && total > 64 << 20;
    if progress {
        let read = Arc::new(AtomicU64::new(0));
        converter = converter.on_progress(move |bytes| {
            let done = read.fetch_add(bytes, Ordering::Relaxed) + bytes;
            eprint!(
                "\r{:3}% of {} MB",
                done * 100 / total.max(1),
                total.div_ceil(1 << 20)
            );
        });
    }
    let threads = args
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let stop = super::signals::stoppable();
    let results = converter.convert_files_until(&args.files, threads, stop.flag());
    let stopped_by = stop.signal();
    drop(stop);
    if progress {
        eprintln!();
    }
    let mut failed = 0;
    let mut stopped = 0;
    let mut topics_seen = std::collections::HashSet::new();
    for (path, result) in args.files.iter().zip(&results) {
        match result {
            Ok(c) => {
                let rows: usize = c.files.iter().map(|f| f.rows).sum();
                let n = c.files.len();
                writeln!(
                    out,
                    "{}: {n} {}, {rows} {}, {}",
                    path.display(),
                    if n == 1 { "file" } else { "files" },
                    if rows == 1 { "row" } else { "rows" },
                    c.metadata.display()
                )?;
                for line in c.lines(&messages, &window) {
                    eprintln!("ulog: {}: {line}", path.display());
                }
                topics_seen.extend(c.files.iter().map(|f| f.topic.clone()));
            }
            Err(ConvertError::Stopped { .. }) => stopped += 1,
            Err(e) => {
                failed += 1;
                match crate::cli::check_path(path, false) {
                    Err(plain) => eprintln!("ulog: {}", plain.text()),
                    Ok(()) => eprintln!("ulog: {e}"),
                }
            }
        }
    }
    // Topics some log defines but none has rows of (in the window).
    for topic in messages.iter().filter(|t| !topics_seen.contains(*t)) {
        eprintln!(
            "ulog: no log has rows of topic `{topic}`{}",
            window.in_words()
        );
    }
    if let Some(signal) = stopped_by {
        let failed = if failed > 0 {
            format!(", {failed} failed")
        } else {
            String::new()
        };
        return Err(Failure::exit(
            // 128 + the signal, as a shell reports a tool the signal ended.
            u8::try_from(128 + signal).unwrap_or(130),
            format!(
                "stopped (signal {signal}): {stopped} of {} logs not converted{failed}; \
                 those under way were finished",
                args.files.len()
            ),
        ));
    }
    if failed > 0 {
        return Err(Failure::exit(
            1,
            format!("{failed} of {} logs not converted", args.files.len()),
        ));
    }
    Ok(())
}

/// A count of 1 or more (`-j`, `--buffer-mb`): 0 would convert nothing, or buffer nothing.
fn at_least_one(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(0) => Err("0 is not allowed: give 1 or more".to_owned()),
        Ok(n) => Ok(n),
        Err(e) => Err(e.to_string()),
    }
}
