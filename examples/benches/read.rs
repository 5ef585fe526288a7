//! Reading throughput on a large log, in MB/s, with baselines measured in the same run.
//!
//! ```text
//! cargo bench -p examples --bench read
//! ```
//! The log (400 MB by default, `ULOG_BENCH_MB` to change) is built from a corpus log
//! (`ULOG_BENCH_SOURCE`, default `px4-ulog-rs/quadrotor_local.ulg` of the corpus) by repeating
//! its data messages with shifted, still increasing timestamps. Benchmarks:
//! - `baseline_copy`: `memcpy` of the whole file (memory bandwidth);
//! - `baseline_header_walk`: follows the 3-byte headers, no validation;
//! - `walk`: (a) message boundaries: every message framed and validated, corruption recovery
//!   armed, rows counted (`read::summarize`);
//! - `open`: `walk` plus the row index (`Log::from_slice`);
//! - `decode_leaves`: (b) every leaf of every row decoded in one pass (`read::fold_rows`, as
//!   the `scan` example does);
//! - `open_then_decode`: `open`, then the leaves decoded from the index (`Scan::log`);
//! - `stream_leaves`: the same through `StreamReader` (memory bounded by a few messages).

use std::hint::black_box;
use std::sync::OnceLock;

use divan::Bencher;
use divan::counter::BytesCount;
use ulog_runtime::Log;

fn big() -> &'static [u8] {
    static BIG: OnceLock<Vec<u8>> = OnceLock::new();
    BIG.get_or_init(|| {
        let corpus = std::env::var("ULOG_CORPUS").unwrap_or_else(|_| {
            concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/testdata/ulog").to_owned()
        });
        let source = std::env::var("ULOG_BENCH_SOURCE")
            .unwrap_or_else(|_| format!("{corpus}/px4-ulog-rs/quadrotor_local.ulg"));
        let mb: usize = std::env::var("ULOG_BENCH_MB")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(400);
        let bytes = std::fs::read(&source)
            .unwrap_or_else(|e| panic!("{source}: {e} (set ULOG_BENCH_SOURCE)"));
        let big = examples::inflate(&bytes, mb * 1_000_000).expect("a clean source log");
        eprintln!("benchmark log: {} bytes from {source}", big.len());
        big
    })
}

fn main() {
    divan::main();
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn baseline_copy(b: Bencher) {
    let data = big();
    let mut out = vec![0u8; data.len()];
    b.counter(BytesCount::new(data.len())).bench_local(|| {
        out.copy_from_slice(black_box(data));
        black_box(&out);
    });
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn baseline_header_walk(b: Bencher) {
    let data = big();
    b.counter(BytesCount::new(data.len())).bench_local(|| {
        let (mut pos, mut n) = (16usize, 0u64);
        while pos + 3 <= data.len() {
            pos += 3 + usize::from(u16::from_le_bytes([data[pos], data[pos + 1]]));
            n += 1;
        }
        black_box(n)
    });
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn walk(b: Bencher) {
    let data = big();
    b.counter(BytesCount::new(data.len()))
        .bench_local(|| black_box(ulog_runtime::read::summarize(black_box(data)).unwrap().rows));
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn open(b: Bencher) {
    let data = big();
    b.counter(BytesCount::new(data.len()))
        .bench_local(|| black_box(Log::from_slice(black_box(data)).unwrap().row_count()));
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn decode_leaves(b: Bencher) {
    let data = big();
    b.counter(BytesCount::new(data.len()))
        .bench_local(|| black_box(examples::Scan::bytes(black_box(data)).unwrap().all));
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn open_then_decode(b: Bencher) {
    let data = big();
    b.counter(BytesCount::new(data.len())).bench_local(|| {
        let log = Log::from_slice(black_box(data)).unwrap();
        black_box(examples::Scan::log(&log).all)
    });
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn stream_leaves(b: Bencher) {
    let data = big();
    b.counter(BytesCount::new(data.len()))
        .bench_local(|| black_box(examples::Scan::stream(black_box(data)).unwrap().all));
}
