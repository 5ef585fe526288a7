//! Derived structs read the corpus: checked against each file's own formats, their values
//! equal pyulog's (first and last rows of every instance, row counts), every row equals the
//! dynamic reader's, and the streaming reader decodes the same rows.
//!
//! A typed value is turned back into named columns independently of its decoder: it is
//! encoded with its own format, then read by the dynamic reader under that format.

use std::collections::BTreeMap;
use std::path::Path;

use serde_json::Value as Json;
use ulog_runtime::schema::Schema;
use ulog_runtime::typed::{TypedDecoder, encode_row};
use ulog_runtime::value::RowPlan;
use ulog_runtime::{Event, Log, Scalar, StreamReader, Topic, TypedError, ULog};
use ulog_tests::{corpus_files, oracle, pyulog_blind_ranges, scalar_matches, short_name};

/// Reads every PX4 generation's attitude: `rollspeed` left the topic in 2018 and
/// `timestamp_sample` arrived in 2020.
#[derive(ULog, Debug, Clone, PartialEq)]
struct VehicleAttitude {
    timestamp: u64,
    q: [f32; 4],
    rollspeed: Option<f32>,
    timestamp_sample: Option<u64>,
}

#[derive(ULog, Debug, Clone, PartialEq)]
struct SensorCombined {
    timestamp: u64,
    gyro_rad: [f32; 3],
    accelerometer_m_s2: [f32; 3],
    accelerometer_timestamp_relative: i32,
}

/// `gyro_integral_dt` was a float until 2018, then `uint32_t` microseconds.
#[derive(ULog, Debug, Clone, PartialEq)]
#[ulog(name = "sensor_combined")]
struct SensorCombinedIntegralUs {
    timestamp: u64,
    gyro_integral_dt: u32,
}

#[derive(ULog, Debug, Clone, PartialEq)]
struct VehicleLocalPosition {
    timestamp: u64,
    ref_timestamp: u64,
    ref_lat: f64,
    ref_lon: f64,
    x: f32,
    y: f32,
    z: f32,
    vx: f32,
    vy: f32,
    vz: f32,
    xy_valid: bool,
    z_valid: bool,
    heading: Option<f32>,
    yaw: Option<f32>,
    delta_xy: Option<[f32; 2]>,
}

/// `esc_report` exactly as PX4 v1.14 logs it, padding included.
#[derive(ULog, Debug, Clone, Copy, PartialEq)]
#[ulog(name = "esc_report", exact)]
struct EscReport {
    timestamp: u64,
    esc_errorcount: u32,
    esc_rpm: i32,
    esc_voltage: f32,
    esc_current: f32,
    esc_temperature: f32,
    failures: u16,
    esc_address: u8,
    esc_cmdcount: u8,
    esc_state: u8,
    actuator_function: u8,
    esc_power: i8,
    #[ulog(padding)]
    _padding0: [u8; 5],
}

/// `esc_status` exactly as PX4 v1.14 logs it: inner padding, then 8 nested reports.
#[derive(ULog, Debug, Clone, PartialEq)]
#[ulog(name = "esc_status", exact)]
struct EscStatus {
    timestamp: u64,
    counter: u16,
    esc_count: u8,
    esc_connectiontype: u8,
    esc_online_flags: u8,
    esc_armed_flags: u8,
    #[ulog(padding)]
    _padding0: [u8; 2],
    esc: [EscReport; 8],
}

/// Named columns of a typed value: encoded under its own format, read dynamically.
fn columns<T: ULog>(value: &T) -> BTreeMap<String, Scalar> {
    let mut schema = Schema::new();
    for f in T::FORMAT.formats() {
        schema.insert(f).unwrap();
    }
    let id = schema.id(T::FORMAT.name).unwrap();
    let plan = RowPlan::new(&mut schema, id).unwrap();
    let mut row = Vec::new();
    value.encode(&mut row);
    let mut leaves = Vec::new();
    assert!(plan.for_each_leaf(&row, |s| leaves.push(s)));
    plan.columns(&schema)
        .into_iter()
        .zip(leaves)
        .map(|(c, v)| (c.name, v))
        .collect()
}

/// Values by their encodings (NaN equals itself there).
fn encoded<'a, T: ULog + 'a>(values: impl IntoIterator<Item = &'a T>) -> Vec<Vec<u8>> {
    values
        .into_iter()
        .map(|v| {
            let mut out = Vec::new();
            v.encode(&mut out);
            out
        })
        .collect()
}

/// What one topic check found.
#[derive(Default)]
struct Tally {
    files: usize,
    rows: usize,
    values: usize,
}

/// Checks topic `T` in every corpus file whose oracle has data for it; `refuse` says which
/// files' formats `T` must be refused for (with the error to expect).
fn check_topic<T: Topic + Clone>(refuse: impl Fn(&Path) -> Option<String>) -> Tally {
    let mut tally = Tally::default();
    let mut failures = Vec::new();
    for path in corpus_files() {
        let Some(o) = oracle(&path) else { continue };
        let name = short_name(&path);
        let topic = T::FORMAT.name;
        let subs: Vec<&Json> = o["pyulog"]["subscriptions"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|s| s["name"] == topic)
            .collect();
        if subs.is_empty() {
            continue;
        }
        let log = Log::open(&path).unwrap();
        let typed = match (log.topic::<T>(), refuse(&path)) {
            (Ok(t), None) => t,
            (Err(e), Some(expected)) => {
                assert_eq!(e.to_string(), expected, "{name}");
                continue;
            }
            (Ok(_), Some(_)) => panic!("{name}: {topic} should have been refused"),
            (Err(e), None) => panic!("{name}: {e}"),
        };
        tally.files += 1;
        let blind = pyulog_blind_ranges(&log);
        let decoder = typed.decoder();
        for s in subs {
            let multi_id = u8::try_from(s["multi_id"].as_u64().unwrap()).unwrap();
            let from_topic: Vec<T> = typed.instance(multi_id).unwrap().collect();
            // The same rows through the dynamic reader, each decoded by the typed decoder.
            let mut ours = Vec::new();
            for sub in log.subscriptions().iter().filter(|x| x.name == topic) {
                if sub.multi_id != multi_id {
                    continue;
                }
                for row in log.rows(sub) {
                    let value = decoder.decode_row(&row).unwrap();
                    // Every column the struct has equals the dynamic reader's column.
                    let dynamic: BTreeMap<String, Scalar> = row
                        .plan()
                        .unwrap()
                        .columns(row.schema())
                        .into_iter()
                        .zip({
                            let mut leaves = Vec::new();
                            row.for_each_leaf(|l| leaves.push(l));
                            leaves
                        })
                        .map(|(c, v)| (c.name, v))
                        .collect();
                    for (col, v) in columns(&value) {
                        if let Some(d) = dynamic.get(&col)
                            && !col.contains("_padding")
                            && d.as_f64().to_bits() != v.as_f64().to_bits()
                            && !(matches!(v, Scalar::Bool(_)))
                        {
                            failures.push(format!("{name} {topic} {col}: typed {v}, dynamic {d}"));
                        }
                    }
                    let in_blind = blind.iter().any(|r| r.contains(&row.offset));
                    ours.push((value, in_blind));
                }
            }
            assert!(
                encoded(&from_topic) == encoded(ours.iter().map(|(v, _)| v)),
                "{name}: Log::topic and TypedDecoder::decode_row disagree"
            );
            let seen: Vec<T> = ours
                .into_iter()
                .filter(|(_, b)| !b)
                .map(|(v, _)| v)
                .collect();
            assert_eq!(
                seen.len() as u64,
                s["n_data"].as_u64().unwrap(),
                "{name} {topic}/{multi_id}: rows"
            );
            tally.rows += seen.len();
            let n = seen.len();
            let picks = (0..n.min(3)).map(|i| (&s["first_rows"][i], i)).chain(
                (n.saturating_sub(3)..n)
                    .enumerate()
                    .map(|(j, i)| (&s["last_rows"][j], i)),
            );
            for (expected, i) in picks {
                for (col, v) in columns(&seen[i]) {
                    match expected.get(&col) {
                        Some(e) => {
                            tally.values += 1;
                            if !scalar_matches(e, v) {
                                failures.push(format!(
                                    "{name} {topic}/{multi_id} row {i} {col}: typed {v}, pyulog {e}"
                                ));
                            }
                        }
                        // A column only the struct has must be an absent optional field.
                        None => assert!(
                            T::FORMAT
                                .fields
                                .iter()
                                .any(|f| f.optional && col.starts_with(f.name)),
                            "{name}: {col} is not in the file"
                        ),
                    }
                }
            }
        }
        // The streaming reader, checked when the subscription arrives, decodes the same rows.
        let file = std::io::BufReader::new(std::fs::File::open(&path).unwrap());
        let mut reader = StreamReader::new(file).unwrap();
        let mut decoder: Option<TypedDecoder<T>> = None;
        let mut streamed = Vec::new();
        while let Some(event) = reader.next_event().unwrap() {
            match event {
                Event::Subscription(s) if s.name == topic && decoder.is_none() => {
                    decoder = Some(TypedDecoder::new(reader.metadata().schema()).unwrap());
                }
                Event::Row(row) => {
                    if let Some(v) = decoder.as_ref().and_then(|d| d.decode_row(&row)) {
                        streamed.push(v);
                    }
                }
                _ => {}
            }
        }
        let all: Vec<T> = typed.rows().map(|(_, v)| v).collect();
        assert!(
            encoded(&streamed) == encoded(&all),
            "{name}: streaming and whole-file rows differ"
        );
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    tally
}

fn never(_: &Path) -> Option<String> {
    None
}

/// The corpus must hold the topic (unless there is no corpus outside CI).
fn expect_some(tally: &Tally, min_files: usize) {
    if !corpus_files().is_empty() {
        assert!(tally.files >= min_files, "only {} files", tally.files);
        assert!(tally.values > 0);
    }
}

#[test]
fn vehicle_attitude_across_px4_generations() {
    let t = check_topic::<VehicleAttitude>(never);
    expect_some(&t, 11);
    eprintln!(
        "vehicle_attitude: {} files, {} rows, {} values",
        t.files, t.rows, t.values
    );
}

#[test]
fn vehicle_attitude_optional_fields_follow_the_file() {
    for path in corpus_files() {
        let log = Log::open(&path).unwrap();
        let Ok(topic) = log.topic::<VehicleAttitude>() else {
            continue;
        };
        let format = log.metadata().schema().get("vehicle_attitude").unwrap();
        let first = topic.rows().next().unwrap().1;
        assert_eq!(
            first.rollspeed.is_some(),
            format.field("rollspeed").is_some()
        );
        assert_eq!(
            first.timestamp_sample.is_some(),
            format.field("timestamp_sample").is_some()
        );
    }
}

#[test]
fn sensor_combined() {
    let t = check_topic::<SensorCombined>(never);
    expect_some(&t, 11);
}

#[test]
fn sensor_combined_integral_type_changed_in_2018() {
    let expected = "sensor_combined: gyro_integral_dt is float in the file, u32 in struct \
                    SensorCombinedIntegralUs";
    let t = check_topic::<SensorCombinedIntegralUs>(|path| {
        let log = Log::open(path).unwrap();
        let f = log.metadata().schema().get("sensor_combined")?;
        (f.field("gyro_integral_dt")?.ty.name() == "float").then(|| expected.to_owned())
    });
    expect_some(&t, 6);
}

#[test]
fn vehicle_local_position() {
    let t = check_topic::<VehicleLocalPosition>(never);
    expect_some(&t, 11);
}

#[test]
fn esc_status_nested_with_padding_exactly() {
    let t = check_topic::<EscStatus>(|path| {
        let log = Log::open(path).unwrap();
        let f = log.metadata().schema().get("esc_status")?;
        let ours = EscStatus::FORMAT.to_format();
        (*f != ours).then(|| {
            format!(
                "esc_status: exact mode: the file's format `{f}` differs from struct \
                 EscStatus's `{ours}`"
            )
        })
    });
    expect_some(&t, 1);
    assert_eq!(t.rows, 126, "the rows of sample_px4_events.ulg");
}

#[test]
fn esc_status_rows_reencode_to_the_file_bytes() {
    let mut checked = 0;
    for path in corpus_files() {
        let log = Log::open(&path).unwrap();
        let Ok(topic) = log.topic::<EscStatus>() else {
            continue;
        };
        let sub = log.subscription("esc_status", 0).unwrap();
        for (row, value) in log.rows(sub).zip(topic.instance(0).unwrap()) {
            let mut bytes = Vec::new();
            encode_row(&value, &mut bytes);
            assert_eq!(bytes, row.data, "{}", short_name(&path));
            checked += 1;
        }
    }
    if !corpus_files().is_empty() {
        assert_eq!(checked, 126);
    }
}

#[test]
fn absent_topics_are_named() {
    for path in corpus_files() {
        let log = Log::open(&path).unwrap();
        if log.metadata().schema().get("esc_status").is_some() {
            continue;
        }
        assert_eq!(
            log.topic::<EscStatus>().unwrap_err(),
            TypedError::NoSuchTopic {
                topic: "esc_status".into(),
                rust_type: "EscStatus"
            }
        );
    }
}
