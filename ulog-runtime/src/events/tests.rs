//! The events decoder on hand-written metadata. Every expected message is what pyulog
//! 1.3.0's `libevents_parse` parser gives for the same template and argument bytes (run
//! once, by hand, with the same definitions); the metadata tests use xz streams made here
//! with lzma-rust2's encoder, and a log made by the writer.

use std::io::Write;

use serde_json::json;

use super::*;

/// Definitions with one event (component 1, sub-id 5) of this template and arguments, and
/// the enums pyulog was run with.
fn definitions(template: &str, args: &[&str]) -> EventDefinitions {
    let arguments: Vec<_> = args
        .iter()
        .enumerate()
        .map(|(i, t)| json!({"type": t, "name": format!("a{i}")}))
        .collect();
    let doc = json!({
        "version": 2,
        "components": {"1": {
            "namespace": "px4",
            "enums": {
                "e_t": {"type": "uint8_t", "entries": {
                    "1": {"name": "a", "description": "Alpha"},
                    "2": {"name": "b", "description": "Beta"}}},
                "b_t": {"type": "uint8_t", "is_bitfield": true, "separator": ", ", "entries": {
                    "1": {"name": "a", "description": "A"},
                    "4": {"name": "c", "description": "C"}}}
            },
            "event_groups": {"default": {"events": {"5": {
                "name": "t", "message": template, "arguments": arguments,
                "description": "<profile name=\"dev\">see <param>P_{1}</param></profile>"
            }}}}
        }}
    });
    EventDefinitions::from_json(doc.to_string().as_bytes()).unwrap()
}

fn row(id: u32, args: &[u8], log_levels: u8) -> EventRow {
    let mut arguments = args.to_vec();
    arguments.resize(25, 0);
    EventRow {
        timestamp: 1_000,
        id,
        sequence: Some(3),
        arguments,
        log_levels,
        offset: 0,
    }
}

/// The message of the test event with these arguments.
fn message(template: &str, types: &[&str], args: &[u8]) -> Result<String, FormatError> {
    let defs = definitions(template, types);
    decode(&row((1 << 24) | 5, args, 0x66), &defs)
        .unwrap()
        .message
}

fn f(x: f32) -> Vec<u8> {
    x.to_le_bytes().to_vec()
}

#[test]
fn templates_format_as_pyulog_formats_them() {
    let u = &["uint8_t"][..];
    let seven = &[7u8][..];
    for (template, types, args, expected) in [
        ("plain {1}", u, seven.to_vec(), "plain 7"),
        (
            "  leading/trailing ws {1}  \n",
            u,
            seven.to_vec(),
            "leading/trailing ws 7",
        ),
        ("idx0 {0} idx2 {2}", u, seven.to_vec(), "idx0 {0} idx2 {2}"),
        ("no close {1", u, seven.to_vec(), "no close {1"),
        (
            "bad fmt {1:x} {1:.} {1:2} {1m_x} { 1}",
            u,
            seven.to_vec(),
            "bad fmt {1:x} {1:.} {1:2} {1m_x} { 1}",
        ),
        ("{1:} colon only", u, seven.to_vec(), "7 colon only"),
        ("{1:m} colon+unit", &["float"], f(1.5), "1.5 m colon+unit"),
        (
            "{1:.2} int with decimals",
            u,
            seven.to_vec(),
            "7.00 int with decimals",
        ),
        (
            "{1:.2C} {1m^2} {1m/s} {1C}",
            &["float"],
            f(21.5),
            "21.50 C 21.5 m^2 21.5 m/s 21.5 C",
        ),
        (
            "{01} leading zero idx",
            u,
            seven.to_vec(),
            "7 leading zero idx",
        ),
        (
            "{1:.12} big precision",
            &["float"],
            f(0.1),
            "0.100000001490 big precision",
        ),
        (
            "{1} enum,{1m} enum+unit",
            &["e_t"],
            vec![2],
            "Beta enum,Beta m enum+unit",
        ),
        ("bits {1}", &["b_t"], vec![5], "bits A, C"),
        ("bits {1}", &["b_t"], vec![7], "bits A, (unknown: 7), C"),
        (
            "esc \\{1} and \\\\ and \\<param>X</param> and trailing \\",
            u,
            seven.to_vec(),
            "esc {1} and \\ and <param>X</param> and trailing",
        ),
        (
            "tag <param>P_{1}</param> after {1}",
            u,
            seven.to_vec(),
            "tag P_{1} after 7",
        ),
        (
            "tag <a href=\"http://x\">link {1}</a> {1}",
            u,
            seven.to_vec(),
            "tag link {1} 7",
        ),
        ("tag <a>http://u</a>", &[], vec![], "tag http://u"),
        (
            "<profile name=\"dev\">DEV {1}</profile>|<profile name=\"!dev\">NOTDEV</profile>|<profile name=\"normal\">NORMAL</profile>|<profile>NONAME</profile>",
            u,
            seven.to_vec(),
            "DEV 7|||",
        ),
        (
            "unknown <b>bold {1}</b> tag",
            u,
            seven.to_vec(),
            "unknown  tag",
        ),
        ("unclosed <param>X", &[], vec![], "unclosed <param>X"),
        (
            "uppercase <B>x</B> and <a  href=\"x\">y</a>",
            &[],
            vec![],
            "uppercase <B>x</B> and <a  href=\"x\">y</a>",
        ),
        ("empty <param></param>.", &[], vec![], "empty ."),
        ("lt at end <", &[], vec![], "lt at end <"),
        ("a < b > c", &[], vec![], "a < b > c"),
        (
            "nested <profile name=\"dev\">a<profile name=\"dev\">b</profile>c</profile>",
            &[],
            vec![],
            "nested abc",
        ),
        ("unicode ± {1} é", u, seven.to_vec(), "unicode ± 7 é"),
        ("ws\u{a0}nbsp\u{1f}", &[], vec![], "ws\u{a0}nbsp"),
        ("{1}{2}", &["uint8_t", "int8_t"], vec![7, 0xff], "7-1"),
        (
            "{1} f32 max",
            &["float"],
            f(f32::MAX),
            "3.4028234663852886e+38 f32 max",
        ),
    ] {
        assert_eq!(
            message(template, types, &args).as_deref(),
            Ok(expected),
            "{template:?}"
        );
    }
    let mut wide = u64::MAX.to_le_bytes().to_vec();
    wide.extend_from_slice(&i64::MIN.to_le_bytes());
    assert_eq!(
        message("uint64 {1} int64 {2}", &["uint64_t", "int64_t"], &wide).unwrap(),
        "uint64 18446744073709551615 int64 -9223372036854775808"
    );
}

#[test]
fn floats_print_as_python_prints_them() {
    let plain = "to {1}ms";
    let rounded = "Climb to {1:.1m_v} above home";
    for (bits, plain_text, rounded_text) in [
        (
            0.1f32.to_bits(),
            "to 0.10000000149011612ms",
            "Climb to 0.1 m above home",
        ),
        (
            100.0f32.to_bits(),
            "to 100.0ms",
            "Climb to 100.0 m above home",
        ),
        (
            1e20f32.to_bits(),
            "to 1.0000000200408773e+20ms",
            "Climb to 100000002004087734272.0 m above home",
        ),
        (
            1e16f32.to_bits(),
            "to 1.0000000272564224e+16ms",
            "Climb to 10000000272564224.0 m above home",
        ),
        (
            1e-5f32.to_bits(),
            "to 9.999999747378752e-06ms",
            "Climb to 0.0 m above home",
        ),
        (2.25f32.to_bits(), "to 2.25ms", "Climb to 2.2 m above home"),
        (
            2.35f32.to_bits(),
            "to 2.3499999046325684ms",
            "Climb to 2.3 m above home",
        ),
        (
            (-0.04f32).to_bits(),
            "to -0.03999999910593033ms",
            "Climb to -0.0 m above home",
        ),
        (
            (-0.0f32).to_bits(),
            "to -0.0ms",
            "Climb to -0.0 m above home",
        ),
        (0x7fc0_0000, "to nanms", "Climb to nan m above home"),
        (0xffc0_0000, "to nanms", "Climb to nan m above home"),
        (
            f32::INFINITY.to_bits(),
            "to infms",
            "Climb to inf m above home",
        ),
        (
            f32::NEG_INFINITY.to_bits(),
            "to -infms",
            "Climb to -inf m above home",
        ),
        (1, "to 1.401298464324817e-45ms", "Climb to 0.0 m above home"),
    ] {
        let args = bits.to_le_bytes();
        assert_eq!(message(plain, &["float"], &args).unwrap(), plain_text);
        assert_eq!(message(rounded, &["float"], &args).unwrap(), rounded_text);
    }
    // `.0` rounds the exact binary value half to even.
    for (x, text) in [(0.5f32, "0 m"), (1.5, "2 m"), (2.5, "2 m")] {
        assert_eq!(message("{1:.0m_v}", &["float"], &f(x)).unwrap(), text);
    }
}

#[test]
fn enum_values_and_errors_are_those_of_the_python_parser() {
    // An enum's text with a number format: pyulog's ValueError.
    assert_eq!(
        message("{1:.2} enum with decimals", &["e_t"], &[1]),
        Err(FormatError::PrecisionOfEnum {
            arg: 1,
            precision: 2
        })
    );
    assert_eq!(message("{1}", &["e_t"], &[9]).unwrap(), "(unknown: 9)");
    assert_eq!(message("bits {1}", &["b_t"], &[0]).unwrap(), "bits");
    // A type the metadata does not define: pyulog's KeyError at parse time.
    let defs = definitions("{1}", &["nope_t"]);
    assert!(matches!(
        decode(&row((1 << 24) | 5, &[1], 0x66), &defs),
        Err(EventError::UnknownType { ty, .. }) if ty == "nope_t"
    ));
    // Arguments beyond the row's bytes: pyulog's struct.error.
    let defs = definitions("{1}", &["uint64_t"; 4]);
    assert_eq!(
        decode(&row((1 << 24) | 5, &[], 0x66), &defs),
        Err(EventError::ShortArguments {
            event: "t".into(),
            need: 32,
            have: 25
        })
    );
    // An id no component or group has.
    let defs = definitions("{1}", &["uint8_t"]);
    assert_eq!(
        decode(&row(33_554_431, &[], 0x66), &defs),
        Err(EventError::UnknownId(33_554_431))
    );
    assert_eq!(
        EventError::UnknownId(7).to_string(),
        "[Unknown event with ID 7]"
    );
}

#[test]
fn a_decoded_event_has_its_definition_levels_and_description() {
    let defs = definitions("Armed by {1}", &["e_t"]);
    let r = row((1 << 24) | 5, &[1], 0x64);
    assert_eq!(
        (r.internal_level().name(), r.external_level().name()),
        ("INFO", "WARNING")
    );
    assert_eq!(EventLevel(12).name(), "UNKNOWN");
    let e = decode(&r, &defs).unwrap();
    assert_eq!(
        (e.name.as_str(), e.namespace.as_str(), e.group.as_str()),
        ("t", "px4", "default")
    );
    assert_eq!(e.message.unwrap(), "Armed by Alpha");
    assert_eq!(e.description, Some(Ok("see P_{1}".to_owned())));
    assert_eq!(
        e.arguments,
        [("a0".to_owned(), ArgValue::U8(1), Ok("Alpha".to_owned()))]
    );
}

#[test]
fn definitions_refuse_what_the_python_parser_refuses() {
    for (doc, error) in [
        (json!({"version": 0}), "unexpected version 0"),
        (json!({}), "unexpected version 0"),
        (
            json!({"version": 2, "components": {"x": {"namespace": "n"}}}),
            "key `x`",
        ),
        (json!([1, 2]), "events metadata"),
    ] {
        let e = EventDefinitions::from_json(doc.to_string().as_bytes()).unwrap_err();
        assert!(e.to_string().contains(error), "{e}");
    }
    // Groups without events and components without groups are fine.
    let ok =
        json!({"version": 1, "components": {"3": {"namespace": "n", "event_groups": {"g": {}}}}});
    assert!(
        EventDefinitions::from_json(ok.to_string().as_bytes())
            .unwrap()
            .is_empty()
    );
}

fn xz(data: &[u8]) -> Vec<u8> {
    let mut w =
        lzma_rust2::XzWriter::new(Vec::new(), lzma_rust2::XzOptions::with_preset(6)).unwrap();
    w.write_all(data).unwrap();
    w.finish().unwrap()
}

fn sha256_hex(data: &[u8]) -> String {
    use sha2::Digest;
    sha2::Sha256::digest(data)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

fn metadata_json() -> Vec<u8> {
    json!({
        "version": 2,
        "components": {"1": {"namespace": "px4", "event_groups": {
            "default": {"events": {"5": {"name": "armed", "message": "Armed by {1}",
                "arguments": [{"type": "uint8_t", "name": "why"}]}}},
            "health": {"events": {"6": {"name": "h", "message": "health"}}}
        }}}
    })
    .to_string()
    .into_bytes()
}

#[test]
fn metadata_decodes_checks_its_digest_and_fails_clearly() {
    let json = metadata_json();
    let compressed = xz(&json);
    let sha = sha256_hex(&compressed);
    let m = EventsMetadata::decode(&compressed, Some(&sha)).unwrap();
    assert_eq!(m.verification, Verification::Matches);
    assert_eq!(m.json_len, json.len());
    assert_eq!(m.definitions.len(), 2);
    assert_eq!(
        EventsMetadata::decode(&compressed, None)
            .unwrap()
            .verification,
        Verification::NoDigest
    );
    let wrong = "0".repeat(64);
    assert!(matches!(
        EventsMetadata::decode(&compressed, Some(&wrong)).unwrap().verification,
        Verification::Mismatch { expected, actual } if expected == wrong && actual == sha
    ));
    // Truncated, or a flipped byte: an error, no panic.
    let cut = EventsMetadata::decode(&compressed[..compressed.len() / 2], None).unwrap_err();
    assert!(cut.to_string().contains("does not decompress"), "{cut}");
    let mut flipped = compressed.clone();
    let mid = flipped.len() / 2;
    flipped[mid] ^= 0x55;
    assert!(EventsMetadata::decode(&flipped, None).is_err());
    assert!(matches!(
        EventsMetadata::decode(b"not xz at all", None),
        Err(MetadataError::Xz { .. })
    ));
    // Valid xz of something that is not the metadata.
    assert!(matches!(
        EventsMetadata::decode(&xz(b"{\"version\": 2, \"components\": 7}"), None),
        Err(MetadataError::Definitions(_))
    ));
}

/// A log with the metadata in continued parts of uneven size, its digest, and event rows.
fn log_with_events(parts: &[usize], digest: Option<&str>) -> Vec<u8> {
    use crate::{Scalar, Value, Writer, WriterOptions};
    let compressed = xz(&metadata_json());
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    w.info("sys_name", &Value::String("PX4".into())).unwrap();
    let mut at = 0usize;
    for (i, &n) in parts.iter().chain(std::iter::once(&usize::MAX)).enumerate() {
        let end = at.saturating_add(n).min(compressed.len());
        if at == end {
            break;
        }
        let part = Value::Array(
            compressed[at..end]
                .iter()
                .map(|&b| Value::Scalar(Scalar::UInt8(b)))
                .collect(),
        );
        w.multi_info(metadata::METADATA_KEY, &part, i > 0).unwrap();
        at = end;
    }
    let sha = digest.map_or_else(|| sha256_hex(&compressed), str::to_owned);
    w.info(metadata::SHA256_KEY, &Value::String(sha)).unwrap();
    w.format("event:uint64_t timestamp;uint32_t id;uint16_t event_sequence;uint8_t[25] arguments;uint8_t log_levels;")
        .unwrap();
    let sub = w.subscribe("event", 0).unwrap();
    for (t, id, arg, levels) in [
        (3_000u64, (1u32 << 24) | 5, 7u8, 0x66u8),
        (1_000, (1 << 24) | 6, 0, 0x66),
        (2_000, (1 << 24) | 5, 9, 0x88),
        (4_000, (2 << 24) | 1, 0, 0x33),
    ] {
        let mut data = t.to_le_bytes().to_vec();
        data.extend_from_slice(&id.to_le_bytes());
        data.extend_from_slice(&1u16.to_le_bytes());
        let mut args = [0u8; 25];
        args[0] = arg;
        data.extend_from_slice(&args);
        data.push(levels);
        w.data(sub, &data).unwrap();
    }
    w.log(b'6', 3_000, "Armed by 7\t").unwrap();
    w.log(b'6', 3_000, "at the same time").unwrap();
    w.log(b'4', 500, "first").unwrap();
    w.into_inner()
}

#[test]
fn a_logs_events_come_from_metadata_in_continued_parts() {
    let log = Log::from_vec(log_with_events(&[100, 37, 1169], None)).unwrap();
    let events = log.events();
    let m = events.metadata.as_ref().unwrap();
    assert_eq!(m.verification, Verification::Matches);
    assert_eq!(events.rows.len(), 4);
    let e = decode(&events.rows[0], &m.definitions).unwrap();
    assert_eq!(e.message.unwrap(), "Armed by 7");
    // As ulog_messages lists them: level 8 and other groups left out, the unknown id
    // shown, the tab-ended string that duplicates an event left out, sorted by time with
    // events first.
    let lines: Vec<String> = messages(&log)
        .lines
        .iter()
        .map(MessageLine::pyulog_line)
        .collect();
    assert_eq!(
        lines,
        [
            "0:00:00.000 WARNING: first",
            "0:00:00.003 INFO: Armed by 7",
            "0:00:00.003 INFO: at the same time",
            "0:00:00.004 ERROR: [Unknown event with ID 33554433]",
        ]
    );
    // A digest that does not match: decoded anyway, as pyulog does, and said.
    let log = Log::from_vec(log_with_events(&[1169], Some(&"ab".repeat(32)))).unwrap();
    let m = messages(&log);
    assert_eq!(m.lines.len(), 4);
    assert!(m.notes[0].contains("sha256"), "{:?}", m.notes);
}

#[test]
fn without_usable_metadata_the_rows_stay_and_the_reason_is_given() {
    let mut bytes = log_with_events(&[1169], None);
    // Damage the compressed metadata inside the file.
    let at = bytes
        .windows(6)
        .position(|w| w == [0xfd, b'7', b'z', b'X', b'Z', 0])
        .unwrap();
    bytes[at + 40] ^= 0xff;
    let log = Log::from_vec(bytes).unwrap();
    let events = log.events();
    assert_eq!(events.rows.len(), 4, "the rows stay available");
    assert!(events.metadata.is_err());
    let m = messages(&log);
    assert!(
        m.warnings[0].starts_with("Failed to get event parser: "),
        "{:?}",
        m.warnings
    );
    assert_eq!(m.lines.len(), 2, "the logged strings still");
    // The string that duplicates an event is left out as pyulog leaves it out, and said,
    // since no event shows what it said.
    assert!(
        m.notes
            .iter()
            .any(|n| n.starts_with("1 logged string ending in a tab left out")),
        "{:?}",
        m.notes
    );
}

#[test]
fn every_integer_type_reads_little_endian_with_its_sign() {
    let mut args = Vec::new();
    args.extend_from_slice(&0xfffeu16.to_le_bytes());
    args.extend_from_slice(&(-2i16).to_le_bytes());
    args.extend_from_slice(&4_000_000_000u32.to_le_bytes());
    args.extend_from_slice(&(-5i32).to_le_bytes());
    args.push(0x80);
    assert_eq!(
        message(
            "{1} {2} {3} {4} {5}",
            &["uint16_t", "int16_t", "uint32_t", "int32_t", "int8_t"],
            &args
        )
        .unwrap(),
        "65534 -2 4000000000 -5 -128"
    );
}

#[test]
fn a_stream_decodes_the_same_events_as_the_whole_file() {
    let bytes = log_with_events(&[500, 1169], None);
    let whole = Log::from_vec(bytes.clone()).unwrap().events();
    let mut reader = crate::StreamReader::new(&bytes[..]).unwrap();
    let (mut layout, mut metadata, mut rows): (Option<EventLayout>, _, _) =
        (None, None, Vec::new());
    while let Some(event) = reader.next_event().unwrap() {
        // The subscription's format id; the layout is made once the event is done with.
        let subscribed = match &event {
            crate::Event::Subscription(s) if s.name == TOPIC => s.format(),
            crate::Event::Row(row) => {
                if let Some(l) = &layout {
                    rows.push(l.read(row).unwrap());
                }
                None
            }
            _ => None,
        };
        if let Some(id) = subscribed {
            layout = Some(EventLayout::of(reader.metadata().schema(), id).unwrap());
            metadata = Some(EventsMetadata::of(reader.metadata()).unwrap());
        }
    }
    assert_eq!(rows, whole.rows);
    let defs = &metadata.unwrap().definitions;
    let messages: Vec<_> = rows
        .iter()
        .map(|r| decode(r, defs).map(|e| e.message))
        .collect();
    let expected: Vec<_> = whole
        .rows
        .iter()
        .map(|r| decode(r, &whole.metadata.as_ref().unwrap().definitions).map(|e| e.message))
        .collect();
    assert_eq!(messages, expected);
    assert_eq!(messages[0], Ok(Ok("Armed by 7".to_owned())));
}

#[test]
fn tagged_strings_are_listed_only_when_asked_for() {
    use crate::{Value, Writer, WriterOptions};
    for sys_name in ["PX4", "other"] {
        let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
        w.info("sys_name", &Value::String(sys_name.into())).unwrap();
        w.log(b'6', 1_000, "plain").unwrap();
        w.log_tagged(b'4', 3, 2_000, "tagged").unwrap();
        w.log(b'3', 3_000, "later").unwrap();
        let log = Log::from_vec(w.into_inner()).unwrap();
        let lines =
            |m: Messages| -> Vec<String> { m.lines.iter().map(MessageLine::pyulog_line).collect() };
        // As ulog_messages prints them: pyulog lists `L` messages only.
        assert_eq!(
            lines(messages(&log)),
            ["0:00:00.001 INFO: plain", "0:00:00.003 ERROR: later"],
            "{sys_name}"
        );
        assert_eq!(
            lines(all_messages(&log)),
            [
                "0:00:00.001 INFO: plain",
                "0:00:00.002 WARNING: [tag 3] tagged",
                "0:00:00.003 ERROR: later"
            ],
            "{sys_name}"
        );
        assert_eq!(all_messages(&log).lines[1].kind, MessageKind::Tagged(3));
    }
}
