//! `ulog anonymize`: positions, times and identifiers of a log hidden, as a new log, over
//! `rewrite::Anonymize`.

use std::io::Write;
use std::path::PathBuf;

use crate::rewrite::{Anonymize, Rewrite, Target};

use crate::cli::Failure;

/// `ulog anonymize FILE -o OUT [--origin LAT,LON | --seed N] [--keep-time]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log.
    file: PathBuf,
    /// The new log (never the input).
    #[arg(short, long)]
    output: PathBuf,
    /// Move the log's first position to this latitude,longitude (degrees).
    #[arg(
        long,
        value_name = "LAT,LON",
        allow_hyphen_values = true,
        conflicts_with = "seed"
    )]
    origin: Option<String>,
    /// Draw the place and the offsets from this seed (the same seed, the same output);
    /// without it or --origin, a random seed that is not shown.
    #[arg(long)]
    seed: Option<u64>,
    /// Keep UTC times, dates and the header's start time as they are.
    #[arg(long)]
    keep_time: bool,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    crate::cli::check_path(&args.file, false)?;
    let target = match (&args.origin, args.seed) {
        (Some(text), _) => {
            let parsed = text.split_once(',').and_then(|(a, b)| {
                Some((a.trim().parse::<f64>().ok()?, b.trim().parse::<f64>().ok()?))
            });
            match parsed {
                Some((lat, lon)) if lat.abs() <= 90.0 && lon.abs() <= 180.0 => {
                    Target::Origin { lat, lon }
                }
                _ => {
                    return Err(Failure::exit(
                        2,
                        format!("--origin {text}: expected LAT,LON in degrees, as 47.3977,8.5456"),
                    ));
                }
            }
        }
        (None, Some(seed)) => Target::Seed(seed),
        (None, None) => Target::Seed(random_seed()),
    };
    let report = Rewrite::new()
        .anonymize(Anonymize {
            target,
            keep_time: args.keep_time,
        })
        .run_file(&args.file, &args.output)
        .map_err(|e| crate::cli::rewrite_failure(&args.file, e))?;
    crate::cli::report_rewrite(&report, &args.output, out)
}

/// A seed nobody chose: from the process's randomly keyed hasher.
fn random_seed() -> u64 {
    use std::hash::{BuildHasher, Hasher};
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u128(
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos()),
    );
    h.finish()
}
