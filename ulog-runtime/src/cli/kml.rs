//! `ulog kml`: the GPS track as pyulog's `ulog2kml` writes it, over `tools::kml`.

use std::io::Write;
use std::path::PathBuf;

use crate::tools::{KmlOptions, kml};

use crate::cli::Failure;

/// `ulog kml FILE [-o track.kml] [--topic T] [--camera-trigger T] [-i]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log.
    file: PathBuf,
    /// The KML file to write.
    #[arg(short, long, default_value = "track.kml")]
    output: PathBuf,
    /// The topic with the positions (default: vehicle_gnss, or vehicle_gps_position in
    /// older logs).
    #[arg(long)]
    topic: Option<String>,
    /// A camera trigger topic (e.g. camera_capture): a placemark per trigger.
    #[arg(long)]
    camera_trigger: Option<String>,
    /// Leave out bytes of text that are not UTF-8 (pyulog's `-i`); without it such text is
    /// an error.
    #[arg(short, long)]
    ignore: bool,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    crate::cli::output_file(&args.output)?;
    let log = crate::cli::open(&args.file)?;
    crate::cli::check_utf8(&log, &args.file, args.ignore, "-i")?;
    crate::cli::report_damage(&log, &args.file);
    crate::cli::pyulog_warnings(&log, out)?;
    let options = KmlOptions {
        topic: args.topic.clone(),
        camera_trigger: args.camera_trigger.clone(),
    };
    let text = kml(&log, &options).map_err(|e| Failure::at(&args.file, e))?;
    std::fs::write(&args.output, text).map_err(|e| crate::cli::write_failure(&args.output, &e))
}
