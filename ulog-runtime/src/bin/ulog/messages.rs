//! `ulog messages`: logged and tagged strings as pyulog's `ulog_messages` prints them.

use std::io::Write;
use std::path::PathBuf;

use ulog_runtime::Log;

use crate::Failure;
use crate::info::hms;

/// `ulog messages FILE`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log.
    file: PathBuf,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    messages(&crate::open(&args.file)?, out)
}

/// As pyulog's `ulog_messages`: `h:mm:ss.mmm LEVEL: text`; tagged strings add `[tag N]`.
fn messages(log: &Log<'_>, out: &mut impl Write) -> Result<(), Failure> {
    for m in log.logged_messages() {
        let ms = m.timestamp / 1000;
        let level = m.level().map_or("UNKNOWN", |l| l.name());
        let tag = m.tag.map(|t| format!("[tag {t}] ")).unwrap_or_default();
        writeln!(
            out,
            "{}.{:03} {level}: {tag}{}",
            hms(ms * 1000),
            ms % 1000,
            m.text
        )?;
    }
    Ok(())
}
