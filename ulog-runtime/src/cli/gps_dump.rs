//! `ulog gps-dump`: the raw GPS byte streams as pyulog's `ulog_extract_gps_dump` writes
//! them (`<stem>_<instance>_to_device.dat`, `..._from_device.dat`), over `tools::gps_dump`.

use std::io::Write;
use std::path::PathBuf;

use crate::tools::{GpsDumpError, gps_dump};

use crate::cli::Failure;

/// `ulog gps-dump FILE [-o DIR] [-i INSTANCE] [-x]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log.
    file: PathBuf,
    /// Output folder (default: the current one); it must exist.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// The receiver: 0 the main one, 1 the secondary.
    #[arg(short, long, default_value_t = 0)]
    instance: u8,
    /// Leave out bytes of text that are not UTF-8 (pyulog's `-x`); without it such text is
    /// an error.
    #[arg(short = 'x', long)]
    ignore: bool,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    if let Some(dir) = &args.output {
        crate::cli::output_folder(dir)?;
    }
    let log = crate::cli::open(&args.file)?;
    crate::cli::check_utf8(&log, &args.file, args.ignore, "-x")?;
    crate::cli::report_damage(&log, &args.file);
    crate::cli::pyulog_warnings(&log, out)?;
    let dump = match gps_dump(&log, args.instance) {
        Ok(d) => d,
        Err(GpsDumpError::NoGpsDump) => {
            writeln!(
                out,
                "File {} does not contain gps_dump messages!",
                args.file.display()
            )?;
            return Ok(());
        }
        Err(GpsDumpError::WrongFormat) => {
            writeln!(out, "Error: gps_dump message has wrong format")?;
            return Err(Failure::exit(255, "gps_dump message has wrong format"));
        }
        Err(e) => return Err(Failure::at(&args.file, e)),
    };
    // pyulog's names: the log's file name without `.ulg`, in the output folder.
    let stem = crate::file_names::log_stem(&args.file);
    let prefix = match &args.output {
        Some(dir) => dir.join(&stem).display().to_string(),
        None => stem,
    };
    let to = format!("{prefix}_{}_to_device.dat", args.instance);
    let from = format!("{prefix}_{}_from_device.dat", args.instance);
    if dump.dropouts > 0 {
        writeln!(out, "Warning: file contains {} dropouts", dump.dropouts)?;
    }
    writeln!(out, "Creating files {to} and {from}")?;
    std::fs::write(&to, &dump.to_device).map_err(|e| Failure::at(to.as_ref(), e))?;
    std::fs::write(&from, &dump.from_device).map_err(|e| Failure::at(from.as_ref(), e))?;
    Ok(())
}
