//! The rewriter on logs made by the writer and laid out by hand, read back by the reader.

use super::*;
use crate::read::{Message, ParamValue};
use crate::{Chars, Log, LogLevel, ULog, Writer, WriterOptions};

#[derive(ULog, Clone, Copy)]
struct Cell {
    v: f32,
    #[ulog(padding)]
    _pad: [u8; 4],
}

#[derive(ULog)]
#[ulog(name = "battery_status")]
struct Battery {
    timestamp: u64,
    voltage_v: f32,
    cells: [Cell; 2],
    id: Chars<4>,
}

#[derive(ULog)]
#[ulog(name = "vehicle_gps_position")]
struct Gps {
    timestamp: u64,
    time_utc_usec: u64,
    lat: i32,
    lon: i32,
    alt: i32,
    satellites_used: u8,
}

#[derive(ULog)]
#[ulog(name = "vehicle_global_position")]
struct Global {
    timestamp: u64,
    lat: f64,
    lon: f64,
    alt: f32,
}

/// A log over 10 s: battery at 1 Hz (two instances), GPS at 5 Hz, a logged string and a
/// parameter change every second, a dropout and syncs.
fn flight() -> Vec<u8> {
    let mut w = Writer::new(
        Vec::new(),
        WriterOptions {
            start_timestamp: 0,
            default_parameters: true,
        },
    )
    .unwrap();
    let text = |s: &str| Value::String(s.to_owned());
    w.info("sys_name", &text("PX4")).unwrap();
    w.info("sys_uuid", &text("0123456789abcdef")).unwrap();
    w.info("time_ref_utc", &Value::Scalar(crate::Scalar::Int32(3600)))
        .unwrap();
    w.multi_info("boot_console_output", &text("serial 42"), false)
        .unwrap();
    w.parameter("BAT_N_CELLS", ParamValue::Int32(4)).unwrap();
    w.parameter("MC_ROLL_P", ParamValue::Float(6.5)).unwrap();
    w.default_parameter("MC_ROLL_P", ParamValue::Float(6.0), 1)
        .unwrap();
    // A format no topic uses.
    w.format("unused:uint64_t timestamp;uint8_t x;").unwrap();
    let b0 = w.topic::<Battery>(0).unwrap();
    let b1 = w.topic::<Battery>(1).unwrap();
    let gps = w.topic::<Gps>(0).unwrap();
    let global = w.topic::<Global>(0).unwrap();
    for i in 0..50u64 {
        let t = i * 200_000;
        if i % 5 == 0 {
            let s = i / 5;
            let battery = Battery {
                timestamp: t,
                voltage_v: 16.0 - s as f32 / 10.0,
                cells: [Cell {
                    v: 4.0,
                    _pad: [0; 4],
                }; 2],
                id: Chars::from("B0"),
            };
            w.write(&b0, &battery).unwrap();
            w.write(
                &b1,
                &Battery {
                    id: Chars::from("B1"),
                    ..battery
                },
            )
            .unwrap();
            w.log(LogLevel::Info, t + 1, &format!("second {s}"))
                .unwrap();
            w.parameter("MC_ROLL_P", ParamValue::Float(6.5 + s as f32))
                .unwrap();
            w.sync().unwrap();
        }
        // 47.397742 N, 8.545594 E moving north-east, about 1 m a row.
        let (lat, lon) = (473_977_420 + i as i32 * 90, 85_455_940 + i as i32 * 130);
        w.write(
            &gps,
            &Gps {
                timestamp: t + 10,
                time_utc_usec: 1_556_195_400_000_000 + t,
                lat,
                lon,
                alt: 488_123,
                satellites_used: 12,
            },
        )
        .unwrap();
        w.write(
            &global,
            &Global {
                timestamp: t + 20,
                lat: f64::from(lat) * 1e-7,
                lon: f64::from(lon) * 1e-7,
                alt: 488.1,
            },
        )
        .unwrap();
    }
    w.dropout(25).unwrap();
    w.log(
        LogLevel::Info,
        9_999_000,
        "file /fs/microsd/log/2019-04-25/12_30_00.ulg",
    )
    .unwrap();
    w.into_inner()
}

fn rewrite(rules: Rewrite, input: &[u8]) -> (Vec<u8>, Report) {
    let mut rules = rules;
    let mut out = Vec::new();
    let report = rules.run(input, &mut out).unwrap();
    (out, report)
}

/// Every message of a file (type and payload), in order, as the framer finds them.
fn messages(bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
    let mut reader = StreamReader::new(bytes).unwrap();
    let mut out = Vec::new();
    while reader.next_event().unwrap().is_some() {
        if let Some(m) = reader.message() {
            out.push((m.ty, m.payload.to_vec()));
        }
    }
    out
}

#[test]
fn without_rules_a_log_comes_out_byte_for_byte() {
    let input = flight();
    let (out, report) = rewrite(Rewrite::new(), &input);
    assert!(out == input, "byte for byte");
    assert_eq!(report.bytes_in, input.len() as u64);
    assert_eq!(report.bytes_out, input.len() as u64);
    assert!(report.skipped.is_empty());
    assert_eq!(report.topics.len(), 4);
    assert!(report.topics.iter().all(|t| t.rows_in == t.rows_out));
}

/// A window no row lies in (given in the wrong clock, say) writes no row, and the report
/// says where the rows of the topics kept lie, as `ulog cut` and `ulog csv` say it; a window
/// with rows says nothing of it.
#[test]
fn a_window_no_row_lies_in_is_said_with_where_the_rows_lie() {
    let input = flight();
    let whole = Log::from_slice(&input).unwrap();
    let times: Vec<u64> = whole.data().map(|r| r.timestamp).collect();
    let (first, last) = (*times.iter().min().unwrap(), *times.iter().max().unwrap());
    let (_, report) = rewrite(
        Rewrite::new().window(Window::seconds(Some(1000.0), Some(2000.0)).unwrap()),
        &input,
    );
    assert_eq!(report.rows().1, 0);
    assert_eq!(report.window_missed(), Some((first, last)));
    let text = report.to_string();
    let line = format!(
        "  no row of the topics kept lies in the window from 1000 s to 2000 s: their rows run \
         from {} s to {} s\n",
        first as f64 / 1e6,
        last as f64 / 1e6
    );
    assert!(text.contains(&line), "{text}");
    let (_, report) = rewrite(
        Rewrite::new().window(Window::seconds(Some(3.0), Some(6.0)).unwrap()),
        &input,
    );
    assert_eq!(report.window_missed(), None);
    assert!(!report.to_string().contains("no row"), "{report}");
}

#[test]
fn a_window_keeps_its_rows_strings_and_changes_and_the_parameters_in_force() {
    let input = flight();
    let (out, report) = rewrite(
        Rewrite::new().window(Window::seconds(Some(3.0), Some(6.0)).unwrap()),
        &input,
    );
    // Each instance's span of rows read is the input's (what `ulog cut` says of a window
    // no row lies in).
    let whole = Log::from_slice(&input).unwrap();
    for t in &report.topics {
        let times: Vec<u64> = whole
            .data()
            .filter(|r| r.subscription.name == t.name && r.subscription.multi_id == t.multi_id)
            .map(|r| r.timestamp)
            .collect();
        let span = times.iter().min().copied().zip(times.iter().max().copied());
        assert!(span.is_some());
        assert_eq!(t.span_in, span, "{}", t.name);
    }
    let log = Log::from_vec(out).unwrap();
    assert!(log.diagnostics().is_empty(), "{:?}", log.diagnostics());
    let times = |topic: &str| -> Vec<u64> {
        log.columns(topic, 0)
            .unwrap()
            .get("timestamp")
            .unwrap()
            .as_uint64()
            .unwrap()
            .to_vec()
    };
    assert_eq!(times("battery_status"), [3_000_000, 4_000_000, 5_000_000]);
    let gps = times("vehicle_gps_position");
    assert_eq!(
        (gps[0], *gps.last().unwrap(), gps.len()),
        (3_000_010, 5_800_010, 15)
    );
    let texts: Vec<&str> = log
        .logged_messages()
        .iter()
        .map(|m| m.text.as_str())
        .collect();
    assert_eq!(texts, ["second 3", "second 4", "second 5"]);
    // The changes before the window are the initial values; the later ones stay changes.
    let p = |name: &str| log.metadata().parameter(name);
    assert_eq!(p("MC_ROLL_P"), Some(ParamValue::Float(6.5 + 2.0)));
    assert_eq!(p("BAT_N_CELLS"), Some(ParamValue::Int32(4)));
    let changes: Vec<f64> = log
        .parameter_changes()
        .iter()
        .map(|c| c.value.as_f64())
        .collect();
    assert_eq!(changes, [9.5, 10.5, 11.5]);
    assert_eq!(report.parameter_changes, (3, 3, 4));
    assert_eq!(report.logged, (3, 8));
    assert!(
        log.metadata().default_parameters().len() == 1,
        "defaults kept"
    );
    assert_eq!(log.dropouts().len(), 0, "the dropout is after the window");
}

#[test]
fn subscriptions_without_rows_in_the_window_are_not_written() {
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let early = w.topic::<Battery>(0).unwrap();
    let late = w.topic::<Global>(0).unwrap();
    let cells = [Cell {
        v: 4.0,
        _pad: [0; 4],
    }; 2];
    for t in 0..10u64 {
        let b = Battery {
            timestamp: t,
            voltage_v: 1.0,
            cells,
            id: Chars::from("x"),
        };
        w.write(&early, &b).unwrap();
    }
    w.write(
        &late,
        &Global {
            timestamp: 100,
            lat: 1.0,
            lon: 2.0,
            alt: 3.0,
        },
    )
    .unwrap();
    let input = w.into_inner();
    let window = Window {
        start_us: Some(50.0),
        end_us: None,
    };
    let (out, report) = rewrite(Rewrite::new().window(window), &input);
    let log = Log::from_vec(out).unwrap();
    let names: Vec<&str> = log
        .subscriptions()
        .iter()
        .map(|s| s.name.as_str())
        .collect();
    assert_eq!(names, ["vehicle_global_position"]);
    assert_eq!(
        report.subscriptions_dropped,
        [("battery_status".to_owned(), 0)]
    );
    // Formats stay: only topic rules drop them.
    assert!(log.metadata().schema().get("battery_status").is_some());
}

#[test]
fn topic_rules_drop_subscriptions_rows_and_formats_nothing_nests() {
    let input = flight();
    let (out, report) = rewrite(
        Rewrite::new().exclude(&["battery_status", "vehicle_gps_position"]),
        &input,
    );
    let log = Log::from_vec(out).unwrap();
    let schema = log.metadata().schema();
    assert!(schema.get("battery_status").is_none());
    assert!(schema.get("vehicle_gps_position").is_none());
    // Nested by the dropped topic only, but not excluded: a topic of that name could
    // follow (a stream's later subscription), and would need it.
    assert!(schema.get("cell").is_some());
    assert!(log.subscription("battery_status", 0).is_none());
    assert_eq!(log.row_count(), 50);
    assert!(
        report
            .formats_dropped
            .contains(&"battery_status".to_owned())
    );
    // The report says which instances the rules kept.
    let kept: Vec<(&str, bool)> = report
        .topics
        .iter()
        .map(|t| (t.name.as_str(), t.kept))
        .collect();
    assert!(kept.contains(&("battery_status", false)), "{kept:?}");
    assert!(
        kept.iter()
            .all(|&(n, k)| k != ["battery_status", "vehicle_gps_position"].contains(&n)),
        "{kept:?}"
    );
    // Only these topics: what they nest stays, the rest goes.
    let (out, report) = rewrite(Rewrite::new().topics(&["battery_status"]), &input);
    let log = Log::from_vec(out).unwrap();
    let mut names: Vec<String> = log
        .metadata()
        .schema()
        .formats()
        .iter()
        .map(|f| f.name.clone())
        .collect();
    names.sort();
    assert_eq!(names, ["battery_status", "cell"]);
    assert_eq!(log.row_count(), 20);
    assert_eq!(
        report.formats_dropped,
        ["unused", "vehicle_gps_position", "vehicle_global_position"]
    );
    assert_eq!(log.logged_messages().len(), 11, "strings are not topics");
}

#[test]
fn info_values_are_dropped_or_replaced() {
    let input = flight();
    let (out, report) = rewrite(
        Rewrite::new()
            .drop_info("sys_uuid")
            .drop_info("boot_console_output")
            .replace_info("sys_name", Value::String("rover".into())),
        &input,
    );
    let log = Log::from_vec(out).unwrap();
    let meta = log.metadata();
    assert!(meta.info_value("sys_uuid").is_none());
    assert!(meta.multi_info().is_empty());
    assert_eq!(
        meta.info_value("sys_name"),
        Some(&Value::String("rover".into()))
    );
    assert_eq!(report.info_replaced, ["sys_name"]);
    assert_eq!(report.info_dropped, ["sys_uuid", "boot_console_output"]);
    assert_eq!(
        log.row_count(),
        Log::from_slice(&input).unwrap().row_count()
    );
}

#[test]
fn typed_and_field_transforms_write_back_into_the_files_layout() {
    // A type of a few fields, in another order: the others stay as they were.
    #[derive(ULog)]
    #[ulog(name = "battery_status")]
    struct Cells {
        timestamp: u64,
        cells: [Cell; 2],
    }
    let input = flight();
    let (out, report) = rewrite(
        Rewrite::new()
            .map(|b: &mut Cells| b.cells[1].v = 3.25)
            .map_rows("vehicle_global_position", |row| {
                let alt = row.get("alt").unwrap().as_f64();
                row.set_f64("alt", alt + 1.0).unwrap();
                assert!(matches!(
                    row.set_f64("alt_nope", 1.0),
                    Err(FieldError::NoSuchField { .. })
                ));
            }),
        &input,
    );
    let before = Log::from_slice(&input).unwrap();
    let after = Log::from_vec(out).unwrap();
    let b0 = after.columns("battery_status", 0).unwrap();
    assert!(
        b0.get("cells[1].v")
            .unwrap()
            .as_float()
            .unwrap()
            .iter()
            .all(|&v| v == 3.25)
    );
    assert!(
        b0.get("cells[0].v")
            .unwrap()
            .as_float()
            .unwrap()
            .iter()
            .all(|&v| v == 4.0)
    );
    assert_eq!(
        b0.get("voltage_v"),
        before
            .columns("battery_status", 0)
            .unwrap()
            .get("voltage_v")
    );
    let alt = after.columns("vehicle_global_position", 0).unwrap();
    assert!(
        alt.get("alt")
            .unwrap()
            .as_float()
            .unwrap()
            .iter()
            .all(|&a| a == 489.1)
    );
    let changed: Vec<(String, usize)> = report
        .topics
        .iter()
        .map(|t| (t.name.clone(), t.rows_changed))
        .collect();
    assert!(changed.contains(&("battery_status".into(), 10)));
    assert!(changed.contains(&("vehicle_gps_position".into(), 0)));
    // A type that does not fit the file's format is refused at the topic's first row.
    #[derive(ULog)]
    #[ulog(name = "battery_status")]
    struct Wrong {
        timestamp: u64,
        voltage_v: f64,
    }
    let mut out = Vec::new();
    let err = Rewrite::new()
        .map(|_: &mut Wrong| {})
        .run(&input[..], &mut out)
        .unwrap_err();
    assert!(
        err.to_string()
            .contains("voltage_v is float in the file, f64 in struct Wrong"),
        "{err}"
    );
}

#[test]
fn appended_data_comes_out_as_one_data_section() {
    let dir = std::env::temp_dir().join(format!("ulog-rewrite-append-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("a.ulg");
    std::fs::write(&path, flight()).unwrap();
    {
        let mut w = Writer::append(&path).unwrap();
        w.log(LogLevel::Warning, 11_000_000, "appended").unwrap();
    }
    let input = std::fs::read(&path).unwrap();
    let (out, _) = rewrite(Rewrite::new(), &input);
    let (a, b) = (
        Log::from_slice(&input).unwrap(),
        Log::from_slice(&out).unwrap(),
    );
    assert!(a.flag_bits().unwrap().has_data_appended());
    assert!(!b.flag_bits().unwrap().has_data_appended());
    assert_eq!(a.row_count(), b.row_count());
    // The same messages, at other offsets.
    let mut moved = b.logged_messages().to_vec();
    for (x, y) in moved.iter_mut().zip(a.logged_messages()) {
        x.offset = y.offset;
    }
    assert_eq!(a.logged_messages(), &moved[..]);
    assert_eq!(moved.last().unwrap().text, "appended");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_damaged_log_rewrites_what_the_reader_recovers() {
    let mut input = flight();
    let n = input.len();
    // Garbage in the middle, and a cut tail.
    input.splice(n / 2..n / 2, [0xFFu8, 0x13, 0x00, 0x42, 0x99]);
    input.truncate(n - 7);
    let read = Log::from_slice(&input).unwrap();
    let (out, report) = rewrite(Rewrite::new(), &input);
    let back = Log::from_slice(&out).unwrap();
    assert!(back.diagnostics().is_empty(), "the output is clean");
    assert_eq!(back.row_count(), read.row_count());
    assert!(report.skipped.damaged_bytes >= 5, "{:?}", report.skipped);
}

#[test]
fn a_version_0_log_comes_out_as_version_1_with_its_messages() {
    let mut bytes = crate::read::FileHeader {
        version: 0,
        start_timestamp: 5,
    }
    .to_bytes()
    .to_vec();
    let msg = |m: Message<'_>, b: &mut Vec<u8>| m.encode(b).unwrap();
    msg(
        Message::Format(b"t:uint32_t timestamp;float x;"),
        &mut bytes,
    );
    msg(
        Message::Subscribe {
            multi_id: 0,
            msg_id: 3,
            name: b"t",
        },
        &mut bytes,
    );
    for ms in [1u32, 2, 3] {
        let mut row = ms.to_le_bytes().to_vec();
        row.extend_from_slice(&1.5f32.to_le_bytes());
        msg(
            Message::Data {
                msg_id: 3,
                data: &row,
            },
            &mut bytes,
        );
    }
    let (out, _) = rewrite(Rewrite::new(), &bytes);
    let log = Log::from_slice(&out).unwrap();
    assert_eq!(log.header().version, 1);
    assert!(log.flag_bits().is_some());
    assert_eq!(
        messages(&out)[1..],
        messages(&bytes)[..],
        "every message kept"
    );
}

#[test]
fn anonymizing_moves_positions_keeps_distances_and_hides_times_and_identifiers() {
    let input = flight();
    let (out, report) = rewrite(Rewrite::new().anonymize(Anonymize::seed(7)), &input);
    let (a, b) = (
        Log::from_slice(&input).unwrap(),
        Log::from_slice(&out).unwrap(),
    );
    let a_report = report.anonymized.as_ref().unwrap();
    let target = a_report.target.unwrap();
    let global = |log: &Log<'_>| -> Vec<(f64, f64)> {
        let c = log.columns("vehicle_global_position", 0).unwrap();
        let lat = c.get("lat").unwrap().as_double().unwrap().to_vec();
        let lon = c.get("lon").unwrap().as_double().unwrap().to_vec();
        lat.into_iter().zip(lon).collect()
    };
    let (pa, pb) = (global(&a), global(&b));
    assert!((pb[0].0 - target.0).abs() < 1e-6 && (pb[0].1 - target.1).abs() < 1e-6);
    let dist = |p: (f64, f64), q: (f64, f64)| {
        let (p1, q1) = (p.0.to_radians(), q.0.to_radians());
        let h = ((q1 - p1) / 2.0).sin().powi(2)
            + p1.cos() * q1.cos() * ((q.1 - p.1).to_radians() / 2.0).sin().powi(2);
        2.0 * 6_371_000.0 * h.sqrt().asin()
    };
    for i in 1..pa.len() {
        let (d0, d1) = (dist(pa[i - 1], pa[i]), dist(pb[i - 1], pb[i]));
        assert!((d0 - d1).abs() < 1e-3, "{i}: {d0} vs {d1}");
    }
    // No original position or time is left in the file's bytes.
    let found = |needle: &[u8]| out.windows(needle.len()).any(|w| w == needle);
    let gps = a.columns("vehicle_gps_position", 0).unwrap();
    for &lat in gps.get("lat").unwrap().as_int32().unwrap() {
        assert!(!found(&lat.to_le_bytes()), "{lat}");
    }
    for &(lat, lon) in &pa {
        assert!(!found(&lat.to_le_bytes()) && !found(&lon.to_le_bytes()));
    }
    for &t in gps.get("time_utc_usec").unwrap().as_uint64().unwrap() {
        assert!(!found(&t.to_le_bytes()), "{t}");
    }
    assert!(!found(b"2019-04-25") && !found(b"12_30_00"));
    assert!(!found(b"0123456789abcdef") && !found(b"serial 42"));
    let meta = b.metadata();
    assert!(meta.info_value("sys_uuid").is_none());
    assert_eq!(
        meta.info_value("time_ref_utc"),
        Some(&Value::Scalar(crate::Scalar::Int32(0))),
        "the time zone"
    );
    assert!(meta.multi_info().is_empty());
    // Altitudes moved by one offset; everything else as it was.
    let alt = |log: &Log<'_>| -> Vec<i32> {
        let c = log.columns("vehicle_gps_position", 0).unwrap();
        c.get("alt").unwrap().as_int32().unwrap().to_vec()
    };
    let offset = a_report.altitude_offset_m;
    assert!(offset != 0.0);
    assert!(
        alt(&a)
            .iter()
            .zip(alt(&b))
            .all(|(x, y)| f64::from(y - x) == offset * 1000.0)
    );
    assert_eq!(
        a.columns("battery_status", 1).unwrap(),
        b.columns("battery_status", 1).unwrap()
    );
    let fields: Vec<(&str, &str, usize)> = a_report
        .fields
        .iter()
        .map(|(t, f, n)| (t.as_str(), f.as_str(), *n))
        .collect();
    assert!(
        fields.contains(&("vehicle_gps_position", "lat/lon", 50)),
        "{fields:?}"
    );
    assert!(fields.contains(&("vehicle_gps_position", "time_utc_usec", 50)));
    assert!(fields.contains(&("vehicle_global_position", "alt", 50)));
    // The same seed, the same output.
    assert_eq!(
        rewrite(Rewrite::new().anonymize(Anonymize::seed(7)), &input).0,
        out
    );
    // An origin: the first position goes there.
    let (out, _) = rewrite(
        Rewrite::new().anonymize(Anonymize::origin(-33.9, 151.2)),
        &input,
    );
    let first = global(&Log::from_slice(&out).unwrap())[0];
    assert!((first.0 + 33.9).abs() < 1e-9 && (first.1 - 151.2).abs() < 1e-9);
}

#[test]
fn the_output_is_never_the_input() {
    let dir = std::env::temp_dir().join(format!("ulog-rewrite-same-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("in.ulg");
    std::fs::write(&path, flight()).unwrap();
    let err = Rewrite::new()
        .run_file(&path, &dir.join(".").join("in.ulg"))
        .unwrap_err();
    assert!(matches!(err, RewriteError::SameFile(_)), "{err}");
    assert_eq!(std::fs::read(&path).unwrap(), flight(), "untouched");
    let report = Rewrite::new()
        .run_file(&path, &dir.join("out.ulg"))
        .unwrap();
    assert_eq!(std::fs::read(dir.join("out.ulg")).unwrap(), flight());
    assert_eq!(report.bytes_out, flight().len() as u64);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_output_file_gets_its_folder_and_a_folder_in_its_place_is_an_error() {
    let dir = std::env::temp_dir().join(format!("ulog-rewrite-out-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("a_folder")).unwrap();
    let path = dir.join("in.ulg");
    std::fs::write(&path, flight()).unwrap();
    // A folder where the file should go: an error naming it, and nothing left inside.
    let err = Rewrite::new()
        .run_file(&path, &dir.join("a_folder"))
        .unwrap_err();
    assert!(
        matches!(&err, RewriteError::Output { path, .. } if path.ends_with("a_folder")),
        "{err}"
    );
    assert_eq!(std::fs::read_dir(dir.join("a_folder")).unwrap().count(), 0);
    assert!(
        !dir.join("a_folder.partial").exists(),
        "no partial file left"
    );
    // A file where its folder should be: an error naming the output.
    std::fs::write(dir.join("a_file"), b"x").unwrap();
    let err = Rewrite::new()
        .run_file(&path, &dir.join("a_file").join("out.ulg"))
        .unwrap_err();
    assert!(
        err.to_string().contains("a_file` is a file, not a folder"),
        "{err}"
    );
    // A folder that does not exist yet is made.
    let nested = dir.join("new").join("deeper").join("out.ulg");
    Rewrite::new().run_file(&path, &nested).unwrap();
    assert_eq!(std::fs::read(&nested).unwrap(), flight());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_subscription_of_an_undefined_format_is_dropped_and_said() {
    // A fuzzer's find: a subscription naming a format the log never defines, kept as it was,
    // made the output a log that does not read clean. A new user's: the rows of a
    // subscription that cannot be read (its format undefined, or nesting a type no format
    // defines) were written without their subscription, rows of no subscription.
    let mut bytes = hand_built(&[
        b"t:uint64_t timestamp;float x;",
        b"broken:uint64_t timestamp;flxat x;",
    ]);
    let msg = |m: Message<'_>, b: &mut Vec<u8>| m.encode(b).unwrap();
    for (msg_id, name) in [(0u16, &b"t"[..]), (1, b"nowhere"), (2, b"broken")] {
        msg(
            Message::Subscribe {
                multi_id: 0,
                msg_id,
                name,
            },
            &mut bytes,
        );
    }
    let mut row = 7u64.to_le_bytes().to_vec();
    row.extend_from_slice(&1.5f32.to_le_bytes());
    for msg_id in [0, 1, 2, 1, 2] {
        msg(Message::Data { msg_id, data: &row }, &mut bytes);
    }
    let input = Log::from_slice(&bytes).unwrap();
    assert!(
        !input.diagnostics().is_empty(),
        "the input says what is odd"
    );
    let (out, report) = rewrite(Rewrite::new(), &bytes);
    let back = Log::from_slice(&out).unwrap();
    assert!(back.diagnostics().is_empty(), "{:?}", back.diagnostics());
    assert_eq!(back.row_count(), 1);
    assert_eq!(back.data().count(), 1);
    assert_eq!(
        report.subscriptions_dropped,
        [("nowhere".to_owned(), 0), ("broken".to_owned(), 0)]
    );
    // Said in the report, with why.
    let text = report.to_string();
    assert!(
        text.contains(
            "  `broken` (msg_id 2) cannot be read, left out with its rows: broken.x: type `flxat`"
        ),
        "{text}"
    );
    assert!(
        text.contains("  `nowhere` (msg_id 1) cannot be read, left out with its rows: no format named `nowhere`"),
        "{text}"
    );
}

#[test]
fn the_report_names_a_few_dropped_subscriptions_and_formats_and_counts_the_rest() {
    let report = |n: u8| Report {
        subscriptions_dropped: (0..n).map(|m| ("t".to_owned(), m)).collect(),
        formats_dropped: (0..n).map(|m| format!("f{m}")).collect(),
        ..Report::default()
    };
    let formats = report(9).to_string();
    assert!(
        formats
            .lines()
            .any(|l| l == "formats not written: f0, f1, f2, f3, f4, f5, f6, f7 and 1 more"),
        "{formats}"
    );
    let line = |r: Report| {
        r.to_string()
            .lines()
            .find(|l| l.starts_with("subscriptions not written: "))
            .unwrap()
            .to_owned()
    };
    assert_eq!(
        line(report(8)),
        "subscriptions not written: t #0, t #1, t #2, t #3, t #4, t #5, t #6, t #7"
    );
    assert_eq!(
        line(report(72)),
        "subscriptions not written: t #0, t #1, t #2, t #3, t #4, t #5, t #6, t #7 and 64 more"
    );
}

#[test]
fn a_topic_subscribed_again_on_its_msg_id_is_written_once() {
    // A fuzzer's find: a file whose subscriptions repeat (spliced), kept as it was, made an
    // output that reads as damage ("msg_id 0 subscribed again").
    let mut bytes = hand_built(&[
        b"t:uint64_t timestamp;float x;",
        b"u:uint64_t timestamp;float y;",
    ]);
    let msg = |m: Message<'_>, b: &mut Vec<u8>| m.encode(b).unwrap();
    let subscribe = |b: &mut Vec<u8>, name: &[u8]| {
        msg(
            Message::Subscribe {
                multi_id: 0,
                msg_id: 0,
                name,
            },
            b,
        )
    };
    let data = |b: &mut Vec<u8>, t: u64| {
        let mut row = t.to_le_bytes().to_vec();
        row.extend_from_slice(&1.5f32.to_le_bytes());
        msg(
            Message::Data {
                msg_id: 0,
                data: &row,
            },
            b,
        );
    };
    subscribe(&mut bytes, b"t");
    data(&mut bytes, 1);
    subscribe(&mut bytes, b"t");
    data(&mut bytes, 2);
    let input = Log::from_slice(&bytes).unwrap();
    assert_eq!(input.diagnostics().len(), 1, "{:?}", input.diagnostics());
    let (out, _) = rewrite(Rewrite::new(), &bytes);
    let back = Log::from_slice(&out).unwrap();
    assert!(back.diagnostics().is_empty(), "{:?}", back.diagnostics());
    let times: Vec<u64> = back.data().map(|r| r.timestamp).collect();
    assert_eq!(times, [1, 2]);
    assert_eq!(
        rewrite(Rewrite::new(), &out).0,
        out,
        "and rewrites to itself"
    );
    // Another topic on the msg_id: written as the input has it (its rows are `u`'s).
    subscribe(&mut bytes, b"u");
    data(&mut bytes, 3);
    let (out, _) = rewrite(Rewrite::new(), &bytes);
    let back = Log::from_slice(&out).unwrap();
    let names: Vec<&str> = back.data().map(|r| r.subscription.name.as_str()).collect();
    assert_eq!(names, ["t", "t", "u"]);
    assert_eq!(back.diagnostics().len(), 1, "{:?}", back.diagnostics());
}

/// A version-1 header (start 0) and these formats, as hand-built bytes.
#[test]
fn a_format_and_an_info_kept_despite_a_note_are_written() {
    // A fuzzer's find: the stream reader gave a format outside the grammar (kept, as pyulog
    // reads it) as a diagnostic only, so the rewrite wrote its subscription without it and
    // the output read as damage; an info value kept as far as it goes was dropped the same way.
    let mut bytes = hand_built(&[b"t:uint64_t timestamp;float a-b;"]);
    let msg = |m: Message<'_>, b: &mut Vec<u8>| m.encode(b).unwrap();
    msg(
        Message::Info(crate::read::KeyValue {
            key: b"char[4] sys_name",
            value: b"\xffab\xfe",
        }),
        &mut bytes,
    );
    msg(
        Message::Subscribe {
            multi_id: 0,
            msg_id: 0,
            name: b"t",
        },
        &mut bytes,
    );
    for t in [1u64, 2] {
        let mut row = t.to_le_bytes().to_vec();
        row.extend_from_slice(&2.5f32.to_le_bytes());
        msg(
            Message::Data {
                msg_id: 0,
                data: &row,
            },
            &mut bytes,
        );
    }
    let input = Log::from_slice(&bytes).unwrap();
    let notes: Vec<String> = input
        .diagnostics()
        .iter()
        .map(|d| d.kind.to_string())
        .collect();
    assert_eq!(notes.len(), 2, "{notes:?}");
    assert!(notes[0].starts_with("format definition `t:uint64_t timestamp;float a-b;` kept"));
    let (out, report) = rewrite(Rewrite::new(), &bytes);
    assert!(report.formats_dropped.is_empty());
    let back = Log::from_slice(&out).unwrap();
    // The same notes of the same messages, and nothing else.
    let back_notes: Vec<String> = back
        .diagnostics()
        .iter()
        .map(|d| d.kind.to_string())
        .collect();
    assert_eq!(back_notes, notes);
    let times: Vec<u64> = back.data().map(|r| r.timestamp).collect();
    assert_eq!(times, [1, 2]);
    assert_eq!(
        back.metadata().info()[0].raw,
        input.metadata().info()[0].raw,
        "the info's bytes"
    );
    // A copy of the copy is the copy.
    assert_eq!(rewrite(Rewrite::new(), &out).0, out);
}

#[test]
fn a_change_before_the_outputs_data_section_is_said_to_be_moved_into_the_initial_parameters() {
    // A fuzzer's find: the input's data section began with a row of no subscription (not
    // written), so a parameter change after it came out among the definitions, where a
    // reader takes it for an initial parameter, and the report said it was written as a
    // change.
    use crate::read::KeyValue;
    let mut bytes = hand_built(&[b"t:uint64_t timestamp;float x;"]);
    let msg = |m: Message<'_>, b: &mut Vec<u8>| m.encode(b).unwrap();
    let param = |v: i32, b: &mut Vec<u8>| {
        msg(
            Message::Parameter(KeyValue {
                key: b"int32_t SYS_X",
                value: &v.to_le_bytes(),
            }),
            b,
        );
    };
    param(1, &mut bytes);
    let mut row = 7u64.to_le_bytes().to_vec();
    row.extend_from_slice(&1.5f32.to_le_bytes());
    msg(
        Message::Data {
            msg_id: 9,
            data: &row,
        },
        &mut bytes,
    );
    param(2, &mut bytes);
    msg(
        Message::Subscribe {
            multi_id: 0,
            msg_id: 0,
            name: b"t",
        },
        &mut bytes,
    );
    param(3, &mut bytes);
    msg(
        Message::Data {
            msg_id: 0,
            data: &row,
        },
        &mut bytes,
    );
    let input = Log::from_slice(&bytes).unwrap();
    let changes = |log: &Log<'_>| -> Vec<(String, ParamValue)> {
        log.parameter_changes()
            .iter()
            .map(|c| (c.name.clone(), c.value))
            .collect()
    };
    let initial = |log: &Log<'_>| log.metadata().initial_parameters()[0].value;
    assert_eq!(initial(&input), ParamValue::Int32(1));
    assert_eq!(changes(&input).len(), 2, "the input has two changes");
    let (out, report) = rewrite(Rewrite::new(), &bytes);
    let back = Log::from_slice(&out).unwrap();
    // The first change comes out as the initial value, the second still a change.
    assert_eq!(initial(&back), ParamValue::Int32(2));
    assert_eq!(changes(&back), [("SYS_X".to_owned(), ParamValue::Int32(3))]);
    assert_eq!(report.parameter_changes, (1, 1, 0));
    assert!(
        report.to_string().contains(
            "parameter changes: 1 written, 1 moved into the initial parameters, 0 left out"
        ),
        "{report}"
    );
}

fn hand_built(formats: &[&[u8]]) -> Vec<u8> {
    let mut bytes = crate::read::FileHeader {
        version: 1,
        start_timestamp: 0,
    }
    .to_bytes()
    .to_vec();
    for f in formats {
        Message::Format(f).encode(&mut bytes).unwrap();
    }
    bytes
}

#[test]
fn excluding_a_topic_keeps_the_type_it_nests_when_that_type_is_a_topic_too() {
    // Found by the rewrite fuzzer: `esc_report` both nested by `esc_status` and subscribed
    // itself; excluding `esc_status` dropped `esc_report`'s format while its subscription
    // and rows were kept, and the output could not read them.
    let mut f = hand_built(&[
        b"esc_report:uint64_t timestamp;int32_t rpm;",
        b"esc_status:uint64_t timestamp;esc_report[2] esc;",
    ]);
    let sub = |multi_id, msg_id, name: &'static [u8]| Message::Subscribe {
        multi_id,
        msg_id,
        name,
    };
    sub(0, 0, b"esc_status").encode(&mut f).unwrap();
    sub(0, 1, b"esc_report").encode(&mut f).unwrap();
    for t in 1..=3u64 {
        let mut status = t.to_le_bytes().to_vec();
        status.extend_from_slice(&[0; 24]);
        Message::Data {
            msg_id: 0,
            data: &status,
        }
        .encode(&mut f)
        .unwrap();
        let mut report = t.to_le_bytes().to_vec();
        report.extend_from_slice(&(100 * t as i32).to_le_bytes());
        Message::Data {
            msg_id: 1,
            data: &report,
        }
        .encode(&mut f)
        .unwrap();
    }
    let (out, report) = rewrite(Rewrite::new().exclude(&["esc_status"]), &f);
    let log = Log::from_vec(out).unwrap();
    assert!(log.diagnostics().is_empty(), "{:?}", log.diagnostics());
    assert!(log.subscription("esc_status", 0).is_none());
    let rpm = log.columns("esc_report", 0).unwrap();
    assert_eq!(
        rpm.get("rpm").unwrap().as_int32(),
        Some(&[100, 200, 300][..])
    );
    assert_eq!(report.formats_dropped, ["esc_status"]);
}
