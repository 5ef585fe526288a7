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

#[test]
fn a_small_budget_writes_more_row_groups_of_the_same_rows() {
    let bytes = log_bytes(20_000);
    let convert = |options: ParquetOptions, name: &str| {
        let root = temp(name);
        let conv = Converter::new(&root, options)
            .convert_reader(&bytes[..], "f.ulg")
            .unwrap();
        let (batches, _, groups) = read(&conv.files[0].path);
        let v: Vec<f32> = column::<Float32Array>(&batches, "voltage_v")
            .iter()
            .flat_map(|a| a.values().iter().copied())
            .collect();
        std::fs::remove_dir_all(&root).unwrap();
        (v, groups)
    };
    let (whole, one) = convert(ParquetOptions::default(), "budget-default");
    let (split, many) = convert(
        ParquetOptions {
            buffer_bytes: 16 << 10,
            batch_bytes: 1 << 10,
            ..ParquetOptions::default()
        },
        "budget-small",
    );
    let (capped, rows_capped) = convert(
        ParquetOptions {
            row_group_rows: 3000,
            ..ParquetOptions::default()
        },
        "budget-rows",
    );
    assert_eq!(one, 1);
    assert!(many > 5, "{many} row groups");
    assert_eq!(rows_capped, 7, "20000 rows in groups of at most 3000");
    assert_eq!(whole.len(), 20_000);
    assert_eq!(whole, split);
    assert_eq!(whole, capped);
}

#[test]
fn hive_layout_partitions_by_topic_log_and_instance() {
    let bytes = log_bytes(10);
    let root = temp("hive");
    let a = root.join("a");
    let b = root.join("b");
    for dir in [&a, &b] {
        std::fs::create_dir_all(dir).unwrap();
        std::fs::write(dir.join("same.ulg"), &bytes).unwrap();
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
    let written = write_topic(&log, "battery", 0, &identity, file, &options)
        .unwrap()
        .unwrap();
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
    assert!(write_topic(&log, "nope", 0, &identity, Vec::new(), &options).is_none());
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
    // No fix yet, then a fix 3 s after boot: the log (which started at 0) began 3 s earlier.
    w.write(
        &gps,
        &VehicleGpsPosition {
            timestamp: 1_000_000,
            time_utc_usec: 0,
        },
    )
    .unwrap();
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
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn a_failed_conversion_leaves_no_partial_files() {
    let bytes = log_bytes(10);
    let root = temp("fail");
    // The log folder is a file: nothing can be made inside it.
    std::fs::create_dir_all(&root).unwrap();
    std::fs::write(root.join("f"), b"in the way").unwrap();
    let err = Converter::new(&root, ParquetOptions::default())
        .convert_reader(&bytes[..], "f.ulg")
        .unwrap_err();
    assert!(matches!(err, ConvertError::Io { .. }), "{err}");
    assert!(
        err.to_string()
            .starts_with(&root.join("f").display().to_string()),
        "{err}"
    );
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
    for layout in [Layout::PerLog, Layout::Hive] {
        let root = temp("names");
        let options = ParquetOptions {
            layout,
            ..ParquetOptions::default()
        };
        let conv = Converter::new(root.join("out"), options)
            .convert_reader(&bytes[..], "../x.ulg")
            .unwrap();
        assert_eq!(conv.files.len(), 2);
        for f in &conv.files {
            assert!(f.path.starts_with(root.join("out")), "{}", f.path.display());
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
