//! Derived structs read the corpus: checked against each file's own formats, their values
//! equal pyulog's (first and last rows of every instance, row counts), every row equals the
//! dynamic reader's, and the streaming reader decodes the same rows.
//!
//! A typed value is turned back into named columns independently of its decoder: it is
//! encoded with its own format, then read by the dynamic reader under that format.

use std::collections::BTreeMap;
use std::path::Path;

use serde_json::Value as Json;
use ulog_runtime::typed::encode_row;
use ulog_runtime::{Chars, Log, Scalar, Topic, TypedError, ULog};
use ulog_tests::typed_check::{Columns, check_typed_file, columns, oracle_instances};
use ulog_tests::{corpus_files, oracle, scalar_matches, short_name};

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

/// One battery type for every PX4 generation: `cell_count` was `int32_t` before 2019 and is
/// `uint8_t` since; `i32` holds both (`widen`).
#[derive(ULog, Debug, Clone, PartialEq)]
struct BatteryStatus {
    timestamp: u64,
    voltage_v: f32,
    remaining: f32,
    #[ulog(widen)]
    cell_count: i32,
    connected: bool,
}

/// The whole struct widens: `system_id` and `component_id` were `uint32_t` in older PX4 and
/// are `uint8_t` now; `failure_detector_status` went from `uint8_t` to `uint16_t` (and the
/// oldest logs lack it).
#[derive(ULog, Debug, Clone, PartialEq)]
#[ulog(widen)]
struct VehicleStatus {
    timestamp: u64,
    nav_state: u8,
    arming_state: u8,
    system_id: u32,
    component_id: u32,
    failure_detector_status: Option<u32>,
    failsafe: bool,
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
fn check_topic<T: Topic>(refuse: impl Fn(&Path) -> Option<Refusal>) -> Tally {
    let mut tally = Tally::default();
    let mut failures = Vec::new();
    for path in corpus_files() {
        let Some(o) = oracle(&path) else { continue };
        let name = short_name(&path);
        let topic = T::FORMAT.name;
        if oracle_instances(&o, topic).is_empty() {
            continue;
        }
        let log = Log::open(&path).unwrap();
        let typed = match (log.topic::<T>(), refuse(&path)) {
            (Ok(t), None) => t,
            (Err(e), Some(expected)) => {
                expected.check(&e.to_string(), &name);
                continue;
            }
            (Ok(_), Some(_)) => panic!("{name}: {topic} should have been refused"),
            (Err(e), None) => panic!("{name}: {e}"),
        };
        tally.files += 1;
        let found = check_typed_file(&path, &o, &log, &typed);
        tally.rows += found.rows;
        tally.values += found.values;
        failures.extend(found.failures);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    tally
}

/// The error a log's topic is expected to be refused with.
enum Refusal {
    /// This text.
    Exactly(String),
    /// A text that begins with the first part and holds the others.
    Holding(Vec<String>),
}

impl Refusal {
    fn check(&self, error: &str, name: &str) {
        match self {
            Refusal::Exactly(text) => assert_eq!(error, text, "{name}"),
            Refusal::Holding(parts) => {
                assert!(error.starts_with(&parts[0]), "{name}: {error}");
                for part in &parts[1..] {
                    assert!(error.contains(part.as_str()), "{name}: `{part}` in {error}");
                }
            }
        }
    }
}

fn never(_: &Path) -> Option<Refusal> {
    None
}

/// The project's corpus must hold the topic (unless there is no corpus outside CI); another
/// folder named by `ULOG_CORPUS` is checked log by log, whatever topics it holds.
fn expect_some(tally: &Tally, min_files: usize) {
    if !corpus_files().is_empty() && ulog_tests::is_project_corpus() {
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
fn battery_status_with_widening_reads_every_log_with_the_topic() {
    let t = check_topic::<BatteryStatus>(never);
    expect_some(&t, 8);
    // Without `widen` the older logs are refused, as before.
    #[derive(ULog, Debug)]
    #[ulog(name = "battery_status")]
    struct Strict {
        timestamp: u64,
        cell_count: i32,
    }
    let refused = corpus_files()
        .iter()
        .filter(|p| {
            let log = Log::open(p).unwrap();
            matches!(log.topic::<Strict>(), Err(TypedError::Mismatch { .. }))
        })
        .count();
    if !corpus_files().is_empty() && ulog_tests::is_project_corpus() {
        assert!(refused >= 3, "{refused}");
    }
}

#[test]
fn vehicle_status_with_widening_reads_every_log_with_the_topic() {
    let t = check_topic::<VehicleStatus>(never);
    expect_some(&t, 11);
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
        (f.field("gyro_integral_dt")?.ty.name() == "float")
            .then(|| Refusal::Exactly(expected.to_owned()))
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
        // Field by field: every field only the file has is named with its type.
        (*f != ours).then(|| {
            let mut parts = vec!["esc_status: ".to_owned(), "exact mode: ".to_owned()];
            for field in f.fields.iter().filter(|x| !x.is_padding()) {
                if ours.field(&field.name).is_none() {
                    parts.push(format!("field `{field}` is in the file, not in struct"));
                }
            }
            Refusal::Holding(parts)
        })
    });
    expect_some(&t, 1);
    if !corpus_files().is_empty() && ulog_tests::is_project_corpus() {
        assert_eq!(t.rows, 126, "the rows of sample_px4_events.ulg");
    }
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
    // The rows of sample_px4_events.ulg, the project corpus's one log with the topic.
    if !corpus_files().is_empty() && ulog_tests::is_project_corpus() {
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
        let err = log.topic::<EscStatus>().unwrap_err();
        let TypedError::NoSuchTopic {
            topic, rust_type, ..
        } = &err
        else {
            panic!("{}: {err}", path.display());
        };
        assert_eq!((topic.as_str(), *rust_type), ("esc_status", "EscStatus"));
    }
}

/// Nested, with padding inside and at its end.
#[derive(ULog, Debug, Clone, Copy, PartialEq)]
struct Motor {
    rpm: i32,
    #[ulog(padding)]
    _pad0: [u8; 2],
    temperature: i16,
    armed: bool,
    tag: Chars<3>,
    currents: [f32; 2],
    #[ulog(padding)]
    _pad1: [u8; 3],
}

/// A topic with inner padding, an array of nested types and trailing padding.
#[derive(ULog, Debug, Clone, PartialEq)]
#[ulog(name = "motor_status")]
struct MotorStatus {
    timestamp: u64,
    count: u8,
    #[ulog(padding)]
    _pad: [u8; 7],
    motors: [Motor; 3],
    voltage: f64,
    #[ulog(padding)]
    _tail: [u8; 4],
}

/// Every basic type, arrays of them, extreme values.
#[derive(ULog, Debug, Clone, PartialEq)]
struct Mixed {
    timestamp: u64,
    d: f64,
    i: i64,
    u: u16,
    s: i8,
    name: Chars<5>,
    v: [f32; 3],
    flags: [bool; 2],
    big: u64,
    small: u32,
    neg: i16,
    byte: u8,
}

fn motor_status(i: u64, instance: u8) -> MotorStatus {
    let motor = |m: u8| Motor {
        rpm: 1_000 * i32::from(m) - i as i32 * 7 + i32::from(instance),
        _pad0: [0; 2],
        temperature: -(i as i16) * 3,
        armed: (i + u64::from(m)).is_multiple_of(2),
        tag: Chars::new(["m0", "m1x", "m"][usize::from(m)]).unwrap(),
        currents: [i as f32 / 7.0, -(f32::from(m)) * 0.1],
        _pad1: [0; 3],
    };
    MotorStatus {
        timestamp: 1_000_000 + i * 10_000 + u64::from(instance),
        count: 3,
        _pad: [0; 7],
        motors: [motor(0), motor(1), motor(2)],
        voltage: 16.8 - i as f64 * 0.01,
        _tail: [0; 4],
    }
}

fn mixed(i: u64) -> Mixed {
    let special = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        -0.0,
        f32::MIN_POSITIVE,
    ];
    Mixed {
        timestamp: 1_000_500 + i * 10_000,
        d: if i == 3 { f64::NAN } else { i as f64 / 3.0 },
        i: i64::MIN + i as i64,
        u: u16::MAX - i as u16,
        s: i8::MIN + i as i8,
        name: Chars::new(&"abcde"[..(i as usize % 6)]).unwrap(),
        v: [special[i as usize % 5], i as f32 * 1e30, -(i as f32)],
        flags: [i.is_multiple_of(2), i.is_multiple_of(3)],
        big: u64::MAX - i,
        small: u32::MAX / (i as u32 + 1),
        neg: i16::MIN + i as i16,
        byte: (i * 13) as u8,
    }
}

/// A file written from derived structs, with every message type around the rows; returns the
/// rows written per `topic/multi_id`, as named columns.
fn typed_interop_file() -> (Vec<u8>, BTreeMap<String, Vec<Columns>>) {
    use ulog_runtime::read::ParamValue;
    use ulog_runtime::{Value, Writer, WriterOptions};
    let options = WriterOptions {
        start_timestamp: 999_000,
        default_parameters: true,
    };
    let mut w = Writer::new(Vec::new(), options).unwrap();
    w.info("sys_name", &Value::String("typed".into())).unwrap();
    w.info("ver_hw", &Value::Scalar(Scalar::Int32(-5))).unwrap();
    w.multi_info("boot", &Value::String("part one".into()), false)
        .unwrap();
    w.multi_info("boot", &Value::String(", part two".into()), true)
        .unwrap();
    w.parameter("MPC_XY_P", ParamValue::Float(0.95)).unwrap();
    w.parameter("SYS_AUTOSTART", ParamValue::Int32(4001))
        .unwrap();
    w.default_parameter("MPC_XY_P", ParamValue::Float(1.0), 2)
        .unwrap();
    w.define::<MotorStatus>().unwrap();
    w.define::<Mixed>().unwrap();
    let motors = [
        w.topic::<MotorStatus>(0).unwrap(),
        w.topic::<MotorStatus>(1).unwrap(),
    ];
    let mix = w.topic::<Mixed>(0).unwrap();
    let mut written: BTreeMap<String, Vec<Columns>> = BTreeMap::new();
    for i in 0..25u64 {
        for (k, sub) in motors.iter().enumerate() {
            let value = motor_status(i, k as u8);
            w.write(sub, &value).unwrap();
            written
                .entry(format!("motor_status/{k}"))
                .or_default()
                .push(columns(&value));
        }
        let value = mixed(i);
        w.write(&mix, &value).unwrap();
        written
            .entry("mixed/0".into())
            .or_default()
            .push(columns(&value));
        if i == 12 {
            w.log(b'4', 1_120_000, "warning halfway").unwrap();
            w.log_tagged(b'6', 3, 1_120_001, "tagged info").unwrap();
            w.parameter("MPC_XY_P", ParamValue::Float(1.25)).unwrap();
            w.sync().unwrap();
            w.dropout(17).unwrap();
        }
    }
    w.unsubscribe(motors[1].id()).unwrap();
    (w.into_inner(), written)
}

#[test]
fn pyulog_reads_every_value_written_from_derived_structs() {
    use std::process::Command;
    let (bytes, written) = typed_interop_file();
    let sha: String = {
        use sha2::{Digest, Sha256};
        Sha256::digest(&bytes)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect()
    };
    let dir = std::env::temp_dir().join(format!("ulog-typed-interop-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("typed.ulg");
    std::fs::write(&path, &bytes).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("py/dump_values.py");
    let committed_path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("data/typed_interop.pyulog.json");
    let live = Command::new("python3")
        .arg(&script)
        .arg(&path)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8(o.stdout).unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
    let text = match live {
        Some(text) => {
            if std::env::var_os("ULOG_REFRESH").is_some() {
                std::fs::write(&committed_path, &text).unwrap();
            }
            text
        }
        None => {
            assert!(
                !ulog_tests::under_ci(),
                "under CI pyulog must be installed (.ci/run does it)"
            );
            eprintln!("pyulog not available: using its committed view of this file");
            std::fs::read_to_string(&committed_path).unwrap()
        }
    };
    let p: Json = serde_json::from_str(&text).unwrap();
    assert_eq!(
        p["sha256"].as_str(),
        Some(sha.as_str()),
        "the writer's output changed: refresh with ULOG_REFRESH=1 (pyulog installed)"
    );
    assert_eq!(p["printed"], "", "pyulog printed warnings");

    // Every row of every instance, every column, every value.
    let data = p["data"].as_object().unwrap();
    assert_eq!(
        data.keys().collect::<Vec<_>>(),
        written.keys().collect::<Vec<_>>()
    );
    let mut values = 0;
    for (key, rows) in &written {
        let theirs = data[key].as_object().unwrap();
        // pyulog also shows inner padding: zeros, as written.
        let (padding, theirs): (Vec<_>, Vec<_>) =
            theirs.iter().partition(|(col, _)| col.contains("_padding"));
        assert!(!padding.is_empty() || key == "mixed/0");
        for (col, column) in padding {
            assert!(
                column.as_array().unwrap().iter().all(|v| v == 0),
                "{key} {col}"
            );
        }
        let ours: Vec<&String> = rows[0].keys().collect();
        assert_eq!(
            theirs.iter().map(|(c, _)| *c).collect::<Vec<_>>(),
            ours,
            "{key}: columns"
        );
        for (col, column) in theirs {
            let column = column.as_array().unwrap();
            assert_eq!(column.len(), rows.len(), "{key}: rows");
            for (r, row) in rows.iter().enumerate() {
                let v = row[col];
                assert!(
                    scalar_matches(&column[r], v),
                    "{key} row {r} {col}: wrote {v}, pyulog {}",
                    column[r]
                );
                values += 1;
            }
        }
    }
    assert_eq!(
        values,
        2 * 25 * written["motor_status/0"][0].len() + 25 * written["mixed/0"][0].len()
    );

    // The other message types around the rows.
    assert_eq!(p["info"]["sys_name"], "typed");
    assert_eq!(p["info"]["ver_hw"], -5);
    assert_eq!(
        p["info_multiple"]["boot"],
        serde_json::json!([["part one", ", part two"]])
    );
    assert_eq!(p["initial_parameters"]["SYS_AUTOSTART"], 4001);
    assert_eq!(p["initial_parameters"]["MPC_XY_P"], 0.949999988079071);
    assert_eq!(p["changed_parameters"][0][1], "MPC_XY_P");
    assert_eq!(p["changed_parameters"][0][2], 1.25);
    assert_eq!(p["default_parameters"]["1"]["MPC_XY_P"], 1.0);
    assert_eq!(
        p["logged_messages"],
        serde_json::json!([[52, 1_120_000, "warning halfway"]])
    );
    assert_eq!(
        p["logged_messages_tagged"]["3"],
        serde_json::json!([[54, 1_120_001, "tagged info"]])
    );
    assert_eq!(p["dropouts"], serde_json::json!([17]));

    // And this reader reads the same rows back as the structs written.
    let log = Log::from_slice(&bytes).unwrap();
    let back: Vec<MotorStatus> = log
        .topic::<MotorStatus>()
        .unwrap()
        .instance(1)
        .unwrap()
        .collect();
    assert_eq!(
        back,
        (0..25).map(|i| motor_status(i, 1)).collect::<Vec<_>>()
    );
}
