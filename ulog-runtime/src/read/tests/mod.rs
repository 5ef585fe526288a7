//! Reader tests over files built message by message from the specification's layouts.

use super::*;
use crate::value::Scalar;

mod odd;

/// A file under construction.
struct File(Vec<u8>);

impl File {
    fn new(version: u8, start: u64) -> File {
        File(
            FileHeader {
                version,
                start_timestamp: start,
            }
            .to_bytes()
            .to_vec(),
        )
    }

    fn v1(start: u64) -> File {
        let mut f = File::new(1, start);
        f.msg(Message::FlagBits(FlagBits::default()));
        f
    }

    fn msg(&mut self, m: Message<'_>) -> u64 {
        let at = self.0.len() as u64;
        m.encode(&mut self.0).unwrap();
        at
    }

    fn format(&mut self, s: &str) {
        self.msg(Message::Format(s.as_bytes()));
    }

    fn info(&mut self, key: &str, value: &[u8]) {
        self.msg(Message::Info(KeyValue {
            key: key.as_bytes(),
            value,
        }));
    }

    fn subscribe(&mut self, multi_id: u8, msg_id: u16, name: &str) {
        self.msg(Message::Subscribe {
            multi_id,
            msg_id,
            name: name.as_bytes(),
        });
    }

    fn data(&mut self, msg_id: u16, data: &[u8]) -> u64 {
        self.msg(Message::Data { msg_id, data })
    }
}

/// `t:uint64_t timestamp;int16_t v;uint8_t[2] _padding0;` rows, shortened as PX4 writes them.
fn row(t: u64, v: i16) -> Vec<u8> {
    let mut r = t.to_le_bytes().to_vec();
    r.extend_from_slice(&v.to_le_bytes());
    r
}

fn values(log: &Log<'_>, topic: &str) -> Vec<(u64, i16)> {
    let sub = log.subscription(topic, 0).unwrap();
    log.rows(sub)
        .map(
            |r| match r.value().unwrap().field("v").unwrap().as_scalar() {
                Some(Scalar::Int16(v)) => (r.timestamp, v),
                other => panic!("{other:?}"),
            },
        )
        .collect()
}

/// Reads `bytes` with the streaming reader, `chunk` bytes per `read` call.
fn stream_rows(bytes: &[u8], chunk: usize) -> (Vec<(u64, Vec<u8>)>, Vec<Diagnostic>) {
    struct Trickle<'a>(&'a [u8], usize);
    impl std::io::Read for Trickle<'_> {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            let n = buf.len().min(self.1).min(self.0.len());
            buf[..n].copy_from_slice(&self.0[..n]);
            self.0 = &self.0[n..];
            Ok(n)
        }
    }
    let mut reader = StreamReader::new(Trickle(bytes, chunk)).unwrap();
    let (mut rows, mut diags) = (Vec::new(), Vec::new());
    while let Some(e) = reader.next_event().unwrap() {
        match e {
            Event::Row(r) => rows.push((r.offset, r.data.to_vec())),
            Event::Diagnostic(d) => diags.push(*d),
            _ => {}
        }
    }
    (rows, diags)
}

fn log_rows(log: &Log<'_>) -> Vec<(u64, Vec<u8>)> {
    log.data().map(|r| (r.offset, r.data.to_vec())).collect()
}

#[test]
fn every_message_type_of_version_1() {
    let mut f = File::new(1, 1_000);
    let mut bits = FlagBits::default();
    bits.compat[0] = FlagBits::COMPAT_DEFAULT_PARAMETERS;
    f.msg(Message::FlagBits(bits));
    f.format("t:uint64_t timestamp;int16_t v;uint8_t[2] _padding0;");
    f.info("char[3] sys_name", b"PX4");
    f.info("uint32_t ver_sw_release", &0x010402ffu32.to_le_bytes());
    f.info("uint8_t[2] blob", &[0xab, 0xcd]);
    f.msg(Message::MultiInfo {
        continued: false,
        entry: KeyValue {
            key: b"char[2] perf",
            value: b"ab",
        },
    });
    f.msg(Message::MultiInfo {
        continued: true,
        entry: KeyValue {
            key: b"char[2] perf",
            value: b"cd",
        },
    });
    f.msg(Message::MultiInfo {
        continued: false,
        entry: KeyValue {
            key: b"char[1] perf",
            value: b"e",
        },
    });
    f.msg(Message::Parameter(KeyValue {
        key: b"float MC_ROLL_P",
        value: &6.5f32.to_le_bytes(),
    }));
    f.msg(Message::Parameter(KeyValue {
        key: b"int32_t SYS_AUTOSTART",
        value: &4001i32.to_le_bytes(),
    }));
    f.msg(Message::DefaultParameter {
        default_types: 3,
        entry: KeyValue {
            key: b"float MC_ROLL_P",
            value: &7.0f32.to_le_bytes(),
        },
    });
    f.subscribe(0, 0, "t");
    f.subscribe(1, 1, "t");
    f.data(0, &row(2_000, -5));
    f.data(1, &row(2_500, 9));
    let mut full = row(3_000, 6);
    full.extend_from_slice(&[0, 0]); // trailing padding included: also valid
    f.data(0, &full);
    f.msg(Message::Logging {
        level: b'6',
        tag: None,
        timestamp: 3_100,
        text: b"hello",
    });
    f.msg(Message::Logging {
        level: b'3',
        tag: Some(7),
        timestamp: 3_200,
        text: b"tagged",
    });
    f.msg(Message::Parameter(KeyValue {
        key: b"float MC_ROLL_P",
        value: &6.75f32.to_le_bytes(),
    }));
    f.msg(Message::Sync);
    f.msg(Message::Dropout { duration_ms: 120 });
    f.msg(Message::Unsubscribe { msg_id: 1 });
    f.info("char[4] late", b"info");
    let log = Log::from_slice(&f.0).unwrap();

    assert_eq!(log.diagnostics(), &[]);
    assert_eq!(
        (log.header().version, log.header().start_timestamp),
        (1, 1_000)
    );
    assert!(log.flag_bits().unwrap().has_default_parameters());
    let m = log.metadata();
    assert_eq!(
        m.info_value("sys_name").and_then(Value::as_str),
        Some("PX4")
    );
    assert_eq!(
        m.info_value("ver_sw_release").and_then(Value::as_scalar),
        Some(Scalar::UInt32(0x010402ff))
    );
    assert_eq!(m.info()[2].type_name, "uint8_t[2]");
    assert_eq!(m.info_value("late").and_then(Value::as_str), Some("info"));
    let perf = &m.multi_info()[0];
    let text = |v: &Vec<Value>| {
        v.iter()
            .map(|x| x.as_str().unwrap().to_owned())
            .collect::<Vec<_>>()
    };
    assert_eq!(
        perf.values.iter().map(text).collect::<Vec<_>>(),
        [vec!["ab", "cd"], vec!["e"]]
    );
    assert_eq!(
        m.initial_parameters()[0],
        Parameter {
            name: "MC_ROLL_P".into(),
            value: ParamValue::Float(6.5)
        }
    );
    assert_eq!(m.initial_parameters()[1].value, ParamValue::Int32(4001));
    assert_eq!(m.default_parameters()[0].default_types, 3);
    let change = &log.parameter_changes()[0];
    assert_eq!(
        (change.timestamp, change.name.as_str(), change.value),
        (3_000, "MC_ROLL_P", ParamValue::Float(6.75))
    );
    assert_eq!(values(&log, "t"), [(2_000, -5), (3_000, 6)]);
    let second = log.subscription("t", 1).unwrap();
    assert_eq!((second.msg_id, log.rows(second).len()), (1, 1));
    let logged = log.logged_messages();
    assert_eq!(
        (logged[0].level(), logged[0].tag, logged[0].text.as_str()),
        (Some(LogLevel::Info), None, "hello")
    );
    assert_eq!(
        (logged[1].level(), logged[1].tag, logged[1].timestamp),
        (Some(LogLevel::Error), Some(7), 3_200)
    );
    assert_eq!(log.sync_offsets().len(), 1);
    assert_eq!(
        (log.dropouts()[0].duration_ms, log.dropouts()[0].timestamp),
        (120, 3_000)
    );
    assert_eq!(m.last_timestamp(), 3_000);

    let (rows, diags) = stream_rows(&f.0, 7);
    assert_eq!(rows, log_rows(&log));
    assert!(diags.is_empty());
}

#[test]
fn version_0_small_timestamps_are_unwrapped() {
    let mut f = File::new(0, 0);
    f.format("s:uint16_t timestamp;int16_t v;");
    f.format("m:uint8_t timestamp;int16_t v;");
    f.subscribe(0, 0, "s");
    f.subscribe(0, 1, "m");
    for (i, raw) in [65_000u16, 65_500, 300, 1_000].into_iter().enumerate() {
        let mut r = raw.to_le_bytes().to_vec();
        r.extend_from_slice(&(i as i16).to_le_bytes());
        f.data(0, &r);
    }
    for raw in [200u8, 250, 10] {
        f.data(1, &[raw, 0, 0]);
    }
    let log = Log::from_slice(&f.0).unwrap();
    assert!(log.flag_bits().is_none());
    assert_eq!(
        values(&log, "s").iter().map(|x| x.0).collect::<Vec<_>>(),
        [65_000, 65_500, 65_836, 66_536]
    );
    // uint8_t timestamps count milliseconds.
    assert_eq!(
        values(&log, "m").iter().map(|x| x.0).collect::<Vec<_>>(),
        [200_000, 250_000, 266_000]
    );
    let (rows, _) = stream_rows(&f.0, 3);
    assert_eq!(rows, log_rows(&log));
}

#[test]
fn appended_segments_are_one_data_section() {
    let mut f = File::v1(0);
    f.format("t:uint64_t timestamp;int16_t v;uint8_t[2] _padding0;");
    f.subscribe(0, 0, "t");
    f.data(0, &row(1, 1));
    // The main data ends in the middle of a message (a crash), then data is appended.
    let cut = f.data(0, &row(2, 2));
    f.0.truncate(cut as usize + 6);
    let first = f.0.len() as u64;
    f.data(0, &row(3, 3));
    let second = f.0.len() as u64;
    f.data(0, &row(4, 4));
    f.msg(Message::Logging {
        level: b'6',
        tag: None,
        timestamp: 5,
        text: b"after",
    });
    let mut bits = FlagBits::default();
    bits.incompat[0] = FlagBits::INCOMPAT_DATA_APPENDED;
    bits.appended_offsets = [first, second, 0];
    f.0[16 + 3..16 + 3 + FLAG_BITS_LEN].copy_from_slice(&bits.to_bytes());

    let log = Log::from_slice(&f.0).unwrap();
    assert_eq!(values(&log, "t"), [(1, 1), (3, 3), (4, 4)]);
    assert_eq!(log.logged_messages()[0].text, "after");
    assert_eq!(log.diagnostics().len(), 1, "{:?}", log.diagnostics());
    let d = &log.diagnostics()[0];
    assert_eq!(
        (d.offset, &d.kind),
        (
            cut,
            &DiagnosticKind::Truncated {
                declared: Some(12),
                available: 3
            }
        )
    );
    let (rows, diags) = stream_rows(&f.0, 5);
    assert_eq!(rows, log_rows(&log));
    assert_eq!(&diags, log.diagnostics());
}

#[test]
fn impossible_appended_offsets_are_reported() {
    let mut f = File::v1(0);
    f.format("t:uint64_t timestamp;int16_t v;");
    f.subscribe(0, 0, "t");
    f.data(0, &row(1, 1));
    let mut bits = FlagBits::default();
    bits.incompat[0] = FlagBits::INCOMPAT_DATA_APPENDED;
    bits.appended_offsets = [10, 1 << 40, 0];
    f.0[16 + 3..16 + 3 + FLAG_BITS_LEN].copy_from_slice(&bits.to_bytes());
    let log = Log::from_slice(&f.0).unwrap();
    assert_eq!(values(&log, "t"), [(1, 1)]);
    let kinds: Vec<_> = log.diagnostics().iter().map(|d| d.kind.clone()).collect();
    assert_eq!(
        kinds,
        [
            DiagnosticKind::BadAppendedOffset(10),
            DiagnosticKind::BadAppendedOffset(1 << 40)
        ]
    );
    // What the exports say on stderr (`ulog json` said nothing of it before).
    let skipped = log.skipped();
    assert_eq!(skipped.ignored_appended_offsets, [10, 1 << 40]);
    assert_eq!(
        skipped.lines(&[]),
        [
            "appended data at byte 10 not read: the offset is impossible (backwards, or past \
             the end of a file cut short)",
            "appended data at byte 1099511627776 not read: the offset is impossible \
             (backwards, or past the end of a file cut short)"
        ]
    );
}

#[test]
fn unknown_incompat_bits_are_refused_by_name() {
    let mut f = File::new(1, 0);
    let mut bits = FlagBits::default();
    bits.incompat[2] = 0b1000;
    f.msg(Message::FlagBits(bits));
    let e = Log::from_slice(&f.0).unwrap_err();
    assert!(matches!(
        e,
        ReadError::IncompatibleFlags { byte: 2, bit: 3 }
    ));
    assert_eq!(
        e.to_string(),
        "unknown incompatible flag: bit 3 of incompat byte 2 is set (only DATA_APPENDED, bit 0 of byte 0, is known); this file needs a newer reader"
    );
    assert!(matches!(
        StreamReader::new(&f.0[..]).unwrap().next_event(),
        Err(ReadError::IncompatibleFlags { .. })
    ));
}

#[test]
fn bad_headers_are_errors() {
    assert!(matches!(
        Log::from_slice(b"PK\x03\x04 a zip file"),
        Err(ReadError::NotULog)
    ));
    assert!(matches!(
        Log::from_slice(b"ULog"),
        Err(ReadError::TooShort { len: 4 })
    ));
    assert!(matches!(
        Log::from_slice(&MAGIC),
        Err(ReadError::TooShort { len: 7 })
    ));
    assert!(matches!(
        StreamReader::new(&b"hello world, not a log"[..]),
        Err(ReadError::NotULog)
    ));
    let f = File::new(7, 0);
    let log = Log::from_slice(&f.0).unwrap();
    assert_eq!(log.diagnostics()[0].kind, DiagnosticKind::UnknownVersion(7));
}

#[test]
fn unknown_types_are_skipped_and_per_message_problems_reported() {
    let mut f = File::v1(0);
    f.format("t:uint64_t timestamp;int16_t v;uint8_t[2] _padding0;");
    f.format("bad format");
    f.subscribe(0, 0, "t");
    f.subscribe(0, 1, "missing");
    // A name that is not UTF-8 is read as pyulog reads it: the invalid bytes left out.
    f.msg(Message::Subscribe {
        multi_id: 1,
        msg_id: 2,
        name: b"t\xff",
    });
    f.data(0, &row(1, 1));
    let unknown = f.msg(Message::Unknown {
        ty: b'X',
        payload: b"future",
    });
    f.data(0, &row(2, 2));
    let orphan = f.data(9, &row(2, 2));
    let short = f.data(0, &row(3, 3)[..7]);
    f.data(0, &row(4, 4));
    let log = Log::from_slice(&f.0).unwrap();
    assert_eq!(values(&log, "t"), [(1, 1), (2, 2), (4, 4)]);
    let found: Vec<(u64, String)> = log
        .diagnostics()
        .iter()
        .map(|d| (d.offset, d.kind.to_string()))
        .collect();
    let at = |off: u64| {
        found
            .iter()
            .find(|x| x.0 == off)
            .map(|x| x.1.clone())
            .unwrap_or_default()
    };
    assert!(
        found
            .iter()
            .any(|x| x.1.starts_with("invalid format definition `bad format`"))
    );
    assert!(
        found
            .iter()
            .any(|x| x.1 == "subscription `missing` (msg_id 1): no format named `missing`")
    );
    assert_eq!(log.subscriptions()[2].name, "t");
    assert_eq!(log.subscriptions()[2].multi_id, 1);
    assert_eq!(at(unknown), "unknown message type 0x58 (6 bytes), skipped");
    assert_eq!(
        at(orphan),
        "data for msg_id 9, which no subscription declares; row skipped"
    );
    assert_eq!(
        at(short),
        "`t` (multi_id 0, msg_id 0): 7-byte row, the format needs 10..=12; row skipped"
    );
}

#[test]
fn nested_and_padded_rows_decode_to_values() {
    let mut f = File::v1(0);
    // Nested type used before it is defined, inner and trailing padding.
    f.format(
        "esc_status:uint64_t timestamp;uint8_t esc_count;uint8_t[3] _padding0;esc_report[2] esc;",
    );
    f.format(
        "esc_report:int32_t esc_rpm;float esc_voltage;uint8_t esc_state;uint8_t[3] _padding0;",
    );
    f.subscribe(0, 0, "esc_status");
    let mut r = 77u64.to_le_bytes().to_vec();
    r.extend_from_slice(&[2, 0xEE, 0xEE, 0xEE]);
    for (rpm, volt, state) in [(1200i32, 15.5f32, 1u8), (-3, 0.25, 2)] {
        r.extend_from_slice(&rpm.to_le_bytes());
        r.extend_from_slice(&volt.to_le_bytes());
        r.extend_from_slice(&[state, 0xEE, 0xEE, 0xEE]);
    }
    // The last element's trailing padding is kept: only top-level trailing padding is dropped.
    f.data(0, &r);
    let log = Log::from_slice(&f.0).unwrap();
    assert_eq!(log.diagnostics(), &[]);
    let row = log.data().next().unwrap();
    assert_eq!(
        row.value().unwrap().to_string(),
        "{timestamp: 77, esc_count: 2, esc: [{esc_rpm: 1200, esc_voltage: 15.5, esc_state: 1}, {esc_rpm: -3, esc_voltage: 0.25, esc_state: 2}]}"
    );
    let columns: Vec<String> = row
        .plan()
        .unwrap()
        .columns(row.schema())
        .into_iter()
        .map(|c| c.name)
        .collect();
    assert_eq!(
        columns[2..5],
        ["esc[0].esc_rpm", "esc[0].esc_voltage", "esc[0].esc_state"]
    );
}

#[test]
fn large_messages_are_legitimate() {
    let mut f = File::v1(0);
    let text = vec![b'x'; 17_424];
    f.msg(Message::MultiInfo {
        continued: false,
        entry: KeyValue {
            key: b"char[17424] hardfault_plain",
            value: &text,
        },
    });
    f.format("t:uint64_t timestamp;int16_t v;");
    f.subscribe(0, 0, "t");
    f.data(0, &row(1, 1));
    let log = Log::from_slice(&f.0).unwrap();
    assert_eq!(log.diagnostics(), &[]);
    assert_eq!(
        log.metadata().multi_info()[0].values[0][0]
            .as_str()
            .unwrap()
            .len(),
        17_424
    );
}

/// A file with `n` rows of `t` and a sync message every 10 rows.
fn clean(n: usize) -> (File, Vec<u64>) {
    let mut f = File::v1(0);
    f.format("t:uint64_t timestamp;int16_t v;uint8_t[2] _padding0;");
    f.subscribe(0, 0, "t");
    let mut offsets = Vec::new();
    for i in 0..n {
        if i % 10 == 0 {
            f.msg(Message::Sync);
        }
        offsets.push(f.data(0, &row(i as u64, i as i16)));
    }
    (f, offsets)
}

#[test]
fn garbage_is_skipped_and_reported_exactly() {
    let (mut f, offsets) = clean(40);
    let at = offsets[15] as usize;
    let garbage = [0xFFu8, 0x13, 0x00, 0x42, 0x99, 0x07, 0x00];
    f.0.splice(at..at, garbage);
    let log = Log::from_slice(&f.0).unwrap();
    assert_eq!(log.row_count(), 40, "every row survives");
    let d = &log.diagnostics()[0];
    assert_eq!(
        (d.offset, &d.kind),
        (
            at as u64,
            &DiagnosticKind::Skipped {
                to: (at + 7) as u64,
                len: 7
            }
        )
    );
    assert_eq!(
        log.corrupt_ranges().collect::<Vec<_>>(),
        vec![(at as u64..(at + 7) as u64)]
    );
    let (rows, diags) = stream_rows(&f.0, 1);
    assert_eq!(rows, log_rows(&log));
    assert_eq!(&diags, log.diagnostics());
}

#[test]
fn a_damaged_size_field_loses_only_its_own_row() {
    let (mut f, offsets) = clean(40);
    // Row 20 claims 2 more bytes than it has: it still fits its format (full size), but the
    // next header is then misaligned.
    let at = offsets[20] as usize;
    f.0[at] += 2;
    let log = Log::from_slice(&f.0).unwrap();
    let got: Vec<i16> = values(&log, "t").into_iter().map(|x| x.1).collect();
    assert!(got.len() >= 39, "{got:?}");
    let expected: Vec<i16> = (0..40).collect();
    assert_eq!(
        got.iter().filter(|v| expected.contains(v)).count(),
        got.len()
    );
    assert!(
        got.contains(&21),
        "the row after the damaged one is recovered"
    );
    assert!(
        log.diagnostics()
            .iter()
            .any(|d| matches!(d.kind, DiagnosticKind::Overlap { .. }))
    );
}

#[test]
fn a_cut_file_keeps_everything_before_the_cut() {
    let (f, offsets) = clean(30);
    for cut in [
        offsets[12] as usize + 1,
        offsets[12] as usize + 4,
        offsets[12] as usize + 12,
    ] {
        let log = Log::from_slice(&f.0[..cut]).unwrap();
        assert_eq!(log.row_count(), 12, "cut at {cut}");
        assert!(matches!(
            log.diagnostics()[0].kind,
            DiagnosticKind::Truncated { .. }
        ));
        let (rows, _) = stream_rows(&f.0[..cut], 4);
        assert_eq!(rows, log_rows(&log));
    }
}

#[test]
fn zeros_up_to_the_end_are_one_skipped_range() {
    let (mut f, offsets) = clean(10);
    let len = f.0.len();
    f.0.extend(std::iter::repeat_n(0u8, 100_000));
    let log = Log::from_slice(&f.0).unwrap();
    assert_eq!(log.row_count(), offsets.len());
    assert_eq!(
        log.corrupt_ranges().collect::<Vec<_>>(),
        vec![(len as u64..(len + 100_000) as u64)]
    );
}

#[test]
fn flag_bits_elsewhere_are_ignored() {
    let (mut f, _) = clean(3);
    let at = f.msg(Message::FlagBits(FlagBits {
        incompat: [0xFF; 8],
        ..FlagBits::default()
    }));
    f.data(0, &row(9, 9));
    let log = Log::from_slice(&f.0).unwrap();
    assert_eq!(log.row_count(), 4);
    assert_eq!(
        log.diagnostics()[0],
        Diagnostic {
            offset: at,
            kind: DiagnosticKind::FlagBitsNotFirst
        }
    );
}

#[test]
fn appended_offsets_near_the_end_of_u64_do_not_overflow() {
    for offset in [u64::MAX, u64::MAX - 1, u64::MAX - 3, 1 << 63] {
        let mut f = File::v1(0);
        f.format("t:uint64_t timestamp;int16_t v;");
        f.subscribe(0, 0, "t");
        f.data(0, &row(1, 1));
        let mut bits = FlagBits::default();
        bits.incompat[0] = FlagBits::INCOMPAT_DATA_APPENDED;
        bits.appended_offsets = [offset, 0, 0];
        f.0[16 + 3..16 + 3 + FLAG_BITS_LEN].copy_from_slice(&bits.to_bytes());
        let log = Log::from_slice(&f.0).unwrap();
        assert_eq!(log.row_count(), 1);
        assert_eq!(
            log.diagnostics()[0].kind,
            DiagnosticKind::BadAppendedOffset(offset)
        );
        let (rows, diags) = stream_rows(&f.0, 3);
        assert_eq!(rows, log_rows(&log));
        assert_eq!(&diags, log.diagnostics());
    }
}

#[test]
fn helpers_pyulog_users_look_for() {
    let version = |v: u32| {
        let mut f = File::v1(0);
        f.info("uint32_t ver_sw_release", &v.to_le_bytes());
        Log::from_vec(f.0).unwrap().metadata().software_version()
    };
    // As pyulog's get_version_info_str: 0xMMmmpptt, tt < 64 is a development build.
    assert_eq!(version(0x010F_01FF).as_deref(), Some("v1.15.1"));
    assert_eq!(version(0x0110_00C0).as_deref(), Some("v1.16.0 (RC)"));
    assert_eq!(version(0x0110_0080).as_deref(), Some("v1.16.0 (beta)"));
    assert_eq!(version(0x0110_0040).as_deref(), Some("v1.16.0 (alpha)"));
    assert_eq!(version(0x010F_0100), None);
    assert_eq!(
        Log::from_vec(File::v1(0).0)
            .unwrap()
            .metadata()
            .software_version(),
        None
    );

    let mut f = File::v1(0);
    let param = |f: &mut File, name: &str, v: i32| {
        f.msg(Message::Parameter(KeyValue {
            key: format!("int32_t {name}").as_bytes(),
            value: &v.to_le_bytes(),
        }));
    };
    param(&mut f, "B_PARAM", 1);
    param(&mut f, "A_PARAM", 2);
    f.format("t:uint64_t timestamp;");
    for (multi_id, msg_id) in [(1, 0), (0, 1)] {
        f.msg(Message::Subscribe {
            multi_id,
            msg_id,
            name: b"t",
        });
    }
    for (msg_id, t) in [(0u16, 10u64), (1, 20), (0, 30)] {
        f.msg(Message::Data {
            msg_id,
            data: &t.to_le_bytes(),
        });
        if t == 20 {
            param(&mut f, "B_PARAM", 5);
            param(&mut f, "A_PARAM", 6);
            param(&mut f, "B_PARAM", 7);
        }
    }
    let log = Log::from_vec(f.0).unwrap();
    assert_eq!(
        log.metadata().parameter("A_PARAM"),
        Some(ParamValue::Int32(2))
    );
    assert_eq!(log.metadata().parameter("C_PARAM"), None);
    let changed: Vec<(&str, Vec<i32>)> = log
        .changed_parameters()
        .into_iter()
        .map(|(n, c)| (n, c.iter().map(|c| c.value.as_f64() as i32).collect()))
        .collect();
    assert_eq!(changed, [("A_PARAM", vec![6]), ("B_PARAM", vec![5, 7])]);
    let topics: Vec<String> = log
        .topics()
        .iter()
        .map(|t| {
            let (first, last) = (t.first_timestamp.unwrap(), t.last_timestamp.unwrap());
            format!("{}#{} {} rows {first}..{last}", t.name, t.multi_id, t.rows)
        })
        .collect();
    assert_eq!(topics, ["t#0 1 rows 20..20", "t#1 2 rows 10..30"]);
}

#[test]
fn read_definitions_stops_at_the_data_section() {
    let mut f = File::v1(0);
    f.format("t:uint64_t timestamp;int16_t v;uint8_t[2] _padding0;");
    f.info("char[3] sys_name", b"PX4");
    f.msg(Message::Parameter(KeyValue {
        key: b"int32_t SYS_AUTOSTART",
        value: &4001i32.to_le_bytes(),
    }));
    // A sync message may come before the data section: reading goes on past it.
    f.msg(Message::Sync);
    f.format("u:uint64_t timestamp;");
    f.subscribe(0, 1, "t");
    f.data(1, &row(10, 7));
    // What follows is not read: another subscription, and bytes that are not a message.
    f.subscribe(0, 2, "u");
    f.0.extend_from_slice(&[0xff; 64]);
    let meta = StreamReader::read_definitions(&f.0[..]).unwrap();
    assert!(meta.schema().get("t").is_some());
    assert!(
        meta.schema().get("u").is_some(),
        "formats after a sync are read"
    );
    assert_eq!(
        meta.info_value("sys_name").and_then(Value::as_str),
        Some("PX4")
    );
    assert_eq!(
        meta.parameter("SYS_AUTOSTART"),
        Some(ParamValue::Int32(4001))
    );
    let names: Vec<&str> = meta
        .subscriptions()
        .iter()
        .map(|s| s.name.as_str())
        .collect();
    assert_eq!(names, ["t"], "stops at the first `A`");
    // A log whose first data message is a row of no subscription stops there too.
    let mut orphan = File::v1(0);
    orphan.format("t:uint64_t timestamp;int16_t v;uint8_t[2] _padding0;");
    orphan.data(1, &row(10, 7));
    orphan.subscribe(0, 1, "t");
    let meta = StreamReader::read_definitions(&orphan.0[..]).unwrap();
    assert!(meta.subscriptions().is_empty());
    // A log that is only definitions, and bytes that are not a log.
    let mut only = File::v1(0);
    only.format("t:uint64_t timestamp;");
    let meta = StreamReader::read_definitions(&only.0[..]).unwrap();
    assert_eq!(meta.schema().formats().len(), 1);
    assert!(StreamReader::read_definitions(&b"not a log at all"[..]).is_err());
}

#[test]
fn the_stream_gives_each_events_message_as_the_file_holds_it() {
    let (mut f, _) = clean(25);
    f.msg(Message::Logging {
        level: b'6',
        tag: None,
        timestamp: 30,
        text: b"bytes \xff kept",
    });
    // Damage (no message) between rows.
    f.0.extend_from_slice(&[0xFF, 0x13, 0x00, 0x42]);
    f.data(0, &row(31, 7));
    struct Trickle<'a>(&'a [u8]);
    impl std::io::Read for Trickle<'_> {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            let n = buf.len().min(7).min(self.0.len());
            buf[..n].copy_from_slice(&self.0[..n]);
            self.0 = &self.0[n..];
            Ok(n)
        }
    }
    let mut reader = StreamReader::new(Trickle(&f.0)).unwrap();
    assert!(reader.message().is_none(), "nothing read yet");
    let (mut messages, mut diagnostics) = (0, 0);
    while let Some(e) = reader.next_event().unwrap() {
        let diagnostic = matches!(e, Event::Diagnostic(_));
        let raw = reader.message();
        if diagnostic {
            assert!(raw.is_none());
            diagnostics += 1;
            continue;
        }
        let raw = raw.unwrap();
        let start = raw.offset as usize;
        let size = usize::from(u16::from_le_bytes([f.0[start], f.0[start + 1]]));
        assert_eq!(raw.ty, f.0[start + 2]);
        assert_eq!(raw.payload, &f.0[start + 3..start + 3 + size]);
        messages += 1;
    }
    // Flag bits, format, subscription, 3 syncs, 26 rows, the logged string.
    assert_eq!((messages, diagnostics), (33, 1));
}

#[test]
fn any_single_bit_flip_of_a_rows_size_costs_at_most_that_row() {
    // Rows of varied bytes, long enough that a size grown by a high bit still ends inside
    // the file (on bytes that may look like a message header), no syncs to fall back on.
    let mut f = File::v1(0);
    f.format("t:uint64_t timestamp;int16_t v;uint8_t[2] _padding0;uint32_t[16] noise;");
    f.subscribe(0, 0, "t");
    let mut offsets = Vec::new();
    let mut x = 0x2545_f491_u32;
    for i in 0..6000u64 {
        let mut data = row(i, i as i16);
        data.extend_from_slice(&[0, 0]);
        for _ in 0..16 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            data.extend_from_slice(&x.to_le_bytes());
        }
        offsets.push(f.data(0, &data));
    }
    for (k, &victim) in [100usize, 2500, 4000].iter().enumerate() {
        for bit in 0..16 {
            let mut bytes = f.0.clone();
            let at = offsets[victim] as usize;
            let size = u16::from_le_bytes([bytes[at], bytes[at + 1]]) ^ (1 << bit);
            bytes[at..at + 2].copy_from_slice(&size.to_le_bytes());
            let log = Log::from_slice(&bytes).unwrap();
            let got: Vec<i16> = values(&log, "t").into_iter().map(|x| x.1).collect();
            let expected: Vec<i16> = (0..6000).filter(|&i| i != victim as i16).collect();
            let without: Vec<i16> = got
                .iter()
                .copied()
                .filter(|&v| v != victim as i16)
                .collect();
            assert_eq!(
                without.len(),
                expected.len(),
                "row {victim} bit {bit}: rows lost"
            );
            assert_eq!(
                without, expected,
                "row {victim} bit {bit}: every other row, in order"
            );
            if k == 0 {
                let (rows, diags) = stream_rows(&bytes, 4096);
                assert_eq!(rows, log_rows(&log), "bit {bit}: the stream reads the same");
                assert_eq!(&diags, log.diagnostics(), "bit {bit}");
            }
        }
    }
}

#[test]
fn for_each_message_shows_each_rows_time_in_the_metadata() {
    // Runs of ten rows between syncs: the fast path takes each run in one go.
    let (f, _) = clean(95);
    let mut reader = StreamReader::new(&f.0[..]).unwrap();
    let mut seen = Vec::new();
    reader
        .for_each_message(|meta, event, _| {
            if let Event::Row(row) = &event {
                seen.push((row.timestamp, meta.last_timestamp()));
            }
            Ok::<(), ReadError>(())
        })
        .unwrap();
    assert_eq!(seen.len(), 95);
    for (t, latest) in seen {
        assert_eq!(latest, t, "the metadata's latest time at the row of {t}");
    }
}

#[test]
fn for_each_message_stopped_by_an_error_goes_on_after_the_row_it_stopped_at() {
    // The error comes mid-run of the fast path: the rows given so far are read, and the
    // next event is the row after the one the callback refused.
    let (f, _) = clean(95);
    let all = stream_rows(&f.0, 4096).0;
    let mut reader = StreamReader::new(&f.0[..]).unwrap();
    let mut given = Vec::new();
    let stopped = reader.for_each_message(|_, event, _| {
        if let Event::Row(row) = &event {
            given.push(row.offset);
            if given.len() == 5 {
                return Err(ReadError::Io(std::io::Error::other("enough")));
            }
        }
        Ok(())
    });
    assert!(matches!(stopped, Err(ReadError::Io(_))));
    let mut rest = Vec::new();
    reader
        .for_each_event(|event| {
            if let Event::Row(row) = &event {
                rest.push(row.offset);
            }
        })
        .unwrap();
    let offsets: Vec<u64> = all.iter().map(|r| r.0).collect();
    assert_eq!(offsets.len(), 95);
    assert_eq!(given, offsets[..5], "the first five rows, once");
    assert_eq!(rest, offsets[5..], "then the others, once each");
}

/// Each subscription's row offsets as [`Log::data`] finds them, row by row.
fn offsets_row_by_row(log: &Log<'_>) -> Vec<Vec<u64>> {
    let mut by_sub = vec![Vec::new(); log.subscriptions().len()];
    for row in log.data() {
        by_sub[row.subscription.index].push(row.offset);
    }
    by_sub
}

#[test]
fn rows_sorted_by_subscription_on_several_threads_are_the_rows_in_file_order() {
    // Three topics, rows interleaved unevenly, a msg_id given to another topic halfway
    // and one with no rows: on 1 to 7 threads (runs of 1 to 40 rows), each subscription
    // gets its rows, in file order.
    let mut f = File::v1(0);
    f.format("a:uint64_t timestamp;int16_t v;uint8_t[2] _padding0;");
    f.format("b:uint64_t timestamp;int16_t v;uint8_t[2] _padding0;");
    f.subscribe(0, 1, "a");
    f.subscribe(0, 2, "b");
    f.subscribe(1, 3, "b");
    for i in 0..40u16 {
        f.data(1 + i % 3 / 2, &row(u64::from(i), i as i16));
        if i == 25 {
            f.subscribe(0, 1, "b");
        }
    }
    let log = Log::from_vec(f.0).unwrap();
    let expected = offsets_row_by_row(&log);
    assert_eq!(expected.len(), 4);
    assert_eq!(
        expected.iter().map(Vec::len).collect::<Vec<_>>(),
        [18, 13, 0, 9]
    );
    for threads in 1..=7 {
        assert_eq!(
            log.offsets_by_subscription(threads, 1),
            expected,
            "{threads} threads"
        );
    }
    assert_eq!(values(&log, "a").len(), 18);
}

#[test]
fn rows_of_subscriptions_numbered_past_the_index_s_two_bytes_are_found_from_their_message() {
    // The row index keeps each row's subscription in two bytes: subscription 65,535 and
    // later are looked up from the row's msg_id instead.
    let mut f = File::v1(0);
    f.format("a:uint64_t timestamp;int16_t v;uint8_t[2] _padding0;");
    for msg_id in 0..=u16::MAX {
        f.subscribe(0, msg_id, "a");
    }
    f.subscribe(1, 7, "a");
    for (k, msg_id) in [0, 65_534, 65_535, 7, 65_535, 1].into_iter().enumerate() {
        f.data(msg_id, &row(k as u64, 0));
    }
    let log = Log::from_vec(f.0).unwrap();
    let expected = offsets_row_by_row(&log);
    let counts = |by_sub: &[Vec<u64>]| [0, 1, 65_534, 65_535, 65_536].map(|s| by_sub[s].len());
    assert_eq!(counts(&expected), [1, 1, 1, 2, 1]);
    for threads in 1..=3 {
        assert_eq!(
            log.offsets_by_subscription(threads, 1),
            expected,
            "{threads} threads"
        );
    }
    let last = &log.subscriptions()[65_536];
    assert_eq!(log.rows(last).map(|r| r.timestamp).collect::<Vec<_>>(), [3]);
}

/// A file the walk is told is near 2^64 bytes long (a sparse file can claim 2^63) splits
/// without overflowing, and reads what it holds.
#[test]
fn a_file_length_near_the_end_of_u64_splits_without_overflow() {
    struct Huge<'a>(&'a [u8]);
    impl<'a> walk::Parts for Huge<'a> {
        type Part<'p>
            = &'a [u8]
        where
            Self: 'p;
        fn len(&self) -> u64 {
            u64::MAX - 7
        }
        fn part(&self, _: u64) -> &'a [u8] {
            self.0
        }
        fn boundary(&self, _: &framer::Framer, _: u64) -> Result<Option<u64>, ReadError> {
            Ok(None)
        }
    }
    let (f, offsets) = clean(30);
    let header = FileHeader::parse(&f.0).unwrap();
    let mut src = &f.0[..];
    let (_, all) =
        walk::collect_from(header, &mut src, &Huge(&f.0), walk::RowCount::default(), 3).unwrap();
    assert_eq!(walk::RowSink::len(&all.sink), offsets.len());
}

/// A window that met the end of its input reads on when the input has grown (a log still
/// being written): the end is no longer taken for the end of the file.
#[test]
fn a_window_at_the_end_reads_on_when_the_input_grows() {
    /// Its bytes up to `limit`, then nothing (0) until the limit moves.
    struct Growing {
        bytes: Vec<u8>,
        at: usize,
        limit: usize,
    }
    impl std::io::Read for Growing {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            let n = buf.len().min(self.limit - self.at);
            buf[..n].copy_from_slice(&self.bytes[self.at..self.at + n]);
            self.at += n;
            Ok(n)
        }
    }
    let input = Growing {
        bytes: (0..100).collect(),
        at: 0,
        limit: 50,
    };
    let mut w = window::Window::new(window::Reading(input), 0);
    w.fill(0).unwrap();
    assert_eq!((w.bytes().len(), w.eof), (50, false));
    w.fill(0).unwrap();
    assert!(w.eof, "the input said it had nothing more");
    w.input.0.limit = 100;
    w.fill(0).unwrap();
    assert!(!w.eof, "more came after the end");
    assert_eq!(w.bytes(), &(0..100).collect::<Vec<u8>>()[..]);
}

#[test]
fn a_parameter_after_a_logged_string_a_thread_read_ahead_is_a_change() {
    // Found by the rewrite fuzzer: a thread reading ahead started at the log's first
    // logged string (its data section's first message, the definitions before it long),
    // and the thread reading the part before it took the parameter after that part, then,
    // for an initial parameter: the change was lost and the initial value overwritten.
    let mut f = File::v1(0);
    f.format("t:uint64_t timestamp;int16_t v;uint8_t[2] _padding0;");
    f.msg(Message::Parameter(KeyValue {
        key: b"float MC_ROLL_P",
        value: &6.5f32.to_le_bytes(),
    }));
    // Definitions to the middle of the file: info values of zeros.
    let zeros = vec![0u8; 60_000];
    while f.0.len() < 4_700_000 {
        f.info("uint8_t[60000] blob", &zeros);
    }
    let first_logged = f.0.len();
    for i in 0..2_000u64 {
        f.msg(Message::Logging {
            level: b'6',
            tag: None,
            timestamp: i,
            text: b"a logged string of the data section",
        });
    }
    // A message a thread reading ahead hands back, then the change.
    f.info("char[2] late", b"ok");
    let change = f.msg(Message::Parameter(KeyValue {
        key: b"float MC_ROLL_P",
        value: &7.25f32.to_le_bytes(),
    }));
    f.subscribe(0, 0, "t");
    // The file's middle, where the second thread's part starts looking for a boundary, a
    // kilobyte before the first logged string: inside an info value's zeros, where none is.
    let mut t = 10_000;
    while f.0.len() < 2 * (first_logged - 1_000) {
        f.data(0, &row(t, 1));
        t += 1_000;
    }
    let facts = |threads| {
        let (summary, _) = fold_rows_on(threads, &f.0, || (), |_, _| {}).unwrap();
        let changes: Vec<(String, u64)> = summary
            .parameter_changes
            .iter()
            .map(|c| (c.name.clone(), c.offset))
            .collect();
        let initial = summary.metadata.parameter("MC_ROLL_P");
        (changes, initial, summary.diagnostics)
    };
    let one = facts(1);
    assert_eq!(one.0, [("MC_ROLL_P".to_owned(), change)]);
    assert_eq!(one.1, Some(ParamValue::Float(6.5)));
    assert!(one.2.is_empty(), "{:?}", one.2);
    assert_eq!(facts(2), one, "two threads");
    let log = Log::from_slice(&f.0).unwrap();
    assert_eq!(log.parameter_changes().len(), 1);
}
