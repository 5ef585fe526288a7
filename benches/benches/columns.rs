//! Columns and Parquet conversion: MB/s of input and the peak memory each adds, with the
//! CSV export of the same log as the baseline measured in the same run.
//!
//! ```text
//! cargo bench -p ulog-benches --bench columns
//! ```
//! The log (400 MB by default, `ULOG_BENCH_MB` to change) is built from
//! `pyulog/sample_log_small.ulg` of the corpus (`ULOG_BENCH_SOURCE` to change) as the `read`
//! benchmark builds its log, and written to a temporary file. Benchmarks:
//! - `columns`: every row of every topic instance into typed columns ([`ColumnBuilder`]),
//!   in batches of 64 KiB of rows, no Arrow (a [`StreamReader`] over the file);
//! - `columns_arrow`: the same, each batch made an Arrow record batch;
//! - `log_columns`: [`Log::columns`] of every topic instance of the opened (memory-mapped)
//!   log, each instance's rows in one batch;
//! - `log_record_batches`: [`arrow::record_batches`] of every topic instance of the opened
//!   log, batches of 65,536 rows;
//! - `parquet_one_log`: [`Converter::convert_file`], what `ulog parquet FILE -o DIR` does:
//!   one streaming pass, ZSTD, `metadata.json`;
//! - `parquet_many_logs`: [`Converter::convert_files`] of 8 logs of an eighth of the size
//!   each, on every core (what `ulog parquet *.ulg -o DIR` does);
//! - `csv_one_log`: the baseline, [`csv::export`] of the same log (what `ulog csv` does).
//!
//! After the run, a table gives the peak resident memory (Linux `VmHWM`, what `time -v`
//! calls maximum resident set size) of a process of its own doing each benchmark's work
//! once, beside that of a process doing nothing: the inputs are files, never held in memory
//! (but `csv_one_log` maps its log, as `ulog csv` does); `ULOG_BENCH_NO_PEAK` leaves the
//! table out.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use divan::Bencher;
use divan::counter::BytesCount;
use ulog_runtime::columns::csv::{self, CsvOptions};
use ulog_runtime::columns::parquet::{Converter, ParquetOptions};
use ulog_runtime::columns::{ColumnBuilder, ColumnSpec, arrow};
use ulog_runtime::{Event, Log, StreamReader};

const SOURCE: &str = "pyulog/sample_log_small.ulg";
const MANY: usize = 8;

fn dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| match std::env::var_os("ULOG_BENCH_DIR") {
        Some(dir) => PathBuf::from(dir),
        None => {
            let dir =
                std::env::temp_dir().join(format!("ulog-bench-columns-{}", std::process::id()));
            std::fs::create_dir_all(&dir).expect("a temporary folder");
            dir
        }
    })
}

/// The benchmark log, as a file, and its size.
fn big() -> &'static (PathBuf, u64) {
    static BIG: OnceLock<(PathBuf, u64)> = OnceLock::new();
    BIG.get_or_init(|| {
        let path = dir().join("big.ulg");
        if std::env::var_os(PEAK_VAR).is_none() {
            std::fs::write(&path, examples::bench_log(SOURCE, 1)).expect("the log written");
        }
        let len = std::fs::metadata(&path).expect("the log").len();
        (path, len)
    })
}

/// [`MANY`] logs of an eighth of the benchmark log's size each, as files, and their total.
fn many() -> &'static (Vec<PathBuf>, u64) {
    static MANY_LOGS: OnceLock<(Vec<PathBuf>, u64)> = OnceLock::new();
    MANY_LOGS.get_or_init(|| {
        let paths: Vec<PathBuf> = (0..MANY)
            .map(|i| dir().join(format!("log{i}.ulg")))
            .collect();
        if std::env::var_os(PEAK_VAR).is_none() {
            let one = examples::bench_log(SOURCE, MANY);
            for path in &paths {
                std::fs::write(path, &one).expect("a log written");
            }
        }
        let total = paths
            .iter()
            .map(|p| std::fs::metadata(p).expect("a log").len())
            .sum();
        (paths, total)
    })
}

/// The high-water mark of this process's resident memory, bytes (Linux `VmHWM`).
fn peak_rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb: u64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb * 1024)
}

/// Each benchmark's work, once: what the peak-memory table measures, each in a process of
/// its own.
const WORKLOADS: [(&str, fn()); 6] = [
    ("nothing (the process)", || {}),
    ("columns", || {
        black_box(columns_pass(&mut |_, c| {
            black_box(c.rows());
        }));
    }),
    ("columns_arrow", arrow_pass),
    ("parquet_one_log", || {
        let converter = Converter::new(dir().join("one"), ParquetOptions::default());
        black_box(converter.convert_file(&big().0).unwrap());
    }),
    ("parquet_many_logs", || {
        let converter = Converter::new(dir().join("many"), ParquetOptions::default());
        black_box(converter.convert_files(&many().0, threads()));
    }),
    ("csv_one_log", csv_pass),
];

const PEAK_VAR: &str = "ULOG_BENCH_PEAK_OF";

fn main() {
    if let Ok(name) = std::env::var(PEAK_VAR) {
        // A child of the table below: one workload, then its peak.
        let (_, work) = WORKLOADS
            .iter()
            .find(|(n, _)| *n == name)
            .expect("a workload");
        work();
        println!("{}", peak_rss().unwrap_or(0));
        return;
    }
    // Build the inputs before any measurement (the children find them in place).
    big();
    many();
    divan::main();
    if std::env::var_os("ULOG_BENCH_NO_PEAK").is_some() {
        let _ = std::fs::remove_dir_all(dir());
        return;
    }
    println!("\npeak resident memory of a process doing each benchmark's work once (VmHWM):");
    let me = std::env::current_exe().expect("this benchmark");
    for (name, _) in WORKLOADS {
        let out = std::process::Command::new(&me)
            .env(PEAK_VAR, name)
            .env("ULOG_BENCH_DIR", dir())
            .output()
            .expect("the benchmark runs");
        let peak: Option<u64> = String::from_utf8_lossy(&out.stdout).trim().parse().ok();
        match peak.filter(|&p| p > 0) {
            Some(p) => println!("  {name:<22} {:>8.1} MiB", p as f64 / (1 << 20) as f64),
            None => println!("  {name:<22} (not measurable here)"),
        }
    }
    let _ = std::fs::remove_dir_all(dir());
}

fn threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Every row of every instance through column builders; `f` gets each batch.
fn columns_pass(f: &mut dyn FnMut(&ColumnSpec, ulog_runtime::columns::Columns)) -> usize {
    let (path, _) = big();
    let file = std::io::BufReader::with_capacity(1 << 16, std::fs::File::open(path).unwrap());
    let mut reader = StreamReader::new(file).unwrap();
    let mut builders: Vec<Option<(ColumnBuilder, usize)>> = Vec::new();
    let mut rows = 0;
    reader
        .for_each_event(|event| {
            let Event::Row(row) = &event else { return };
            let id = usize::from(row.subscription.msg_id);
            if builders.len() <= id {
                builders.resize_with(id + 1, || None);
            }
            let slot = builders[id].get_or_insert_with(|| {
                let spec = ColumnSpec::of(row.schema(), row.subscription.format().unwrap())
                    .expect("a readable format");
                let batch = ((64 << 10) / spec.row_len().max(1)).max(1);
                (ColumnBuilder::with_capacity(spec, batch), batch)
            });
            slot.0.push(row.data, row.timestamp);
            rows += 1;
            if slot.0.rows() >= slot.1 {
                let spec = slot.0.spec().clone();
                f(&spec, slot.0.take());
            }
        })
        .unwrap();
    for (builder, _) in builders.iter_mut().flatten() {
        let spec = builder.spec().clone();
        f(&spec, builder.take());
    }
    rows
}

fn arrow_pass() {
    let mut schemas = std::collections::HashMap::new();
    black_box(columns_pass(&mut |spec, c| {
        let schema = schemas
            .entry(spec.format().to_owned())
            .or_insert_with(|| arrow::schema(spec, "t"))
            .clone();
        black_box(arrow::record_batch(&schema, c).unwrap().num_rows());
    }));
}

fn csv_pass() {
    let out = dir().join("csv");
    std::fs::create_dir_all(&out).unwrap();
    let log = Log::open(&big().0).unwrap();
    let files = csv::export(&log, "big", &out, &[], &CsvOptions::default(), &mut || {}).unwrap();
    black_box(files.len());
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn columns(b: Bencher) {
    b.counter(BytesCount::new(big().1))
        .bench_local(WORKLOADS[1].1);
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn columns_arrow(b: Bencher) {
    b.counter(BytesCount::new(big().1)).bench_local(arrow_pass);
}

/// The opened benchmark log and its topic instances.
fn opened() -> &'static (Log<'static>, Vec<(String, u8)>) {
    static OPENED: OnceLock<(Log<'static>, Vec<(String, u8)>)> = OnceLock::new();
    OPENED.get_or_init(|| {
        let log = Log::open(&big().0).expect("the log opens");
        let mut instances: Vec<(String, u8)> = log
            .subscriptions()
            .iter()
            .map(|s| (s.name.clone(), s.multi_id))
            .collect();
        instances.sort();
        instances.dedup();
        // Its pages in memory before any sample.
        for (topic, multi_id) in &instances {
            black_box(log.columns(topic, *multi_id).map(|c| c.rows()).ok());
        }
        (log, instances)
    })
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn log_columns(b: Bencher) {
    let (log, instances) = opened();
    b.counter(BytesCount::new(big().1)).bench_local(|| {
        for (topic, multi_id) in instances {
            black_box(log.columns(topic, *multi_id).map(|c| c.rows()).ok());
        }
    });
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn log_record_batches(b: Bencher) {
    let (log, instances) = opened();
    b.counter(BytesCount::new(big().1)).bench_local(|| {
        for (topic, multi_id) in instances {
            for batch in arrow::record_batches(log, topic, *multi_id, 1 << 16)
                .into_iter()
                .flatten()
            {
                black_box(batch.unwrap().num_rows());
            }
        }
    });
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn parquet_one_log(b: Bencher) {
    let converter = Converter::new(dir().join("one"), ParquetOptions::default());
    b.counter(BytesCount::new(big().1)).bench_local(|| {
        black_box(converter.convert_file(&big().0).unwrap().files.len());
    });
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn parquet_many_logs(b: Bencher) {
    let converter = Converter::new(dir().join("many"), ParquetOptions::default());
    b.counter(BytesCount::new(many().1)).bench_local(|| {
        for r in converter.convert_files(&many().0, threads()) {
            black_box(r.unwrap().files.len());
        }
    });
}

#[divan::bench(sample_count = 2, sample_size = 1)]
fn csv_one_log(b: Bencher) {
    b.counter(BytesCount::new(big().1)).bench_local(csv_pass);
}
