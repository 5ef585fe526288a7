//! Writes a large log made from a real one, for benchmarks and memory measurements:
//! the source, then its data rows repeated with shifted, still increasing timestamps.
//!
//! ```text
//! cargo run --release -p examples --example inflate -- SOURCE.ulg OUT.ulg [MEGABYTES]
//! ```

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(src), Some(dst)) = (args.first(), args.get(1)) else {
        eprintln!("usage: inflate SOURCE.ulg OUT.ulg [MEGABYTES (default 400)]");
        return ExitCode::from(2);
    };
    let mb: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(400);
    let result = std::fs::read(src)
        .map_err(|e| e.to_string())
        .and_then(|bytes| examples::inflate(&bytes, mb * 1_000_000).map_err(|e| e.to_string()))
        .and_then(|big| {
            std::fs::write(dst, &big)
                .map(|()| big.len())
                .map_err(|e| e.to_string())
        });
    match result {
        Ok(len) => {
            println!("wrote {dst}: {len} bytes");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("inflate: {e}");
            ExitCode::FAILURE
        }
    }
}
