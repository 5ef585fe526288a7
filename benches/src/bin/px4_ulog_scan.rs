//! The `scan` figures computed with px4-ulog 0.6.1's streaming reader (the base of PX4's
//! Flight Review v2): the baseline `scan` is measured against, decoding the same leaves
//! (every non-padding leaf; `char` as a signed byte, `bool` as 0/1, the sum of the finite
//! values as `f64`), so both print the same `msgs=N leaves=L sum=S` line.
//!
//! ```text
//! cargo run --release -p ulog-benches --bin px4_ulog_scan -- FILE
//! ```

use std::process::ExitCode;

use ulog_benches::px4_ulog_ref;

fn main() -> ExitCode {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: px4_ulog_scan FILE");
        return ExitCode::from(2);
    };
    match px4_ulog_ref::scan_file(&path) {
        Ok(f) => {
            println!("msgs={} leaves={} sum={:.6e}", f.rows, f.leaves, f.sum);
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("px4_ulog_scan: {path}: {e}");
            ExitCode::FAILURE
        }
    }
}
