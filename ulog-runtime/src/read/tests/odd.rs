//! Logs that bend the rules, as other tools, forks and old firmware write them: every class
//! keeps the bytes that are there (at least what pyulog keeps) and reports what is odd.

use super::*;

fn kinds(log: &Log<'_>) -> Vec<String> {
    log.diagnostics()
        .iter()
        .map(|d| d.kind.to_string())
        .collect()
}

fn multi(f: &mut File, continued: bool, key: &str, value: &[u8]) {
    f.msg(Message::MultiInfo {
        continued,
        entry: KeyValue {
            key: key.as_bytes(),
            value,
        },
    });
}

#[test]
fn values_that_do_not_fit_their_key_are_kept() {
    let blob: Vec<u8> = (0..=255u8).cycle().take(338 + 338 + 100).collect();
    let mut f = File::v1(0);
    // A re-serialized log: the key says 1169 bytes, each part has what it has.
    multi(&mut f, false, "uint8_t[1169] metadata_events", &blob[..338]);
    multi(
        &mut f,
        true,
        "uint8_t[1169] metadata_events",
        &blob[338..676],
    );
    multi(&mut f, true, "uint8_t[1169] metadata_events", &blob[676..]);
    f.info("uint32_t short", &[1, 2, 3]);
    f.info("uint16_t long", &[1, 2, 3]);
    f.info("float[2] partial", &[0, 0, 0xc0, 0x3f, 9, 9]);
    let log = Log::from_vec(f.0).unwrap();
    let m = &log.metadata().multi_info()[0];
    assert_eq!(
        (m.key.as_str(), m.type_name.as_str()),
        ("metadata_events", "uint8_t[1169]")
    );
    // The continued parts join to every byte, as pyulog joins them.
    assert_eq!(m.joined(0).unwrap(), blob);
    assert_eq!(m.values[0].len(), 3);
    let Value::Array(first) = &m.values[0][0] else {
        panic!("{:?}", m.values[0][0])
    };
    assert_eq!(first.len(), 338, "typed as far as the bytes go");
    let info = |k: &str| {
        log.metadata()
            .info()
            .iter()
            .find(|i| i.key == k)
            .unwrap()
            .clone()
    };
    assert_eq!(info("short").value, Value::Bytes(vec![1, 2, 3]));
    assert_eq!(info("long").value, Value::Scalar(Scalar::UInt16(0x0201)));
    assert_eq!(info("long").raw, [1, 2, 3]);
    assert_eq!(
        info("partial").value,
        Value::Array(vec![Value::Scalar(Scalar::Float(1.5))])
    );
    assert_eq!(
        kinds(&log),
        [
            "`uint8_t[1169] metadata_events`: 338 value bytes, the type needs 1169; kept as they are",
            "`uint8_t[1169] metadata_events`: 338 value bytes, the type needs 1169; kept as they are",
            "`uint8_t[1169] metadata_events`: 100 value bytes, the type needs 1169; kept as they are",
            "`uint32_t short`: 3 value bytes, the type needs 4; kept as they are",
            "`uint16_t long`: 3 value bytes, the type needs 2; kept as they are",
            "`float[2] partial`: 6 value bytes, the type needs 8; kept as they are",
        ]
    );
}

#[test]
fn keys_and_format_names_outside_the_grammar_are_kept_whole() {
    let mut f = File::v1(0);
    f.info("char[11] Build Date", b"2024-03-18 ");
    f.info("string remark", b"no basic type");
    f.info("notype", b"x");
    // A writer that does not follow the name grammar of formats and fields.
    f.format("gps.raw data:uint64_t timestamp;float alt m;;int8_t x-y;");
    f.subscribe(0, 0, "gps.raw data");
    let mut row = 7u64.to_le_bytes().to_vec();
    row.extend_from_slice(&2.5f32.to_le_bytes());
    row.push(0xff);
    f.data(0, &row);
    let log = Log::from_vec(f.0).unwrap();
    let m = log.metadata();
    assert_eq!(
        m.info_value("Build Date").and_then(Value::as_str),
        Some("2024-03-18 ")
    );
    assert_eq!(
        m.info_value("remark"),
        Some(&Value::Bytes(b"no basic type".to_vec()))
    );
    assert_eq!(m.info_value("notype"), Some(&Value::Bytes(b"x".to_vec())));
    let sub = log.subscription("gps.raw data", 0).unwrap();
    let value = log.rows(sub).next().unwrap().value().unwrap();
    assert_eq!(value.to_string(), "{timestamp: 7, alt m: 2.5, x-y: -1}");
    assert_eq!(
        kinds(&log),
        [
            "`char[11] Build Date`: the name `Build Date` is outside the key grammar (kept whole)",
            "`string remark`: `string` is not a basic type; the value is kept as bytes",
            "`notype`: the key has no type",
            "format definition `gps.raw data:uint64_t timestamp;float alt m;;int8_t x-y;` kept as \
             it is: message name `gps.raw data`: character '.' is not allowed in a message name \
             (allowed: a-z A-Z 0-9 _ - /); field name `alt m`: character ' ' is not allowed in a \
             field name (allowed: a-z A-Z 0-9 _); field name `x-y`: character '-' is not allowed \
             in a field name (allowed: a-z A-Z 0-9 _)",
        ]
    );
}

#[test]
fn names_that_are_not_utf8_keep_their_valid_part() {
    let mut f = File::v1(0);
    let format_at = f.msg(Message::Format(b"t\xffopic:uint64_t timestamp;uint8_t v;"));
    f.msg(Message::Subscribe {
        multi_id: 0,
        msg_id: 0,
        name: b"t\xffopic",
    });
    f.data(0, &[1, 0, 0, 0, 0, 0, 0, 0, 9]);
    let info_at = f.msg(Message::Info(KeyValue {
        key: b"char[2] k\xffey",
        value: b"o\xffk",
    }));
    let param_at = f.msg(Message::Parameter(KeyValue {
        key: b"int32_t P\xffX",
        value: &1i32.to_le_bytes(),
    }));
    let logged_at = f.msg(Message::Logging {
        level: b'6',
        tag: None,
        timestamp: 1,
        text: b"bad \xfe byte",
    });
    let log = Log::from_vec(f.0).unwrap();
    // Every text that is not UTF-8 is found, as pyulog's tools fail on each without `-i`.
    assert_eq!(log.not_utf8(), [format_at, info_at, param_at, logged_at]);
    // As pyulog reads them: the invalid bytes left out, the data kept.
    let sub = log.subscription("topic", 0).unwrap();
    assert_eq!(log.rows(sub).count(), 1);
    assert_eq!(
        log.metadata().info_value("key").and_then(Value::as_str),
        Some("ok")
    );
    let logged = &log.logged_messages()[0];
    assert_eq!(
        (logged.text.as_str(), logged.valid_utf8),
        ("bad  byte", false)
    );
    assert_eq!(
        kinds(&log),
        [
            "format definition `topic:uint64_t timestamp;uint8_t v;` kept as it is: not UTF-8 \
             (the invalid bytes are left out)",
            "`char[2] key`: the key is not UTF-8 (the invalid bytes are left out); the text is \
             not UTF-8 (the invalid bytes are left out)",
        ]
    );
}

#[test]
fn a_version_1_file_without_flag_bits_and_an_absolute_start_time() {
    let mut f = File::new(1, 1_710_773_350_346_000);
    f.format("t:uint64_t timestamp;");
    f.subscribe(0, 0, "t");
    f.data(0, &1_710_773_350_400_000u64.to_le_bytes());
    let log = Log::from_vec(f.0).unwrap();
    assert_eq!((log.header().version, log.flag_bits()), (1, None));
    assert_eq!(log.row_count(), 1);
    assert_eq!(
        log.header().start_utc().unwrap().to_string(),
        "2024-03-18 14:49:10.346000 UTC"
    );
    for (us, text) in [
        (946_684_800_000_000, "2000-01-01 00:00:00.000000 UTC"),
        (951_782_400_000_001, "2000-02-29 00:00:00.000001 UTC"),
        (4_102_444_799_999_999, "2099-12-31 23:59:59.999999 UTC"),
        (4_107_542_400_000_000, "2100-03-01 00:00:00.000000 UTC"),
    ] {
        assert_eq!(UtcTime::from_unix_us(us).to_string(), text);
    }
    assert_eq!(UtcTime::from_unix_us(u64::MAX).year, 586_524);
    // Before 2000 a boot time; from 2100 on damage (a header of 2^64-1 µs read as the year
    // 586524 before): neither is a date.
    for start_timestamp in [946_684_799_999_999, 4_102_444_800_000_000, u64::MAX] {
        let header = FileHeader {
            version: 1,
            start_timestamp,
        };
        assert!(header.start_utc().is_none(), "{start_timestamp}");
    }
    assert_eq!(
        FileHeader {
            version: 1,
            start_timestamp: 4_102_444_799_999_999
        }
        .start_utc()
        .unwrap()
        .year,
        2099
    );
}

#[test]
fn a_msg_id_given_to_another_topic_keeps_each_row_with_its_subscription() {
    // Found by the whole_file fuzzer: rows before the second `A` of a msg_id were counted
    // as the later topic's.
    let mut f = File::v1(0);
    f.msg(Message::Format(b"a:uint64_t timestamp;uint8_t x;"));
    f.msg(Message::Format(
        b"b:uint64_t timestamp;uint16_t y;uint16_t z;",
    ));
    f.msg(Message::Subscribe {
        multi_id: 0,
        msg_id: 0,
        name: b"a",
    });
    f.msg(Message::Data {
        msg_id: 0,
        data: &[1, 0, 0, 0, 0, 0, 0, 0, 9],
    });
    f.msg(Message::Data {
        msg_id: 0,
        data: &[2, 0, 0, 0, 0, 0, 0, 0, 8],
    });
    f.msg(Message::Subscribe {
        multi_id: 0,
        msg_id: 0,
        name: b"b",
    });
    f.msg(Message::Data {
        msg_id: 0,
        data: &[3, 0, 0, 0, 0, 0, 0, 0, 5, 0, 6, 0],
    });
    let log = Log::from_vec(f.0).unwrap();
    let [a, b] = log.subscriptions() else {
        panic!("two subscriptions");
    };
    let rows = |s| {
        log.rows(s)
            .map(|r| (r.timestamp, r.subscription.name.clone()))
            .collect::<Vec<_>>()
    };
    assert_eq!(rows(a), [(1, "a".to_owned()), (2, "a".to_owned())]);
    assert_eq!(rows(b), [(3, "b".to_owned())]);
    let names: Vec<String> = log.data().map(|r| r.subscription.name.clone()).collect();
    assert_eq!(names, ["a", "a", "b"]);
    assert_eq!(
        log.columns("b", 0).unwrap().get("z").unwrap().as_uint16(),
        Some(&[6][..])
    );
    assert_eq!(
        kinds(&log),
        ["msg_id 0 subscribed again (was `a`), now `b`"]
    );
}

#[test]
fn a_msg_id_subscribed_again_to_a_topic_that_cannot_be_read_says_both() {
    // Found by the rewrite fuzzer: the note of the msg_id subscribed again replaced the
    // subscription's own (no format; no timestamp), so the topic left out was not said.
    let mut f = File::v1(0);
    f.msg(Message::Format(b"a:uint64_t timestamp;uint8_t x;"));
    f.msg(Message::Format(b"e:uint64_t time;uint8_t x;"));
    f.msg(Message::Subscribe {
        multi_id: 0,
        msg_id: 0,
        name: b"a",
    });
    f.msg(Message::Subscribe {
        multi_id: 0,
        msg_id: 0,
        name: b"nowhere",
    });
    f.msg(Message::Subscribe {
        multi_id: 0,
        msg_id: 0,
        name: b"e",
    });
    f.msg(Message::Data {
        msg_id: 0,
        data: &[3, 0, 0, 0, 0, 0, 0, 0, 5],
    });
    let expected = [
        "subscription `nowhere` (msg_id 0): no format named `nowhere`",
        "msg_id 0 subscribed again (was `a`), now `nowhere`",
        "topic `e` has no unsigned integer `timestamp` field; its rows get timestamp 0",
        "msg_id 0 subscribed again (was `nowhere`), now `e`",
    ];
    let log = Log::from_slice(&f.0).unwrap();
    assert_eq!(kinds(&log), expected);
    assert_eq!(
        crate::read::Skipped::of(log.diagnostics()).unreadable_topics,
        [(
            "nowhere".to_owned(),
            0,
            "no format named `nowhere`".to_owned()
        )]
    );
    // The stream says the same, a byte at a time and all at once.
    for chunk in [1, 4096] {
        let (rows, diagnostics) = super::stream_rows(&f.0, chunk);
        assert_eq!(rows.len(), 1);
        let said: Vec<String> = diagnostics.iter().map(|d| d.kind.to_string()).collect();
        assert_eq!(said, expected, "chunks of {chunk}");
    }
}
