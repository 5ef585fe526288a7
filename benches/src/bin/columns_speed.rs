//! The time `Log::open` takes (`open S` line), the first `Log::columns` call, which makes the
//! per-subscription row index (`index S`), then `Log::columns` and
//! `columns::arrow::record_batches` of every topic instance of the log, one after the other
//! (`columns S` and `batches S` lines), and every instance's columns in one pass,
//! `Log::all_column_parts` (`all S`).
//! It uses only APIs older versions of the library have too, so that
//! `benches/columns_vs.sh` can build it against another commit and run both interleaved.
//!
//! ```text
//! cargo run --release -p ulog-benches --bin columns_speed -- LOG
//! ```

use std::time::Instant;

fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: columns_speed LOG");
        std::process::exit(2);
    };
    let t = Instant::now();
    let log = match ulog_runtime::Log::open(&path) {
        Ok(log) => log,
        Err(e) => {
            eprintln!("columns_speed: {path}: {e}");
            std::process::exit(1);
        }
    };
    println!(
        "open {:.6} {}",
        t.elapsed().as_secs_f64(),
        log.subscriptions().len()
    );
    let mut instances = Vec::new();
    for s in log.subscriptions() {
        if !instances.contains(&(s.name.clone(), s.multi_id)) {
            instances.push((s.name.clone(), s.multi_id));
        }
    }
    // The per-subscription row index is made at its first use.
    let t = Instant::now();
    if let Some((name, multi_id)) = instances.first() {
        let _ = log.columns(name, *multi_id);
    }
    println!("index {:.6} {}", t.elapsed().as_secs_f64(), instances.len());
    let t = Instant::now();
    let mut rows = 0;
    for (name, multi_id) in &instances {
        rows += log.columns(name, *multi_id).map_or(0, |c| c.rows());
    }
    println!("columns {:.6} {rows}", t.elapsed().as_secs_f64());
    let t = Instant::now();
    let mut rows = 0;
    for (name, multi_id) in &instances {
        for batch in ulog_runtime::columns::arrow::record_batches(&log, name, *multi_id, 1 << 16)
            .into_iter()
            .flatten()
        {
            rows += batch.map_or(0, |b| b.num_rows());
        }
    }
    println!("batches {:.6} {rows}", t.elapsed().as_secs_f64());
    let t = Instant::now();
    let parts = log.all_column_parts();
    let rows: usize = parts.iter().flat_map(|(_, _, p)| p).map(|c| c.rows()).sum();
    drop(parts);
    println!("all {:.6} {rows}", t.elapsed().as_secs_f64());
}
