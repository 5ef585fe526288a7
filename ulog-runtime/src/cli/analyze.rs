//! `ulog analyze`: the flight analysis of logs, as text or JSON, over `analysis::Analysis`.

use std::io::Write;
use std::path::PathBuf;

use crate::analysis::Analysis;

use crate::cli::Failure;

/// `ulog analyze FILE... [--json]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The logs.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// One JSON object per log (a line each): `log`, the path as given, then the analysis,
    /// with flight-review-rs's keys where it has the same fact.
    #[arg(long)]
    json: bool,
}

/// A line of `--json`: which log, then its analysis.
#[derive(serde::Serialize)]
struct Line<'a> {
    log: std::borrow::Cow<'a, str>,
    #[serde(flatten)]
    analysis: &'a Analysis,
}

/// Each log's analysis in turn; a log that cannot be read is said on stderr and the others
/// are still analysed (as `ulog parquet` converts the others), the exit code 1 at the end.
pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    let mut failed = 0;
    // Whether a text summary is already out (the next one follows a blank line).
    let mut shown = false;
    for path in &args.files {
        let analysis = match crate::cli::open_mapped(path)
            .and_then(|file| Analysis::of_bytes(&file).map_err(|e| Failure::at(path, e)))
        {
            Ok(analysis) => analysis,
            Err(e) => {
                eprintln!("ulog: {}", e.text());
                failed += 1;
                continue;
            }
        };
        if args.json {
            let line = Line {
                log: path.to_string_lossy(),
                analysis: &analysis,
            };
            serde_json::to_writer(&mut *out, &line)?;
            writeln!(out)?;
        } else {
            if shown {
                writeln!(out)?;
            }
            shown = true;
            writeln!(out, "{}", path.display())?;
            write!(out, "{analysis}")?;
        }
    }
    if failed > 0 {
        return Err(Failure::exit(
            1,
            format!("{failed} of {} logs not analysed", args.files.len()),
        ));
    }
    Ok(())
}
