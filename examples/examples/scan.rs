//! Decodes every data row of every subscription through the dynamic path and prints
//! `msgs=N leaves=L sum=S`: N rows, L non-padding leaf values (nested types recursed, every
//! array element counted, `char` as int8, `bool` as 0/1), S the sum of the finite ones.
//!
//! ```text
//! cargo run --release -p examples --example scan -- FILE [--topics] [--stream]
//! ```
//! `--topics` prints `topic multi_id rows sum` per subscription with data instead;
//! `--stream` reads through `StreamReader` (bounded memory) instead of a memory map.

use std::process::ExitCode;

use examples::Scan;
use ulog_runtime::read::MappedFile;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let topics = args.iter().any(|a| a == "--topics");
    let stream = args.iter().any(|a| a == "--stream");
    let Some(path) = args.iter().find(|a| !a.starts_with("--")) else {
        eprintln!("usage: scan FILE [--topics] [--stream]");
        return ExitCode::from(2);
    };
    let scan = if stream {
        std::fs::File::open(path)
            .map_err(ulog_runtime::ReadError::from)
            .and_then(|f| Scan::stream(std::io::BufReader::new(f)))
    } else {
        // The file, memory-mapped, read in one pass on all cores.
        MappedFile::open(path).and_then(|file| Scan::mapped(&file))
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
