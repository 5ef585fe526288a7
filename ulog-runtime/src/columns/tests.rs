//! Columns of hand-laid rows: names, order, types and values.

use super::*;
use crate::read::{FileHeader, Message};

fn spec_of(formats: &[&str], root: &str, ulog2csv: bool) -> (Schema, ColumnSpec) {
    let mut schema = Schema::new();
    for f in formats {
        schema.insert(f.parse().unwrap()).unwrap();
    }
    let id = schema.id(root).unwrap();
    let spec = if ulog2csv {
        ColumnSpec::like_ulog2csv(&mut schema, id).unwrap()
    } else {
        ColumnSpec::new(&mut schema, id).unwrap()
    };
    (schema, spec)
}

const FORMATS: [&str; 2] = [
    "outer:float[2] q;uint64_t timestamp;inner[2] e;char[4] name;bool ok;char c;uint8_t[3] _padding0;",
    "inner:int16_t a;uint8_t[2] _padding0;double b;",
];

fn row(q: [f32; 2], t: u64, e: [(i16, f64); 2], name: &[u8; 4], ok: u8, c: u8) -> Vec<u8> {
    let mut r = Vec::new();
    for x in q {
        r.extend_from_slice(&x.to_le_bytes());
    }
    r.extend_from_slice(&t.to_le_bytes());
    for (a, b) in e {
        r.extend_from_slice(&a.to_le_bytes());
        r.extend_from_slice(&[0xAA, 0xBB]);
        r.extend_from_slice(&b.to_le_bytes());
    }
    r.extend_from_slice(name);
    r.extend_from_slice(&[ok, c]);
    r
}

#[test]
fn names_order_and_kinds_follow_pyulog() {
    let (_, spec) = spec_of(&FORMATS, "outer", false);
    let names: Vec<(&str, &str)> = spec
        .columns()
        .iter()
        .map(|c| (c.name.as_str(), c.ulog_type.as_str()))
        .collect();
    assert_eq!(
        names,
        [
            ("timestamp", "uint64_t"),
            ("q[0]", "float"),
            ("q[1]", "float"),
            ("e[0].a", "int16_t"),
            ("e[0].b", "double"),
            ("e[1].a", "int16_t"),
            ("e[1].b", "double"),
            ("name", "char[4]"),
            ("ok", "bool"),
            ("c", "char"),
        ]
    );
    assert_eq!(spec.columns()[7].kind, ColumnKind::Text { len: 4 });
    // As ulog2csv: the padding of nested types shown, the top-level one not.
    let (_, csv) = spec_of(&FORMATS, "outer", true);
    let names: Vec<&str> = csv.columns().iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names[3..7],
        ["e[0].a", "e[0]._padding0[0]", "e[0]._padding0[1]", "e[0].b"]
    );
}

#[test]
fn rows_fill_typed_columns_in_batches() {
    let (_, spec) = spec_of(&FORMATS, "outer", false);
    let mut b = ColumnBuilder::with_capacity(spec.clone(), 4);
    assert!(b.push(
        &row([1.5, -2.0], 10, [(-3, 0.25), (4, 8.0)], b"ab\0x", 2, 0xFF),
        10
    ));
    assert!(b.push(
        &row([f32::NAN, 0.0], 20, [(5, -1.0), (6, 2.0)], b"abcd", 0, b'A'),
        20
    ));
    assert!(!b.push(&[0; 10], 30), "too short: nothing added");
    let cols = b.take();
    assert_eq!(cols.rows(), 2);
    assert_eq!(
        cols.get("timestamp").unwrap().as_uint64(),
        Some(&[10, 20][..])
    );
    let q0 = cols.get("q[0]").unwrap().as_float().unwrap();
    assert_eq!((q0[0], q0[1].is_nan()), (1.5, true));
    assert_eq!(cols.get("e[1].a").unwrap().as_int16(), Some(&[4, 6][..]));
    assert_eq!(
        cols.get("e[0].b").unwrap().as_double(),
        Some(&[0.25, -1.0][..])
    );
    assert_eq!(
        cols.get("name").unwrap().as_text().unwrap(),
        ["ab".to_owned(), "abcd".to_owned()]
    );
    assert_eq!(cols.get("ok").unwrap().as_bool(), Some(&[true, false][..]));
    assert_eq!(cols.get("c").unwrap().as_char(), Some(&[0xFF, b'A'][..]));
    assert_eq!(cols.get("c").unwrap().to_f64().unwrap(), [-1.0, 65.0]);
    // The next batch starts empty.
    assert!(b.push(
        &row([3.0, 4.0], 30, [(0, 0.0), (0, 0.0)], b"\0\0\0\0", 1, 0),
        30
    ));
    let next = b.take();
    assert_eq!(next.rows(), 1);
    assert_eq!(
        next.get("name").unwrap().as_text().unwrap(),
        [String::new()]
    );
}

#[test]
fn many_rows_fill_columns_across_the_builders_stages() {
    // More rows than a stage holds, in a builder and in a row batch made columns later: every
    // value where it belongs.
    let (_, spec) = spec_of(&FORMATS, "outer", false);
    let spec = std::sync::Arc::new(spec);
    let mut b = ColumnBuilder::new(spec.clone());
    let mut batch = RowBatch::with_capacity(spec.clone(), 0);
    let n = 10_000u32;
    for i in 0..n {
        let f = i as f32;
        let data = row(
            [f, -f],
            u64::from(i),
            [(i as i16, f64::from(i) / 4.0), (-(i as i16), 0.5)],
            if i % 2 == 0 { b"even" } else { b"odd\0" },
            (i % 3) as u8,
            (i % 256) as u8,
        );
        assert!(b.push(&data, u64::from(i) * 10));
        assert!(batch.push(&data, u64::from(i) * 10));
    }
    let built = b.take();
    assert_eq!(built, batch.columns(), "a builder and a row batch agree");
    assert_eq!(built.rows(), n as usize);
    let q1 = built.get("q[1]").unwrap().as_float().unwrap();
    let e0a = built.get("e[0].a").unwrap().as_int16().unwrap();
    let e0b = built.get("e[0].b").unwrap().as_double().unwrap();
    let ts = built.get("timestamp").unwrap().as_uint64().unwrap();
    let name = built.get("name").unwrap().as_text().unwrap();
    let ok = built.get("ok").unwrap().as_bool().unwrap();
    for i in [0, 1, 999, 1000, 4097, 9_999usize] {
        assert_eq!(q1[i], -(i as f32), "row {i}");
        assert_eq!(e0a[i], i as i16, "row {i}");
        assert_eq!(e0b[i], i as f64 / 4.0, "row {i}");
        assert_eq!(ts[i], i as u64 * 10, "row {i}");
        assert_eq!(name[i], if i % 2 == 0 { "even" } else { "odd" }, "row {i}");
        assert_eq!(ok[i], i % 3 != 0, "row {i}");
    }
}

#[test]
fn a_log_gives_the_columns_of_an_instance_with_unwrapped_timestamps() {
    // Version 0 with a uint16_t timestamp that wraps: the column holds the unwrapped µs.
    let rows = [(65_000u16, 1.0f32), (100, 2.0)].map(|(ts, x)| {
        let mut data = ts.to_le_bytes().to_vec();
        data.extend_from_slice(&x.to_le_bytes());
        data
    });
    let log = one_topic_log(
        0,
        b"t:uint16_t timestamp;float x;",
        &[0],
        rows.map(|r| (0, r)),
    );
    let cols = log.columns("t", 0).unwrap();
    assert_eq!(cols.defs()[0].ulog_type, "uint16_t");
    assert_eq!(
        cols.get("timestamp").unwrap().as_uint64(),
        Some(&[65_000, 65_636][..])
    );
    assert_eq!(cols.get("x").unwrap().as_float(), Some(&[1.0, 2.0][..]));
    assert_eq!(
        log.columns("t", 1).unwrap_err().to_string(),
        "`t` has no instance 1 (instances: [0])"
    );
    assert_eq!(
        log.columns("nope", 0).unwrap_err().to_string(),
        "the log has no topic `nope`"
    );
    assert_eq!(
        log.columns("tt", 0).unwrap_err().to_string(),
        "the log has no topic `tt`; did you mean `t`?"
    );
}

#[test]
fn all_columns_in_one_pass_equal_each_instances_columns() {
    // Two topics, two instances of one, a resubscription, a wrapping version-0 timestamp and
    // more rows than the pass has threads: each instance's columns as `columns` gives them.
    let mut f = FileHeader {
        version: 0,
        start_timestamp: 0,
    }
    .to_bytes()
    .to_vec();
    Message::Format(b"t:uint16_t timestamp;float x;")
        .encode(&mut f)
        .unwrap();
    Message::Format(b"u:uint16_t timestamp;int8_t k;char[3] s;")
        .encode(&mut f)
        .unwrap();
    for (multi_id, msg_id, name) in [(0, 0, &b"t"[..]), (1, 1, b"t"), (0, 2, b"u")] {
        Message::Subscribe {
            multi_id,
            msg_id,
            name,
        }
        .encode(&mut f)
        .unwrap();
    }
    let mut ts = 0u16;
    for i in 0..1_000u32 {
        ts = ts.wrapping_add(997);
        let msg_id = match i % 3 {
            1 if i > 500 => 3,
            k => k as u16,
        };
        let mut data = ts.to_le_bytes().to_vec();
        if msg_id == 2 {
            data.push(i as u8);
            data.extend_from_slice(b"ab\0");
        } else {
            data.extend_from_slice(&(i as f32).to_le_bytes());
        }
        Message::Data {
            msg_id,
            data: &data,
        }
        .encode(&mut f)
        .unwrap();
        if i == 500 {
            // Instance 1 of `t` resubscribed under a new id.
            Message::Subscribe {
                multi_id: 1,
                msg_id: 3,
                name: b"t",
            }
            .encode(&mut f)
            .unwrap();
        }
    }
    let log = Log::from_vec(f).unwrap();
    let all = log.all_columns();
    let names: Vec<(&str, u8)> = all.iter().map(|(t, m, _)| (t.as_str(), *m)).collect();
    assert_eq!(names, [("t", 0), ("t", 1), ("u", 0)]);
    // Parts: on more than one core, an instance's rows in more than one part, in order.
    let parts = log.all_column_parts();
    assert_eq!(parts.len(), all.len());
    for ((_, _, p), (_, _, joined)) in parts.iter().zip(&all) {
        assert_eq!(p.iter().map(Columns::rows).sum::<usize>(), joined.rows());
        let ts: Vec<u64> = p
            .iter()
            .flat_map(|c| c.get("timestamp").unwrap().as_uint64().unwrap().to_vec())
            .collect();
        assert_eq!(ts, joined.get("timestamp").unwrap().as_uint64().unwrap());
    }
    for (topic, multi_id, cols) in &all {
        assert_eq!(
            cols,
            &log.columns(topic, *multi_id).unwrap(),
            "{topic} {multi_id}"
        );
        assert!(cols.rows() > 300, "{topic} {multi_id}: {}", cols.rows());
    }
    // One instance's columns gathered on three threads (one of them a resubscribed
    // instance, whose rows merge from two subscriptions), each writing its run of rows in
    // place: the columns one thread makes.
    for (topic, multi_id, cols) in &all {
        let one = Columns::from_rows(
            cols.spec().clone(),
            log.instance_rows(&log.instance(topic, *multi_id))
                .map(|r| (r.data, r.timestamp)),
            0,
        );
        assert_eq!(&one, cols, "{topic} {multi_id}");
        let three = log.columns_on(3, 50, topic, *multi_id).unwrap();
        assert_eq!(&three, cols, "{topic} {multi_id}");
        assert_eq!(three.rows(), cols.rows());
    }
    // The errors of one thread's.
    for (topic, multi_id) in [("tt", 0), ("t", 7)] {
        assert_eq!(
            log.columns_on(3, 50, topic, multi_id).unwrap_err(),
            log.columns_on(1, 50, topic, multi_id).unwrap_err()
        );
    }
}

#[test]
fn rows_too_short_leave_no_gap_between_the_runs_of_a_gathering() {
    // Rows of 12 bytes, every seventh cut to its timestamp: the reader leaves those out
    // (a diagnostic each), and the columns of the rest are the same made on one thread,
    // two or three.
    let rows: Vec<Vec<u8>> = (0..400u64)
        .map(|i| {
            let mut data = i.to_le_bytes().to_vec();
            if i % 7 != 3 {
                data.extend_from_slice(&(i as f32).to_le_bytes());
            }
            data
        })
        .collect();
    let log = one_topic_log(
        1,
        b"t:uint64_t timestamp;float x;",
        &[0],
        rows.into_iter().map(|r| (0, r)),
    );
    let kept: Vec<u64> = (0..400).filter(|i| i % 7 != 3).collect();
    let xs: Vec<f32> = kept.iter().map(|&i| i as f32).collect();
    for threads in [1, 2, 3] {
        let cols = log.columns_on(threads, 50, "t", 0).unwrap();
        assert_eq!(cols.rows(), kept.len(), "{threads} threads");
        assert_eq!(
            cols.get("timestamp").unwrap().as_uint64(),
            Some(&kept[..]),
            "{threads} threads"
        );
        assert_eq!(
            cols.get("x").unwrap().as_float(),
            Some(&xs[..]),
            "{threads} threads"
        );
    }
}

/// A log of one topic `t` of format `format`, instance 0 subscribed under each of
/// `msg_ids`, with `rows` (message id, data) as its data.
fn one_topic_log(
    version: u8,
    format: &[u8],
    msg_ids: &[u16],
    rows: impl IntoIterator<Item = (u16, Vec<u8>)>,
) -> Log<'static> {
    let mut f = FileHeader {
        version,
        start_timestamp: 0,
    }
    .to_bytes()
    .to_vec();
    Message::Format(format).encode(&mut f).unwrap();
    for &msg_id in msg_ids {
        Message::Subscribe {
            multi_id: 0,
            msg_id,
            name: b"t",
        }
        .encode(&mut f)
        .unwrap();
    }
    for (msg_id, data) in rows {
        Message::Data {
            msg_id,
            data: &data,
        }
        .encode(&mut f)
        .unwrap();
    }
    Log::from_vec(f).unwrap()
}

#[test]
fn threads_gathering_runs_of_many_batches_write_the_columns_one_thread_makes() {
    // Rows of 216 bytes (about 150 a staged batch), a text column among numbers, 3,000 rows
    // of one instance subscribed twice (its rows merged from two message ids): each thread's
    // run spans several batches, each written after the last.
    let rows = (0..3_000u64).map(|i| {
        let mut data = (i * 10).to_le_bytes().to_vec();
        data.extend_from_slice(&(i as f32 * 0.25).to_le_bytes());
        let mut text = format!("row {i}").into_bytes();
        text.resize(200, 0);
        data.extend_from_slice(&text);
        data.extend_from_slice(&((i % 600) as i16 - 300).to_le_bytes());
        data.extend_from_slice(&[u8::from(i % 3 == 0), (i % 251) as u8]);
        (u16::from(i % 5 == 0), data)
    });
    let log = one_topic_log(
        1,
        b"t:uint64_t timestamp;float x;char[200] s;int16_t k;bool b;uint8_t u;",
        &[0, 1],
        rows,
    );
    let (subs, spec) = log.instance_spec("t", 0).unwrap();
    assert_eq!(subs.len(), 2);
    let one = Columns::from_rows(
        spec.clone(),
        log.instance_rows(&subs).map(|r| (r.data, r.timestamp)),
        0,
    );
    assert_eq!(one.rows(), 3_000);
    assert_eq!(one.get("s").unwrap().as_text().unwrap()[2_999], "row 2999");
    for threads in [2, 3, 5, 8, 13] {
        let gathered = super::gather::columns(&spec, log.instance_rows(&subs).split(threads))
            .expect("no row is too short");
        assert_eq!(gathered, one, "{threads} threads");
        assert_eq!(gathered.rows(), 3_000, "{threads} threads");
    }
}

#[test]
fn a_row_batch_of_timestamps_alone_keeps_every_timestamp() {
    // A format with nothing but its timestamp: rows of no bytes. More rows than a block of
    // 32 KiB of rows (the rows' bytes are no guide to how many there are).
    let (_, spec) = spec_of(&["heartbeat:uint64_t timestamp;"], "heartbeat", false);
    let spec = std::sync::Arc::new(spec);
    assert_eq!(spec.row_len(), 0);
    let mut batch = RowBatch::with_capacity(spec.clone(), 0);
    let n = 40_000u64;
    for i in 0..n {
        assert!(batch.push(&(i * 7).to_le_bytes(), i * 7));
    }
    let columns = batch.columns();
    assert_eq!(columns.rows(), n as usize);
    let ts = columns.get("timestamp").unwrap().as_uint64().unwrap();
    assert_eq!(ts.len(), n as usize);
    assert!(ts.iter().enumerate().all(|(i, &t)| t == i as u64 * 7));
}

#[test]
fn a_text_of_no_length_as_the_only_field_gives_an_empty_string_a_row() {
    // A format built in code may hold what the parser refuses: `char[0]`, here its only
    // field, so that its rows have no bytes.
    let mut format: crate::schema::Format = "t:char[1] s;".parse().unwrap();
    format.fields[0].array_len = Some(0);
    let mut schema = Schema::new();
    schema.insert(format).unwrap();
    let id = schema.id("t").unwrap();
    let spec = std::sync::Arc::new(ColumnSpec::new(&mut schema, id).unwrap());
    assert_eq!(spec.row_len(), 0);
    let mut b = ColumnBuilder::new(spec.clone());
    let mut batch = RowBatch::with_capacity(spec, 0);
    for t in [1, 2, 3] {
        assert!(b.push(&[], t));
        assert!(batch.push(&[], t));
    }
    let cols = b.take();
    assert_eq!(cols.rows(), 3);
    assert_eq!(cols.get("s").unwrap().as_text().unwrap(), ["", "", ""]);
    assert_eq!(batch.columns(), cols);
}

#[test]
fn a_window_refuses_bounds_no_row_could_lie_between() {
    let nan = Window::seconds(Some(f64::NAN), None).unwrap_err();
    assert!(
        matches!(nan, WindowError::NotFinite { bound: "start", .. }),
        "{nan:?}"
    );
    assert_eq!(
        Window::seconds(None, Some(1e303)).unwrap_err().to_string(),
        "the window's end (1e303 s) is beyond any time a log can hold"
    );
    assert!(matches!(
        Window::seconds(Some(-2e13), None),
        Err(WindowError::OutOfRange { bound: "start", .. })
    ));
    assert!(Window::seconds(None, Some(1.8e13)).is_ok(), "within u64 µs");
    let inf = Window::seconds(Some(1.0), Some(f64::INFINITY)).unwrap_err();
    assert!(
        matches!(inf, WindowError::NotFinite { bound: "end", .. }),
        "{inf:?}"
    );
    assert_eq!(
        Window::seconds(Some(30.0), Some(20.0)),
        Err(WindowError::Empty {
            start: 30.0,
            end: 20.0
        })
    );
    assert_eq!(
        Window::seconds(Some(5.0), Some(5.0)),
        Err(WindowError::Empty {
            start: 5.0,
            end: 5.0
        })
    );
    assert_eq!(
        Window::seconds(Some(30.0), Some(20.0))
            .unwrap_err()
            .to_string(),
        "the window ends (20 s) at or before its start (30 s), so no row lies in it"
    );
    let w = Window::seconds(Some(1.5), Some(2.0)).unwrap();
    assert_eq!(
        (w.start_us, w.end_us),
        (Some(1_500_000.0), Some(2_000_000.0))
    );
    assert_eq!(w.to_string(), "from 1.5 s to 2 s");
    assert_eq!(
        Window::seconds(None, Some(2.0)).unwrap().to_string(),
        "before 2 s"
    );
    assert_eq!(
        Window::seconds(Some(-1.0), None).unwrap().to_string(),
        "from -1 s"
    );
    let open = Window::seconds(None, None).unwrap();
    assert!(!open.is_bounded());
    assert_eq!(open, Window::default());
    assert!(w.is_bounded());
}
