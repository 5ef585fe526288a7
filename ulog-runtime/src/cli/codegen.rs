//! `ulog codegen`: the Rust types `ulog_runtime::codegen` makes for logs or `.msg` folders.

use std::io::Write;
use std::path::PathBuf;

use crate::codegen::{Builder, Merge};

use crate::cli::Failure;

/// `ulog codegen FILE... [-m a,b] [--msg-dir DIR] [--strict | --widest]`.
#[derive(clap::Args)]
#[command(arg_required_else_help = true)]
pub(crate) struct Args {
    /// Logs: one type per format; with several, one type per topic that reads every log.
    files: Vec<PathBuf>,
    /// A folder of PX4 `.msg` files (PX4-Autopilot's `msg/`), as another input.
    #[arg(long, value_name = "DIR")]
    msg_dir: Vec<PathBuf>,
    /// Only these topics (comma-separated) and the types they nest.
    #[arg(short, long, value_delimiter = ',')]
    messages: Vec<String>,
    /// With several inputs, a field whose types have no lossless common type is an error
    /// (default: left out of the merged type, with a doc comment).
    #[arg(long, conflicts_with = "widest")]
    strict: bool,
    /// Every number the widest type of its kind (u64, i64, f64), so that the types also read
    /// newer versions that widened a field (`Merge::Widest`).
    #[arg(long)]
    widest: bool,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    let messages = crate::cli::topic_list(&args.messages);
    if args.files.is_empty() && args.msg_dir.is_empty() {
        return Err(Failure::exit(2, "give logs, or `--msg-dir DIR`"));
    }
    let topics: Vec<&str> = messages.iter().map(String::as_str).collect();
    let mut builder = Builder::new();
    for file in &args.files {
        let log = crate::cli::open(file)?;
        // `-m` selects from the inputs that have the topics; logs lacking one still count.
        let present: Vec<&str> = topics
            .iter()
            .copied()
            .filter(|t| log.metadata().schema().get(t).is_some())
            .collect();
        if !topics.is_empty()
            && present.is_empty()
            && args.files.len() == 1
            && args.msg_dir.is_empty()
        {
            let missing: Vec<String> = messages.clone();
            crate::cli::check_topics(&log, file, &missing)?;
        }
        if topics.is_empty() {
            builder.ulog(file);
        } else if !present.is_empty() {
            builder.ulog_topics(file, &present);
        }
    }
    for dir in &args.msg_dir {
        crate::cli::check_path(dir, true)?;
        if topics.is_empty() {
            builder.msg_dir(dir);
        } else {
            builder.msg_dir_topics(dir, &topics);
        }
    }
    if args.widest {
        builder.merge(Merge::Widest);
    } else if args.files.len() + args.msg_dir.len() > 1 {
        builder.merge(if args.strict {
            Merge::Strict
        } else {
            Merge::Lossless
        });
    }
    out.write_all(builder.render()?.as_bytes())?;
    Ok(())
}
