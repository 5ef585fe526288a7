//! Typed formats against hand-laid bytes and hand-written format strings.

use super::*;
use crate::schema::Schema;
use crate::{Chars, Event, Log, StreamReader, ULog, Writer, WriterOptions};

#[derive(ULog, Debug, Clone, Copy, PartialEq, Default)]
struct EscReport {
    esc_rpm: i32,
    esc_voltage: f32,
    #[ulog(padding)]
    _pad: [u8; 3],
}

#[derive(ULog, Debug, Clone, PartialEq)]
#[ulog(name = "esc_status")]
struct EscStatus {
    timestamp: u64,
    esc_count: u8,
    esc: [EscReport; 2],
    #[ulog(padding)]
    _pad: [u8; 7],
}

#[derive(ULog, Debug, PartialEq)]
struct VehicleGpsPosition {
    timestamp: u64,
    #[ulog(rename = "type")]
    kind: u8,
    ok: bool,
    name: Chars<6>,
    q: [f32; 2],
    alt: Option<f64>,
}

fn schema(formats: &[&str]) -> Schema {
    let mut s = Schema::new();
    for f in formats {
        s.insert(f.parse().unwrap()).unwrap();
    }
    s
}

#[test]
fn formats_print_as_px4_writes_them() {
    let printed: Vec<String> = EscStatus::FORMAT
        .formats()
        .iter()
        .map(|f| f.to_string())
        .collect();
    assert_eq!(
        printed,
        [
            "esc_report:int32_t esc_rpm;float esc_voltage;uint8_t[3] _padding0;",
            "esc_status:uint64_t timestamp;uint8_t esc_count;esc_report[2] esc;uint8_t[7] _padding0;",
        ]
    );
    assert_eq!(
        VehicleGpsPosition::FORMAT.to_format().to_string(),
        "vehicle_gps_position:uint64_t timestamp;uint8_t type;bool ok;char[6] name;float[2] q;double alt;"
    );
    assert_eq!(EscReport::FORMAT.name, "esc_report");
    assert_eq!(
        (EscStatus::FORMAT.size(), EscStatus::FORMAT.payload_size()),
        (38, 31)
    );
}

#[test]
fn encoding_is_the_packed_little_endian_layout() {
    let value = EscStatus {
        timestamp: 0x0102_0304_0506_0708,
        esc_count: 2,
        esc: [
            EscReport {
                esc_rpm: -2,
                esc_voltage: 1.5,
                _pad: [9; 3],
            },
            EscReport {
                esc_rpm: 300,
                esc_voltage: -0.25,
                _pad: [0; 3],
            },
        ],
        _pad: [0; 7],
    };
    let mut expected = vec![8, 7, 6, 5, 4, 3, 2, 1, 2];
    expected.extend_from_slice(&[0xfe, 0xff, 0xff, 0xff, 0x00, 0x00, 0xc0, 0x3f, 0, 0, 0]);
    expected.extend_from_slice(&[0x2c, 0x01, 0, 0, 0x00, 0x00, 0x80, 0xbe, 0, 0, 0]);
    let mut full = Vec::new();
    value.encode(&mut full);
    assert_eq!(full[..31], expected[..], "padding is written as zeros");
    assert_eq!(full[31..], [0; 7]);
    let mut row = Vec::new();
    encode_row(&value, &mut row);
    assert_eq!(row, expected, "rows omit the trailing padding");

    let s = schema(&[
        "esc_report:int32_t esc_rpm;float esc_voltage;uint8_t[3] _padding0;",
        "esc_status:uint64_t timestamp;uint8_t esc_count;esc_report[2] esc;uint8_t[7] _padding0;",
    ]);
    let decoder = TypedDecoder::<EscStatus>::new(&s).unwrap();
    let mut back = value.clone();
    back.esc[0]._pad = [0; 3];
    assert_eq!(decoder.decode(&row), Some(back));
    // The last field read ends at byte 28: the nested padding after it is never read.
    assert!(decoder.decode(&row[..28]).is_some());
    assert_eq!(
        decoder.decode(&row[..27]),
        None,
        "too short for the fields read"
    );
}

#[test]
fn fields_match_by_name_whatever_the_order_and_padding() {
    // The file's order, extra fields and padding differ from the struct's.
    let s = schema(&[
        "esc_status:esc_report[2] esc;uint64_t timestamp;uint16_t extra;uint8_t esc_count;",
        "esc_report:uint8_t[2] _padding0;float esc_voltage;int32_t esc_rpm;float esc_temp;",
    ]);
    let decoder = TypedDecoder::<EscStatus>::new(&s).unwrap();
    let mut row = Vec::new();
    for (v, rpm) in [(3.5f32, 10i32), (4.5, -20)] {
        row.extend_from_slice(&[0xaa, 0xbb]);
        row.extend_from_slice(&v.to_le_bytes());
        row.extend_from_slice(&rpm.to_le_bytes());
        row.extend_from_slice(&99f32.to_le_bytes());
    }
    row.extend_from_slice(&77u64.to_le_bytes());
    row.extend_from_slice(&[1, 2, 5]);
    let got = decoder.decode(&row).unwrap();
    assert_eq!(got.timestamp, 77);
    assert_eq!(got.esc_count, 5);
    assert_eq!((got.esc[0].esc_rpm, got.esc[0].esc_voltage), (10, 3.5));
    assert_eq!((got.esc[1].esc_rpm, got.esc[1].esc_voltage), (-20, 4.5));
}

/// A nested struct named otherwise than the file's nested format.
#[derive(ULog, Debug, Clone, Copy, PartialEq, Default)]
struct Motor {
    esc_rpm: i32,
}

#[derive(ULog, Debug, Clone, PartialEq)]
#[ulog(name = "esc_status")]
struct MotorStatus {
    timestamp: u64,
    esc: [Motor; 2],
}

/// A nested struct whose format name is not the file's: the error says both names and the
/// attribute that gives the file's, rather than only that the types differ.
#[test]
fn a_nested_struct_of_another_name_is_told_the_files_name() {
    let s = schema(&[
        "esc_status:uint64_t timestamp;esc_report[2] esc;",
        "esc_report:int32_t esc_rpm;",
    ]);
    let err = TypedDecoder::<MotorStatus>::new(&s).unwrap_err();
    assert_eq!(
        err.to_string(),
        "esc_status: esc is esc_report[2] in the file, [Motor; 2] in struct MotorStatus: struct Motor is \
         format `motor`, the file's is `esc_report` (`#[ulog(name = \"esc_report\")]` on \
         struct Motor names it so)"
    );
}

#[test]
fn a_mismatch_names_the_topic_every_path_and_both_sides() {
    let s = schema(&[
        "esc_status:uint64_t timestamp;uint16_t esc_count;esc_report[4] esc;",
        "esc_report:float esc_rpm;float esc_voltage;",
    ]);
    let err = TypedDecoder::<EscStatus>::new(&s).unwrap_err();
    assert_eq!(
        err.to_string(),
        "esc_status: 3 differences between the file and struct EscStatus:\n  \
         esc_count is uint16_t in the file, u8 in struct EscStatus\n  \
         esc is esc_report[4] in the file, [EscReport; 2] in struct EscStatus\n  \
         esc[].esc_rpm is float in the file, i32 in struct EscReport"
    );
    // `?` in `main` prints `Debug`: the same text, one difference per line.
    assert_eq!(format!("{err:?}"), err.to_string());
    let s = schema(&[
        "esc_status:uint64_t timestamp;uint8_t esc_count;esc_report[2] esc;",
        "esc_report:float esc_rpm;double esc_voltage;",
    ]);
    let err = TypedDecoder::<EscStatus>::new(&s).unwrap_err();
    assert_eq!(
        err.to_string(),
        "esc_status: 2 differences between the file and struct EscStatus:\n  \
         esc[].esc_rpm is float in the file, i32 in struct EscReport\n  \
         esc[].esc_voltage is double in the file, f32 in struct EscReport"
    );
    let TypedError::Mismatch { mismatches, .. } = err else {
        panic!("a mismatch")
    };
    assert_eq!(mismatches[0].path, "esc[].esc_rpm");
}

#[test]
fn missing_fields_are_errors_unless_optional() {
    let s = schema(&["vehicle_gps_position:uint64_t timestamp;uint8_t type;bool ok;char[6] name;"]);
    let err = TypedDecoder::<VehicleGpsPosition>::new(&s).unwrap_err();
    assert_eq!(
        err.to_string(),
        "vehicle_gps_position: q is in struct VehicleGpsPosition but not in the file \
         (make it an `Option` to accept files without it)"
    );
    let s = schema(&[
        "vehicle_gps_position:uint64_t timestamp;uint8_t type;bool ok;char[6] name;float[2] q;",
    ]);
    let decoder = TypedDecoder::<VehicleGpsPosition>::new(&s).unwrap();
    let mut row = 5u64.to_le_bytes().to_vec();
    row.extend_from_slice(&[3, 2]); // type, ok (any non-zero byte is true)
    row.extend_from_slice(b"gps\0\0\0");
    row.extend_from_slice(&1f32.to_le_bytes());
    row.extend_from_slice(&2f32.to_le_bytes());
    let got = decoder.decode(&row).unwrap();
    assert_eq!(
        got,
        VehicleGpsPosition {
            timestamp: 5,
            kind: 3,
            ok: true,
            name: Chars::new("gps").unwrap(),
            q: [1.0, 2.0],
            alt: None,
        }
    );
    assert_eq!(got.name.as_str(), Ok("gps"));
}

#[derive(ULog, Debug, PartialEq)]
#[ulog(name = "sensor", exact)]
struct ExactSensor {
    timestamp: u64,
    x: f32,
    #[ulog(padding)]
    _pad: [u8; 4],
}

#[test]
fn exact_mode_refuses_any_difference() {
    let same = schema(&["sensor:uint64_t timestamp;float x;uint8_t[4] _padding0;"]);
    assert!(TypedDecoder::<ExactSensor>::new(&same).is_ok());
    // Each difference named, field by field, not the two formats printed whole.
    for (other, expected) in [
        (
            "sensor:float x;uint64_t timestamp;uint8_t[4] _padding0;",
            "sensor: 2 differences between the file and struct ExactSensor:\n  \
             exact mode: fields in another order: x timestamp in the file, timestamp x in \
             struct ExactSensor\n  \
             exact mode: padding differs: uint8_t[4] after `timestamp` in the file; \
             uint8_t[4] after `x` in struct ExactSensor",
        ),
        (
            "sensor:uint64_t timestamp;float x;",
            "sensor: exact mode: padding differs: none in the file; uint8_t[4] after `x` in \
             struct ExactSensor",
        ),
        (
            "sensor:uint64_t timestamp;float x;uint8_t[4] _padding0;float y;",
            "sensor: exact mode: field `float y` is in the file, not in struct ExactSensor",
        ),
        (
            "sensor:uint64_t timestamp;double x;uint8_t[4] _padding0;",
            "sensor: exact mode: field `x` is double in the file, float in struct ExactSensor",
        ),
        (
            "sensor:uint64_t timestamp;float x;uint8_t[4] _padding1;",
            "sensor: exact mode: padding differs: _padding1 in the file; _padding0 in struct \
             ExactSensor",
        ),
    ] {
        let err = TypedDecoder::<ExactSensor>::new(&schema(&[other])).unwrap_err();
        assert_eq!(err.to_string(), expected, "{other}");
    }
}

#[test]
fn absent_topics_are_their_own_errors() {
    let err = TypedDecoder::<ExactSensor>::new(&schema(&["other:uint64_t timestamp;"]));
    assert_eq!(
        err.unwrap_err().to_string(),
        "the file has no format `sensor` (wanted by struct ExactSensor)"
    );
    // Close names are suggested, closest first.
    let err = TypedDecoder::<ExactSensor>::new(&schema(&[
        "sensors:uint64_t timestamp;",
        "sensor_combined:uint64_t timestamp;",
        "battery:uint64_t timestamp;",
        "senso:uint64_t timestamp;",
    ]));
    assert_eq!(
        err.unwrap_err().to_string(),
        "the file has no format `sensor` (wanted by struct ExactSensor); did you mean \
         `senso`, `sensors` or `sensor_combined`?"
    );
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    w.define::<ExactSensor>().unwrap();
    let sub = w.topic::<EscStatus>(1).unwrap();
    w.write(
        &sub,
        &EscStatus {
            timestamp: 1,
            esc_count: 0,
            esc: [EscReport::default(); 2],
            _pad: [0; 7],
        },
    )
    .unwrap();
    let log = Log::from_vec(w.into_inner()).unwrap();
    assert_eq!(
        log.topic::<ExactSensor>().unwrap_err(),
        TypedError::NotLogged {
            topic: "sensor".into()
        }
    );
    let topic = log.topic::<EscStatus>().unwrap();
    assert_eq!(
        topic.instance(0).unwrap_err().to_string(),
        "`esc_status` has no instance 0 in the file (instances: [1])"
    );
    assert_eq!(topic.instance(1).unwrap().count(), 1);
}

fn status(t: u64, rpm: i32) -> EscStatus {
    EscStatus {
        timestamp: t,
        esc_count: 2,
        esc: [
            EscReport {
                esc_rpm: rpm,
                esc_voltage: t as f32 / 2.0,
                _pad: [0; 3],
            },
            EscReport {
                esc_rpm: -rpm,
                esc_voltage: 0.5,
                _pad: [0; 3],
            },
        ],
        _pad: [0; 7],
    }
}

#[test]
fn written_rows_read_back_per_instance_and_in_file_order() {
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let a = w.topic::<EscStatus>(0).unwrap();
    let b = w.topic::<EscStatus>(1).unwrap();
    let order = [(a, 1, 10), (b, 2, 20), (b, 3, 30), (a, 4, 40), (b, 5, 50)];
    for (sub, t, rpm) in order {
        w.write(&sub, &status(t, rpm)).unwrap();
    }
    let bytes = w.into_inner();
    let log = Log::from_slice(&bytes).unwrap();
    // The dynamic reader sees the same format and rows of 31 bytes (trailing padding omitted).
    let sub = log.subscription("esc_status", 1).unwrap();
    assert_eq!(sub.payload_sizes(), Some((31, 38)));
    assert!(log.rows(sub).all(|r| r.data.len() == 31));
    let first = log.rows(sub).next().unwrap().value().unwrap();
    assert_eq!(
        first.field("timestamp").and_then(|v| v.as_scalar()),
        Some(crate::Scalar::UInt64(2))
    );
    let topic = log.topic::<EscStatus>().unwrap();
    assert_eq!(topic.multi_ids(), [0, 1]);
    let zero: Vec<EscStatus> = topic.instance(0).unwrap().collect();
    assert_eq!(zero, [status(1, 10), status(4, 40)]);
    let all: Vec<(u8, u64)> = topic.rows().map(|(m, s)| (m, s.timestamp)).collect();
    assert_eq!(all, [(0, 1), (1, 2), (1, 3), (0, 4), (1, 5)]);

    // The same through the streaming reader, checked once when the subscription arrives.
    let mut reader = StreamReader::new(&bytes[..]).unwrap();
    let mut decoder = None;
    let mut streamed = Vec::new();
    while let Some(event) = reader.next_event().unwrap() {
        match event {
            Event::Subscription(s) if s.name == "esc_status" && decoder.is_none() => {
                decoder = Some(TypedDecoder::<EscStatus>::new(reader.metadata().schema()).unwrap());
            }
            Event::Row(row) => {
                streamed.push(
                    decoder
                        .as_ref()
                        .unwrap()
                        .decode_row(&row)
                        .unwrap()
                        .timestamp,
                );
            }
            _ => {}
        }
    }
    assert_eq!(streamed, [1, 2, 3, 4, 5]);
}

#[test]
fn a_second_layout_under_one_name_is_refused_and_the_file_stays_valid() {
    #[derive(ULog)]
    #[ulog(name = "esc_report")]
    struct OtherReport {
        timestamp: u64,
    }
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let a = w.topic::<EscStatus>(0).unwrap();
    let err = w.topic::<OtherReport>(0).unwrap_err();
    assert!(err.to_string().contains("esc_report"), "{err}");
    w.write(&a, &status(1, 1)).unwrap();
    let log = Log::from_vec(w.into_inner()).unwrap();
    assert!(log.diagnostics().is_empty(), "{:?}", log.diagnostics());
    assert_eq!(log.topic::<EscStatus>().unwrap().rows().count(), 1);
}

#[test]
fn topics_are_declared_before_rows_and_formats_refused_after() {
    #[derive(ULog)]
    struct Late {
        timestamp: u64,
    }
    #[derive(ULog)]
    struct Later {
        timestamp: u64,
    }
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    // Several topics before the first row: the obvious first program works.
    let a = w.topic::<EscStatus>(0).unwrap();
    let late = w.topic::<Late>(0).unwrap();
    w.info("sys_name", &crate::Value::String("test".into()))
        .unwrap();
    w.write(&a, &status(1, 1)).unwrap();
    // Once rows are written, a new format cannot be read by anyone any more: refused.
    let err = w.topic::<Later>(0).unwrap_err();
    assert!(
        matches!(&err, crate::WriteError::DefinitionsClosed(n) if n == "later"),
        "{err}"
    );
    // Formats already written stay usable: a second instance of the same topic.
    let b = w.topic::<EscStatus>(1).unwrap();
    w.write(&b, &status(2, 2)).unwrap();
    w.write(&late, &Late { timestamp: 3 }).unwrap();
    let bytes = w.into_inner();
    let log = Log::from_slice(&bytes).unwrap();
    assert!(log.diagnostics().is_empty(), "{:?}", log.diagnostics());
    assert_eq!(log.topic::<EscStatus>().unwrap().rows().count(), 2);
    assert_eq!(log.topic::<Late>().unwrap().rows().count(), 1);
    assert!(log.metadata().schema().get("later").is_none());
    // The info written after the declarations is still in the definitions section, and the
    // subscriptions come after it, in msg_id order.
    assert!(log.metadata().info_value("sys_name").is_some());
    let ids: Vec<(u16, &str)> = log
        .subscriptions()
        .iter()
        .map(|s| (s.msg_id, s.name.as_str()))
        .collect();
    assert_eq!(ids, [(0, "esc_status"), (1, "late"), (2, "esc_status")]);
    let first_a = bytes
        .windows(3)
        .position(|w| w[2] == b'A' && w[0] == 0x0d)
        .unwrap();
    let info = bytes.windows(3).position(|w| w[2] == b'I').unwrap();
    assert!(info < first_a);
}

#[test]
fn waiting_subscriptions_are_written_by_flush_and_drop() {
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    w.topic::<EscStatus>(0).unwrap();
    let log = Log::from_vec(w.into_inner()).unwrap();
    assert_eq!(log.subscriptions().len(), 1, "into_inner writes it");

    let dir = std::env::temp_dir().join(format!("ulog-drop-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("declared.ulg");
    {
        let mut w = Writer::create(&path, WriterOptions::default()).unwrap();
        w.topic::<EscStatus>(3).unwrap();
    }
    let log = Log::read(&path).unwrap();
    assert_eq!(log.subscriptions()[0].multi_id, 3, "drop writes it");
    std::fs::remove_dir_all(&dir).unwrap();

    // A parameter after a declared topic is a change, as it was when subscribing wrote at once.
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    w.parameter("BEFORE", crate::read::ParamValue::Int32(1))
        .unwrap();
    w.topic::<EscStatus>(0).unwrap();
    w.parameter("AFTER", crate::read::ParamValue::Int32(2))
        .unwrap();
    let log = Log::from_vec(w.into_inner()).unwrap();
    assert_eq!(log.metadata().initial_parameters().len(), 1);
    assert_eq!(log.parameter_changes()[0].name, "AFTER");
}

#[derive(ULog, Debug, PartialEq)]
#[ulog(name = "battery_status", widen)]
struct WideBattery {
    timestamp: u64,
    cell_count: i32,
    voltage_v: f64,
    cells: [u32; 2],
    temperature: Option<f64>,
}

#[test]
fn widened_fields_read_narrower_file_types_exactly() {
    // Newer PX4: uint8_t cell_count, float voltage; older: int32_t and double.
    let narrow = schema(&[
        "battery_status:uint64_t timestamp;float voltage_v;uint16_t[2] cells;uint8_t cell_count;int16_t temperature;",
    ]);
    let decoder = TypedDecoder::<WideBattery>::new(&narrow).unwrap();
    let mut row = 9u64.to_le_bytes().to_vec();
    row.extend_from_slice(&15.7f32.to_le_bytes());
    row.extend_from_slice(&65_535u16.to_le_bytes());
    row.extend_from_slice(&7u16.to_le_bytes());
    row.push(200);
    row.extend_from_slice(&(-40i16).to_le_bytes());
    assert_eq!(
        decoder.decode(&row),
        Some(WideBattery {
            timestamp: 9,
            cell_count: 200,
            voltage_v: f64::from(15.7f32),
            cells: [65_535, 7],
            temperature: Some(-40.0),
        })
    );
    let same = schema(&[
        "battery_status:uint64_t timestamp;int32_t cell_count;double voltage_v;uint32_t[2] cells;",
    ]);
    let decoder = TypedDecoder::<WideBattery>::new(&same).unwrap();
    let mut row = 1u64.to_le_bytes().to_vec();
    row.extend_from_slice(&(-3i32).to_le_bytes());
    row.extend_from_slice(&0.1f64.to_le_bytes());
    row.extend_from_slice(&u32::MAX.to_le_bytes());
    row.extend_from_slice(&0u32.to_le_bytes());
    let got = decoder.decode(&row).unwrap();
    assert_eq!(
        (got.cell_count, got.voltage_v, got.cells, got.temperature),
        (-3, 0.1, [u32::MAX, 0], None)
    );
}

#[test]
fn lossy_widening_is_refused_with_every_path() {
    let s = schema(&[
        "battery_status:uint64_t timestamp;uint32_t cell_count;int64_t voltage_v;int8_t[2] cells;",
    ]);
    let err = TypedDecoder::<WideBattery>::new(&s).unwrap_err();
    assert_eq!(
        err.to_string(),
        "battery_status: 3 differences between the file and struct WideBattery:\n  \
         cell_count is uint32_t in the file, i32 in struct WideBattery (not a lossless widening)\n  \
         voltage_v is int64_t in the file, f64 in struct WideBattery (not a lossless widening)\n  \
         cells is int8_t[2] in the file, [u32; 2] in struct WideBattery (not a lossless widening)"
    );
    // Without `widen` nothing but the same type is accepted.
    #[derive(ULog, Debug)]
    #[ulog(name = "battery_status")]
    struct Strict {
        timestamp: u64,
        #[ulog(widen)]
        cell_count: i32,
        voltage_v: f64,
    }
    let s = schema(&["battery_status:uint64_t timestamp;uint8_t cell_count;float voltage_v;"]);
    assert_eq!(
        TypedDecoder::<Strict>::new(&s).unwrap_err().to_string(),
        "battery_status: voltage_v is float in the file, f64 in struct Strict (every float \
         value fits in f64: `#[ulog(widen)]` on the field accepts it)"
    );
    // Writing a widened type writes its own, wider format.
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let sub = w.topic::<WideBattery>(0).unwrap();
    let value = WideBattery {
        timestamp: 4,
        cell_count: -1,
        voltage_v: 0.5,
        cells: [1, 2],
        temperature: Some(20.0),
    };
    w.write(&sub, &value).unwrap();
    let log = Log::from_vec(w.into_inner()).unwrap();
    assert_eq!(
        log.metadata()
            .schema()
            .get("battery_status")
            .unwrap()
            .to_string(),
        "battery_status:uint64_t timestamp;int32_t cell_count;double voltage_v;uint32_t[2] cells;double temperature;"
    );
    assert_eq!(
        log.topic::<WideBattery>()
            .unwrap()
            .instance(0)
            .unwrap()
            .next(),
        Some(value)
    );
}

#[derive(ULog, Debug, Clone, PartialEq)]
#[ulog(topics(
    "vehicle_attitude",
    "vehicle_attitude_groundtruth",
    "estimator_attitude"
))]
struct VehicleAttitude {
    timestamp: u64,
    q: [f32; 4],
    mode: crate::Char,
}

#[test]
fn one_type_reads_and_writes_every_topic_of_its_layout() {
    assert_eq!(
        VehicleAttitude::FORMAT.topics,
        [
            "vehicle_attitude",
            "vehicle_attitude_groundtruth",
            "estimator_attitude"
        ]
    );
    let value = |t| VehicleAttitude {
        timestamp: t,
        q: [1.0, 0.0, 0.0, t as f32],
        mode: crate::Char(b'M'),
    };
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let own = w.topic::<VehicleAttitude>(0).unwrap();
    let truth = w
        .topic_as::<VehicleAttitude>("vehicle_attitude_groundtruth", 0)
        .unwrap();
    let est = w
        .topic_as::<VehicleAttitude>("estimator_attitude", 1)
        .unwrap();
    w.write(&own, &value(1)).unwrap();
    w.write(&truth, &value(2)).unwrap();
    w.write(&est, &value(3)).unwrap();
    let bytes = w.into_inner();
    let log = Log::from_slice(&bytes).unwrap();
    assert_eq!(
        log.metadata()
            .schema()
            .get("estimator_attitude")
            .unwrap()
            .to_string(),
        "estimator_attitude:uint64_t timestamp;float[4] q;char mode;"
    );
    let read = |topic: &str, multi_id| -> Vec<VehicleAttitude> {
        log.topic_as::<VehicleAttitude>(topic)
            .unwrap()
            .instance(multi_id)
            .unwrap()
            .collect()
    };
    assert_eq!(read("vehicle_attitude", 0), [value(1)]);
    assert_eq!(read("vehicle_attitude_groundtruth", 0), [value(2)]);
    assert_eq!(read("estimator_attitude", 1), [value(3)]);
    let topic = log
        .topic_as::<VehicleAttitude>("estimator_attitude")
        .unwrap();
    assert_eq!(topic.name(), "estimator_attitude");
    assert_eq!(
        topic.instance(0).unwrap_err().to_string(),
        "`estimator_attitude` has no instance 0 in the file (instances: [1])"
    );
    // The dynamic reader sees the `char` as its byte.
    let row = log
        .rows(log.subscription("estimator_attitude", 1).unwrap())
        .next()
        .unwrap();
    assert_eq!(
        row.value().unwrap().field("mode").unwrap().as_scalar(),
        Some(crate::Scalar::Char(b'M'))
    );
    // Streaming, under the other name too.
    let mut reader = StreamReader::new(&bytes[..]).unwrap();
    let mut decoded = Vec::new();
    let mut decoder = None;
    while let Some(event) = reader.next_event().unwrap() {
        match event {
            Event::Subscription(s) if s.name == "vehicle_attitude_groundtruth" => {
                decoder = Some(
                    reader
                        .typed_as::<VehicleAttitude>("vehicle_attitude_groundtruth")
                        .unwrap(),
                );
            }
            Event::Row(row) => decoded.extend(decoder.as_ref().and_then(|d| d.decode_row(&row))),
            _ => {}
        }
    }
    assert_eq!(decoded, [value(2)]);
    // Checked like the type's own name: a different layout under the other name is refused.
    let s = schema(&["estimator_attitude:uint64_t timestamp;float[3] q;char mode;"]);
    assert_eq!(
        TypedDecoder::<VehicleAttitude>::new_as(&s, "estimator_attitude")
            .unwrap_err()
            .to_string(),
        "estimator_attitude: q is float[3] in the file, [f32; 4] in struct VehicleAttitude"
    );
}

#[test]
fn chars_from_text_checked_or_cut_at_a_character() {
    use std::str::FromStr;
    let exact: Chars<4> = "auto".parse().unwrap();
    assert_eq!(exact.as_bytes(), b"auto");
    assert_eq!(Chars::<4>::from_str("au").unwrap().as_bytes(), b"au\0\0");
    let err = Chars::<4>::from_str("abcé").unwrap_err();
    assert_eq!((err.len, err.capacity), (5, 4));
    // `From` keeps what fits and never splits a character: "é" is two bytes.
    assert_eq!(Chars::<4>::from("abcé").as_bytes(), b"abc\0");
    assert_eq!(Chars::<5>::from("abcé").as_str(), Ok("abcé"));
    assert_eq!(format!("{}", Chars::<8>::from("rover")), "rover");
}

/// A stream's decoder made before the topic's format is read says the definitions are not
/// all read yet (not that the file lacks the format); made at the topic's subscription, it
/// works; and a topic the file lacks is still "the file has no format" once the definitions
/// are read.
#[test]
fn a_streams_decoder_made_too_early_says_the_definitions_are_not_read() {
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    w.format("other:uint64_t timestamp;").unwrap();
    let sub = w.topic::<EscStatus>(0).unwrap();
    let status = EscStatus {
        timestamp: 5,
        esc_count: 2,
        esc: [EscReport::default(); 2],
        _pad: [0; 7],
    };
    w.write(&sub, &status).unwrap();
    let bytes = w.into_inner();
    let mut reader = StreamReader::new(&bytes[..]).unwrap();
    // The first definition only: `other`.
    while reader.metadata().schema().formats().is_empty() {
        reader.next_event().unwrap().expect("a definition");
    }
    let err = reader.typed::<EscStatus>().unwrap_err();
    assert_eq!(
        err.to_string(),
        "no format `esc_status` (wanted by struct EscStatus) among the 1 read so far: the \
         stream's definitions are not all read yet (make the decoder at the topic's \
         `Event::Subscription`)"
    );
    let mut decoded = Vec::new();
    let mut decoder = None;
    while let Some(event) = reader.next_event().unwrap() {
        match event {
            Event::Subscription(s) if s.name == "esc_status" => {
                decoder = Some(reader.typed::<EscStatus>().unwrap());
                let err = reader.typed::<VehicleGpsPosition>().unwrap_err();
                assert_eq!(
                    err.to_string(),
                    "the file has no format `vehicle_gps_position` (wanted by struct \
                     VehicleGpsPosition)"
                );
            }
            Event::Row(row) => decoded.extend(decoder.as_ref().unwrap().decode_row(&row)),
            _ => {}
        }
    }
    assert_eq!(decoded, [status]);
}

/// A struct that reads a file's `char` or `char[N]` as bytes is told the types that read them.
#[test]
fn bytes_for_chars_are_told_char_and_chars() {
    #[derive(ULog, Debug)]
    struct Label {
        timestamp: u64,
        name: [u8; 6],
        mark: u8,
    }
    let s = schema(&["label:uint64_t timestamp;char[6] name;char mark;"]);
    let err = TypedDecoder::<Label>::new(&s).unwrap_err();
    assert_eq!(
        err.to_string(),
        "label: 2 differences between the file and struct Label:\n  \
         name is char[6] in the file, [u8; 6] in struct Label (`char[6]` text is read by \
         `ulog_runtime::Chars<6>`)\n  \
         mark is char in the file, u8 in struct Label (a `char` is read by \
         `ulog_runtime::Char`)"
    );
}

/// A nested field that is one struct in the file and an array in the struct: its nested
/// differences are listed too, at paths without `[]` (the file's field is no array).
#[test]
fn nested_differences_of_a_single_nested_field_have_no_brackets() {
    let s = schema(&[
        "esc_status:uint64_t timestamp;uint8_t esc_count;esc_report esc;",
        "esc_report:float esc_rpm;float esc_voltage;",
    ]);
    let err = TypedDecoder::<EscStatus>::new(&s).unwrap_err();
    assert_eq!(
        err.to_string(),
        "esc_status: 2 differences between the file and struct EscStatus:\n  \
         esc is esc_report in the file, [EscReport; 2] in struct EscStatus\n  \
         esc.esc_rpm is float in the file, i32 in struct EscReport"
    );
}
