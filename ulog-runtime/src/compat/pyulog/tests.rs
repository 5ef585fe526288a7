//! pyulog's rules on hand-built files (each case checked against pyulog 1.3.0 when it was
//! written; the corpus is compared with pyulog live by the Python package's tests).

use super::*;

fn msg(ty: u8, body: &[u8]) -> Vec<u8> {
    let mut m = (body.len() as u16).to_le_bytes().to_vec();
    m.push(ty);
    m.extend_from_slice(body);
    m
}

fn info(ty: u8, key: &str, value: &[u8]) -> Vec<u8> {
    let mut b = vec![key.len() as u8];
    b.extend_from_slice(key.as_bytes());
    b.extend_from_slice(value);
    msg(ty, &b)
}

fn header() -> Vec<u8> {
    let mut f = b"ULog\x01\x12\x35\x01".to_vec();
    f.extend_from_slice(&1000u64.to_le_bytes());
    f
}

fn add(multi_id: u8, msg_id: u16, name: &str) -> Vec<u8> {
    let mut b = vec![multi_id];
    b.extend_from_slice(&msg_id.to_le_bytes());
    b.extend_from_slice(name.as_bytes());
    msg(b'A', &b)
}

fn data(msg_id: u16, row: &[u8]) -> Vec<u8> {
    let mut b = msg_id.to_le_bytes().to_vec();
    b.extend_from_slice(row);
    msg(b'D', &b)
}

fn row(t: u64, x: u8) -> Vec<u8> {
    let mut r = t.to_le_bytes().to_vec();
    r.push(x);
    r
}

fn parse(f: &[u8]) -> PyulogFile {
    read(f, &PyulogOptions::default()).unwrap()
}

#[test]
fn info_values_are_what_struct_unpack_gives() {
    let mut f = header();
    f.extend(info(b'I', "char[5] sys name", b"hello"));
    f.extend(info(b'I', "int32_t n", &(-5i32).to_le_bytes()));
    f.extend(info(b'I', "float x", &0.1f32.to_le_bytes()));
    f.extend(info(b'I', "char c", b"Z"));
    f.extend(info(b'I', "uint8_t[3] raw", &[1, 2, 3]));
    f.extend(info(b'I', "bool b", &[7]));
    let p = parse(&f);
    let values: Vec<(&str, &str, &PyValue)> = p
        .info
        .iter()
        .map(|(k, t, v)| (k.as_str(), t.as_str(), v))
        .collect();
    assert_eq!(
        values,
        [
            // The key is the second word only.
            ("sys", "char[5]", &PyValue::Str("hello".into())),
            ("n", "int32_t", &PyValue::Int(-5)),
            ("x", "float", &PyValue::Float(f64::from(0.1f32))),
            ("c", "char", &PyValue::Bytes(b"Z".to_vec())),
            ("raw", "uint8_t[3]", &PyValue::Bytes(vec![1, 2, 3])),
            ("b", "bool", &PyValue::Bool(true)),
        ]
    );
    assert!(!p.file_corrupt);
}

#[test]
fn rows_of_exactly_the_formats_size_are_taken() {
    let mut f = header();
    f.extend(msg(
        b'F',
        b"t:uint64_t timestamp;uint8_t x;uint8_t[3] _padding0;",
    ));
    f.extend(add(0, 1, "t"));
    f.extend(data(1, &row(2000, 1)));
    // With its trailing padding: pyulog drops it and marks the file corrupt.
    let mut padded = row(3000, 2);
    padded.extend_from_slice(&[0, 0, 0]);
    f.extend(data(1, &padded));
    f.extend(data(1, &row(2500, 3)));
    let p = parse(&f);
    assert_eq!(p.data.len(), 1);
    let d = &p.data[0];
    assert_eq!(
        d.fields,
        [
            ("timestamp".to_owned(), "uint64_t".to_owned()),
            ("x".to_owned(), "uint8_t".to_owned())
        ],
        "trailing padding left out"
    );
    assert_eq!(d.rows.len(), 2 * 9);
    assert_eq!((d.rows[8], d.rows[17]), (1, 3));
    assert!(p.file_corrupt);
    assert_eq!(
        p.last_timestamp, 2500,
        "the largest timestamp of rows taken"
    );
}

#[test]
fn a_message_too_short_for_its_unpack_ends_the_data_section_silently() {
    let mut f = header();
    f.extend(msg(b'F', b"t:uint64_t timestamp;uint8_t x;"));
    f.extend(add(0, 1, "t"));
    f.extend(data(1, &row(2000, 1)));
    let short = f.len() as u64;
    f.extend(msg(b'O', &[1, 0, 0]));
    f.extend(data(1, &row(3000, 2)));
    let p = parse(&f);
    assert_eq!(p.data[0].rows.len(), 9, "the rows after it are lost");
    assert!(!p.file_corrupt, "and nothing of pyulog's says so");
    assert!(p.dropouts.is_empty());
    assert_eq!(p.stopped_at, Some(short), "where it stopped");
    assert_eq!(
        parse(&f[..short as usize]).stopped_at,
        None,
        "a log read to its end"
    );
}

#[test]
fn a_row_without_a_timestamp_ends_the_read_unless_its_topic_is_filtered_out() {
    // pyulog unpacks a row's timestamp at the offset after every field when the format has
    // no `timestamp`: past the row, a `struct.error`, the end of its reading. Filtered out,
    // the row is never parsed, and the rows after it are read.
    let mut f = header();
    f.extend(msg(b'F', b"t:uint64_t timestamp;uint8_t x;"));
    f.extend(msg(b'F', b"e:uint64_t time;uint8_t x;"));
    f.extend(add(0, 1, "t"));
    f.extend(add(0, 2, "e"));
    f.extend(data(1, &row(2000, 1)));
    let e_row = f.len() as u64;
    f.extend(data(2, &row(2500, 9)));
    f.extend(data(1, &row(3000, 2)));
    let full = parse(&f);
    assert_eq!(full.stopped_at, Some(e_row));
    let rows = |p: &PyulogFile, name: &str| {
        p.data
            .iter()
            .find(|d| d.name == name)
            .map(|d| d.rows.clone())
    };
    assert_eq!(rows(&full, "t"), Some(row(2000, 1)));
    assert_eq!(
        rows(&full, "e"),
        Some(row(2500, 9)),
        "the row that raised is kept"
    );
    let filtered = read(
        &f,
        &PyulogOptions {
            filter: NameFilter::Names(vec!["t".into()]),
            ..PyulogOptions::default()
        },
    )
    .unwrap();
    assert_eq!(filtered.stopped_at, None);
    assert_eq!(
        rows(&filtered, "t"),
        Some([row(2000, 1), row(3000, 2)].concat())
    );
}

#[test]
fn a_resubscription_replaces_and_the_last_subscribed_comes_first() {
    let mut f = header();
    f.extend(msg(b'F', b"t:uint64_t timestamp;uint8_t x;"));
    f.extend(add(0, 1, "t"));
    f.extend(data(1, &row(2000, 1)));
    f.extend(add(3, 1, "t"));
    f.extend(data(1, &row(3000, 2)));
    f.extend(add(3, 2, "t"));
    f.extend(data(2, &row(4000, 9)));
    let p = parse(&f);
    let seen: Vec<(u16, u8, usize)> = p
        .data
        .iter()
        .map(|d| (d.msg_id, d.multi_id, d.rows.len() / d.row_size))
        .collect();
    assert_eq!(seen, [(2, 3, 1), (1, 3, 1)]);
}

#[test]
fn default_parameters_are_keyed_by_a_bits_value_less_one() {
    let mut f = header();
    let mut body = vec![0b101u8, 7];
    body.extend_from_slice(b"float A");
    body.extend_from_slice(&1.5f32.to_le_bytes());
    f.extend(msg(b'Q', &body));
    let p = parse(&f);
    let keys: Vec<u8> = p.default_parameters.iter().map(|d| d.0).collect();
    assert_eq!(keys, [0, 3]);
}

#[test]
fn a_row_of_no_subscription_warns_once_and_marks_corruption() {
    let mut f = header();
    // A logged string ends the definitions (rows before it would be skipped as unknown).
    let mut logged = vec![b'6'];
    logged.extend_from_slice(&5u64.to_le_bytes());
    logged.extend_from_slice(b"hi");
    f.extend(msg(b'L', &logged));
    f.extend(data(9, &row(1, 1)));
    f.extend(data(9, &row(2, 1)));
    let p = parse(&f);
    assert_eq!(
        p.printed,
        [
            "Warning: no subscription found for message id 9. Continuing, but file is most likely corrupt"
        ]
    );
    assert!(p.file_corrupt);
    assert_eq!(p.missing_ids, [9]);
}

#[test]
fn headers_flags_and_strict_strings_raise_as_pyulog_does() {
    assert_eq!(
        read(b"ULog", &PyulogOptions::default()),
        Err(PyulogError::Header(
            "Invalid file format (Header too short)"
        ))
    );
    assert_eq!(
        read(&[0; 16], &PyulogOptions::default()),
        Err(PyulogError::Header(
            "Invalid file format (Failed to parse header)"
        ))
    );
    let mut f = header();
    let mut flags = vec![0u8; 40];
    flags[8] = 2;
    f.extend(msg(b'B', &flags));
    assert_eq!(
        read(&f, &PyulogOptions::default()),
        Err(PyulogError::IncompatibleFlag)
    );
    let mut f = header();
    f.extend(info(b'I', "char[2] s", b"\xff\xfe"));
    let strict = PyulogOptions {
        strict_strings: true,
        ..PyulogOptions::default()
    };
    assert!(matches!(
        read(&f, &strict),
        Err(PyulogError::Unicode {
            start: 0,
            reason: "invalid start byte",
            ..
        })
    ));
    let p = parse(&f);
    assert_eq!(
        p.info[0].2,
        PyValue::Str(String::new()),
        "invalid bytes left out"
    );
    assert!(!p.file_corrupt);
}

#[test]
fn an_unknown_message_with_sync_bytes_in_it_resumes_after_them() {
    let mut f = header();
    f.extend(msg(b'F', b"t:uint64_t timestamp;uint8_t x;"));
    f.extend(add(0, 1, "t"));
    // An unknown type whose payload holds a sync sequence and then a row.
    let mut payload = vec![0xAA; 4];
    payload.extend_from_slice(&SYNC);
    payload.extend(data(1, &row(5, 4)));
    f.extend(msg(b'X', &payload));
    let p = parse(&f);
    assert_eq!(p.data[0].rows, row(5, 4), "the row inside it is read");
    assert!(p.file_corrupt, "bytes were skipped to the sync");
}

#[test]
fn appended_segments_start_without_subscriptions() {
    let mut f = header();
    let flags_at = f.len();
    f.extend(msg(b'B', &[0u8; 40]));
    f.extend(msg(b'F', b"t:uint64_t timestamp;uint8_t x;"));
    f.extend(add(0, 1, "t"));
    f.extend(data(1, &row(10, 1)));
    let appended = f.len() as u64;
    f.extend(data(1, &row(20, 2)));
    f.extend(add(0, 1, "t"));
    f.extend(data(1, &row(30, 3)));
    // Incompat bit 0 and the offset.
    f[flags_at + 3 + 8] = 1;
    f[flags_at + 3 + 16..flags_at + 3 + 24].copy_from_slice(&appended.to_le_bytes());
    let p = parse(&f);
    assert_eq!(p.appended_offsets, [appended]);
    let rows: Vec<&[u8]> = p.data.iter().map(|d| d.rows.as_slice()).collect();
    assert_eq!(rows, [row(10, 1).as_slice(), row(30, 3).as_slice()]);
    assert!(
        p.file_corrupt,
        "the row before the new subscription had none"
    );
}

#[test]
fn filters_keep_names_or_parts_of_a_text() {
    let mut f = header();
    f.extend(msg(b'F', b"foo:uint64_t timestamp;uint8_t x;"));
    f.extend(msg(b'F', b"foobar:uint64_t timestamp;uint8_t x;"));
    f.extend(add(0, 1, "foo"));
    f.extend(add(0, 2, "foobar"));
    f.extend(data(1, &row(1, 1)));
    f.extend(data(2, &row(1, 1)));
    let names = |filter| {
        let p = read(
            &f,
            &PyulogOptions {
                filter,
                ..PyulogOptions::default()
            },
        )
        .unwrap();
        (
            p.data.iter().map(|d| d.name.clone()).collect::<Vec<_>>(),
            p.filtered_ids,
            p.file_corrupt,
        )
    };
    assert_eq!(
        names(NameFilter::Names(vec!["foo".into()])),
        (vec!["foo".to_owned()], vec![2], false)
    );
    assert_eq!(
        names(NameFilter::Substring("foobarbaz".into())),
        (vec!["foo".to_owned(), "foobar".to_owned()], vec![], false)
    );
}

#[test]
fn damage_never_hangs_or_panics() {
    // Every prefix and a byte flipped at every position of a small file.
    let mut f = header();
    f.extend(msg(b'F', b"t:uint64_t timestamp;uint8_t x;"));
    f.extend(info(b'I', "char[3] a b", b"xyz"));
    f.extend(add(0, 1, "t"));
    for t in 0..20u64 {
        f.extend(data(1, &row(t, 1)));
        f.extend(msg(b'S', &SYNC));
    }
    for n in 0..f.len() {
        let _ = read(&f[..n], &PyulogOptions::default());
        let mut g = f.clone();
        g[n] ^= 0xFF;
        let _ = read(&g, &PyulogOptions::default());
    }
}

#[test]
fn array_sizes_are_read_by_characters_as_python_slices_them() {
    // pyulog's `int(type_str[a+1:b])`, `b` -1 without `]`: the slice ends before the last
    // character, however many bytes it takes (a fuzzer's input panicked on a byte index),
    // and `int()` takes any Unicode decimal digit. Each checked against pyulog 1.3.0.
    for (ty, expected) in [
        ("float[2\u{2db}", Some(("float", 2))),
        ("float[3]\u{e9}", Some(("float", 3))),
        ("float[\u{663}]", Some(("float", 3))),
        ("float[\u{2db}", None),
        ("uint8_t[\u{e9}3]", None),
    ] {
        let mut f = header();
        f.extend(msg(b'B', &[0; 40]));
        f.extend(msg(
            b'F',
            format!("t:uint64_t timestamp;{ty} x;").as_bytes(),
        ));
        let p = parse(&f);
        let got = p.formats.iter().find(|f| f.name == "t").map(|f| {
            let (t, n, _) = &f.fields[1];
            (t.as_str(), *n)
        });
        assert_eq!(got, expected, "{ty}");
    }
}
