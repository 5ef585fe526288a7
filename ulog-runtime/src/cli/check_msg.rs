//! `ulog check-msg DIR FILE`: do these `.msg` definitions make exactly this log's formats?

use std::io::Write;
use std::path::PathBuf;

use crate::codegen::msg::{FormatCheck, MsgSet};

use crate::cli::Failure;

/// `ulog check-msg DIR FILE`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// A folder of PX4 `.msg` files.
    dir: PathBuf,
    /// The log.
    file: PathBuf,
    /// Also list the identical and undefined formats, and print both format strings of
    /// each that differs.
    #[arg(short, long)]
    verbose: bool,
}

/// One line per format of the log that differs (or, with `-v`, every format), then
/// `N/M formats identical`; exit 0 only when all M formats the folder defines are identical
/// and M > 0, else 1.
pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    crate::cli::check_path(&args.dir, true)?;
    let set = MsgSet::read_dir(&args.dir).map_err(|e| Failure::from(e.to_string()))?;
    let log = crate::cli::open(&args.file)?;
    let check = set.check(log.metadata().schema());
    let file_name = |i: usize| {
        set.files()[i]
            .path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    for (name, result) in &check.formats {
        match result {
            FormatCheck::Identical { file } if args.verbose => {
                writeln!(out, "{name}: identical ({})", file_name(*file))?;
            }
            FormatCheck::Identical { .. } => {}
            FormatCheck::NotDefined if args.verbose => {
                writeln!(out, "{name}: not defined by the folder")?;
            }
            FormatCheck::NotDefined => {}
            FormatCheck::Differs {
                file,
                expected,
                differences,
            } => {
                writeln!(out, "{name}: differs from {}", file_name(*file))?;
                for d in differences {
                    writeln!(out, "  {}", d.describe("the log", "the .msg"))?;
                }
                if args.verbose {
                    let logged = log
                        .metadata()
                        .schema()
                        .get(name)
                        .map(ToString::to_string)
                        .unwrap_or_default();
                    writeln!(out, "  log:  {logged}")?;
                    writeln!(out, "  .msg: {expected}")?;
                }
            }
        }
    }
    let (n, m) = (check.identical(), check.defined());
    writeln!(out, "{n}/{m} formats identical")?;
    if check.all_identical() {
        Ok(())
    } else {
        out.flush()?;
        Err(Failure::exit(
            1,
            if m == 0 {
                format!(
                    "{}: defines none of the formats of {}",
                    args.dir.display(),
                    args.file.display()
                )
            } else {
                format!("{}: {} of {m} formats differ", args.file.display(), m - n)
            },
        ))
    }
}
