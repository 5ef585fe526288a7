//! `ulog cut`: a log cut to a time window and filtered by topic, as a new log, over
//! `rewrite::Rewrite`.

use std::io::Write;
use std::path::PathBuf;

use crate::rewrite::Rewrite;

use crate::cli::Failure;

/// `ulog cut FILE -o OUT [--start S] [--end E] [-m a,b] [--exclude c,d]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log.
    file: PathBuf,
    /// The new log (never the input).
    #[arg(short, long)]
    output: PathBuf,
    /// Only what lies from this time on, in seconds of log time (as `ulog csv`).
    #[arg(long, alias = "time_s", allow_negative_numbers = true)]
    start: Option<f64>,
    /// Only what lies before this time, in seconds.
    #[arg(long, alias = "time_e", allow_negative_numbers = true)]
    end: Option<f64>,
    /// Only these topics (comma-separated).
    #[arg(short, long, value_delimiter = ',')]
    messages: Vec<String>,
    /// Not these topics (comma-separated).
    #[arg(long, value_delimiter = ',')]
    exclude: Vec<String>,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    let messages = crate::cli::topic_list(&args.messages);
    let exclude = crate::cli::topic_list(&args.exclude);
    let window = crate::cli::window(args.start, args.end)?;
    crate::cli::check_path(&args.file, false)?;
    let topics: Vec<String> = messages.iter().chain(&exclude).cloned().collect();
    crate::cli::check_topics_in_files(std::slice::from_ref(&args.file), &topics)?;
    let both: Vec<&str> = messages
        .iter()
        .filter(|t| exclude.contains(t))
        .map(String::as_str)
        .collect();
    if !both.is_empty() {
        // The exclusion wins: said, since no rule keeps the topic then.
        eprintln!(
            "ulog: {}: `{}` both kept (-m) and excluded (--exclude): left out",
            args.file.display(),
            both.join("`, `")
        );
    }
    let report = Rewrite::new()
        .window(window)
        .topics(&messages)
        .exclude(&exclude)
        .run_file(&args.file, &args.output)
        .map_err(|e| crate::cli::rewrite_failure(&args.file, e))?;
    // A window no row of the topics kept lies in is said by the report itself
    // (`Report::window_missed`), with where their rows lie, and on stderr as `csv` and
    // `parquet` say it, so that an output with no rows is never quiet.
    crate::cli::report_rewrite(&report, &args.output, out)?;
    if let Some(span) = report.window_missed() {
        crate::cli::report_empty_window(&args.file, &window, Some(span));
    }
    Ok(())
}
