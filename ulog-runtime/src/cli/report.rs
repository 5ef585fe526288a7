//! `ulog report`: a flight report of a log as one self-contained HTML file, over
//! `report::Report`.

use std::io::Write;
use std::path::PathBuf;

use crate::report::Report;

use crate::cli::Failure;

/// `ulog report FILE [-o report.html]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log.
    file: PathBuf,
    /// The HTML file to write (default: the log's name with `.html`, in the current folder).
    #[arg(short, long)]
    output: Option<PathBuf>,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    let path = args.output.clone().unwrap_or_else(|| {
        PathBuf::from(format!("{}.html", crate::file_names::log_stem(&args.file)))
    });
    crate::cli::output_file(&path)?;
    let log = crate::cli::open(&args.file)?;
    let name = args.file.file_name().map_or_else(
        || args.file.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let report = Report::of_log(&log, &name)
        .map_err(|e| Failure::exit(1, format!("{}: {e}", args.file.display())))?;
    std::fs::write(&path, report.html()).map_err(|e| crate::cli::write_failure(&path, &e))?;
    writeln!(
        out,
        "{}: {} plots ({} the log cannot give), {}",
        args.file.display(),
        report.plots.len(),
        report.left_out.len(),
        path.display()
    )?;
    Ok(())
}
