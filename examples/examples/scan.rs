//! Decodes every data row of every subscription through the dynamic path and prints
//! `msgs=N leaves=L sum=S`: N rows, L non-padding leaf values (nested types recursed, every
//! array element counted, `char` as int8, `bool` as 0/1), S the sum of the finite ones.
//!
//! ```text
//! cargo run --release -p examples --example scan -- FILE [--topics] [--mmap | --stream]
//! ```
//! By default the file is read by positioned reads on all cores
//! ([`ulog_runtime::read::fold_file`]); `--mmap` maps it instead (on all cores,
//! [`MappedFile::fold_rows`]); `--stream` reads it through `StreamReader` (one core,
//! bounded memory). `--topics` prints `topic multi_id rows sum` per subscription with data.

use std::process::ExitCode;

use examples::Scan;
use ulog_runtime::read::MappedFile;

const USAGE: &str = "usage: scan FILE [--topics] [--mmap | --stream]";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Some(unknown) = args
        .iter()
        .find(|a| a.starts_with("--") && !["--topics", "--mmap", "--stream"].contains(&a.as_str()))
    {
        eprintln!("scan: unknown option {unknown}\n{USAGE}");
        return ExitCode::from(2);
    }
    let topics = args.iter().any(|a| a == "--topics");
    let mmap = args.iter().any(|a| a == "--mmap");
    let stream = args.iter().any(|a| a == "--stream");
    let Some(path) = args.iter().find(|a| !a.starts_with("--")) else {
        eprintln!("{USAGE}");
        return ExitCode::from(2);
    };
    if mmap && stream {
        eprintln!("scan: --mmap and --stream are two ways to read; pick one\n{USAGE}");
        return ExitCode::from(2);
    }
    let scan = if stream {
        std::fs::File::open(path)
            .map_err(ulog_runtime::ReadError::from)
            .and_then(|f| Scan::stream(std::io::BufReader::new(f)))
    } else if mmap {
        // The file, memory-mapped, read in one pass on all cores.
        MappedFile::open(path).and_then(|file| Scan::mapped(&file))
    } else {
        // The file read by positioned reads, in one pass on all cores.
        ulog_runtime::read::open_file(path)
            .map_err(ulog_runtime::ReadError::from)
            .and_then(|f| Scan::file(&f))
    };
    let scan = match scan {
        Ok(scan) => scan,
        Err(e) => {
            eprintln!("scan: {path}: {e}");
            return ExitCode::FAILURE;
        }
    };
    if topics {
        for ((topic, multi_id, _), t) in &scan.topics {
            println!("{topic} {multi_id} {} {:.6e}", t.rows, t.sum);
        }
    } else {
        let t = scan.all;
        println!("msgs={} leaves={} sum={:.6e}", t.rows, t.leaves, t.sum);
    }
    ExitCode::SUCCESS
}
