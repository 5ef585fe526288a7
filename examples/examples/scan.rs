//! Decodes every data row of every subscription through the dynamic path and prints
//! `msgs=N leaves=L sum=S`: N rows, L non-padding leaf values, S the sum of the finite ones.
//!
//! ```text
//! cargo run --release -p examples --example scan -- FILE [--topics] [--stream]
//! ```
//! `--topics` prints `topic multi_id rows sum` per subscription with data instead;
//! `--stream` reads through `StreamReader` (bounded memory) instead of a memory map.

use std::collections::BTreeMap;
use std::process::ExitCode;

use ulog_runtime::{Event, Log, Row, StreamReader};

#[derive(Default)]
struct Totals {
    rows: u64,
    leaves: u64,
    sum: f64,
}

impl Totals {
    fn add(&mut self, row: &Row<'_>) {
        self.rows += 1;
        let (mut leaves, mut sum) = (0u64, 0.0f64);
        row.for_each_leaf(|v| {
            leaves += 1;
            let x = v.as_f64();
            if x.is_finite() {
                sum += x;
            }
        });
        self.leaves += leaves;
        self.sum += sum;
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let topics = args.iter().any(|a| a == "--topics");
    let stream = args.iter().any(|a| a == "--stream");
    let Some(path) = args.iter().find(|a| !a.starts_with("--")) else {
        eprintln!("usage: scan FILE [--topics] [--stream]");
        return ExitCode::from(2);
    };
    match run(path, topics, stream) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("scan: {path}: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(path: &str, topics: bool, stream: bool) -> Result<(), ulog_runtime::ReadError> {
    // Keyed by (topic, multi_id, msg_id) so the output order is stable.
    let mut per_topic: BTreeMap<(String, u8, u16), Totals> = BTreeMap::new();
    let mut all = Totals::default();
    let mut add = |row: &Row<'_>| {
        if topics {
            let s = row.subscription;
            per_topic
                .entry((s.name.clone(), s.multi_id, s.msg_id))
                .or_default()
                .add(row);
        } else {
            all.add(row);
        }
    };
    if stream {
        let file = std::fs::File::open(path)?;
        let mut reader = StreamReader::new(file)?;
        while let Some(event) = reader.next_event()? {
            if let Event::Row(row) = event {
                add(&row);
            }
        }
    } else {
        let log = Log::open(path)?;
        for row in log.data() {
            add(&row);
        }
    }
    if topics {
        for ((topic, multi_id, _), t) in &per_topic {
            println!("{topic} {multi_id} {} {:.6e}", t.rows, t.sum);
        }
    } else {
        println!(
            "msgs={} leaves={} sum={:.6e}",
            all.rows, all.leaves, all.sum
        );
    }
    Ok(())
}
