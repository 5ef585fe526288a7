//! `ulog csv`: one file per topic instance, as pyulog's `ulog2csv` writes them.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::columns::csv::{CsvOptions, export};

use crate::cli::{Failure, Progress};

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
    #[arg(long, alias = "time_s", allow_negative_numbers = true)]
    start: Option<f64>,
    /// Only rows before this time, in seconds (pyulog's `-te`, `--time_e`).
    #[arg(long, alias = "time_e", allow_negative_numbers = true)]
    end: Option<f64>,
    /// Leave out bytes of text that are not UTF-8 (pyulog's `-i`); without it such text is
    /// an error.
    #[arg(short, long)]
    ignore: bool,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    let messages = crate::cli::topic_list(&args.messages);
    // A bound of 0 is none, as in ulog2csv (whose test of a bound is Python's truth: `-te 0`
    // writes every row there).
    let bound = |b: Option<f64>| b.filter(|&s| s != 0.0);
    let window = crate::cli::window(bound(args.start), bound(args.end))?;
    let log = crate::cli::open(&args.file)?;
    crate::cli::check_utf8(&log, &args.file, args.ignore, "-i")?;
    crate::cli::check_topics(&log, &args.file, &messages)?;
    let options = CsvOptions {
        delimiter: args.delimiter.clone(),
        window,
    };
    let dir = match &args.output {
        Some(d) => {
            let created = !d.is_dir();
            crate::cli::output_folder(d)?;
            if created {
                writeln!(out, "Creating output directory {}", d.display())?;
            }
            d.clone()
        }
        None => args.file.parent().map(Path::to_owned).unwrap_or_default(),
    };
    let stem = crate::file_names::log_stem(&args.file);
    let mut progress = Progress::new(log.row_count(), log.bytes().len());
    let written = export(&log, &stem, &dir, &messages, &options, &mut || {
        progress.add(1);
    })
    .map_err(|(path, e)| Failure::at(&path, e))?;
    progress.done();
    for f in &written {
        if let Some(other) = &f.collided_with {
            eprintln!(
                "ulog: {}: topics `{other}` and `{}` map to one file name; `{}` #{} goes to {}",
                args.file.display(),
                f.topic,
                f.topic,
                f.multi_id,
                f.path.display()
            );
        }
    }
    // What ulog2csv prints: a line per file, by topic and instance, with the instance's
    // rows in the whole log (not only the window's).
    let topics = log.topics();
    let mut lines: Vec<_> = written.iter().collect();
    lines.sort_by(|a, b| (&a.topic, a.multi_id).cmp(&(&b.topic, b.multi_id)));
    for f in lines {
        let rows = topics
            .iter()
            .find(|t| t.name == f.topic && t.multi_id == f.multi_id)
            .map_or(0, |t| t.rows);
        writeln!(out, "Writing {} ({rows} data points)", f.path.display())?;
    }
    if options.window.is_bounded() && !written.is_empty() && written.iter().all(|f| f.rows == 0) {
        // Where the rows of the topics asked for lie (the header's start can be later than
        // the first row).
        let asked = || {
            topics
                .iter()
                .filter(|t| messages.is_empty() || messages.contains(&t.name))
        };
        let first = asked().filter_map(|t| t.first_timestamp).min();
        let last = asked().filter_map(|t| t.last_timestamp).max();
        crate::cli::report_empty_window(&args.file, &options.window, first.zip(last));
    }
    crate::cli::report_skipped(
        &log.skipped(),
        &args.file,
        &messages,
        written.is_empty().then_some("CSV"),
        // Which files there are does not depend on the window (a topic with no row in it
        // gets its header line, as ulog2csv writes it).
        &crate::columns::Window::default(),
    );
    Ok(())
}
