//! The writer, proven two ways:
//! - every corpus file, read and written back through the writer's calls in file order,
//!   reads back with the same formats, info, parameters, strings and rows (and the same bytes
//!   where the input was written in the writer's canonical way);
//! - pyulog reads a file the writer made (nested formats, arrays, inner and trailing padding,
//!   two instances, every message type) and sees exactly what this reader sees and what was
//!   written.

mod rewrite;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde_json::Value as Json;
use sha2::{Digest, Sha256};
use ulog_runtime::read::{Event, Message, ParamValue, StreamReader};
use ulog_runtime::write::{SubscriptionId, Writer, WriterOptions};
use ulog_runtime::{Log, Scalar, Value};
use ulog_tests::{check_file, corpus_files, pyulog_view, short_name, under_ci};

/// Writes `input` again through the writer, message by message in file order.
fn rewrite(input: &[u8]) -> Vec<u8> {
    let log = Log::from_slice(input).unwrap();
    let options = WriterOptions {
        start_timestamp: log.header().start_timestamp,
        default_parameters: log.flag_bits().is_some_and(|b| b.has_default_parameters()),
    };
    let mut w = Writer::new(Vec::new(), options).unwrap();
    let mut ids: HashMap<u16, SubscriptionId> = HashMap::new();
    let mut reader = StreamReader::new(input).unwrap();
    loop {
        // Definitions are read back from the metadata once the event is let go.
        let definition = match reader.next_event().unwrap() {
            None => break,
            Some(Event::Definition { offset, .. }) => offset,
            Some(event) => {
                match event {
                    Event::Subscription(s) => {
                        let id = w.subscribe(&s.name, s.multi_id).unwrap();
                        ids.insert(s.msg_id, id);
                    }
                    Event::Row(r) => w.data(ids[&r.subscription.msg_id], r.data).unwrap(),
                    Event::Logged(m) => match m.tag {
                        None => w.log(m.level_byte, m.timestamp, &m.text).unwrap(),
                        Some(tag) => w
                            .log_tagged(m.level_byte, tag, m.timestamp, &m.text)
                            .unwrap(),
                    },
                    Event::ParameterChange(c) => w.parameter(&c.name, c.value).unwrap(),
                    Event::Dropout(d) => w.dropout(d.duration_ms).unwrap(),
                    Event::Sync { .. } => w.sync().unwrap(),
                    Event::Definition { .. } | Event::Diagnostic(_) => {}
                }
                continue;
            }
        };
        let meta = reader.metadata();
        {
            {
                let at = definition as usize;
                let size = usize::from(u16::from_le_bytes([input[at], input[at + 1]]));
                let msg = Message::parse(input[at + 2], &input[at + 3..at + 3 + size]).unwrap();
                let key_name = |key: &[u8]| {
                    String::from_utf8_lossy(key)
                        .rsplit(' ')
                        .next()
                        .unwrap()
                        .to_owned()
                };
                match msg {
                    Message::Format(text) => {
                        w.format(std::str::from_utf8(text).unwrap()).unwrap();
                    }
                    Message::Info(kv) => {
                        let key = key_name(kv.key);
                        w.info(&key, meta.info_value(&key).unwrap()).unwrap();
                    }
                    Message::MultiInfo { continued, entry } => {
                        let key = key_name(entry.key);
                        let m = meta.multi_info().iter().find(|m| m.key == key).unwrap();
                        w.multi_info(&key, m.values.last().unwrap().last().unwrap(), continued)
                            .unwrap();
                    }
                    Message::Parameter(kv) => {
                        let name = key_name(kv.key);
                        let p = meta
                            .initial_parameters()
                            .iter()
                            .find(|p| p.name == name)
                            .unwrap();
                        w.parameter(&name, p.value).unwrap();
                    }
                    Message::DefaultParameter { .. } => {
                        let q = meta.default_parameters().last().unwrap();
                        w.default_parameter(&q.name, q.value, q.default_types)
                            .unwrap();
                    }
                    Message::Unsubscribe { msg_id } => {
                        if let Some(&id) = ids.get(&msg_id) {
                            w.unsubscribe(id).unwrap();
                        }
                    }
                    _ => {}
                }
            }
        }
    }
    w.into_inner()
}

/// What must survive a round trip.
fn content(log: &Log<'_>) -> Vec<String> {
    let m = log.metadata();
    let mut out = vec![
        format!("{:?}", log.header().start_timestamp),
        m.schema().to_string(),
    ];
    out.extend(m.info().iter().map(|i| format!("{i:?}")));
    out.extend(m.multi_info().iter().map(|i| format!("{i:?}")));
    out.extend(m.initial_parameters().iter().map(|p| format!("{p:?}")));
    out.extend(m.default_parameters().iter().map(|p| format!("{p:?}")));
    out.extend(
        log.logged_messages()
            .iter()
            .map(|l| format!("{:?} {:?} {} {}", l.level_byte, l.tag, l.timestamp, l.text)),
    );
    out.extend(
        log.parameter_changes()
            .iter()
            .map(|c| format!("{} {:?}", c.name, c.value)),
    );
    out.extend(log.dropouts().iter().map(|d| d.duration_ms.to_string()));
    out.push(format!("{} syncs", log.sync_offsets().len()));
    for s in log.subscriptions() {
        // The msg_id is not content: the writer numbers subscriptions 0, 1, 2... in order.
        out.push(format!("{} {}", s.name, s.multi_id));
        out.extend(log.rows(s).map(|r| format!("{} {:?}", r.timestamp, r.data)));
    }
    out
}

#[test]
fn corpus_round_trips_through_the_writer() {
    let mut identical = Vec::new();
    for path in corpus_files() {
        let input = std::fs::read(&path).unwrap();
        let log = Log::from_slice(&input).unwrap();
        let output = rewrite(&input);
        let back = Log::from_slice(&output).unwrap();
        assert_eq!(back.diagnostics(), &[], "{}", short_name(&path));
        let (ours, theirs) = (content(&back), content(&log));
        if let Some(i) = (0..ours.len().max(theirs.len())).find(|&i| ours.get(i) != theirs.get(i)) {
            panic!(
                "{}: content differs after a round trip at item {i}:\n written back: {:?}\n original:     {:?}",
                short_name(&path),
                ours.get(i),
                theirs.get(i)
            );
        }
        if output == input {
            identical.push(short_name(&path));
        }
        // A clean version-1 file with the writer's flag bits and msg_ids numbered in order is
        // written the writer's way; it must come back byte for byte.
        let in_order = log
            .subscriptions()
            .iter()
            .enumerate()
            .all(|(i, s)| usize::from(s.msg_id) == i);
        let canonical = in_order
            && log.header().version == 1
            && log.diagnostics().is_empty()
            && log
                .flag_bits()
                .is_some_and(|b| b.appended_offsets == [0; 3] && b.incompat == [0; 8]);
        if canonical && input[16..19] == [40, 0, b'B'] {
            assert_eq!(output.len(), input.len(), "{}", short_name(&path));
            assert!(
                output == input,
                "{}: a canonical file must round-trip byte for byte",
                short_name(&path)
            );
        }
    }
    eprintln!("byte-identical round trips: {identical:?}");
}

/// A file with every message type, nested and padded formats, arrays and two instances.
fn interop_file() -> Vec<u8> {
    let mut w = Writer::new(
        Vec::new(),
        WriterOptions {
            start_timestamp: 1_000_000,
            default_parameters: true,
        },
    )
    .unwrap();
    w.format("esc_status:uint64_t timestamp;uint8_t esc_count;uint8_t[3] _padding0;esc_report[2] esc;uint8_t[4] _padding1;").unwrap();
    w.format("esc_report:int32_t esc_rpm;float esc_voltage;bool armed;char[3] tag;int16_t[2] t;int8_t _padding0;").unwrap();
    w.format("mix:uint64_t timestamp;double d;int64_t i;uint16_t u;char[5] name;float[3] v;")
        .unwrap();
    w.info("sys_name", &Value::String("interop".into()))
        .unwrap();
    w.info(
        "ver_sw_release",
        &Value::Scalar(Scalar::UInt32(0x0109_00ff)),
    )
    .unwrap();
    w.info("time_ref_utc", &Value::Scalar(Scalar::Int32(-3600)))
        .unwrap();
    w.info(
        "blob",
        &Value::Array(
            (0..4)
                .map(|i| Value::Scalar(Scalar::UInt8(i * 60)))
                .collect(),
        ),
    )
    .unwrap();
    w.multi_info("perf", &Value::String("first".into()), false)
        .unwrap();
    w.multi_info("perf", &Value::String(" continued".into()), true)
        .unwrap();
    w.multi_info("perf", &Value::String("second".into()), false)
        .unwrap();
    w.parameter("MC_ROLL_P", ParamValue::Float(6.5)).unwrap();
    w.parameter("SYS_AUTOSTART", ParamValue::Int32(4001))
        .unwrap();
    w.default_parameter("MC_ROLL_P", ParamValue::Float(7.0), 1)
        .unwrap();
    w.default_parameter("SYS_AUTOSTART", ParamValue::Int32(0), 3)
        .unwrap();
    let esc = [
        w.subscribe("esc_status", 0).unwrap(),
        w.subscribe("esc_status", 1).unwrap(),
    ];
    let mix = w.subscribe("mix", 0).unwrap();
    for i in 0..20u64 {
        for (k, &id) in esc.iter().enumerate() {
            let mut r = (1_000_000 + i * 10_000 + k as u64).to_le_bytes().to_vec();
            r.extend_from_slice(&[2, 0, 0, 0]);
            for e in 0..2i32 {
                r.extend_from_slice(&(1_000 * e + i as i32 - 7).to_le_bytes());
                r.extend_from_slice(&(14.8f32 + e as f32 * 0.1).to_le_bytes());
                r.push(u8::from((i + e as u64).is_multiple_of(2)));
                r.extend_from_slice(b"e\x01z");
                r.extend_from_slice(&(-(i as i16)).to_le_bytes());
                r.extend_from_slice(&(i as i16 * 300).to_le_bytes());
                r.push(0);
            }
            w.data(id, &r).unwrap();
        }
        let mut m = (1_000_500 + i * 10_000).to_le_bytes().to_vec();
        m.extend_from_slice(&(i as f64 / 3.0).to_le_bytes());
        m.extend_from_slice(&(i64::MIN + i as i64).to_le_bytes());
        m.extend_from_slice(&(u16::MAX - i as u16).to_le_bytes());
        m.extend_from_slice(b"abcde");
        for v in [f32::NAN, f32::INFINITY, -0.0] {
            m.extend_from_slice(&(if i.is_multiple_of(2) { v } else { i as f32 }).to_le_bytes());
        }
        w.data(mix, &m).unwrap();
        if i == 10 {
            w.log(b'6', 1_100_000, "halfway").unwrap();
            w.log_tagged(b'3', 7, 1_100_001, "tagged error").unwrap();
            w.parameter("MC_ROLL_P", ParamValue::Float(6.75)).unwrap();
            w.sync().unwrap();
            w.dropout(42).unwrap();
        }
    }
    w.unsubscribe(esc[1]).unwrap();
    w.into_inner()
}

fn sha256(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

#[test]
fn pyulog_reads_what_the_writer_writes() {
    let bytes = interop_file();
    let dir = std::env::temp_dir().join(format!("ulog-interop-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path: PathBuf = dir.join("interop.ulg");
    std::fs::write(&path, &bytes).unwrap();
    let committed: Json =
        serde_json::from_str(include_str!("../../data/interop.ulg.oracle.json")).unwrap();
    let oracle = match pyulog_view(&path) {
        Some(o) => {
            if std::env::var_os("ULOG_REFRESH").is_some() {
                let to = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/interop.ulg.oracle.json");
                std::fs::write(to, serde_json::to_string_pretty(&o).unwrap() + "\n").unwrap();
            }
            o
        }
        None => {
            assert!(
                !under_ci(),
                "under CI pyulog must be installed (.ci/run does it)"
            );
            eprintln!("pyulog not available: using the committed pyulog view of this file");
            assert_eq!(
                committed["sha256"].as_str(),
                Some(sha256(&bytes).as_str()),
                "the writer's output changed; regenerate tests/data/interop.ulg.oracle.json with oracle.py"
            );
            committed
        }
    };
    assert!(
        oracle.get("pyulog_error").is_none(),
        "pyulog failed: {:?}",
        oracle.get("pyulog_error")
    );
    assert_eq!(oracle["pyulog_printed"].as_str(), Some(""), "pyulog warned");
    let diffs = check_file(&path, &oracle);
    assert!(
        diffs.is_empty(),
        "pyulog and this reader differ:\n{}",
        diffs.join("\n")
    );
    // And what pyulog reads is what was written.
    let p = &oracle["pyulog"];
    assert_eq!(p["info"]["sys_name"]["value"], "interop");
    assert_eq!(p["info"]["time_ref_utc"]["value"], -3600);
    assert_eq!(p["info"]["blob"]["value"]["hex"], "003c78b4");
    assert_eq!(
        p["info_multiple"]["perf"]["value"],
        serde_json::json!([["first", " continued"], ["second"]])
    );
    assert_eq!(p["initial_parameters"]["SYS_AUTOSTART"], 4001);
    assert_eq!(p["changed_parameters"][0][2], 6.75);
    assert_eq!(p["default_parameters"]["1"]["SYS_AUTOSTART"], 0);
    assert_eq!(p["logged_messages"][0]["message"], "halfway");
    assert_eq!(p["logged_messages_tagged"][0]["tag"], 7);
    assert_eq!(p["dropouts"][0]["duration"], 42);
    let subs = p["subscriptions"].as_array().unwrap();
    assert_eq!(subs.len(), 3);
    let esc1 = subs
        .iter()
        .find(|s| s["name"] == "esc_status" && s["multi_id"] == 1)
        .unwrap();
    assert_eq!(esc1["n_data"], 20);
    assert_eq!(esc1["first_rows"][0]["esc[1].esc_rpm"], 993);
    assert_eq!(esc1["first_rows"][0]["esc[1].tag[1]"], 1);
    assert_eq!(esc1["last_rows"][2]["esc[0].t[1]"], 19 * 300);
    let mix = subs.iter().find(|s| s["name"] == "mix").unwrap();
    assert_eq!(mix["first_rows"][0]["v[0]"], "NaN");
    assert_eq!(mix["first_rows"][0]["i"], i64::MIN);
    std::fs::remove_dir_all(&dir).unwrap();
}
