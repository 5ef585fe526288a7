//! Rewriting speed, in MB/s of input, against copying the file in the same run.
//!
//! ```text
//! cargo bench -p ulog-benches --bench rewrite
//! ```
//! The log (400 MB by default, `ULOG_BENCH_MB` to change) is built from
//! `pyulog/sample_log_small.ulg` of the corpus (`ULOG_BENCH_SOURCE` to change) as the other
//! benchmarks build theirs, and written to a temporary file. Each benchmark reads it from the
//! file and writes a new file beside it, on one thread:
//! - `copy_file`: the baseline, `std::fs::copy` of the file (read and write, no parsing);
//! - `no_rules`: `Rewrite::new()`: every message read, framed, validated and written back;
//! - `cut`: the middle half of the log's time and every topic but the largest, no row
//!   transform (what `ulog cut --start --end --exclude` does);
//! - `anonymize`: every position, altitude and time rewritten (`ulog anonymize`).

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use divan::Bencher;
use divan::counter::BytesCount;
use ulog_runtime::Log;
use ulog_runtime::columns::Window;
use ulog_runtime::rewrite::{Anonymize, Rewrite};

const SOURCE: &str = "pyulog/sample_log_small.ulg";

fn dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("ulog-bench-rewrite-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a temporary folder");
        dir
    })
}

/// The benchmark log as a file, its size, the window of its middle half and its largest
/// topic.
fn big() -> &'static (PathBuf, u64, Window, String) {
    static BIG: OnceLock<(PathBuf, u64, Window, String)> = OnceLock::new();
    BIG.get_or_init(|| {
        let path = dir().join("big.ulg");
        std::fs::write(&path, examples::bench_log(SOURCE, 1)).expect("the log written");
        let log = Log::open(&path).expect("the log reads");
        let (first, last) = log.data().fold((u64::MAX, 0), |(a, b), r| {
            (a.min(r.timestamp), b.max(r.timestamp))
        });
        let span = (last - first) as f64;
        let window = Window {
            start_us: Some(first as f64 + 0.25 * span),
            end_us: Some(first as f64 + 0.75 * span),
        };
        let largest = log
            .topics()
            .into_iter()
            .max_by_key(|t| t.rows)
            .expect("topics")
            .name;
        let len = std::fs::metadata(&path).expect("the log").len();
        (path, len, window, largest)
    })
}

fn run(bencher: Bencher<'_, '_>, make: impl Fn() -> Rewrite + Sync) {
    let (path, len, ..) = big();
    let out = dir().join("out.ulg");
    bencher
        .counter(BytesCount::new(*len))
        .bench(|| black_box(make().run_file(path, &out).expect("rewritten")));
}

#[divan::bench(sample_count = 10)]
fn copy_file(bencher: Bencher<'_, '_>) {
    let (path, len, ..) = big();
    let out = dir().join("copy.ulg");
    bencher
        .counter(BytesCount::new(*len))
        .bench(|| black_box(std::fs::copy(path, &out).expect("copied")));
}

#[divan::bench(sample_count = 10)]
fn no_rules(bencher: Bencher<'_, '_>) {
    run(bencher, Rewrite::new);
}

#[divan::bench(sample_count = 10)]
fn cut(bencher: Bencher<'_, '_>) {
    let (_, _, window, largest) = big();
    run(bencher, || {
        Rewrite::new()
            .window(*window)
            .exclude(std::slice::from_ref(largest))
    });
}

#[divan::bench(sample_count = 10)]
fn anonymize(bencher: Bencher<'_, '_>) {
    run(bencher, || Rewrite::new().anonymize(Anonymize::seed(1)));
}

fn main() {
    divan::main();
    let _ = std::fs::remove_dir_all(dir());
}
