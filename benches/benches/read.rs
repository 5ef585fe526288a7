//! Reading throughput on a large log, in MB/s, with baselines measured in the same run.
//!
//! ```text
//! cargo bench -p ulog-benches --bench read
//! ```
//! The log (400 MB by default, `ULOG_BENCH_MB` to change) is built from a corpus log
//! (`ULOG_BENCH_SOURCE`, default `px4-ulog-rs/quadrotor_local.ulg` of the corpus) by repeating
//! its data messages with shifted, still increasing timestamps. Benchmarks:
//! - `baseline_copy`: `memcpy` of the whole file (memory bandwidth);
//! - `baseline_header_walk`: follows the 3-byte headers, no validation;
//! - `walk`: (a) message boundaries: every message framed and validated, corruption recovery
//!   armed, rows counted (`read::summarize`);
//! - `open`: `walk` plus the row index (`Log::from_slice`);
//! - `decode_leaves`: (b) every leaf of every row decoded in one pass (`read::fold_rows`, the
//!   walk the `scan` example makes over a file, here over bytes in memory);
//! - `open_then_decode`: `open`, then the leaves decoded from the index (`Scan::log`);
//! - `stream_leaves`: the same through `StreamReader` (memory bounded by a few messages), one
//!   thread;
//! - `decode_leaves_one_core`: `decode_leaves` on one thread (`read::fold_rows_on(1, ..)`);
//! - `px4_ulog_leaves`: the baseline of the three above: px4-ulog 0.6.1's streaming parser
//!   decoding the same leaves of the same bytes in memory (`benches/src/px4_ulog_ref.rs`), one
//!   thread. `stream_leaves` and `decode_leaves_one_core` against it are the per-core
//!   figures; `decode_leaves` against it the wall-time figure on this machine's cores.
//! - `typed_sensor_combined`: every `sensor_combined` row of the opened log decoded into a
//!   derived struct (`Log::topic`, check included), against `dynamic_sensor_combined`: the
//!   same rows' leaves through the dynamic plan. Both count rows/s and bytes of those rows.

use std::hint::black_box;
use std::sync::OnceLock;

use divan::Bencher;

use divan::counter::{BytesCount, ItemsCount};
use ulog_benches::px4_ulog_ref;
use ulog_runtime::{Log, ULog};

/// `sensor_combined` as PX4 v1.13 logs it (the benchmark's source log), every field.
#[derive(ULog)]
struct SensorCombined {
    timestamp: u64,
    gyro_rad: [f32; 3],
    gyro_integral_dt: u32,
    accelerometer_timestamp_relative: i32,
    accelerometer_m_s2: [f32; 3],
    accelerometer_integral_dt: u32,
    accelerometer_clipping: u8,
    gyro_clipping: u8,
    accel_calibration_count: u8,
    gyro_calibration_count: u8,
}

fn opened() -> &'static Log<'static> {
    static LOG: OnceLock<Log<'static>> = OnceLock::new();
    LOG.get_or_init(|| {
        let log = Log::from_slice(big()).expect("the benchmark log reads");
        // Build the row index once, outside the measurements.
        for sub in log.subscriptions() {
            black_box(log.rows(sub).len());
        }
        log
    })
}

/// Rows and bytes of `sensor_combined` in the benchmark log.
fn sensor_combined_size(log: &Log<'_>) -> (usize, usize) {
    let sub = log.subscription("sensor_combined", 0).expect("logged");
    (
        log.rows(sub).len(),
        log.rows(sub).map(|r| r.data.len()).sum(),
    )
}

fn big() -> &'static [u8] {
    static BIG: OnceLock<Vec<u8>> = OnceLock::new();
    BIG.get_or_init(|| examples::bench_log("px4-ulog-rs/quadrotor_local.ulg", 1))
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

#[divan::bench(sample_count = 10, sample_size = 1)]
fn decode_leaves_one_core(b: Bencher) {
    let data = big();
    b.counter(BytesCount::new(data.len()))
        .bench_local(|| black_box(examples::Scan::bytes_on(1, black_box(data)).unwrap().all));
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn px4_ulog_leaves(b: Bencher) {
    let data = big();
    // Both sides decode the same leaves to the same figures.
    let ours = examples::Scan::bytes(data).unwrap().all;
    let theirs = px4_ulog_ref::scan_bytes(data);
    assert_eq!((ours.rows, ours.leaves), (theirs.rows, theirs.leaves));
    assert!((ours.sum - theirs.sum).abs() <= 1e-9 * ours.sum.abs());
    b.counter(BytesCount::new(data.len()))
        .bench_local(|| black_box(px4_ulog_ref::scan_bytes(black_box(data))));
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn typed_sensor_combined(b: Bencher) {
    let log = opened();
    let (rows, bytes) = sensor_combined_size(log);
    b.counter(ItemsCount::new(rows))
        .counter(BytesCount::new(bytes))
        .bench_local(|| {
            let topic = log
                .topic::<SensorCombined>()
                .expect("matches the source log");
            let mut sum = 0.0f64;
            for row in topic.instance(0).expect("instance 0") {
                sum += f64::from(row.accelerometer_m_s2[2] + row.gyro_rad[0])
                    + row.timestamp as f64
                    + f64::from(row.gyro_integral_dt + u32::from(row.gyro_clipping));
            }
            black_box(sum)
        });
}

#[divan::bench(sample_count = 10, sample_size = 1)]
fn dynamic_sensor_combined(b: Bencher) {
    let log = opened();
    let (rows, bytes) = sensor_combined_size(log);
    let sub = log.subscription("sensor_combined", 0).expect("logged");
    b.counter(ItemsCount::new(rows))
        .counter(BytesCount::new(bytes))
        .bench_local(|| {
            let mut sum = 0.0f64;
            for row in log.rows(sub) {
                row.for_each_leaf(|v| sum += v.as_f64());
            }
            black_box(sum)
        });
}
