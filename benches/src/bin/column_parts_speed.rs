//! `Log::columns` (one core) against `Log::column_parts` (every core) for every topic
//! instance of a log, in one process, alternating round by round, and the medians:
//!
//! ```text
//! cargo run --release -p ulog-benches --bin column_parts_speed -- LOG [ROUNDS]
//! ```
//!
//! Both gather each instance's rows from all over the file into fresh columns; the log is
//! opened and its per-subscription row index made before the clock starts.

use std::time::Instant;

fn main() {
    let mut args = std::env::args().skip(1);
    let (Some(path), rounds) = (args.next(), args.next()) else {
        eprintln!("usage: column_parts_speed LOG [ROUNDS]");
        std::process::exit(2);
    };
    let rounds: usize = rounds.map_or(Ok(7), |r| r.parse()).unwrap_or_else(|_| {
        eprintln!("column_parts_speed: ROUNDS is a number");
        std::process::exit(2);
    });
    let log = match ulog_runtime::Log::open(&path) {
        Ok(log) => log,
        Err(e) => {
            eprintln!("column_parts_speed: {path}: {e}");
            std::process::exit(1);
        }
    };
    let instances: Vec<(String, u8)> = log
        .instances(&[])
        .iter()
        .map(|g| (g[0].name.clone(), g[0].multi_id))
        .collect();
    // The per-subscription row index is made at its first use.
    if let Some((name, multi_id)) = instances.first() {
        let _ = log.columns(name, *multi_id);
    }
    let (mut whole, mut parts) = (Vec::new(), Vec::new());
    for r in 0..rounds {
        for parted in if r % 2 == 0 {
            [false, true]
        } else {
            [true, false]
        } {
            let t = Instant::now();
            let mut rows = 0;
            for (name, multi_id) in &instances {
                rows += if parted {
                    log.column_parts(name, *multi_id)
                        .map_or(0, |p| p.iter().map(|c| c.rows()).sum())
                } else {
                    log.columns(name, *multi_id).map_or(0, |c| c.rows())
                };
            }
            let secs = t.elapsed().as_secs_f64();
            if parted { &mut parts } else { &mut whole }.push((secs, rows));
        }
    }
    let median = |v: &mut Vec<(f64, usize)>| {
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        v[v.len() / 2]
    };
    let (w, rows) = median(&mut whole);
    let (p, _) = median(&mut parts);
    println!(
        "{} instances, {rows} rows, {rounds} rounds, {} cores",
        instances.len(),
        std::thread::available_parallelism().map_or(1, usize::from)
    );
    println!("  Log::columns       {w:.3} s");
    println!("  Log::column_parts  {p:.3} s   ({:.2}x)", w / p);
}
