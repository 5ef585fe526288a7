//! `ulog params`: parameters as pyulog's `ulog_params` writes them, over
//! `tools::params`.

use std::io::Write;
use std::path::PathBuf;

use crate::tools::{DefaultKind, ParamsFormat, ParamsOptions, params};

use crate::cli::Failure;

/// `ulog params FILE [OUTPUT] [-f csv|octave|qgc] [-i] [-c] [-t] [-l ,] [-d ...] [--ignore]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log.
    file: PathBuf,
    /// Write here instead of to stdout.
    output: Option<PathBuf>,
    /// `csv`, `octave` or `qgc` (QGroundControl's parameter file).
    #[arg(short, long, value_enum, default_value = "csv")]
    format: FormatArg,
    /// Only the initial values (no changes).
    #[arg(short, long)]
    initial: bool,
    /// Only the parameters that changed during the log.
    #[arg(short, long)]
    changed: bool,
    /// After each parameter, a line with the change timestamps (csv).
    #[arg(short, long)]
    timestamps: bool,
    /// Separator between name and values (csv).
    #[arg(short = 'l', long, default_value = ",")]
    delimiter: String,
    /// Print default parameters instead: `system` or `current_setup`.
    #[arg(short, long, value_parser = ["system", "current_setup"])]
    default: Option<String>,
    /// Leave out bytes of text that are not UTF-8 (pyulog's `--ignore`); without it such
    /// text is an error.
    #[arg(long)]
    ignore: bool,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum FormatArg {
    Csv,
    Octave,
    Qgc,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    let log = crate::cli::open(&args.file)?;
    crate::cli::check_utf8(&log, &args.file, args.ignore, "--ignore")?;
    crate::cli::report_damage(&log, &args.file);
    crate::cli::pyulog_warnings(&log, out)?;
    let options = ParamsOptions {
        format: match args.format {
            FormatArg::Csv => ParamsFormat::Csv,
            FormatArg::Octave => ParamsFormat::Octave,
            FormatArg::Qgc => ParamsFormat::Qgc,
        },
        initial: args.initial,
        changed: args.changed,
        timestamps: args.timestamps,
        delimiter: args.delimiter.clone(),
        default: args.default.as_deref().map(|d| match d {
            "system" => DefaultKind::System,
            _ => DefaultKind::CurrentSetup,
        }),
    };
    match &args.output {
        Some(path) => {
            crate::cli::output_file(path)?;
            let file =
                std::fs::File::create(path).map_err(|e| crate::cli::write_failure(path, &e))?;
            let mut file = std::io::BufWriter::new(file);
            params(&log, &options, &mut file)
                .and_then(|()| file.flush().map_err(Into::into))
                .map_err(|e| Failure::at(path, e))
        }
        None => params(&log, &options, out).map_err(|e| match e {
            crate::tools::ParamsError::Io(io) => Failure::from(io),
            other => Failure::at(&args.file, other),
        }),
    }
}
