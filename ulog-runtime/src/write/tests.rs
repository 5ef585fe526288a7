//! Writer tests: what is written reads back, misuse writes nothing, appending, crashes.

use super::*;
use crate::read::LogLevel;
use crate::{DiagnosticKind, Log};

fn new_writer(default_parameters: bool) -> Writer<Vec<u8>> {
    Writer::new(
        Vec::new(),
        WriterOptions {
            start_timestamp: 500,
            default_parameters,
        },
    )
    .unwrap()
}

/// `esc_status` with a nested, padded `esc_report`: inner and trailing padding.
fn esc_formats(w: &mut Writer<Vec<u8>>) {
    w.format("esc_status:uint64_t timestamp;uint8_t esc_count;uint8_t[3] _padding0;esc_report[2] esc;uint8_t[4] _padding1;")
        .unwrap();
    w.format(
        "esc_report:int32_t esc_rpm;float esc_voltage;uint8_t esc_state;uint8_t[3] _padding0;",
    )
    .unwrap();
}

fn esc_row(t: u64, rpm: i32) -> Vec<u8> {
    let mut r = t.to_le_bytes().to_vec();
    r.extend_from_slice(&[2, 0, 0, 0]);
    for k in 0..2 {
        r.extend_from_slice(&(rpm + k).to_le_bytes());
        r.extend_from_slice(&12.5f32.to_le_bytes());
        r.extend_from_slice(&[1, 0, 0, 0]);
    }
    r
}

#[test]
fn everything_written_reads_back() {
    let mut w = new_writer(true);
    esc_formats(&mut w);
    w.info("sys_name", &Value::String("rover".into())).unwrap();
    w.info(
        "ver_sw_release",
        &Value::Scalar(Scalar::UInt32(0x0104_02ff)),
    )
    .unwrap();
    w.info(
        "blob",
        &Value::Array(vec![
            Value::Scalar(Scalar::UInt8(1)),
            Value::Scalar(Scalar::UInt8(2)),
        ]),
    )
    .unwrap();
    w.multi_info("perf", &Value::String("ab".into()), false)
        .unwrap();
    w.multi_info("perf", &Value::String("cd".into()), true)
        .unwrap();
    w.parameter("MC_ROLL_P", ParamValue::Float(6.5)).unwrap();
    w.parameter("SYS_AUTOSTART", ParamValue::Int32(4001))
        .unwrap();
    w.default_parameter("MC_ROLL_P", ParamValue::Float(7.0), 3)
        .unwrap();
    let a = w.subscribe("esc_status", 0).unwrap();
    let b = w.subscribe("esc_status", 1).unwrap();
    assert_eq!((a, b), (SubscriptionId(0), SubscriptionId(1)));
    w.data(a, &esc_row(1_000, 100)).unwrap();
    let mut full = esc_row(1_100, 200);
    full.extend_from_slice(&[0; 4]); // with the trailing padding: also valid
    w.data(b, &full).unwrap();
    w.log(b'6', 1_200, "takeoff").unwrap();
    w.log_tagged(b'4', 3, 1_300, "tagged").unwrap();
    w.parameter("MC_ROLL_P", ParamValue::Float(6.75)).unwrap();
    w.sync().unwrap();
    w.dropout(50).unwrap();
    w.unsubscribe(b).unwrap();
    let bytes = w.into_inner();

    let log = Log::from_slice(&bytes).unwrap();
    assert_eq!(log.diagnostics(), &[]);
    assert_eq!(
        (log.header().version, log.header().start_timestamp),
        (1, 500)
    );
    assert!(log.flag_bits().unwrap().has_default_parameters());
    let m = log.metadata();
    assert_eq!(m.schema().len(), 2);
    assert_eq!(
        m.info_value("sys_name").and_then(Value::as_str),
        Some("rover")
    );
    assert_eq!(m.info()[1].type_name, "uint32_t");
    assert_eq!(m.info()[2].type_name, "uint8_t[2]");
    assert_eq!(m.multi_info()[0].values.len(), 1);
    assert_eq!(m.multi_info()[0].values[0].len(), 2);
    assert_eq!(m.initial_parameters().len(), 2);
    assert_eq!(m.default_parameters()[0].default_types, 3);
    assert_eq!(log.parameter_changes()[0].value, ParamValue::Float(6.75));
    let rows: Vec<(u8, u64, String)> = log
        .data()
        .map(|r| {
            (
                r.subscription.multi_id,
                r.timestamp,
                r.value().unwrap().field("esc").unwrap().to_string(),
            )
        })
        .collect();
    assert_eq!(rows[0], (0, 1_000, "[{esc_rpm: 100, esc_voltage: 12.5, esc_state: 1}, {esc_rpm: 101, esc_voltage: 12.5, esc_state: 1}]".into()));
    assert_eq!((rows[1].0, rows[1].1), (1, 1_100));
    let logged = log.logged_messages();
    assert_eq!(
        (logged[0].level(), logged[0].text.as_str()),
        (Some(LogLevel::Info), "takeoff")
    );
    assert_eq!((logged[1].tag, logged[1].timestamp), (Some(3), 1_300));
    assert_eq!(log.sync_offsets().len(), 1);
    assert_eq!(log.dropouts()[0].duration_ms, 50);
}

#[test]
fn misuse_is_refused_and_writes_nothing() {
    let mut w = new_writer(false);
    esc_formats(&mut w);
    let len = w.get_ref().len();
    let check = |w: &Writer<Vec<u8>>, e: WriteError, expected: &str| {
        assert_eq!(e.to_string(), expected);
        assert_eq!(w.get_ref().len(), len, "nothing written for: {expected}");
    };
    let e = w.data(SubscriptionId(0), &[0; 8]).unwrap_err();
    check(&w, e, "no subscription with msg_id 0");
    let e = w.format("esc_report:int32_t esc_rpm;").unwrap_err();
    check(
        &w,
        e,
        "format `esc_report` is defined twice, differently: `esc_report:int32_t esc_rpm;float esc_voltage;uint8_t esc_state;uint8_t[3] _padding0;` and `esc_report:int32_t esc_rpm;`",
    );
    let e = w.format("bad name:uint8_t x;").unwrap_err();
    check(
        &w,
        e,
        "invalid format `bad name:uint8_t x;`: at byte 3: character ' ' is not allowed in a message name (allowed: a-z A-Z 0-9 _ - /)",
    );
    let e = w.subscribe("nope", 0).unwrap_err();
    check(
        &w,
        e,
        "no format named `nope` was written; write it (and the formats it nests) first",
    );
    w.format("outer:uint64_t timestamp;inner x;").unwrap();
    let len = w.get_ref().len();
    let e = w.subscribe("outer", 0).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("format `outer` cannot be subscribed: outer.x: type `inner`"),
        "{e}"
    );
    assert_eq!(w.get_ref().len(), len);
    let s = w.subscribe("esc_status", 0).unwrap();
    let len = w.get_ref().len();
    let e = w.data(s, &[0; 10]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "`esc_status` rows are 36 to 40 bytes (the trailing padding may be left out), got 10"
    );
    assert_eq!(w.get_ref().len(), len);
    // Without trailing padding, one size.
    w.format("plain:uint64_t timestamp;float x;").unwrap();
    let p = w.subscribe("plain", 0).unwrap();
    let len = w.get_ref().len();
    let e = w.data(p, &[0; 3]).unwrap_err();
    assert_eq!(e.to_string(), "`plain` rows are 12 bytes, got 3");
    let e = w
        .default_parameter("X", ParamValue::Int32(1), 1)
        .unwrap_err();
    assert!(matches!(e, WriteError::DefaultParametersNotDeclared));
    let e = w
        .info(&"k".repeat(300), &Value::String("v".into()))
        .unwrap_err();
    assert!(
        matches!(e, WriteError::TooLarge(MessageTooLarge { what: "key", .. })),
        "{e}"
    );
    let e = w
        .info("big", &Value::String("x".repeat(70_000)))
        .unwrap_err();
    assert!(
        matches!(
            e,
            WriteError::TooLarge(MessageTooLarge {
                what: "payload",
                ..
            })
        ),
        "{e}"
    );
    let e = w.info("bad key", &Value::String("v".into())).unwrap_err();
    assert!(matches!(e, WriteError::InvalidValue { .. }), "{e}");
    assert_eq!(w.get_ref().len(), len);
    // The file is still valid.
    let log = Log::from_slice(w.get_ref()).unwrap();
    assert_eq!(log.diagnostics(), &[]);
}

#[test]
fn an_instance_is_subscribed_once_until_it_is_unsubscribed() {
    let mut w = new_writer(false);
    esc_formats(&mut w);
    let first = w.subscribe("esc_status", 0).unwrap();
    let other = w.subscribe("esc_status", 1).unwrap();
    let e = w.subscribe("esc_status", 0).unwrap_err();
    assert_eq!(
        e.to_string(),
        "`esc_status` instance 0 is already subscribed (msg_id 0); write its rows through that \
         subscription, or give this one another multi_id"
    );
    w.data(first, &esc_row(1, 100)).unwrap();
    w.data(other, &esc_row(2, 200)).unwrap();
    w.unsubscribe(first).unwrap();
    let again = w.subscribe("esc_status", 0).unwrap();
    assert_ne!(again, first);
    w.data(again, &esc_row(3, 300)).unwrap();
    // Read back: instance 0 has its rows of both subscriptions, instance 1 its own, and
    // refusing wrote nothing a reader stumbles on.
    let log = Log::from_slice(w.get_ref()).unwrap();
    assert_eq!(log.diagnostics(), &[]);
    let instances = log.instances(&["esc_status".to_owned()]);
    let rows = |multi_id| {
        let subs = instances
            .iter()
            .find(|g| g[0].multi_id == multi_id)
            .unwrap();
        log.instance_rows(subs)
            .map(|r| r.timestamp)
            .collect::<Vec<_>>()
    };
    assert_eq!(rows(0), [1, 3]);
    assert_eq!(rows(1), [2]);
}

#[test]
fn a_file_cut_anywhere_reads_up_to_its_last_complete_message() {
    let mut w = new_writer(false);
    esc_formats(&mut w);
    let s = w.subscribe("esc_status", 0).unwrap();
    let mut ends = Vec::new();
    for i in 0..5 {
        w.data(s, &esc_row(i * 100, i as i32)).unwrap();
        ends.push(w.get_ref().len());
    }
    let bytes = w.into_inner();
    for cut in ends[0]..=bytes.len() {
        let log = Log::from_slice(&bytes[..cut]).unwrap();
        let complete = ends.iter().filter(|&&e| e <= cut).count();
        assert_eq!(log.row_count(), complete, "cut at {cut}");
        assert!(
            log.diagnostics()
                .iter()
                .all(|d| matches!(d.kind, DiagnosticKind::Truncated { .. }))
        );
    }
}

#[test]
fn appending_sets_the_flag_and_the_offset() {
    let dir = std::env::temp_dir().join(format!("ulog-append-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("append.ulg");
    let mut w = Writer::new(
        std::io::BufWriter::new(std::fs::File::create(&path).unwrap()),
        WriterOptions::default(),
    )
    .unwrap();
    w.format("t:uint64_t timestamp;int32_t v;").unwrap();
    let t = w.subscribe("t", 0).unwrap();
    let row = |ts: u64, v: i32| [ts.to_le_bytes().as_slice(), &v.to_le_bytes()].concat();
    w.data(t, &row(1, 1)).unwrap();
    w.flush().unwrap();
    drop(w);
    let first_len = std::fs::metadata(&path).unwrap().len();

    for round in 0..3u64 {
        let mut a = Writer::append(&path).unwrap();
        a.data(t, &row(10 + round, 10)).unwrap();
        let u = a.subscribe("t", 1).unwrap();
        assert_eq!(u.0, 1 + round as u16);
        a.data(u, &row(20 + round, 20)).unwrap();
        drop(a);
    }
    assert!(
        matches!(Writer::append(&path), Err(WriteError::CannotAppend(_))),
        "all three offsets used"
    );

    let log = Log::read(&path).unwrap();
    assert_eq!(log.diagnostics(), &[]);
    let bits = log.flag_bits().unwrap();
    assert!(bits.has_data_appended());
    assert_eq!(bits.appended_offsets[0], first_len);
    assert!(
        bits.appended_offsets[0] < bits.appended_offsets[1]
            && bits.appended_offsets[1] < bits.appended_offsets[2]
    );
    assert_eq!(log.row_count(), 7);
    assert_eq!(
        log.rows(log.subscription("t", 0).unwrap())
            .map(|r| r.timestamp)
            .collect::<Vec<_>>(),
        [1, 10, 11, 12]
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sync_and_dropout_wait_for_the_data_section_and_refusals_write_nothing() {
    // Found by the writer_ops fuzzer: a sync before any subscription went into the
    // definitions section, where readers skip it (pyulog drops such a dropout).
    let mut w = new_writer(false);
    w.format("t:uint64_t timestamp;").unwrap();
    let before = w.get_ref().len();
    assert!(matches!(
        w.sync(),
        Err(WriteError::NoDataSection("a sync message"))
    ));
    assert!(matches!(
        w.dropout(5),
        Err(WriteError::NoDataSection("a dropout"))
    ));
    assert_eq!(w.get_ref().len(), before);
    // A flush with no subscription waiting leaves the definitions open, and so does a
    // logged string refused as too long.
    w.flush().unwrap();
    assert!(w.log(b'6', 0, &"x".repeat(70_000)).is_err());
    assert_eq!(w.get_ref().len(), before);
    w.format("early:uint64_t timestamp;").unwrap();
    // A parameter is still an initial one.
    w.parameter("P", ParamValue::Int32(1)).unwrap();
    let sub = w.subscribe("t", 0).unwrap();
    // A logged string too long for its message is refused before the waiting subscription
    // goes out.
    let before = w.get_ref().len();
    assert!(w.log(b'6', 0, &"x".repeat(70_000)).is_err());
    assert_eq!(w.get_ref().len(), before, "nothing written");
    // So is a parameter change whose name is too long for its message.
    let e = w
        .parameter(&"P".repeat(300), ParamValue::Int32(2))
        .unwrap_err();
    assert!(
        matches!(e, WriteError::TooLarge(MessageTooLarge { what: "key", .. })),
        "{e}"
    );
    assert_eq!(w.get_ref().len(), before, "nothing written");
    // The definitions are still open: a format can still be written.
    w.format("late:uint64_t timestamp;").unwrap();
    w.sync().unwrap();
    w.dropout(5).unwrap();
    w.data(sub, &7u64.to_le_bytes()).unwrap();
    let log = Log::from_vec(w.into_inner()).unwrap();
    assert!(log.diagnostics().is_empty());
    assert_eq!(log.metadata().initial_parameters().len(), 1);
    assert_eq!(log.dropouts().len(), 1);
    assert_eq!(log.metadata().sync_count(), 1);
    assert_eq!(log.row_count(), 1);
}
