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

use std::io::Write;
use std::process::ExitCode;

use examples::Scan;
use ulog_runtime::read::MappedFile;

const USAGE: &str = "usage: scan FILE [--topics] [--mmap | --stream]
  reads FILE by positioned reads on all cores (the default), through a memory map on all
  cores (--mmap), or through StreamReader on one core (--stream, which also reads a pipe
  such as /dev/stdin); prints `msgs=N leaves=L sum=S`, or `topic multi_id rows sum` per
  topic instance (--topics)";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--help" || a == "-h") {
        println!("{USAGE}");
        return ExitCode::SUCCESS;
    }
    let usage = |why: &str| {
        eprintln!("scan: {why}\n{USAGE}");
        ExitCode::from(2)
    };
    if let Some(unknown) = args.iter().find(|a| {
        a.starts_with('-')
            && a.len() > 1
            && !["--topics", "--mmap", "--stream"].contains(&a.as_str())
    }) {
        return usage(&format!("unknown option {unknown}"));
    }
    let topics = args.iter().any(|a| a == "--topics");
    let mmap = args.iter().any(|a| a == "--mmap");
    let stream = args.iter().any(|a| a == "--stream");
    let files: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    let path = match files.as_slice() {
        [path] => *path,
        [] => return usage("no FILE"),
        [_, extra, ..] => return usage(&format!("one FILE only ({extra} is a second)")),
    };
    if mmap && stream {
        return usage("--mmap and --stream are two ways to read; pick one");
    }
    let scan = if stream {
        ulog_runtime::read::open_file(path)
            .or_else(|e| match e.kind() {
                // A pipe or a device is what a stream reads.
                std::io::ErrorKind::InvalidInput => std::fs::File::open(path),
                _ => Err(e),
            })
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
            .map_err(|e| match e {
                // Only a stream reads a pipe or a device.
                ulog_runtime::ReadError::Io(io)
                    if io.kind() == std::io::ErrorKind::InvalidInput =>
                {
                    ulog_runtime::ReadError::Io(std::io::Error::new(
                        io.kind(),
                        format!("{io} (--stream reads a pipe or a device)"),
                    ))
                }
                e => e,
            })
    };
    let scan = match scan {
        Ok(scan) => scan,
        Err(e) => {
            eprintln!("scan: {path}: {e}");
            return ExitCode::FAILURE;
        }
    };
    let mut out = std::io::stdout().lock();
    let printed = if topics {
        scan.topics
            .iter()
            .try_for_each(|((topic, multi_id, _), t)| {
                writeln!(out, "{topic} {multi_id} {} {:.6e}", t.rows, t.sum)
            })
    } else {
        let t = scan.all;
        writeln!(out, "msgs={} leaves={} sum={:.6e}", t.rows, t.leaves, t.sum)
    };
    match printed {
        // A reader that stopped early (`scan FILE --topics | head`) wanted no more.
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            eprintln!("scan: {e}");
            ExitCode::FAILURE
        }
        _ => ExitCode::SUCCESS,
    }
}
