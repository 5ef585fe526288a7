//! The converter on logs made by the writer, read back with parquet-rs's own reader (pyarrow
//! and DuckDB read the corpus conversions in the CLI tests).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use arrow_array::{Float32Array, RecordBatch, UInt64Array};
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use sha2::Digest;

use super::*;
use crate::{ULog, Writer, WriterOptions};

#[derive(ULog)]
struct Battery {
    timestamp: u64,
    voltage_v: f32,
    cells: [u16; 3],
}

#[derive(ULog)]
#[ulog(name = "sensors/gyro")]
struct Gyro {
    timestamp: u64,
    x: u8,
}

/// A log of `rows` battery rows on two instances, and a topic with a `/` in its name.
fn log_bytes(rows: u64) -> Vec<u8> {
    log_bytes_with(rows, |_, _| {})
}

/// [`log_bytes`], `more` writing what else it wants after the rows of each time `t`.
fn log_bytes_with(rows: u64, mut more: impl FnMut(&mut Writer<Vec<u8>>, u64)) -> Vec<u8> {
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let text = |s: &str| crate::Value::String(s.to_owned());
    w.info("sys_name", &text("PX4")).unwrap();
    w.info("ver_hw", &text("TEST_BOARD")).unwrap();
    let b0 = w.topic::<Battery>(0).unwrap();
    let b1 = w.topic::<Battery>(1).unwrap();
    let gyro = w.topic::<Gyro>(0).unwrap();
    for t in 0..rows {
        let v = Battery {
            timestamp: t,
            voltage_v: t as f32 / 8.0,
            cells: [1, 2, t as u16],
        };
        w.write(&b0, &v).unwrap();
        if t % 2 == 0 {
            w.write(&b1, &v).unwrap();
        }
        more(&mut w, t);
    }
    w.write(&gyro, &Gyro { timestamp: 5, x: 7 }).unwrap();
    w.into_inner()
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ulog-parquet-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Every batch of a Parquet file, and its key-value metadata.
fn read(path: &Path) -> (Vec<RecordBatch>, HashMap<String, String>, usize) {
    let builder =
        ParquetRecordBatchReaderBuilder::try_new(std::fs::File::open(path).unwrap()).unwrap();
    let meta = builder.metadata().clone();
    let kv = meta
        .file_metadata()
        .key_value_metadata()
        .unwrap()
        .iter()
        .map(|kv| (kv.key.clone(), kv.value.clone().unwrap_or_default()))
        .collect();
    let batches = builder.build().unwrap().map(Result::unwrap).collect();
    (batches, kv, meta.num_row_groups())
}

fn column<'a, T: 'static>(batches: &'a [RecordBatch], name: &str) -> Vec<&'a T> {
    batches
        .iter()
        .map(|b| {
            b.column_by_name(name)
                .unwrap()
                .as_any()
                .downcast_ref::<T>()
                .unwrap()
        })
        .collect()
}

#[test]
fn a_log_becomes_a_file_per_instance_with_its_identity() {
    let bytes = log_bytes(1000);
    let root = temp("identity");
    let conv = Converter::new(&root, ParquetOptions::default())
        .convert_reader(&bytes[..], "flight.ulg")
        .unwrap();
    assert_eq!(conv.log_dir, "flight");
    assert_eq!(conv.bytes, bytes.len() as u64);
    let files: Vec<(String, u8, usize)> = conv
        .files
        .iter()
        .map(|f| {
            (
                f.path.strip_prefix(&root).unwrap().display().to_string(),
                f.multi_id,
                f.rows,
            )
        })
        .collect();
    assert_eq!(
        files,
        [
            ("flight/battery_0.parquet".to_owned(), 0, 1000),
            ("flight/battery_1.parquet".to_owned(), 1, 500),
            ("flight/sensors_gyro_0.parquet".to_owned(), 0, 1)
        ]
    );
    let (batches, kv, _) = read(&conv.files[1].path);
    let sha: String = sha2::Sha256::digest(&bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    assert_eq!(kv["ulog.sha256"], sha);
    assert_eq!(kv["ulog.file_name"], "flight.ulg");
    assert_eq!(kv["ulog.sys_name"], "PX4");
    assert_eq!(kv["ulog.ver_hw"], "TEST_BOARD");
    assert!(!kv.contains_key("ulog.ver_sw"), "the log has none");
    assert_eq!(kv["ulog.topic"], "battery");
    assert_eq!(kv["ulog.multi_id"], "1");
    assert_eq!(kv["ulog.format"], Battery::FORMAT.to_format().to_string());
    let ts: Vec<u64> = column::<UInt64Array>(&batches, "timestamp")
        .iter()
        .flat_map(|a| a.values().iter().copied())
        .collect();
    assert_eq!(ts, (0..1000).step_by(2).collect::<Vec<_>>());
    let v: Vec<f32> = column::<Float32Array>(&batches, "voltage_v")
        .iter()
        .flat_map(|a| a.values().iter().copied())
        .collect();
    assert_eq!(v[3], 6.0 / 8.0);
    assert_eq!(
        batches[0]
            .schema()
            .fields()
            .iter()
            .map(|f| f.name().as_str())
            .collect::<Vec<_>>(),
        ["timestamp", "voltage_v", "cells[0]", "cells[1]", "cells[2]"]
    );
    assert_eq!(
        batches[0].schema().field(4).metadata()["ulog.type"],
        "uint16_t"
    );
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&conv.metadata).unwrap()).unwrap();
    assert_eq!(meta["log"]["sha256"], sha.as_str());
    assert_eq!(meta["info"]["sys_name"], "PX4");
    assert_eq!(meta["topics"].as_array().unwrap().len(), 3);
    assert!(std::fs::read_dir(root.join("flight")).unwrap().all(|e| {
        !e.unwrap()
            .file_name()
            .to_string_lossy()
            .ends_with(".partial")
    }));
    std::fs::remove_dir_all(&root).unwrap();
}

/// Every file's `voltage_v` and `cells[2]` columns, by file name, and its row groups.
fn battery_values(root: &Path, conv: &Conversion) -> Vec<(String, Vec<f32>, Vec<u16>, usize)> {
    conv.files
        .iter()
        .filter(|f| f.topic == "battery")
        .map(|f| {
            let (batches, _, groups) = read(&f.path);
            let v = column::<Float32Array>(&batches, "voltage_v")
                .iter()
                .flat_map(|a| a.values().iter().copied())
                .collect();
            let c = column::<arrow_array::UInt16Array>(&batches, "cells[2]")
                .iter()
                .flat_map(|a| a.values().iter().copied())
                .collect();
            let name = f.path.strip_prefix(root).unwrap().display().to_string();
            (name, v, c, groups)
        })
        .collect()
}

#[test]
fn a_small_budget_writes_more_row_groups_of_the_same_rows() {
    let rows = 20_000u64;
    let bytes = log_bytes(rows);
    // What the log was written with: instance 0 every row, instance 1 every other.
    let expected = |multi_id: u64| -> (Vec<f32>, Vec<u16>) {
        (0..rows)
            .filter(|t| multi_id == 0 || t % 2 == 0)
            .map(|t| (t as f32 / 8.0, t as u16))
            .unzip()
    };
    for (name, options, groups) in [
        ("budget-default", ParquetOptions::default(), [1, 1]),
        (
            "budget-small",
            ParquetOptions {
                buffer_bytes: 16 << 10,
                batch_bytes: 1 << 10,
                ..ParquetOptions::default()
            },
            [0, 0],
        ),
        (
            "budget-rows",
            ParquetOptions {
                row_group_rows: 3000,
                ..ParquetOptions::default()
            },
            [7, 4],
        ),
        (
            // Row groups shorter than a batch of 64 KiB (thousands of rows).
            "budget-rows-within-a-batch",
            ParquetOptions {
                row_group_rows: 500,
                ..ParquetOptions::default()
            },
            [40, 20],
        ),
        (
            // Every column through parquet-rs's writer, with dictionaries (INT64 ones
            // falling back to DELTA_BINARY_PACKED).
            "dictionary",
            ParquetOptions {
                dictionary: true,
                ..ParquetOptions::default()
            },
            [1, 1],
        ),
    ] {
        let root = temp(name);
        let conv = Converter::new(&root, options)
            .convert_reader(&bytes[..], "f.ulg")
            .unwrap();
        let files = battery_values(&root, &conv);
        assert_eq!(files.len(), 2, "{name}");
        for (m, (file, v, c, g)) in files.into_iter().enumerate() {
            let (ev, ec) = expected(m as u64);
            assert_eq!(file, format!("f/battery_{m}.parquet"));
            assert!(v == ev && c == ec, "{name}: {file} holds other values");
            let (batches, ..) = read(&root.join(&file));
            let timestamps: Vec<u64> = column::<UInt64Array>(&batches, "timestamp")
                .iter()
                .flat_map(|a| a.values().iter().copied())
                .collect();
            let want: Vec<u64> = (0..rows).filter(|t| m == 0 || t % 2 == 0).collect();
            assert!(timestamps == want, "{name}: {file} holds other timestamps");
            match groups[m] {
                0 => assert!(g > 5, "{name}: {file}: {g} row groups"),
                n => assert_eq!(g, n, "{name}: {file}"),
            }
        }
        std::fs::remove_dir_all(&root).unwrap();
    }
}

#[test]
fn rows_of_a_reused_msg_id_go_to_the_topic_subscribed_last() {
    use crate::read::{FileHeader, FlagBits, Message};
    let mut bytes = FileHeader {
        version: 1,
        start_timestamp: 0,
    }
    .to_bytes()
    .to_vec();
    let mut put = |m: Message<'_>| m.encode(&mut bytes).unwrap();
    put(Message::FlagBits(FlagBits::default()));
    put(Message::Format(b"a:uint64_t timestamp;uint8_t x;"));
    put(Message::Format(
        b"b:uint64_t timestamp;uint16_t y;uint16_t z;",
    ));
    put(Message::Subscribe {
        multi_id: 0,
        msg_id: 0,
        name: b"a",
    });
    put(Message::Data {
        msg_id: 0,
        data: &[1, 0, 0, 0, 0, 0, 0, 0, 9],
    });
    put(Message::Unsubscribe { msg_id: 0 });
    put(Message::Subscribe {
        multi_id: 0,
        msg_id: 0,
        name: b"b",
    });
    put(Message::Data {
        msg_id: 0,
        data: &[2, 0, 0, 0, 0, 0, 0, 0, 5, 0, 6, 0],
    });
    put(Message::Data {
        msg_id: 0,
        data: &[3, 0, 0, 0, 0, 0, 0, 0, 7, 0, 8, 0],
    });
    let root = temp("reuse");
    for (how, conv) in both_ways(&bytes, "r.ulg", &root, ParquetOptions::default()) {
        let conv = conv.unwrap();
        let rows: Vec<(&str, usize)> = conv
            .files
            .iter()
            .map(|f| (f.topic.as_str(), f.rows))
            .collect();
        assert_eq!(rows, [("a", 1), ("b", 2)], "{how}");
        let (batches, _, _) = read(&conv.files[1].path);
        let z: Vec<u16> = column::<arrow_array::UInt16Array>(&batches, "z")
            .iter()
            .flat_map(|a| a.values().iter().copied())
            .collect();
        assert_eq!(z, [6, 8], "{how}");
    }
    std::fs::remove_dir_all(&root).unwrap();
}

/// `bytes` converted as a stream ([`Converter::convert_reader`]) and as a file named
/// `name` ([`Converter::convert_file`], which maps it), each into a folder of its own
/// under `dir`.
fn both_ways(
    bytes: &[u8],
    name: &str,
    dir: &Path,
    options: ParquetOptions,
) -> [(&'static str, Result<Conversion, ConvertError>); 2] {
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    let stream = Converter::new(dir.join("stream"), options.clone()).convert_reader(bytes, name);
    let file = Converter::new(dir.join("file"), options).convert_file(&path);
    [("stream", stream), ("file", file)]
}

#[test]
fn a_file_converts_as_its_bytes_read_as_a_stream() {
    use crate::read::{LogLevel, ParamValue};
    // More than a progress step (8 MB) and many reads (logged strings of 60 kB among the
    // rows), with a parameter change, a dropout, junk in the middle and a message cut short
    // at the end.
    let long = "x".repeat(60_000);
    let mut bytes = log_bytes_with(20_000, |w, t| {
        if t % 130 == 0 {
            w.log(LogLevel::Info, t, &format!("{t} {long}")).unwrap();
        }
        if t == 5_000 {
            w.parameter("P", ParamValue::Int32(3)).unwrap();
            w.dropout(20).unwrap();
            w.log(LogLevel::Warning, t, "junk before this").unwrap();
        }
    });
    // The logged string's message starts 12 bytes before its text (size, type, level,
    // timestamp).
    let text = bytes
        .windows(16)
        .position(|w| w == b"junk before this")
        .unwrap();
    bytes.splice(text - 12..text - 12, [0xAB; 1_000]);
    bytes.truncate(bytes.len() - 5);
    assert!(bytes.len() > 9 << 20);
    let dir = temp("file-or-stream");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("f.ulg");
    std::fs::write(&path, &bytes).unwrap();
    let stream = Converter::new(dir.join("stream"), ParquetOptions::default())
        .convert_reader(&bytes[..], "f.ulg")
        .unwrap();
    assert!(
        stream.skipped.damaged_bytes >= 1_000,
        "{:?}",
        stream.skipped
    );
    let tables = |conv: &Conversion, root: &Path| {
        conv.files
            .iter()
            .map(|f| {
                let (batches, kv, _) = read(&f.path);
                let at = f.path.strip_prefix(root).unwrap().to_owned();
                (at, f.topic.clone(), f.multi_id, f.rows, batches, kv)
            })
            .collect::<Vec<_>>()
    };
    let json = |conv: &Conversion| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(&conv.metadata).unwrap()).unwrap()
    };
    let sha: String = sha2::Sha256::digest(&bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    assert_eq!(json(&stream)["log"]["sha256"], sha.as_str());
    // Hashed as read (no encoder), by the encoder's thread (one) or on a thread of its own
    // (two).
    for encoders in [Some(0), Some(1), Some(2)] {
        let progress = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
        let seen = progress.clone();
        let root = dir.join(format!("file-{encoders:?}"));
        let file = Converter::new(
            &root,
            ParquetOptions {
                encoders,
                ..ParquetOptions::default()
            },
        )
        .on_progress(move |n| {
            seen.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
        })
        .convert_file(&path)
        .unwrap();
        assert_eq!(
            progress.load(std::sync::atomic::Ordering::Relaxed),
            bytes.len() as u64,
            "{encoders:?}: progress of every byte"
        );
        assert_eq!(
            (file.bytes, &file.skipped),
            (stream.bytes, &stream.skipped),
            "{encoders:?}"
        );
        assert!(
            tables(&file, &root) == tables(&stream, &dir.join("stream")),
            "{encoders:?}: the tables"
        );
        assert_eq!(json(&file), json(&stream), "{encoders:?}: metadata.json");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_new_conversion_of_a_log_replaces_the_files_of_the_earlier_one() {
    let root = temp("again");
    let converter = Converter::new(&root, ParquetOptions::default());
    converter
        .convert_reader(&log_bytes(10)[..], "f.ulg")
        .unwrap();
    assert!(root.join("f/sensors_gyro_0.parquet").is_file());
    // The same log name, now converted with only one topic: the others' files go.
    let only = Converter::new(
        &root,
        ParquetOptions {
            topics: vec!["battery".into()],
            ..ParquetOptions::default()
        },
    );
    let conv = only.convert_reader(&log_bytes(10)[..], "f.ulg").unwrap();
    assert_eq!(conv.files.len(), 2);
    let mut names: Vec<String> = std::fs::read_dir(root.join("f"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["battery_0.parquet", "battery_1.parquet", "metadata.json"]
    );
    // A window no row of an instance falls in: no file for it.
    let late = Converter::new(
        &root,
        ParquetOptions {
            window: Window::seconds(Some(1.0), None).unwrap(),
            ..ParquetOptions::default()
        },
    );
    let conv = late.convert_reader(&log_bytes(10)[..], "g.ulg").unwrap();
    assert!(conv.files.is_empty(), "{:?}", conv.files);
    // It says where the rows are: battery rows at 0 to 9 µs, the gyro's at 5 µs.
    assert_eq!(conv.row_span_us, Some((0, 9)));
    let window = Window::seconds(Some(1.0), None).unwrap();
    assert_eq!(
        conv.lines(&[], &window),
        [
            "no Parquet file written: no topic has rows that can be read in the window from 1 s \
          (their rows run from 0 s to 0.000009 s)"
        ]
    );
    // Of the topics asked for only.
    let gyro = Converter::new(
        &root,
        ParquetOptions {
            window,
            topics: vec!["sensors/gyro".into()],
            ..ParquetOptions::default()
        },
    );
    let conv = gyro.convert_reader(&log_bytes(10)[..], "h.ulg").unwrap();
    assert_eq!(conv.row_span_us, Some((5, 5)));
    assert_eq!(
        conv.lines(&["sensors/gyro".into()], &window),
        [
            "no Parquet file written: the topics asked for have no rows that can be read in the \
          window from 1 s (their rows run from 0.000005 s to 0.000005 s)"
        ]
    );
    // metadata.json says the window (its per-topic rows are the whole log's); without
    // one it has no `window`.
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(root.join("g/metadata.json")).unwrap()).unwrap();
    assert_eq!(
        meta["window"],
        serde_json::json!({"start_s": 1.0, "end_s": null})
    );
    let whole: serde_json::Value =
        serde_json::from_slice(&std::fs::read(root.join("f/metadata.json")).unwrap()).unwrap();
    assert!(whole.get("window").is_none(), "{whole}");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn hive_layout_partitions_by_topic_log_and_instance() {
    let root = temp("hive");
    let a = root.join("a");
    let b = root.join("b");
    // Two different logs of one stem.
    for (dir, rows) in [(&a, 10), (&b, 11)] {
        std::fs::create_dir_all(dir).unwrap();
        std::fs::write(dir.join("same.ulg"), log_bytes(rows)).unwrap();
    }
    let out = root.join("out");
    let converter = Converter::new(
        &out,
        ParquetOptions {
            layout: Layout::Hive,
            topics: vec!["battery".to_owned()],
            ..ParquetOptions::default()
        },
    );
    let results = converter.convert_files(&[a.join("same.ulg"), b.join("same.ulg")], 2);
    let dirs: Vec<String> = results
        .iter()
        .map(|r| r.as_ref().unwrap().log_dir.clone())
        .collect();
    assert_eq!(
        dirs,
        ["log=same", "log=same~2"],
        "two logs of one stem do not collide"
    );
    for dir in &dirs {
        for m in 0..2 {
            let p = out.join(format!("topic=battery/{dir}/multi_id={m}/data.parquet"));
            assert!(p.is_file(), "{}", p.display());
        }
        assert!(out.join(format!("metadata/{dir}/metadata.json")).is_file());
    }
    assert!(!out.join("topic=sensors_gyro").exists(), "not asked for");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn a_stopped_fleet_conversion_starts_no_log_and_says_so_of_each() {
    let root = temp("stopped");
    std::fs::create_dir_all(&root).unwrap();
    let paths: Vec<PathBuf> = (0..4)
        .map(|i| {
            let p = root.join(format!("log{i}.ulg"));
            std::fs::write(&p, log_bytes(10)).unwrap();
            p
        })
        .collect();
    let out = root.join("out");
    let converter = Converter::new(&out, ParquetOptions::default());
    let stop = std::sync::atomic::AtomicBool::new(true);
    for threads in [1, 3] {
        let results = converter.convert_files_until(&paths, threads, &stop);
        assert_eq!(results.len(), paths.len());
        for (r, p) in results.iter().zip(&paths) {
            match r {
                Err(e @ ConvertError::Stopped { log }) => {
                    assert_eq!(log, &p.display().to_string());
                    assert!(e.to_string().contains("not converted"), "{e}");
                }
                other => panic!("{}: {other:?}", p.display()),
            }
        }
        assert!(
            std::fs::read_dir(&out).map_or(true, |d| d.count() == 0),
            "nothing written"
        );
    }
    // Not stopped: every log converted.
    stop.store(false, std::sync::atomic::Ordering::Relaxed);
    let results = converter.convert_files_until(&paths, 2, &stop);
    assert!(results.iter().all(Result::is_ok), "{results:?}");
    for i in 0..4 {
        assert!(out.join(format!("log{i}/metadata.json")).is_file());
    }
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn write_topic_takes_the_window_and_says_what_it_wrote() {
    let log = crate::Log::from_vec(log_bytes(100)).unwrap();
    let identity = LogIdentity::of_log(&log, "x.ulg");
    let path =
        std::env::temp_dir().join(format!("ulog-write-topic-{}.parquet", std::process::id()));
    let file = std::fs::File::create(&path).unwrap();
    let options = ParquetOptions {
        window: Window {
            start_us: Some(10.0),
            end_us: Some(20.0),
        },
        ..ParquetOptions::default()
    };
    let written = write_topic(&log, "battery", 0, &identity, file, &options).unwrap();
    assert_eq!(
        written,
        TableWritten {
            rows: 10,
            row_groups: 1
        }
    );
    let (batches, kv, _) = read(&path);
    let ts: Vec<u64> = column::<UInt64Array>(&batches, "timestamp")
        .iter()
        .flat_map(|a| a.values().iter().copied())
        .collect();
    assert_eq!(ts, (10..20).collect::<Vec<_>>());
    assert_eq!(kv["ulog.file_name"], "x.ulg");
    std::fs::remove_file(&path).unwrap();
    let none = write_topic(&log, "nope", 0, &identity, Vec::new(), &options).unwrap_err();
    assert_eq!(
        none.to_string(),
        "no topic instance `nope` #0 with rows that can be read"
    );
}

#[test]
fn the_start_date_comes_from_the_header_or_the_first_gps_fix() {
    #[derive(ULog)]
    struct VehicleGpsPosition {
        timestamp: u64,
        time_utc_usec: u64,
    }
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let gps = w.topic::<VehicleGpsPosition>(0).unwrap();
    // No fix yet, a damaged row (a date in the year 586524), then a fix 3 s after boot:
    // the log (which started at 0) began 3 s earlier.
    for (timestamp, time_utc_usec) in [(1_000_000, 0), (2_000_000, u64::MAX)] {
        w.write(
            &gps,
            &VehicleGpsPosition {
                timestamp,
                time_utc_usec,
            },
        )
        .unwrap();
    }
    let utc = 1_710_773_350_000_000;
    w.write(
        &gps,
        &VehicleGpsPosition {
            timestamp: 3_000_000,
            time_utc_usec: utc,
        },
    )
    .unwrap();
    let bytes = w.into_inner();
    let log = crate::Log::from_vec(bytes.clone()).unwrap();
    let identity = LogIdentity::of_log(&log, "g.ulg");
    assert_eq!(
        identity.start_utc.as_deref(),
        Some("2024-03-18 14:49:07.000000 UTC")
    );
    let root = temp("gps");
    let conv = Converter::new(&root, ParquetOptions::default())
        .convert_reader(&bytes[..], "g.ulg")
        .unwrap();
    let (_, kv, _) = read(&conv.files[0].path);
    assert_eq!(kv["ulog.start_utc"], "2024-03-18 14:49:07.000000 UTC");
    // metadata.json gives the same date twice: the log's identity and its facts (which
    // gave none from a header without a date), and so does a whole-file log's facts.
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&conv.metadata).unwrap()).unwrap();
    assert_eq!(meta["log"]["start_utc"], "2024-03-18 14:49:07.000000 UTC");
    assert_eq!(meta["start_utc"], "2024-03-18 14:49:07.000000 UTC");
    assert_eq!(
        crate::document::LogFacts::of_log(&log).start_utc.as_deref(),
        Some("2024-03-18 14:49:07.000000 UTC")
    );
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn the_start_date_is_the_first_fix_in_the_file_whatever_the_gps_topic() {
    #[derive(ULog)]
    struct SensorGps {
        timestamp: u64,
        time_utc_usec: u64,
    }
    #[derive(ULog)]
    struct VehicleGpsPosition {
        timestamp: u64,
        time_utc_usec: u64,
    }
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    // sensor_gps is subscribed first, but vehicle_gps_position has the first fix.
    let sensor = w.topic::<SensorGps>(0).unwrap();
    let vehicle = w.topic::<VehicleGpsPosition>(0).unwrap();
    let utc = 1_710_773_350_000_000;
    let sensor_row = |timestamp, time_utc_usec| SensorGps {
        timestamp,
        time_utc_usec,
    };
    w.write(&sensor, &sensor_row(1_000_000, 0)).unwrap();
    w.write(
        &vehicle,
        &VehicleGpsPosition {
            timestamp: 2_000_000,
            time_utc_usec: utc,
        },
    )
    .unwrap();
    // A later fix that disagrees by 7 s: not the one taken.
    w.write(&sensor, &sensor_row(3_000_000, utc + 8_000_000))
        .unwrap();
    let bytes = w.into_inner();
    let expected = "2024-03-18 14:49:08.000000 UTC";
    let log = crate::Log::from_vec(bytes.clone()).unwrap();
    assert_eq!(
        LogIdentity::of_log(&log, "g.ulg").start_utc.as_deref(),
        Some(expected)
    );
    assert_eq!(
        crate::document::LogFacts::of_log(&log).start_utc.as_deref(),
        Some(expected)
    );
    assert_eq!(log.start_utc().unwrap().to_string(), expected);
    let root = temp("gps_order");
    let conv = Converter::new(&root, ParquetOptions::default())
        .convert_reader(&bytes[..], "g.ulg")
        .unwrap();
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&conv.metadata).unwrap()).unwrap();
    assert_eq!(meta["log"]["start_utc"], expected);
    assert_eq!(meta["start_utc"], expected);
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn a_failed_conversion_leaves_no_file_behind() {
    let bytes = log_bytes(5000);
    let root = temp("fail");
    // The second table's file cannot be made (a folder is in its place), after the first
    // table has written row groups: nothing of the log may stay.
    std::fs::create_dir_all(root.join("f/battery_1.parquet.partial")).unwrap();
    let options = ParquetOptions {
        buffer_bytes: 4 << 10,
        batch_bytes: 1 << 10,
        ..ParquetOptions::default()
    };
    let err = Converter::new(&root, options)
        .convert_reader(&bytes[..], "f.ulg")
        .unwrap_err();
    assert!(
        err.to_string()
            .contains("battery_1.parquet: topic `battery` #1"),
        "{err}"
    );
    let mut left: Vec<String> = std::fs::read_dir(root.join("f"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(
        left,
        ["battery_1.parquet.partial"],
        "only the folder in the way is left"
    );
    // Not a log: nothing made at all.
    let not_ulog = Converter::new(&root, ParquetOptions::default())
        .convert_reader(&b"not a log at all"[..], "g.ulg")
        .unwrap_err();
    assert!(
        not_ulog.to_string().starts_with("g.ulg: not a ULog file"),
        "{not_ulog}"
    );
    assert!(!root.join("g").exists());
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn no_name_from_a_log_writes_outside_the_output_folder() {
    use crate::read::{FileHeader, FlagBits, Message};
    let mut bytes = FileHeader {
        version: 1,
        start_timestamp: 0,
    }
    .to_bytes()
    .to_vec();
    let mut put = |m: Message<'_>| m.encode(&mut bytes).unwrap();
    put(Message::FlagBits(FlagBits::default()));
    // Names outside the format grammar, as odd logs have them: kept, and made safe.
    put(Message::Format(
        b"../../escape:uint64_t timestamp;uint8_t x;",
    ));
    put(Message::Format(b"..:uint64_t timestamp;uint8_t x;"));
    put(Message::Subscribe {
        multi_id: 0,
        msg_id: 0,
        name: b"../../escape",
    });
    put(Message::Subscribe {
        multi_id: 0,
        msg_id: 1,
        name: b"..",
    });
    put(Message::Data {
        msg_id: 0,
        data: &[1, 0, 0, 0, 0, 0, 0, 0, 9],
    });
    put(Message::Data {
        msg_id: 1,
        data: &[2, 0, 0, 0, 0, 0, 0, 0, 8],
    });
    // A name whose file name is shortened to the longest one file systems take: its
    // `.partial` name too (it was not, and the whole log failed).
    let long = "l".repeat(250);
    put(Message::Format(
        format!("{long}:uint64_t timestamp;uint8_t x;").as_bytes(),
    ));
    put(Message::Subscribe {
        multi_id: 0,
        msg_id: 2,
        name: long.as_bytes(),
    });
    put(Message::Data {
        msg_id: 2,
        data: &[3, 0, 0, 0, 0, 0, 0, 0, 7],
    });
    for layout in [Layout::PerLog, Layout::Hive] {
        let root = temp("names");
        let options = ParquetOptions {
            layout,
            ..ParquetOptions::default()
        };
        let conv = Converter::new(root.join("out"), options)
            .convert_reader(&bytes[..], "../x.ulg")
            .unwrap();
        assert_eq!(conv.files.len(), 3);
        for f in &conv.files {
            assert!(f.path.starts_with(root.join("out")), "{}", f.path.display());
            assert!(f.path.file_name().unwrap().len() <= crate::file_names::MAX_FILE_NAME);
            let rel = f.path.strip_prefix(root.join("out")).unwrap();
            assert!(
                rel.components()
                    .all(|c| matches!(c, std::path::Component::Normal(_))),
                "{}",
                rel.display()
            );
            assert_eq!(read(&f.path).1["ulog.topic"], f.topic);
        }
        assert!(conv.metadata.starts_with(root.join("out")));
        assert_eq!(
            std::fs::read_dir(&root).unwrap().count(),
            1,
            "only `out` was made"
        );
        std::fs::remove_dir_all(&root).unwrap();
    }
}

/// Rows of `battery` #0 in a converted file, and the log digest it says it comes from.
fn battery_rows(path: &Path) -> (usize, String) {
    let (batches, kv, _) = read(path);
    (
        batches.iter().map(RecordBatch::num_rows).sum(),
        kv["ulog.sha256"].clone(),
    )
}

#[test]
fn a_conversion_never_replaces_another_logs_files() {
    for layout in [Layout::PerLog, Layout::Hive] {
        let root = temp(&format!("same-stem-{layout:?}"));
        let (a, b, c) = (root.join("a"), root.join("b"), root.join("c"));
        for (dir, rows) in [(&a, 10), (&b, 11), (&c, 10)] {
            std::fs::create_dir_all(dir).unwrap();
            std::fs::write(dir.join("test.ulg"), log_bytes(rows)).unwrap();
        }
        let digest = |p: &Path| {
            let d = sha2::Sha256::digest(std::fs::read(p).unwrap());
            d.iter().map(|b| format!("{b:02x}")).collect::<String>()
        };
        let (sha_a, sha_b) = (digest(&a.join("test.ulg")), digest(&b.join("test.ulg")));
        assert_eq!(sha_a, digest(&c.join("test.ulg")), "c is a copy of a");
        let out = root.join("out");
        // Each conversion its own converter, as separate runs of `ulog parquet` are.
        let convert = |log: &Path| {
            let options = ParquetOptions {
                layout,
                ..ParquetOptions::default()
            };
            Converter::new(&out, options).convert_file(log).unwrap()
        };
        let first = convert(&a.join("test.ulg"));
        let second = convert(&b.join("test.ulg"));
        assert_eq!(first.notes, Vec::<String>::new());
        assert_ne!(first.log_dir, second.log_dir, "{layout:?}");
        assert!(second.log_dir.ends_with("test~2"), "{}", second.log_dir);
        assert_eq!(second.notes.len(), 1, "{:?}", second.notes);
        assert!(
            second.notes[0].contains("holds another log") && second.notes[0].contains("test~2"),
            "{}",
            second.notes[0]
        );
        let battery = |c: &Conversion| {
            let f = c
                .files
                .iter()
                .find(|f| f.topic == "battery" && f.multi_id == 0)
                .unwrap();
            battery_rows(&f.path)
        };
        assert_eq!(battery(&first), (10, sha_a.clone()), "a's files kept");
        assert_eq!(battery(&second), (11, sha_b.clone()));
        // The same log again (and an identical copy of it) replaces its own folder,
        // whichever name it has.
        for again in [a.join("test.ulg"), c.join("test.ulg"), b.join("test.ulg")] {
            let conv = convert(&again);
            let expected = if again.starts_with(&b) {
                &second.log_dir
            } else {
                &first.log_dir
            };
            assert_eq!(&conv.log_dir, expected, "{}", again.display());
            assert_eq!(conv.notes.is_empty(), !again.starts_with(&b));
        }
        assert_eq!(battery(&first), (10, sha_a.clone()));
        assert_eq!(battery(&second), (11, sha_b.clone()));
        // A folder whose metadata.json does not say which log it holds is never replaced.
        let foreign = layout.metadata_path(&out, &layout.log_dir("other", 1));
        std::fs::create_dir_all(foreign.parent().unwrap()).unwrap();
        std::fs::write(&foreign, b"{}").unwrap();
        std::fs::write(a.join("other.ulg"), log_bytes(3)).unwrap();
        let other = convert(&a.join("other.ulg"));
        assert!(other.log_dir.ends_with("other~2"), "{}", other.log_dir);
        assert_eq!(std::fs::read(&foreign).unwrap(), b"{}");
        std::fs::remove_dir_all(&root).unwrap();
    }
}

#[test]
fn logs_of_one_stem_in_one_run_take_folders_in_the_order_given() {
    let root = temp("one-run");
    let paths: Vec<PathBuf> = ["a", "b", "c"]
        .iter()
        .zip([4, 5, 4])
        .map(|(d, rows)| {
            let dir = root.join(d);
            std::fs::create_dir_all(&dir).unwrap();
            let p = dir.join("x.ulg");
            std::fs::write(&p, log_bytes(rows)).unwrap();
            p
        })
        .collect();
    let out = root.join("out");
    let converter = Converter::new(&out, ParquetOptions::default());
    for _ in 0..2 {
        let dirs: Vec<(String, usize)> = converter
            .convert_files(&paths, 3)
            .into_iter()
            .map(|r| {
                let c = r.unwrap();
                (c.log_dir, c.notes.len())
            })
            .collect();
        // c is a's twin: it replaces a's folder, as a conversion of a would.
        assert_eq!(
            dirs,
            [
                ("x".to_owned(), 0),
                ("x~2".to_owned(), 1),
                ("x".to_owned(), 0)
            ]
        );
    }
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn metadata_json_holds_the_flight_analysis_unless_left_out() {
    use crate::analysis::tests::{Faults, flight};
    let bytes = flight(Faults {
        motor: true,
        steps: true,
        ..Faults::default()
    });
    // Through text, as metadata.json is read (the same parsing of each number).
    let expected: serde_json::Value = serde_json::from_str(
        &serde_json::to_string(&crate::analysis::Analysis::of_log(
            &Log::from_slice(&bytes).unwrap(),
        ))
        .unwrap(),
    )
    .unwrap();
    for encoders in [Some(0), Some(2), None] {
        let root = temp(&format!("analysis-{encoders:?}"));
        let conv = Converter::new(
            &root,
            ParquetOptions {
                encoders,
                ..ParquetOptions::default()
            },
        )
        .convert_reader(&bytes[..], "flight.ulg")
        .unwrap();
        let doc: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&conv.metadata).unwrap()).unwrap();
        let mut got = doc["analysis"].clone();
        // The per-field means are summed in another order (columns, not rows): equal to
        // the last bits.
        let (want_fields, got_fields) = (
            expected["field_stats"].as_array().unwrap(),
            got["field_stats"].as_array().unwrap(),
        );
        assert_eq!(want_fields.len(), got_fields.len(), "{encoders:?}");
        for (w, g) in want_fields.iter().zip(got_fields) {
            for key in ["topic", "multi_id", "field", "min", "max", "count"] {
                assert_eq!(w[key], g[key], "{encoders:?}: {w}");
            }
            let (wm, gm) = (w["mean"].as_f64().unwrap(), g["mean"].as_f64().unwrap());
            assert!((wm - gm).abs() <= 1e-12 * wm.abs().max(1.0), "{w} vs {g}");
        }
        got["field_stats"] = expected["field_stats"].clone();
        assert_eq!(got, expected, "{encoders:?}: the analysis of the log");
        assert_eq!(got["diagnostics"][0]["id"], "motor_failure");
        std::fs::remove_dir_all(&root).unwrap();
    }
    let root = temp("no-analysis");
    let conv = Converter::new(
        &root,
        ParquetOptions {
            analysis: false,
            ..ParquetOptions::default()
        },
    )
    .convert_reader(&bytes[..], "flight.ulg")
    .unwrap();
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&conv.metadata).unwrap()).unwrap();
    assert!(doc.get("analysis").is_none(), "left out when asked");
    assert!(doc.get("files").is_some());
    std::fs::remove_dir_all(&root).unwrap();
}

/// An output shared with the test, to read back what a table wrote.
#[derive(Clone, Default)]
struct SharedOutput(std::sync::Arc<std::sync::Mutex<Vec<u8>>>);

impl std::io::Write for SharedOutput {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl encode::Output for SharedOutput {}

/// A reading thread that gives batches faster than the workers encode them encodes some
/// itself rather than wait. With no worker started at all, it would wait forever; it
/// encodes every batch, in order, and the table holds them all.
#[test]
fn the_reading_thread_encodes_batches_itself_when_the_workers_fall_behind() {
    use encode::{Encoder, TableWork};
    let log = Log::from_vec(log_bytes(1)).unwrap();
    let sub = &log.subscriptions()[0];
    assert_eq!(sub.name, "battery");
    let spec = std::sync::Arc::new(
        ColumnSpec::of(log.metadata().schema(), sub.format().unwrap()).unwrap(),
    );
    let identity = LogIdentity::of_log(&log, "f.ulg");
    let out = SharedOutput::default();
    let table = Table::new(&spec, "battery", 0, out.clone(), &ParquetOptions::default());
    // One worker planned, none started.
    let encoder = std::sync::Arc::new(Encoder::<SharedOutput>::pool(64 << 10, 1));
    let t = encoder.add(TableWork { table, stats: None });
    // 200,000 rows of 18 bytes: 3.6 MB, past the 1 MiB that may wait for a worker.
    let rows = 200_000u64;
    let (sent, done) = std::sync::mpsc::channel();
    let reader = {
        let (encoder, spec) = (encoder.clone(), spec.clone());
        std::thread::spawn(move || {
            for first in (0..rows).step_by(1000) {
                let mut batch = crate::columns::RowBatch::with_capacity(spec.clone(), 1000);
                for t in first..first + 1000 {
                    let mut row = t.to_le_bytes().to_vec();
                    row.extend_from_slice(&(t as f32 / 8.0).to_le_bytes());
                    row.extend_from_slice(&[1, 0, 2, 0]);
                    row.extend_from_slice(&(t as u16).to_le_bytes());
                    assert!(batch.push(&row, t));
                }
                encoder.push(t, batch).unwrap();
            }
            encoder.finish();
            // The batches still waiting, encoded on this thread too.
            encoder.work();
            sent.send(()).unwrap();
        })
    };
    assert!(
        done.recv_timeout(std::time::Duration::from_secs(30))
            .is_ok(),
        "the reading thread waited for a worker that never came"
    );
    reader.join().unwrap();
    let mut tables = encoder.take_tables().map_err(|(_, e)| e).unwrap();
    let work = tables.pop().unwrap();
    let (written, counts) = work.table.close(&identity, true).unwrap();
    assert!(written);
    assert_eq!(counts.rows, rows as usize);
    let bytes = bytes::Bytes::from(out.0.lock().unwrap().clone());
    let reader = ParquetRecordBatchReaderBuilder::try_new(bytes).unwrap();
    assert!(
        reader.metadata().num_row_groups() > 1,
        "the budget makes several"
    );
    let batches: Vec<RecordBatch> = reader.build().unwrap().map(Result::unwrap).collect();
    let times: Vec<u64> = column::<UInt64Array>(&batches, "timestamp")
        .into_iter()
        .flat_map(|a| a.values().iter().copied())
        .collect();
    let volts: Vec<f32> = column::<Float32Array>(&batches, "voltage_v")
        .into_iter()
        .flat_map(|a| a.values().iter().copied())
        .collect();
    assert_eq!(times, (0..rows).collect::<Vec<_>>(), "every row, in order");
    assert!(volts.iter().zip(0..).all(|(&v, t)| v == t as f32 / 8.0));
}

/// The reading thread and a worker encoding side by side (a small budget keeps the worker
/// writing row groups, so batches pile up past the in-flight bound and the reader encodes
/// some of them itself): each table still holds its rows, in order.
#[test]
fn a_reader_and_a_worker_encoding_side_by_side_keep_each_tables_rows_in_order() {
    let rows = 150_000u64;
    let bytes = log_bytes(rows);
    let root = temp("side-by-side");
    let options = ParquetOptions {
        buffer_bytes: 16 << 10,
        batch_bytes: 1 << 10,
        encoders: Some(1),
        ..ParquetOptions::default()
    };
    let conv = Converter::new(&root, options)
        .convert_reader(&bytes[..], "f.ulg")
        .unwrap();
    let files = battery_values(&root, &conv);
    assert_eq!(files.len(), 2);
    for (m, (file, v, c, groups)) in files.into_iter().enumerate() {
        let (ev, ec): (Vec<f32>, Vec<u16>) = (0..rows)
            .filter(|t| m == 0 || t % 2 == 0)
            .map(|t| (t as f32 / 8.0, t as u16))
            .unzip();
        assert!(v == ev && c == ec, "{file}: rows missing or out of order");
        assert!(groups > 5, "{file}: {groups} row groups");
    }
    std::fs::remove_dir_all(&root).unwrap();
}

/// Where row groups fall depends on the log and the options only: converted inline, with
/// one worker or with three (the reader then encoding some batches itself), and twice
/// with each, a log gives the same files byte for byte, each of many row groups.
#[test]
fn the_same_log_gives_the_same_files_on_any_number_of_threads() {
    let bytes = log_bytes(60_000);
    let root = temp("same-files");
    let mut outputs = Vec::new();
    for (run, encoders) in [0, 1, 3, 0, 1, 3].into_iter().enumerate() {
        let options = ParquetOptions {
            buffer_bytes: 16 << 10,
            batch_bytes: 1 << 10,
            encoders: Some(encoders),
            ..ParquetOptions::default()
        };
        let conv = Converter::new(root.join(run.to_string()), options)
            .convert_reader(&bytes[..], "f.ulg")
            .unwrap();
        let files: Vec<(String, Vec<u8>)> = conv
            .files
            .iter()
            .map(|f| {
                let name = f.path.file_name().unwrap().to_string_lossy().into_owned();
                (name, std::fs::read(&f.path).unwrap())
            })
            .collect();
        assert_eq!(files.len(), 3, "two battery instances and a gyro");
        for f in conv.files.iter().filter(|f| f.topic == "battery") {
            let (.., groups) = read(&f.path);
            assert!(groups > 5, "{}: {groups} row groups", f.path.display());
        }
        outputs.push((encoders, files));
    }
    let (first, expected) = &outputs[0];
    for (encoders, files) in &outputs[1..] {
        for ((name, want), (_, got)) in expected.iter().zip(files) {
            assert!(
                want == got,
                "{name}: {encoders} encoders wrote other bytes than {first}"
            );
        }
    }
    std::fs::remove_dir_all(&root).unwrap();
}

/// A log of awkward floats, `rows` rows: each `float` column more than a 1 MiB page at
/// 300,000 rows (one row group), their pages' bounds rising, falling, both infinities, NaN
/// of either sign and payload (pages of nothing else), and zeros of one sign or both; and a
/// `double` column of the same mix.
fn awkward_floats_log(rows: u32) -> Vec<u8> {
    #[derive(ULog)]
    struct Awkward {
        timestamp: u64,
        rising: f32,
        falling: f32,
        mixed: f32,
        nan_then_numbers: f32,
        zeros: f32,
        positive_zero: f32,
        wide: f64,
    }
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let topic = w.topic::<Awkward>(0).unwrap();
    for i in 0..rows {
        let f = i as f32;
        let mixed = match i % 7 {
            0 => f32::NAN,
            1 => -0.0,
            2 => 0.0,
            3 => f32::INFINITY,
            4 => f32::NEG_INFINITY,
            5 => f,
            _ => -f * 1e-3,
        };
        let nan = f32::from_bits(0x7fc0_0000 | (i & 0xff) | ((i % 3 == 0) as u32) << 31);
        let row = Awkward {
            timestamp: u64::from(i),
            rising: f * 0.5 - 1000.0,
            falling: -f,
            mixed,
            nan_then_numbers: if i < rows * 2 / 3 { nan } else { f },
            zeros: if i % 2 == 0 { 0.0 } else { -0.0 },
            positive_zero: 0.0,
            wide: if i % 5 == 0 {
                f64::NAN
            } else {
                f64::from(mixed) * 1e300
            },
        };
        w.write(&topic, &row).unwrap();
    }
    w.into_inner()
}

/// A float column's bounds as the type-defined order has them: NaN left out (none if
/// nothing else), a zero minimum -0.0 and a zero maximum +0.0; as bits, and the NaN count.
fn type_defined_bounds(values: &[f64]) -> (Option<(u64, u64)>, u64) {
    let numbers: Vec<f64> = values.iter().copied().filter(|v| !v.is_nan()).collect();
    let nans = (values.len() - numbers.len()) as u64;
    let bounds = numbers.iter().copied().reduce(f64::min).map(|lo| {
        let hi = numbers.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let lo = if lo == 0.0 { -0.0 } else { lo };
        let hi = if hi == 0.0 { 0.0 } else { hi };
        (lo.to_bits(), hi.to_bits())
    });
    (bounds, nans)
}

/// `FLOAT` and `DOUBLE` columns' statistics are in the type-defined order, which every
/// reader knows (pyarrow ignores parquet-rs 60's IEEE 754 total order), the footer says
/// so, and they are those of the values: of each chunk, and of each page in the column
/// index (none for a chunk with a page of nothing but NaN), with and without page
/// statistics.
#[test]
fn float_statistics_are_in_the_type_defined_order_and_those_of_the_values() {
    use parquet::arrow::arrow_reader::ArrowReaderOptions;
    use parquet::basic::{ColumnOrder, SortOrder, Type as Physical};
    use parquet::file::page_index::column_index::ColumnIndexMetaData;
    use parquet::file::statistics::Statistics;

    let bytes = awkward_floats_log(300_000);
    for page_statistics in [true, false] {
        let root = temp(&format!("float-stats-{page_statistics}"));
        let options = ParquetOptions {
            page_statistics,
            ..ParquetOptions::default()
        };
        let conv = Converter::new(&root, options)
            .convert_reader(&bytes[..], "f.ulg")
            .unwrap();
        let path = &conv.files[0].path;
        let file = std::fs::File::open(path).unwrap();
        let builder = ParquetRecordBatchReaderBuilder::try_new_with_options(
            file,
            ArrowReaderOptions::new()
                .with_page_index_policy(parquet::file::metadata::PageIndexPolicy::Optional),
        )
        .unwrap();
        let meta = builder.metadata().clone();
        let batches: Vec<RecordBatch> = builder.build().unwrap().map(Result::unwrap).collect();
        let schema = meta.file_metadata().schema_descr();
        let orders = meta.file_metadata().column_orders().unwrap();
        let mut checked = 0;
        for (c, order) in orders.iter().enumerate() {
            let physical = schema.column(c).physical_type();
            if !matches!(physical, Physical::FLOAT | Physical::DOUBLE) {
                continue;
            }
            assert_eq!(*order, ColumnOrder::TYPE_DEFINED_ORDER(SortOrder::SIGNED));
            let name = schema.column(c).name().to_owned();
            let values: Vec<f64> = batches
                .iter()
                .flat_map(|b| {
                    let col = b.column_by_name(&name).unwrap();
                    arrow_array::cast::AsArray::as_primitive_opt::<arrow_array::types::Float32Type>(
                        col,
                    )
                    .map(|a| a.values().iter().map(|&v| f64::from(v)).collect::<Vec<_>>())
                    .unwrap_or_else(|| {
                        arrow_array::cast::AsArray::as_primitive::<arrow_array::types::Float64Type>(
                            col,
                        )
                        .values()
                        .to_vec()
                    })
                })
                .collect();
            assert_eq!(meta.num_row_groups(), 1, "one row group");
            let chunk = meta.row_group(0).column(c);
            let (want, nans) = type_defined_bounds(&values);
            let got = match chunk.statistics().unwrap() {
                Statistics::Float(s) => (
                    s.min_opt()
                        .zip(s.max_opt())
                        .map(|(a, b)| (f64::from(*a).to_bits(), f64::from(*b).to_bits())),
                    s.nan_count_opt(),
                ),
                Statistics::Double(s) => (
                    s.min_opt()
                        .zip(s.max_opt())
                        .map(|(a, b)| (a.to_bits(), b.to_bits())),
                    s.nan_count_opt(),
                ),
                other => panic!("{name}: {other:?}"),
            };
            assert_eq!(got, (want, Some(nans)), "{name}: the chunk's statistics");
            // The column index: each page's bounds, over the rows the offset index gives it.
            let page_index = meta.page_index_for_row_group(0);
            let index = page_index.column_index(c);
            let pages = page_index.offset_index(c).unwrap().page_locations();
            let starts: Vec<usize> = pages.iter().map(|p| p.first_row_index as usize).collect();
            let ranges: Vec<std::ops::Range<usize>> = starts
                .iter()
                .zip(starts.iter().skip(1).chain([&values.len()]))
                .map(|(&a, &b)| a..b)
                .collect();
            assert!(
                ranges.len() > 1 || name == "wide",
                "{name}: {} pages",
                ranges.len()
            );
            let expected: Vec<_> = ranges
                .iter()
                .map(|r| type_defined_bounds(&values[r.clone()]))
                .collect();
            let nan_page = expected.iter().any(|(b, _)| b.is_none());
            match index {
                Some(ColumnIndexMetaData::FLOAT(ix)) => {
                    assert!(page_statistics && !nan_page, "{name}: an index");
                    for (k, (b, n)) in expected.iter().enumerate() {
                        let (lo, hi) = b.unwrap();
                        assert_eq!(
                            f64::from(*ix.min_value(k).unwrap()).to_bits(),
                            lo,
                            "{name} page {k}"
                        );
                        assert_eq!(
                            f64::from(*ix.max_value(k).unwrap()).to_bits(),
                            hi,
                            "{name} page {k}"
                        );
                        assert_eq!(ix.nan_count(k), Some(*n as i64), "{name} page {k}");
                    }
                }
                Some(ColumnIndexMetaData::DOUBLE(ix)) => {
                    assert!(page_statistics && !nan_page, "{name}: an index");
                    for (k, (b, n)) in expected.iter().enumerate() {
                        let (lo, hi) = b.unwrap();
                        assert_eq!(ix.min_value(k).unwrap().to_bits(), lo, "{name} page {k}");
                        assert_eq!(ix.max_value(k).unwrap().to_bits(), hi, "{name} page {k}");
                        assert_eq!(ix.nan_count(k), Some(*n as i64), "{name} page {k}");
                    }
                }
                None => {
                    assert!(!page_statistics || nan_page, "{name}: no index")
                }
                Some(other) => panic!("{name}: {other:?}"),
            }
            checked += 1;
        }
        assert_eq!(checked, 7, "every float column");
        std::fs::remove_dir_all(&root).unwrap();
    }
}

/// A log file's SHA-256 is the same however it is taken: as the file is read (no encoder
/// thread), by the encoder's thread from copies of what was read (one), or on a thread of
/// its own (two encoders or more).
#[test]
fn a_files_sha256_is_the_same_hashed_as_read_or_on_a_thread_of_its_own() {
    let bytes = log_bytes(3000);
    let dir = temp("sha-file");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("flight.ulg");
    std::fs::write(&path, &bytes).unwrap();
    let sha: String = sha2::Sha256::digest(&bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    for encoders in [Some(0), Some(1), Some(2), Some(3)] {
        let root = dir.join(format!("out-{encoders:?}"));
        let conv = Converter::new(
            &root,
            ParquetOptions {
                encoders,
                ..ParquetOptions::default()
            },
        )
        .convert_file(&path)
        .unwrap();
        assert_eq!(conv.bytes, bytes.len() as u64, "{encoders:?}");
        let meta: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&conv.metadata).unwrap()).unwrap();
        assert_eq!(meta["log"]["sha256"], sha.as_str(), "{encoders:?}");
        let (_, kv, _) = read(&conv.files[0].path);
        assert_eq!(kv["ulog.sha256"], sha, "{encoders:?}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_output_folder_that_is_a_file_is_an_error_not_an_endless_search() {
    // Every log folder name under a file would fail alike ("not a directory"): the
    // conversion must stop with an error, not try `f~2`, `f~3`... for ever.
    let root = temp("file-root");
    std::fs::create_dir_all(&root).unwrap();
    let file = root.join("out.ulg");
    std::fs::write(&file, b"a file, not a folder").unwrap();
    let bytes = log_bytes(100);
    for out in [file.clone(), file.join("sub")] {
        let (tx, rx) = std::sync::mpsc::channel();
        let (at, log) = (out.clone(), bytes.clone());
        std::thread::spawn(move || {
            let converted = Converter::new(&at, ParquetOptions::default())
                .convert_reader(&log[..], "f.ulg")
                .map(|_| ());
            let _ = tx.send(converted);
        });
        let result = rx
            .recv_timeout(std::time::Duration::from_secs(60))
            .unwrap_or_else(|_| panic!("{}: the conversion did not end", out.display()));
        // Refused before the log is read, naming the output folder.
        let err = result.unwrap_err();
        assert!(
            matches!(&err, ConvertError::Io { path, .. } if *path == out),
            "{err}"
        );
        let why = if out == file {
            "a file; the output is a folder (give a folder's path)".to_owned()
        } else {
            format!("`{}` is a file, not a folder", file.display())
        };
        assert_eq!(err.to_string(), format!("{}: {why}", out.display()));
    }
    assert_eq!(std::fs::read(&file).unwrap(), b"a file, not a folder");
    std::fs::remove_dir_all(&root).unwrap();
}

/// The column chunks of `ours` say what parquet-rs's own writer says in `theirs` of the
/// same values in the same pages (one row group, pages of 1,000 values, 2,500 a column):
/// the encodings, the page encoding statistics, the values counted, the statistics, the
/// offset index's rows and the column index; and their sizes and offsets are those of
/// their pages. Gives `ours`' values, read by parquet-rs's Arrow reader.
fn assert_chunks_agree(theirs: Vec<u8>, ours: Vec<u8>, columns: usize) -> Vec<RecordBatch> {
    use parquet::file::reader::{FileReader, SerializedFileReader};
    use parquet::file::serialized_reader::ReadOptionsBuilder;
    let open = |bytes: &Vec<u8>| {
        SerializedFileReader::new_with_options(
            bytes::Bytes::from(bytes.clone()),
            ReadOptionsBuilder::new().with_page_index().build(),
        )
        .unwrap()
    };
    let (t_file, o_file) = (open(&theirs), open(&ours));
    let (tm, om) = (t_file.metadata(), o_file.metadata());
    for c in 0..columns {
        let (t, o) = (tm.row_group(0).column(c), om.row_group(0).column(c));
        assert_eq!(
            o.encodings().collect::<Vec<_>>(),
            t.encodings().collect::<Vec<_>>(),
            "column {c}"
        );
        assert_eq!(
            o.page_encoding_stats(),
            t.page_encoding_stats(),
            "column {c}"
        );
        assert_eq!(o.num_values(), t.num_values(), "column {c}");
        assert_eq!(o.compression(), t.compression(), "column {c}");
        assert_eq!(o.statistics(), t.statistics(), "column {c}");
        assert_eq!(o.dictionary_page_offset(), None);
        let (tp, op) = (
            tm.page_index_for_row_group(0),
            om.page_index_for_row_group(0),
        );
        let (ti, oi) = (tp.offset_index(c).unwrap(), op.offset_index(c).unwrap());
        let rows = |ix: &parquet::file::page_index::offset_index::OffsetIndexMetaData| {
            ix.page_locations()
                .iter()
                .map(|p| p.first_row_index)
                .collect::<Vec<_>>()
        };
        assert_eq!(rows(oi), vec![0, 1000, 2000], "column {c}");
        assert_eq!(rows(oi), rows(ti), "column {c}");
        let pages = oi.page_locations();
        assert_eq!(o.data_page_offset(), pages[0].offset, "column {c}");
        assert_eq!(
            o.compressed_size(),
            pages
                .iter()
                .map(|p| i64::from(p.compressed_page_size))
                .sum::<i64>(),
            "column {c}"
        );
        assert!(op.column_index(c).is_some(), "column {c}: a column index");
        assert_eq!(op.column_index(c), tp.column_index(c), "column {c}");
    }
    ParquetRecordBatchReaderBuilder::try_new(bytes::Bytes::from(ours))
        .unwrap()
        .build()
        .unwrap()
        .map(Result::unwrap)
        .collect()
}

/// parquet-rs's writer properties for [`assert_chunks_agree`]: pages of 1,000 values, ZSTD.
fn thousand_value_pages(
    encoding: Option<parquet::basic::Encoding>,
) -> std::sync::Arc<parquet::file::properties::WriterProperties> {
    use parquet::basic::Compression;
    use parquet::file::properties::EnabledStatistics;
    let mut b = parquet::file::properties::WriterProperties::builder()
        .set_compression(Compression::ZSTD(
            parquet::basic::ZstdLevel::try_new(1).unwrap(),
        ))
        .set_dictionary_enabled(false)
        .set_statistics_enabled(EnabledStatistics::Page)
        .set_data_page_row_count_limit(1000)
        .set_write_batch_size(1000);
    if let Some(e) = encoding {
        b = b.set_encoding(e);
    }
    std::sync::Arc::new(b.build())
}

/// Batches of `v` cut where pages are not (at 700, 701 and 1,700 of 2,500).
fn uneven_batches<T: Clone>(
    v: &[T],
    make: impl Fn(Vec<T>) -> crate::columns::ColumnValues,
) -> Vec<crate::columns::ColumnValues> {
    [0, 700, 701, 1700, 2500]
        .windows(2)
        .map(|c| make(v[c[0]..c[1]].to_vec()))
        .collect()
}

/// A file of one row group written by parquet-rs's column writers, given a page's values
/// at a time (`write(column index, writer)` writes each column).
fn written_by_parquet_rs(
    schema: &std::sync::Arc<parquet::schema::types::Type>,
    props: std::sync::Arc<parquet::file::properties::WriterProperties>,
    columns: usize,
    write: impl Fn(usize, &mut parquet::file::writer::SerializedColumnWriter<'_>),
) -> Vec<u8> {
    let mut out = Vec::new();
    let mut w =
        parquet::file::writer::SerializedFileWriter::new(&mut out, schema.clone(), props).unwrap();
    let mut rg = w.next_row_group().unwrap();
    for c in 0..columns {
        let mut col = rg.next_column().unwrap().unwrap();
        write(c, &mut col);
        col.close().unwrap();
    }
    rg.close().unwrap();
    w.close().unwrap();
    out
}

/// A file of one row group whose chunks `write` writes here.
fn written_here(
    schema: &std::sync::Arc<parquet::schema::types::Type>,
    props: std::sync::Arc<parquet::file::properties::WriterProperties>,
    columns: usize,
    write: impl Fn(
        usize,
        &mut parquet::file::writer::SerializedRowGroupWriter<'_, &mut Vec<u8>>,
        parquet::schema::types::ColumnDescPtr,
    ),
) -> Vec<u8> {
    let mut out = Vec::new();
    let mut w =
        parquet::file::writer::SerializedFileWriter::new(&mut out, schema.clone(), props).unwrap();
    let mut rg = w.next_row_group().unwrap();
    let descrs = parquet::schema::types::SchemaDescriptor::new(schema.clone());
    for c in 0..columns {
        write(c, &mut rg, descrs.column(c));
    }
    rg.close().unwrap();
    w.close().unwrap();
    out
}

/// A `FLOAT` or `DOUBLE` column chunk written by [`chunk::write_float_chunk`] says what
/// parquet-rs's own column writer says of the same values in pages of the same size
/// ([`assert_chunks_agree`]), and the values read back are those written, split into
/// batches anyhow.
#[test]
fn float_chunks_say_what_parquet_rs_says_of_the_same_pages() {
    use parquet::data_type::{DoubleType, FloatType};
    use parquet::schema::parser::parse_message_type;

    let schema = std::sync::Arc::new(
        parse_message_type("message m { required float f; required double d; }").unwrap(),
    );
    // No NaN and no zero: there the two writers' orders differ (see the float statistics
    // test); rising then falling pages.
    let f: Vec<f32> = (0..2500)
        .map(|i| {
            if i < 1800 {
                i as f32 + 0.5
            } else {
                -(i as f32)
            }
        })
        .collect();
    let d: Vec<f64> = f.iter().map(|&v| f64::from(v) * 1e100).collect();
    let theirs = written_by_parquet_rs(&schema, thousand_value_pages(None), 2, |c, col| {
        for k in (0..2500).step_by(1000) {
            let end = (k + 1000).min(2500);
            if c == 0 {
                col.typed::<FloatType>()
                    .write_batch(&f[k..end], None, None)
                    .unwrap();
            } else {
                col.typed::<DoubleType>()
                    .write_batch(&d[k..end], None, None)
                    .unwrap();
            }
        }
    });
    let batches = [
        uneven_batches(&f, crate::columns::ColumnValues::Float),
        uneven_batches(&d, crate::columns::ColumnValues::Double),
    ];
    let ours = written_here(&schema, thousand_value_pages(None), 2, |c, rg, descr| {
        chunk::write_float_chunk(rg, descr, 1000, true, 1, batches[c].iter()).unwrap();
    });
    let read = assert_chunks_agree(theirs, ours, 2);
    let got_f: Vec<f32> = read
        .iter()
        .flat_map(|b| {
            arrow_array::cast::AsArray::as_primitive::<arrow_array::types::Float32Type>(b.column(0))
                .values()
                .to_vec()
        })
        .collect();
    let got_d: Vec<f64> = read
        .iter()
        .flat_map(|b| {
            arrow_array::cast::AsArray::as_primitive::<arrow_array::types::Float64Type>(b.column(1))
                .values()
                .to_vec()
        })
        .collect();
    assert_eq!((got_f, got_d), (f, d));
}

/// An `INT64` column chunk written by [`chunk::write_int64_chunk`] (DELTA_BINARY_PACKED)
/// says what parquet-rs's own column writer says of the same values in pages of the same
/// size with the same encoding ([`assert_chunks_agree`]: unsigned bounds for a `uint64_t`
/// column), and every bit pattern comes back: the extremes next to each other (deltas that
/// wrap), runs of one value (deltas of no width), a last block and miniblock cut short.
#[test]
fn int64_chunks_say_what_parquet_rs_says_of_the_same_pages() {
    use parquet::basic::Encoding;
    use parquet::data_type::Int64Type;
    use parquet::schema::parser::parse_message_type;

    let schema = std::sync::Arc::new(
        parse_message_type(
            "message m { required int64 s; required int64 u (INTEGER(64, false)); }",
        )
        .unwrap(),
    );
    let odd = [i64::MIN, i64::MAX, 0, -1, 1, i64::MIN + 1, 5];
    let s: Vec<i64> = (0..2500i64)
        .map(|i| match i {
            // Rising pages, then extremes, then a run of one value.
            0..1000 => i * 1000 + (i % 7) * 13,
            1000..2000 => odd[(i % 7) as usize].wrapping_add(i),
            _ => 42,
        })
        .collect();
    let u: Vec<u64> = s.iter().map(|&v| v as u64).collect();
    let as_i64: Vec<i64> = u.iter().map(|&v| v as i64).collect();
    let delta = || thousand_value_pages(Some(Encoding::DELTA_BINARY_PACKED));
    let theirs = written_by_parquet_rs(&schema, delta(), 2, |c, col| {
        let v = if c == 0 { &s } else { &as_i64 };
        for k in (0..2500).step_by(1000) {
            let end = (k + 1000).min(2500);
            col.typed::<Int64Type>()
                .write_batch(&v[k..end], None, None)
                .unwrap();
        }
    });
    let batches = [
        uneven_batches(&s, crate::columns::ColumnValues::Int64),
        uneven_batches(&u, crate::columns::ColumnValues::UInt64),
    ];
    let ours = written_here(&schema, delta(), 2, |c, rg, descr| {
        chunk::write_int64_chunk(rg, descr, 1000, true, 1, batches[c].iter()).unwrap();
    });
    let read = assert_chunks_agree(theirs, ours, 2);
    let column = |c: usize| -> Vec<i64> {
        read.iter()
            .flat_map(|b| {
                let col = b.column(c);
                arrow_array::cast::AsArray::as_primitive_opt::<arrow_array::types::Int64Type>(col)
                    .map(|a| a.values().to_vec())
                    .unwrap_or_else(|| {
                        arrow_array::cast::AsArray::as_primitive::<arrow_array::types::UInt64Type>(
                            col,
                        )
                        .values()
                        .iter()
                        .map(|&v| v as i64)
                        .collect()
                    })
            })
            .collect()
    };
    assert_eq!((column(0), column(1)), (s, as_i64));
}

/// `INT64` columns (64-bit integers, signed or not, and the timestamps) are
/// DELTA_BINARY_PACKED, and every bit pattern comes back: the extremes next to each other
/// (deltas that wrap), in several pages and row groups; their statistics in each one's
/// order (unsigned for `uint64_t`).
#[test]
fn sixty_four_bit_integers_of_any_bits_come_back_delta_encoded() {
    use arrow_array::Int64Array;
    use parquet::basic::Encoding;
    use parquet::file::statistics::Statistics;

    #[derive(ULog)]
    struct Wide {
        timestamp: u64,
        u: u64,
        i: i64,
    }
    let pattern_u = [0, u64::MAX, 1, u64::MAX - 1, 1 << 63, (1 << 63) - 1, 12_345];
    let pattern_i = [i64::MIN, i64::MAX, 0, -1, 1, i64::MIN + 1, -987_654_321];
    let rows = 300_000u64;
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let topic = w.topic::<Wide>(0).unwrap();
    let mut want = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..rows {
        let row = Wide {
            // Rising, with jumps of every size.
            timestamp: k * 1000 + (k % 7) * (k % 13),
            u: pattern_u[(k % 7) as usize].wrapping_add(k / 7),
            i: pattern_i[(k % 7) as usize].wrapping_add((k / 7) as i64),
        };
        want.0.push(row.timestamp);
        want.1.push(row.u);
        want.2.push(row.i);
        w.write(&topic, &row).unwrap();
    }
    let bytes = w.into_inner();
    let root = temp("int64-delta");
    let conv = Converter::new(
        &root,
        ParquetOptions {
            // Several row groups.
            buffer_bytes: 2 << 20,
            ..ParquetOptions::default()
        },
    )
    .convert_reader(&bytes[..], "wide.ulg")
    .unwrap();
    let path = &conv.files[0].path;
    let (batches, _, row_groups) = read(path);
    assert!(row_groups > 1, "{row_groups} row groups");
    let timestamps: Vec<u64> = column::<UInt64Array>(&batches, "timestamp")
        .iter()
        .flat_map(|a| a.values().to_vec())
        .collect();
    let us: Vec<u64> = column::<UInt64Array>(&batches, "u")
        .iter()
        .flat_map(|a| a.values().to_vec())
        .collect();
    let is: Vec<i64> = column::<Int64Array>(&batches, "i")
        .iter()
        .flat_map(|a| a.values().to_vec())
        .collect();
    assert_eq!((timestamps, us, is), want);
    let reader =
        parquet::file::reader::SerializedFileReader::new(std::fs::File::open(path).unwrap())
            .unwrap();
    let meta = parquet::file::reader::FileReader::metadata(&reader);
    let mut start = 0usize;
    for g in meta.row_groups() {
        let n = g.num_rows() as usize;
        for (c, name) in ["timestamp", "u", "i"].iter().enumerate() {
            let chunk = g.column(c);
            assert!(
                chunk
                    .encodings()
                    .any(|e| e == Encoding::DELTA_BINARY_PACKED),
                "{name}: {:?}",
                chunk.encodings().collect::<Vec<_>>()
            );
            let (lo, hi) = match chunk.statistics().unwrap() {
                // `uint64_t` in an INT64 column: the bounds are the unsigned ones, their bits.
                Statistics::Int64(s) => (*s.min_opt().unwrap(), *s.max_opt().unwrap()),
                other => panic!("{name}: {other:?}"),
            };
            let range = start..start + n;
            let (want_lo, want_hi) = match c {
                0 => (
                    want.0[range.clone()].iter().min().copied().unwrap() as i64,
                    want.0[range].iter().max().copied().unwrap() as i64,
                ),
                1 => (
                    want.1[range.clone()].iter().min().copied().unwrap() as i64,
                    want.1[range].iter().max().copied().unwrap() as i64,
                ),
                _ => (
                    want.2[range.clone()].iter().min().copied().unwrap(),
                    want.2[range].iter().max().copied().unwrap(),
                ),
            };
            assert_eq!(
                (lo, hi),
                (want_lo, want_hi),
                "{name}: row group from {start}"
            );
        }
        start += n;
    }
    assert_eq!(start, rows as usize);
    std::fs::remove_dir_all(&root).unwrap();
}

/// DELTA_BINARY_PACKED pages of every length that ends a block or a miniblock somewhere
/// (one value: a header only; two; a miniblock and one; a block and one or two; miniblocks
/// left unused in the last block) read back as written through parquet-rs's reader, with
/// deltas of every width (none, 1 bit, 64 bits).
#[test]
fn delta_pages_of_any_length_read_back() {
    use parquet::basic::Encoding;
    use parquet::schema::parser::parse_message_type;

    let schema =
        std::sync::Arc::new(parse_message_type("message m { required int64 v; }").unwrap());
    for len in [
        1usize, 2, 3, 32, 33, 64, 65, 127, 128, 129, 130, 161, 257, 1000,
    ] {
        for pattern in 0..3 {
            let values: Vec<i64> = (0..len as i64)
                .map(|i| match pattern {
                    0 => 7,
                    1 => i + (i % 2),
                    _ => {
                        if i % 2 == 0 {
                            i64::MIN + i
                        } else {
                            i64::MAX - i
                        }
                    }
                })
                .collect();
            let batches = [crate::columns::ColumnValues::Int64(values.clone())];
            let props = thousand_value_pages(Some(Encoding::DELTA_BINARY_PACKED));
            let bytes = written_here(&schema, props, 1, |_, rg, descr| {
                chunk::write_int64_chunk(rg, descr, len, true, 1, batches.iter()).unwrap();
            });
            let read: Vec<i64> =
                ParquetRecordBatchReaderBuilder::try_new(bytes::Bytes::from(bytes))
                    .unwrap()
                    .build()
                    .unwrap()
                    .flat_map(|b| {
                        arrow_array::cast::AsArray::as_primitive::<arrow_array::types::Int64Type>(
                            b.unwrap().column(0),
                        )
                        .values()
                        .to_vec()
                    })
                    .collect();
            assert_eq!(read, values, "{len} values, pattern {pattern}");
        }
    }
}

/// A topic instance whose columns would pass `max_columns` open at once is left out with a
/// note; the others are written as ever.
#[test]
fn an_instance_past_the_column_limit_is_left_out_and_said() {
    let bytes = log_bytes_with(10, |_, _| {});
    let root = temp("max-columns");
    // battery #0 and #1 (5 columns each) fit in 11; gyro's 2 more would not.
    let options = ParquetOptions {
        max_columns: 11,
        ..ParquetOptions::default()
    };
    let conv = Converter::new(&root, options)
        .convert_reader(&bytes[..], "wide.ulg")
        .unwrap();
    let written: Vec<(&str, u8)> = conv
        .files
        .iter()
        .map(|f| (f.topic.as_str(), f.multi_id))
        .collect();
    assert_eq!(written, [("battery", 0), ("battery", 1)]);
    assert!(
        conv.notes.iter().any(|n| n.starts_with(
            "1 topic instance left out, their columns past the limit of 11 open at once"
        ) && n.contains("`sensors/gyro` #0 (2 columns)")
            && n.ends_with("their rows are in no file and in no field statistics")),
        "{:?}",
        conv.notes
    );
    // The analysis in metadata.json says its field statistics lack them.
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&conv.metadata).unwrap()).unwrap();
    let missing = json["analysis"]["missing"].as_array().unwrap();
    assert!(
        missing.iter().any(|m| m["fact"] == "field_stats"
            && m["reason"]
                .as_str()
                .unwrap()
                .contains("`sensors/gyro` #0 (2 columns)")),
        "{missing:?}"
    );
    // The default takes them all.
    let conv = Converter::new(&root, ParquetOptions::default())
        .convert_reader(&bytes[..], "wide.ulg")
        .unwrap();
    assert_eq!(conv.files.len(), 3);
    assert!(conv.notes.is_empty(), "{:?}", conv.notes);
    std::fs::remove_dir_all(&root).unwrap();
}
