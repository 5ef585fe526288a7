//! What each fuzz target checks, one function per target, taking the fuzzer's bytes. The
//! targets in `fuzz_targets/` call these; `tests/tests/integration/robustness.rs` runs the same
//! functions on every saved input of `tests/fuzz_regressions/<target>/` under
//! `cargo test` on stable. Nothing here but `ulog_runtime`, `serde_json`, `parquet`,
//! `bytes` and std, so both can compile it.
//!
//! A check panics (which the fuzzer reports) when the library panics, hangs or
//! breaks a promise: the streaming reader not yielding what the whole-file reader yields, a
//! format that does not print back to itself, a layout whose fields leave it, a decoded
//! value that does not encode back, a flight report not made, a writer whose accepted operations do not read back, a
//! Parquet file that does not read back with its rows and its statistics.

#![allow(missing_docs, clippy::missing_panics_doc)]

use std::io::Read;

use ulog_runtime::columns::{ColumnSpec, csv};
use ulog_runtime::read::ParamValue;
use ulog_runtime::schema::{Format, Schema};
use ulog_runtime::{Event, Log, StreamReader, ULog, Value, Writer, WriterOptions};

/// The flight analysis of a log's bytes (its walks on two threads) equals that of its stream
/// (one pass), but for the per-field means, summed in another order. Gives the first.
fn analysis(log: &Log<'_>, data: &[u8]) -> ulog_runtime::analysis::Analysis {
    use ulog_runtime::analysis::Analysis;
    let walked = Analysis::of_log(log);
    let Ok(streamed) = Analysis::of_reader(data) else {
        panic!("the stream refuses a log the whole-file reader reads");
    };
    assert_eq!(walked.field_stats.len(), streamed.field_stats.len());
    for (w, s) in walked.field_stats.iter().zip(&streamed.field_stats) {
        assert_eq!(
            (&w.topic, w.multi_id, &w.field, w.count),
            (&s.topic, s.multi_id, &s.field, s.count)
        );
        let same = |a: f64, b: f64| a.total_cmp(&b).is_eq() || (a == b);
        assert!(same(w.min, s.min) && same(w.max, s.max), "{w:?} vs {s:?}");
        let close = (w.mean - s.mean).abs() <= 1e-9 * w.mean.abs().max(1.0)
            || (w.mean.is_nan() && s.mean.is_nan())
            || w.mean == s.mean;
        assert!(close, "{w:?} vs {s:?}");
    }
    let strip = |a: &Analysis| {
        let mut a = a.clone();
        a.field_stats.clear();
        format!("{a:?}")
    };
    assert_eq!(
        strip(&walked),
        strip(&streamed),
        "the analysis of the walk and of the stream"
    );
    walked
}

/// The flight report of a log is made (plotters given no range it hangs or panics on), and
/// its page holds every plot.
fn report(log: &Log<'_>, analysis: ulog_runtime::analysis::Analysis) {
    let report = ulog_runtime::report::Report::with_analysis(log, "fuzz.ulg", analysis)
        .unwrap_or_else(|e| panic!("no report: {e}"));
    assert_eq!(report.html().matches("<svg").count(), report.plots.len());
}

/// The whole-file reader, and everything built over it: rows and their values, topics,
/// columns, CSV, events and the messages, pyulog's tools, the JSON document.
pub fn whole_file(data: &[u8]) {
    let Ok(log) = Log::from_slice(data) else {
        return;
    };
    let analysis = analysis(&log, data);
    report(&log, analysis);
    for row in log.data() {
        let _ = row.value();
    }
    let _ = log.topics();
    let _ = log.skipped();
    let _ = log.not_utf8();
    for instance in log.instances(&[]) {
        let sub = instance[0];
        if let Ok(cols) = log.columns(&sub.name, sub.multi_id) {
            let rows = log.instance_rows(&instance).count();
            assert_eq!(cols.rows(), rows, "{}: columns of every row", sub.name);
        }
        let _ = csv::write_csv(
            &log,
            &instance,
            std::io::sink(),
            &csv::CsvOptions::default(),
        );
    }
    let events = log.events();
    if let Ok(m) = &events.metadata {
        for row in &events.rows {
            let _ = ulog_runtime::events::decode(row, &m.definitions);
        }
    }
    for line in ulog_runtime::events::messages(&log).lines {
        let _ = line.pyulog_line();
    }
    for format in [
        ulog_runtime::tools::ParamsFormat::Csv,
        ulog_runtime::tools::ParamsFormat::Octave,
        ulog_runtime::tools::ParamsFormat::Qgc,
    ] {
        let options = ulog_runtime::tools::ParamsOptions {
            format,
            ..Default::default()
        };
        let _ = ulog_runtime::tools::params(&log, &options, &mut std::io::sink());
    }
    for m in log.metadata().multi_info() {
        let _ = ulog_runtime::tools::multi_info_text(log.metadata(), &m.key, true);
    }
    let _ = ulog_runtime::tools::kml(&log, &Default::default());
    let _ = ulog_runtime::tools::gps_dump(&log, 0);
    let facts = ulog_runtime::document::LogFacts::of_log(&log);
    serde_json::to_vec(&facts).expect("the facts serialize");
}

/// Reads in chunks of the sizes the first bytes give.
struct Chunked<'a> {
    data: &'a [u8],
    sizes: &'a [u8],
    turn: usize,
}

impl Read for Chunked<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let size = match self.sizes {
            [] => 4096,
            s => 1 + usize::from(s[self.turn % s.len()]) * 37,
        };
        self.turn += 1;
        let n = buf.len().min(size).min(self.data.len());
        buf[..n].copy_from_slice(&self.data[..n]);
        self.data = &self.data[n..];
        Ok(n)
    }
}

/// What a reader gave, to compare.
#[derive(Debug, Default, PartialEq)]
struct Seen {
    /// Offset, msg_id, the subscription's topic and instance, the bytes.
    rows: Vec<(u64, u16, String, u8, Vec<u8>)>,
    logged: Vec<(u64, u64, String)>,
    changes: Vec<(u64, String)>,
    dropouts: Vec<(u64, u16)>,
}

/// The streaming reader fed in chunks of random sizes yields what the whole-file reader
/// yields: the same rows, logged strings, parameter changes and dropouts, and in the end the
/// same initial parameters, info and multi info; event by event and through each of its
/// loops ([`Loop`]), and refuses every log the whole-file reader refuses, each way. The first
/// byte gives how many of the next bytes are chunk sizes; the rest is the log.
pub fn stream_chunks(data: &[u8]) {
    let Some((&n, rest)) = data.split_first() else {
        return;
    };
    let n = usize::from(n % 8).min(rest.len());
    let (sizes, log) = rest.split_at(n);
    let Ok(whole) = Log::from_slice(log) else {
        // Then the streaming reader refuses it too, at the header or on the way.
        let input = Chunked {
            data: log,
            sizes,
            turn: 0,
        };
        let refused = match StreamReader::new(input) {
            Err(_) => true,
            Ok(mut reader) => loop {
                match reader.next_event() {
                    Err(_) => break true,
                    Ok(None) => break false,
                    Ok(Some(_)) => {}
                }
            },
        };
        assert!(
            refused,
            "the streaming reader takes a log the whole-file reader refuses"
        );
        // Its loops too.
        for how in [Loop::ForEachEvent, Loop::ForEachMessage] {
            assert!(
                stream_seen(log, sizes, how).is_err(),
                "{how:?} takes a log the whole-file reader refuses"
            );
        }
        return;
    };
    let mut expected = Seen {
        rows: whole
            .data()
            .map(|r| {
                let s = r.subscription;
                (
                    r.offset,
                    s.msg_id,
                    s.name.clone(),
                    s.multi_id,
                    r.data.to_vec(),
                )
            })
            .collect(),
        ..Seen::default()
    };
    expected.logged = whole
        .logged_messages()
        .iter()
        .map(|m| (m.offset, m.timestamp, m.text.clone()))
        .collect();
    expected.changes = whole
        .parameter_changes()
        .iter()
        .map(|c| (c.offset, c.name.clone()))
        .collect();
    expected.dropouts = whole
        .dropouts()
        .iter()
        .map(|d| (d.offset, d.duration_ms))
        .collect();
    assert_eq!(
        fold_file_rows(log),
        expected.rows,
        "the fold by positioned reads and the whole file differ"
    );
    for how in [Loop::NextEvent, Loop::ForEachEvent, Loop::ForEachMessage] {
        let (seen, end) = stream_seen(log, sizes, how).expect("reading memory does not fail");
        assert_eq!(seen, expected, "{how:?}: stream and whole file differ");
        // What the definitions left when the log ends: the whole-file reader takes it in from
        // the parts its threads read.
        assert_eq!(
            end,
            facts(whole.metadata()),
            "{how:?}: initial parameters or info differ between the stream and the whole file"
        );
    }
}

/// The ways through a stream: event by event, and the two loops that take a closure (whose
/// rows come in runs of the fast path, the closure called from one place).
#[derive(Debug, Clone, Copy)]
enum Loop {
    NextEvent,
    ForEachEvent,
    ForEachMessage,
}

/// What the definitions left when a log ends (as Debug text: a NaN value equals itself
/// there).
fn facts(m: &ulog_runtime::read::Metadata) -> String {
    format!(
        "{:?}\n{:?}\n{:?}",
        m.initial_parameters(),
        m.info(),
        m.multi_info()
    )
}

/// What the streaming reader gives of `log` fed in chunks of `sizes`, read `how`, and the
/// [`facts`] at its end. `ForEachMessage` also checks that each message it hands over is the
/// file's own bytes at its offset, and that each row comes with the message it was read from.
fn stream_seen(
    log: &[u8],
    sizes: &[u8],
    how: Loop,
) -> Result<(Seen, String), ulog_runtime::ReadError> {
    let input = Chunked {
        data: log,
        sizes,
        turn: 0,
    };
    let mut reader = StreamReader::new(input)?;
    let mut seen = Seen::default();
    match how {
        Loop::NextEvent => {
            while let Some(event) = reader.next_event()? {
                seen.take(event);
            }
        }
        Loop::ForEachEvent => reader.for_each_event(|event| seen.take(event))?,
        Loop::ForEachMessage => reader.for_each_message(|_, event, raw| {
            if let Some(m) = raw {
                let at = usize::try_from(m.offset).expect("an offset in memory");
                let end = at + 3 + m.payload.len();
                assert_eq!(
                    log.get(at..end).map(|b| (b[2], &b[3..])),
                    Some((m.ty, m.payload)),
                    "the message at {at} is not the file's bytes"
                );
                assert_eq!(
                    usize::from(u16::from_le_bytes([log[at], log[at + 1]])),
                    m.payload.len(),
                    "the message at {at} is not the size its header says"
                );
            }
            if let Event::Row(r) = &event {
                let m = raw.expect("a row comes with its message");
                assert_eq!((m.ty, m.offset), (b'D', r.offset), "a row's message");
                assert_eq!(
                    m.payload.split_at_checked(2),
                    Some((&r.subscription.msg_id.to_le_bytes()[..], r.data)),
                    "a row is its message's msg_id and bytes"
                );
            }
            seen.take(event);
            Ok::<(), ulog_runtime::ReadError>(())
        })?,
    }
    Ok((seen, facts(reader.metadata())))
}

impl Seen {
    fn take(&mut self, event: Event<'_>) {
        match event {
            Event::Row(r) => {
                let s = r.subscription;
                self.rows.push((
                    r.offset,
                    s.msg_id,
                    s.name.clone(),
                    s.multi_id,
                    r.data.to_vec(),
                ));
            }
            Event::Logged(m) => self.logged.push((m.offset, m.timestamp, m.text)),
            Event::ParameterChange(c) => self.changes.push((c.offset, c.name)),
            Event::Dropout(d) => self.dropouts.push((d.offset, d.duration_ms)),
            _ => {}
        }
    }
}

/// The rows `read::fold_file` gives of `log` written to a file of its own (removed after),
/// as `stream_chunks` compares them.
#[allow(clippy::type_complexity)]
fn fold_file_rows(log: &[u8]) -> Vec<(u64, u16, String, u8, Vec<u8>)> {
    static CALLS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let path =
        std::env::temp_dir().join(format!("ulog-fuzz-fold-{}-{call}.ulg", std::process::id()));
    std::fs::write(&path, log).expect("the temporary folder takes a file");
    let file = std::fs::File::open(&path).expect("the file just written opens");
    let (_, parts) = ulog_runtime::read::fold_file(&file, Vec::new, |rows, r| {
        let s = r.subscription;
        rows.push((
            r.offset,
            s.msg_id,
            s.name.clone(),
            s.multi_id,
            r.data.to_vec(),
        ));
    })
    .expect("a log the whole-file reader reads folds");
    drop(file);
    let _ = std::fs::remove_file(&path);
    parts.concat()
}

/// A format parses, prints, and parses back to itself; the lax parser never panics.
pub fn format_roundtrip(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let _ = Format::parse_lax(&text);
    if let Ok(f) = text.parse::<Format>() {
        let printed = f.to_string();
        let again: Format = printed
            .parse()
            .unwrap_or_else(|e| panic!("{printed:?} does not parse back: {e}"));
        assert_eq!(again, f, "{printed:?}");
        assert_eq!(again.to_string(), printed);
    }
}

/// Formats (one per line) laid out: every field inside its format, in order, the payload
/// within the size; a row plan and columns for each resolved format.
pub fn layout(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let mut schema = Schema::new();
    for line in text.lines().take(64) {
        if let Ok(f) = line.parse::<Format>() {
            let _ = schema.insert(f);
        }
    }
    let _ = schema.resolve_all();
    for i in 0..schema.len() {
        let name = schema.formats()[i].name.clone();
        let Some(id) = schema.id(&name) else { continue };
        let Some(l) = schema.resolved(id) else {
            continue;
        };
        assert!(l.payload_size <= l.size, "{name}");
        let mut end = 0;
        for f in &l.fields {
            assert!(f.offset >= end, "{name}.{}: overlaps", f.name);
            end = f.offset + f.size();
            assert!(end <= l.size, "{name}.{}: outside", f.name);
        }
        if ulog_runtime::value::RowPlan::check(&mut schema, id).is_ok() {
            let spec = ColumnSpec::new(&mut schema, id).expect("a checked format has columns");
            assert!(spec.row_len() <= schema.resolved(id).expect("resolved").size);
        }
    }
}

#[derive(ULog, Debug, Clone, PartialEq)]
#[ulog(nested)]
struct Cell {
    v: i16,
    #[ulog(padding)]
    _pad: [u8; 2],
    t: f32,
}

#[derive(ULog, Debug, Clone, PartialEq)]
struct FuzzTopic {
    timestamp: u64,
    cells: [Cell; 3],
    name: ulog_runtime::typed::Chars<5>,
    ok: bool,
    q: [f64; 2],
    extra: Option<u32>,
}

/// `row` as the encoder writes it: padding zeroed, each `bool` 0 or 1, all else as it is.
fn canonical(schema: &Schema, id: ulog_runtime::schema::FormatId, row: &mut [u8]) {
    use ulog_runtime::schema::{FieldKind, Primitive};
    let layout = schema.resolved(id).expect("resolved").clone();
    for f in &layout.fields {
        for i in 0..usize::from(f.array_len.unwrap_or(1)) {
            let at = f.offset + i * f.elem_size;
            let elem = &mut row[at..at + f.elem_size];
            match f.kind {
                _ if f.padding => elem.fill(0),
                FieldKind::Primitive(Primitive::Bool) => elem[0] = u8::from(elem[0] != 0),
                FieldKind::Nested(nested) => canonical(schema, nested, elem),
                FieldKind::Primitive(_) => {}
            }
        }
    }
}

/// Typed decoding of a derived struct from arbitrary bytes never panics, and what decodes
/// encodes back to the same bytes (padding as zeros, `bool` as 0 or 1); checked against the struct's own format and against a
/// format from the input (its first line), which may or may not match.
pub fn typed(data: &[u8]) {
    let mut schema = Schema::new();
    for f in FuzzTopic::FORMAT.formats() {
        schema.insert(f).expect("its own formats");
    }
    let _ = schema.resolve_all();
    let own = ulog_runtime::typed::TypedDecoder::<FuzzTopic>::new(&schema).expect("its own format");
    if let Some(v) = own.decode(data) {
        let mut bytes = Vec::new();
        ulog_runtime::typed::encode_row(&v, &mut bytes);
        let id = schema.id("fuzz_topic").expect("its own format");
        let mut expected = data.get(..bytes.len()).expect("a row as long").to_vec();
        canonical(&schema, id, &mut expected);
        assert_eq!(bytes, expected, "encode(decode(bytes)) is the bytes");
        let again = own.decode(&bytes).expect("an encoded row decodes");
        let mut bytes2 = Vec::new();
        ulog_runtime::typed::encode_row(&again, &mut bytes2);
        assert_eq!(bytes, bytes2, "decode(encode(x)) is x");
    }
    let split = data.iter().position(|&b| b == b'\n').unwrap_or(data.len());
    let text = String::from_utf8_lossy(&data[..split]);
    let mut other = Schema::new();
    for line in text.split('|') {
        if let Ok(f) = line.parse::<Format>() {
            let _ = other.insert(f);
        }
    }
    let _ = other.resolve_all();
    if let Ok(d) = ulog_runtime::typed::TypedDecoder::<FuzzTopic>::new_as(&other, "fuzz_topic") {
        let _ = d.decode(data.get(split..).unwrap_or_default());
    }
}

/// A file of this process, for inputs the code generator reads from paths.
fn temp_file(ext: &str, data: &[u8]) -> std::path::PathBuf {
    let dir = std::path::Path::new("/dev/shm");
    let dir = if dir.is_dir() {
        dir.to_path_buf()
    } else {
        std::env::temp_dir()
    };
    let path = dir.join(format!("ulog-fuzz-{}.{ext}", std::process::id()));
    std::fs::write(&path, data).expect("a temporary file");
    path
}

/// The code generator on a log's `F` definitions never panics; what it renders names every
/// format it generates.
pub fn codegen_log(data: &[u8]) {
    let path = temp_file("ulg", data);
    let mut b = ulog_runtime::codegen::Builder::new();
    b.ulog(&path);
    if let Ok(types) = b.types() {
        let text = b.render().expect("types render when they generate");
        for t in types {
            let declared = [
                format!("struct {} {{", t.path),
                format!("struct {};", t.path),
            ];
            assert!(declared.iter().any(|d| text.contains(d)), "{}", t.path);
        }
    }
    let _ = std::fs::remove_file(path);
}

/// The code generator on TOML or `.msg` text (the first byte picks) never panics.
pub fn codegen_text(data: &[u8]) {
    let Some((&pick, text)) = data.split_first() else {
        return;
    };
    let mut b = ulog_runtime::codegen::Builder::new();
    let path = if pick % 2 == 0 {
        let p = temp_file("toml", text);
        b.toml(&p);
        p
    } else {
        let p = temp_file("msg", text);
        b.msg(&p);
        p
    };
    let _ = b.render();
    let _ = std::fs::remove_file(path);
}

/// Takes bytes of the input in turn.
struct Ops<'a>(&'a [u8]);

impl Ops<'_> {
    fn byte(&mut self) -> Option<u8> {
        let (&b, rest) = self.0.split_first()?;
        self.0 = rest;
        Some(b)
    }

    fn bytes(&mut self, n: usize) -> Option<&[u8]> {
        let n = n.min(self.0.len());
        let (b, rest) = self.0.split_at(n);
        self.0 = rest;
        Some(b)
    }

    fn u64(&mut self) -> Option<u64> {
        let b = self.bytes(8)?;
        let mut a = [0; 8];
        a[..b.len()].copy_from_slice(b);
        Some(u64::from_le_bytes(a))
    }
}

/// Formats the writer operations draw on.
const FORMATS: [&str; 3] = [
    "alpha:uint64_t timestamp;float x;uint8_t[3] b;uint8_t[1] _padding0;",
    "cell:int16_t v;uint8_t[2] _padding0;",
    "beta:uint64_t timestamp;cell[2] c;char[4] name;bool ok;uint8_t[3] _padding0;",
];
const TOPICS: [&str; 2] = ["alpha", "beta"];

/// What the writer was asked and accepted, to compare with what reads back.
#[derive(Debug, Default)]
struct Model {
    subs: Vec<(String, u8)>,
    rows: Vec<(usize, Vec<u8>)>,
    logged: Vec<(u8, Option<u16>, u64, String)>,
    params: Vec<(String, ParamValue, bool)>,
    dropouts: Vec<u16>,
    syncs: u64,
    info: Vec<(String, String)>,
}

/// Arbitrary writer operations: each either fails, writing nothing, or is read back as
/// written (subscriptions, rows, logged strings, initial parameters and their changes,
/// dropouts, sync messages, info).
pub fn writer_ops(data: &[u8]) {
    let mut ops = Ops(data);
    let start = ops.u64().unwrap_or(0) >> 8;
    let Ok(mut w) = Writer::new(
        Vec::new(),
        WriterOptions {
            start_timestamp: start,
            default_parameters: false,
        },
    ) else {
        return;
    };
    let mut m = Model::default();
    let mut ids = Vec::new();
    for f in FORMATS {
        w.format(f).expect("the formats are valid");
    }
    let mut data_begun = false;
    for _ in 0..200 {
        let Some(op) = ops.byte() else { break };
        let before = w.get_ref().len();
        let ok = match op % 8 {
            0 => {
                let t = TOPICS[usize::from(ops.byte().unwrap_or(0)) % 2];
                let multi = ops.byte().unwrap_or(0) % 3;
                match w.subscribe(t, multi) {
                    Ok(id) => {
                        ids.push(id);
                        m.subs.push((t.to_owned(), multi));
                        // A parameter after the first subscription is a change
                        // (`Writer::parameter`).
                        data_begun = true;
                        true
                    }
                    Err(_) => false,
                }
            }
            1 if !ids.is_empty() => {
                let k = usize::from(ops.byte().unwrap_or(0)) % ids.len();
                let len = usize::from(ops.byte().unwrap_or(0)) % 40;
                let row = ops.bytes(len).unwrap_or_default().to_vec();
                let ok = w.data(ids[k], &row).is_ok();
                if ok {
                    m.rows.push((k, row));
                    data_begun = true;
                }
                ok
            }
            2 | 3 => {
                let level = ops.byte().unwrap_or(b'6');
                let ts = ops.u64().unwrap_or(0);
                let len = usize::from(ops.byte().unwrap_or(0)) % 30;
                let text = String::from_utf8_lossy(ops.bytes(len).unwrap_or_default()).into_owned();
                let tag = (op % 8 == 3).then(|| u16::from(ops.byte().unwrap_or(0)));
                let ok = match tag {
                    Some(t) => w.log_tagged(level, t, ts, &text).is_ok(),
                    None => w.log(level, ts, &text).is_ok(),
                };
                if ok {
                    m.logged.push((level, tag, ts, text));
                    data_begun = true;
                }
                ok
            }
            4 => {
                let name =
                    ["MC_ROLL_P", "SYS_AUTOSTART", "X"][usize::from(ops.byte().unwrap_or(0)) % 3];
                let raw = ops.u64().unwrap_or(0) as u32;
                let value = if raw.is_multiple_of(2) {
                    ParamValue::Int32(raw as i32)
                } else {
                    ParamValue::Float(f32::from_bits(raw))
                };
                let ok = w.parameter(name, value).is_ok();
                if ok {
                    m.params.push((name.to_owned(), value, data_begun));
                }
                ok
            }
            5 => {
                let ms = u16::from(ops.byte().unwrap_or(0));
                let ok = w.dropout(ms).is_ok();
                if ok {
                    m.dropouts.push(ms);
                    data_begun = true;
                }
                ok
            }
            6 => {
                let ok = w.sync().is_ok();
                data_begun |= ok;
                m.syncs += u64::from(ok);
                ok
            }
            _ => {
                let key = ["sys_name", "ver_hw", "note"][usize::from(ops.byte().unwrap_or(0)) % 3];
                let len = usize::from(ops.byte().unwrap_or(0)) % 20;
                let text = String::from_utf8_lossy(ops.bytes(len).unwrap_or_default()).into_owned();
                let ok = w.info(key, &Value::String(text.clone())).is_ok();
                if ok {
                    m.info.retain(|(k, _)| k != key);
                    m.info.push((key.to_owned(), text));
                }
                ok
            }
        };
        if !ok {
            assert_eq!(
                w.get_ref().len(),
                before,
                "a refused operation wrote nothing"
            );
        }
    }
    let bytes = w.into_inner();
    let log = Log::from_slice(&bytes).expect("what the writer writes reads");
    assert!(log.diagnostics().is_empty(), "{:?}", log.diagnostics());
    let subs = log.subscriptions();
    let rows: Vec<(usize, Vec<u8>)> = log
        .data()
        .map(|r| {
            let k = subs
                .iter()
                .position(|s| s.msg_id == r.subscription.msg_id)
                .expect("a subscription");
            (k, r.data.to_vec())
        })
        .collect();
    assert_eq!(rows, m.rows, "rows, as written");
    let subscribed: Vec<(String, u8)> = subs.iter().map(|s| (s.name.clone(), s.multi_id)).collect();
    assert_eq!(subscribed, m.subs, "subscriptions");
    let logged: Vec<(u8, Option<u16>, u64, String)> = log
        .logged_messages()
        .iter()
        .map(|l| (l.level_byte, l.tag, l.timestamp, l.text.clone()))
        .collect();
    assert_eq!(logged, m.logged, "logged strings");
    let dropouts: Vec<u16> = log.dropouts().iter().map(|d| d.duration_ms).collect();
    assert_eq!(dropouts, m.dropouts, "dropouts");
    for (key, text) in &m.info {
        assert_eq!(
            log.metadata().info_value(key),
            Some(&Value::String(text.clone())),
            "info {key}"
        );
    }
    assert_eq!(log.metadata().sync_count(), m.syncs, "sync messages");
    // Initial parameters: each name once, where it first came, with its last value.
    let mut initial: Vec<(String, ParamValue)> = Vec::new();
    for (name, value, _) in m.params.iter().filter(|p| !p.2) {
        match initial.iter_mut().find(|(n, _)| n == name) {
            Some(p) => p.1 = *value,
            None => initial.push((name.clone(), *value)),
        }
    }
    let read: Vec<(String, (bool, u32))> = log
        .metadata()
        .initial_parameters()
        .iter()
        .map(|p| (p.name.clone(), param_bits(p.value)))
        .collect();
    let initial: Vec<(String, (bool, u32))> = initial
        .into_iter()
        .map(|(n, v)| (n, param_bits(v)))
        .collect();
    assert_eq!(read, initial, "initial parameters");
    let changes: Vec<(String, ParamValue)> = log
        .parameter_changes()
        .iter()
        .map(|c| (c.name.clone(), c.value))
        .collect();
    let expected: Vec<(String, ParamValue)> = m
        .params
        .iter()
        .filter(|p| p.2)
        .map(|p| (p.0.clone(), p.1))
        .collect();
    assert_eq!(changes.len(), expected.len(), "parameter changes");
    for ((n, v), (en, ev)) in changes.iter().zip(&expected) {
        assert_eq!(n, en);
        assert_eq!(param_bits(*v), param_bits(*ev), "{n}");
    }
}

fn param_bits(v: ParamValue) -> (bool, u32) {
    match v {
        ParamValue::Int32(i) => (false, i as u32),
        ParamValue::Float(f) => (true, f.to_bits()),
    }
}

/// The rewriter: any input it reads comes out as a log that reads clean (but for notes of
/// the input's it copies: a duplicate msg_id, an odd format, a kept value, a topic without
/// a timestamp), with the rows the
/// whole-file reader finds; rewriting that again changes nothing. A window, topic rules and
/// anonymizing (from the first bytes) never panic, and their outputs read clean too.
pub fn rewrite(data: &[u8]) {
    use ulog_runtime::rewrite::{Anonymize, Rewrite};
    let mut out = Vec::new();
    let Ok(report) = Rewrite::new().run(data, &mut out) else {
        return;
    };
    let input = Log::from_slice(data).expect("what the stream read, the whole-file reader reads");
    let back = Log::from_slice(&out).expect("the rewritten log reads");
    // Clean, but for a msg_id the input subscribes to another topic instance: written as
    // it was (the same instance again is written once). The topic it was before may differ:
    // a subscription between them that cannot be read is not written.
    let dup = |d: &ulog_runtime::Diagnostic| match &d.kind {
        ulog_runtime::DiagnosticKind::DuplicateMsgId { msg_id, topic, .. } => {
            Some((*msg_id, topic.clone()))
        }
        _ => None,
    };
    let input_dups: Vec<_> = input.diagnostics().iter().filter_map(dup).collect();
    let renamed = |d: &ulog_runtime::Diagnostic| dup(d).is_some_and(|k| input_dups.contains(&k));
    // And the input's own notes of messages kept despite them (a format outside the grammar,
    // a value kept as far as it goes, a topic whose format has no timestamp): those messages
    // are copied as they were.
    let kept_note = |d: &ulog_runtime::Diagnostic| {
        matches!(
            d.kind,
            ulog_runtime::DiagnosticKind::OddFormat { .. }
                | ulog_runtime::DiagnosticKind::KeptValue { .. }
                | ulog_runtime::DiagnosticKind::MissingTimestamp { .. }
        ) && input.diagnostics().iter().any(|i| i.kind == d.kind)
    };
    // A change the output holds as an initial parameter (the input's data section began
    // with a message not written; the report counts it moved) gets the reader's note on its
    // key there, which the reader gives no change.
    let moved_change = |moved: usize, d: &ulog_runtime::Diagnostic| {
        moved > 0
            && matches!(&d.kind, ulog_runtime::DiagnosticKind::KeptValue { key, .. }
                if input.parameter_changes().iter().any(|c| key.ends_with(&c.name)))
    };
    assert!(
        back.diagnostics()
            .iter()
            .all(|d| renamed(d) || kept_note(d) || moved_change(report.parameter_changes.1, d)),
        "{:?}",
        back.diagnostics()
    );
    assert_eq!(back.row_count(), input.row_count(), "every row kept");
    assert_eq!(report.bytes_out, out.len() as u64);
    let mut again = Vec::new();
    Rewrite::new()
        .run(&out[..], &mut again)
        .expect("the rewritten log rewrites");
    assert!(again == out, "a rewritten log rewrites to itself");
    let seed = data.get(20).copied().unwrap_or(0);
    let window = ulog_runtime::columns::Window::seconds(
        Some(f64::from(seed) * 0.1),
        Some(f64::from(seed) * 0.1 + 5.0),
    )
    .expect("a window of 5 s");
    for mut rules in [
        Rewrite::new().window(window),
        Rewrite::new().exclude(&[input
            .subscriptions()
            .first()
            .map_or("", |s| s.name.as_str())]),
        Rewrite::new().anonymize(Anonymize::seed(u64::from(seed))),
    ] {
        let mut out = Vec::new();
        let moved = match rules.run(data, &mut out) {
            // What `ulog cut` prints of it.
            Ok(report) => {
                assert!(report.to_string().contains(" bytes read, "));
                report.parameter_changes.1
            }
            // A sentence whose moved altitude no longer fits its message: refused.
            Err(ulog_runtime::rewrite::RewriteError::TooLarge(_)) => continue,
            Err(e) => panic!("what reads once, rewrites: {e}"),
        };
        let cut = Log::from_slice(&out).expect("the output reads");
        assert!(
            cut.diagnostics()
                .iter()
                .all(|d| renamed(d) || kept_note(d) || moved_change(moved, d)),
            "{:?}",
            cut.diagnostics()
        );
    }
}

/// The `rows` values of a column chunk of required values.
fn read_all<T: parquet::data_type::DataType>(
    reader: &mut parquet::column::reader::ColumnReaderImpl<T>,
    rows: usize,
    name: &str,
) -> Vec<T::T> {
    let mut values = Vec::new();
    while values.len() < rows {
        let (records, ..) = reader
            .read_records(rows - values.len(), None, None, &mut values)
            .expect("the values read");
        assert!(records > 0, "{name}: a column chunk ends early");
    }
    values
}

/// The Parquet writer over the whole-file reader: every topic instance that can be read is
/// written (to memory, in row groups of a few batches), reads back with as many rows and row
/// groups as the writer says, each `INT64` column chunk (DELTA_BINARY_PACKED) reads back
/// with the bounds of its values in the column's order, and each `FLOAT` and `DOUBLE`
/// column chunk's statistics are
/// those of its values in the type-defined order the footer gives them (NaN left out, none
/// if there is nothing else; a zero minimum -0.0, a zero maximum +0.0; NaN counted).
pub fn parquet(data: &[u8]) {
    use parquet::basic::{ColumnOrder, SortOrder};
    use parquet::column::reader::ColumnReader;
    use parquet::file::reader::{FileReader, SerializedFileReader};
    use parquet::file::statistics::Statistics;
    use ulog_runtime::columns::parquet::{LogIdentity, ParquetOptions, TableError, write_topic};
    let Ok(log) = Log::from_slice(data) else {
        return;
    };
    let identity = LogIdentity::of_log(&log, "f.ulg");
    let options = ParquetOptions {
        batch_bytes: 1 << 10,
        buffer_bytes: 16 << 10,
        ..ParquetOptions::default()
    };
    // Bounds by the rules, as bits of `f64`s, and the NaN count.
    let expected = |values: &[f64]| {
        let numbers: Vec<f64> = values.iter().copied().filter(|v| !v.is_nan()).collect();
        let lo = numbers.iter().copied().reduce(f64::min);
        let hi = numbers.iter().copied().reduce(f64::max);
        let zero = |v: f64, signed: f64| if v == 0.0 { signed } else { v };
        let bounds = lo
            .zip(hi)
            .map(|(lo, hi)| (zero(lo, -0.0).to_bits(), zero(hi, 0.0).to_bits()));
        (bounds, Some((values.len() - numbers.len()) as u64))
    };
    for instance in log.instances(&[]) {
        let (name, multi_id) = (&instance[0].name, instance[0].multi_id);
        let mut out = Vec::new();
        let written = match write_topic(&log, name, multi_id, &identity, &mut out, &options) {
            Ok(w) => w,
            Err(TableError::NoSuchInstance { .. }) => continue,
            Err(e) => panic!("{name} #{multi_id}: {e}"),
        };
        let file = SerializedFileReader::new(bytes::Bytes::from(out)).expect("the file reads");
        let meta = file.metadata();
        assert_eq!(
            meta.file_metadata().num_rows() as usize,
            written.rows,
            "{name}"
        );
        assert_eq!(meta.num_row_groups(), written.row_groups, "{name}");
        let orders = meta.file_metadata().column_orders().expect("column orders");
        for g in 0..meta.num_row_groups() {
            let group = file.get_row_group(g).expect("a row group");
            for (c, order) in orders.iter().enumerate() {
                let chunk = meta.row_group(g).column(c);
                let rows = chunk.num_values() as usize;
                let values: Vec<f64> = match group.get_column_reader(c) {
                    Ok(ColumnReader::Int64ColumnReader(mut reader)) => {
                        // DELTA_BINARY_PACKED values back, their bounds in the column's
                        // order (unsigned for `uint64_t`).
                        let values = read_all(&mut reader, rows, name);
                        let unsigned = meta.file_metadata().schema_descr().column(c).sort_order()
                            == SortOrder::UNSIGNED;
                        let key = |v: &i64| {
                            if unsigned {
                                i128::from(*v as u64)
                            } else {
                                i128::from(*v)
                            }
                        };
                        let want = values
                            .iter()
                            .min_by_key(|v| key(v))
                            .zip(values.iter().max_by_key(|v| key(v)));
                        let got = match chunk.statistics() {
                            Some(Statistics::Int64(s)) => s.min_opt().zip(s.max_opt()),
                            other => panic!("{name}: an INT64 column chunk's statistics {other:?}"),
                        };
                        assert_eq!(got, want, "{name}: column {c}'s statistics");
                        continue;
                    }
                    Ok(ColumnReader::FloatColumnReader(mut reader)) => {
                        read_all(&mut reader, rows, name)
                            .into_iter()
                            .map(f64::from)
                            .collect()
                    }
                    Ok(ColumnReader::DoubleColumnReader(mut reader)) => {
                        read_all(&mut reader, rows, name)
                    }
                    _ => continue,
                };
                assert_eq!(
                    *order,
                    ColumnOrder::TYPE_DEFINED_ORDER(SortOrder::SIGNED),
                    "{name}"
                );
                let got = match chunk.statistics() {
                    Some(Statistics::Float(s)) => (
                        s.min_opt()
                            .zip(s.max_opt())
                            .map(|(lo, hi)| (f64::from(*lo).to_bits(), f64::from(*hi).to_bits())),
                        s.nan_count_opt(),
                    ),
                    Some(Statistics::Double(s)) => (
                        s.min_opt()
                            .zip(s.max_opt())
                            .map(|(lo, hi)| (lo.to_bits(), hi.to_bits())),
                        s.nan_count_opt(),
                    ),
                    other => panic!("{name}: a float column chunk's statistics {other:?}"),
                };
                assert_eq!(got, expected(&values), "{name}: column {c}'s statistics");
            }
        }
    }
}

/// pyulog's reading (`compat::pyulog`, what `ulog.ULog` shows) of the same bytes read four
/// ways (as given; header only; strict strings; filtered to the first dataset's topic by
/// name) ends without a panic, and the reads agree. Each dataset holds whole rows; a
/// header-only read holds no rows and the same formats; a read with strict strings, when it
/// succeeds, equals the lenient one (no string was invalid); the filtered read of an intact
/// log that pyulog reads to its end holds exactly the full read's datasets of that topic;
/// the datasets of the rows this reader recovers hold whole rows too. (Not tried: a filter
/// by substring, a base offset.)
pub fn pyulog_compat(data: &[u8]) {
    use ulog_runtime::compat::pyulog::{self, NameFilter, PyulogOptions};
    let whole_rows = |file: &pyulog::PyulogFile| {
        for d in &file.data {
            assert!(
                d.rows.len() % d.row_size.max(1) == 0,
                "{} #{}: {} bytes of rows of {} bytes",
                d.name,
                d.multi_id,
                d.rows.len(),
                d.row_size
            );
        }
    };
    let Ok(full) = pyulog::read(data, &PyulogOptions::default()) else {
        return;
    };
    whole_rows(&full);
    let header_only = PyulogOptions {
        header_only: true,
        ..Default::default()
    };
    if let Ok(header) = pyulog::read(data, &header_only) {
        assert!(header.data.is_empty(), "a header-only read holds no rows");
        assert_eq!(
            header.formats, full.formats,
            "the formats of a header-only read"
        );
    }
    let strict = PyulogOptions {
        strict_strings: true,
        ..Default::default()
    };
    if let Ok(strict) = pyulog::read(data, &strict) {
        // Compared as printed: a NaN parameter equals itself there.
        assert!(
            format!("{strict:?}") == format!("{full:?}"),
            "strict strings that all decode read as lenient ones"
        );
    }
    // On a damaged log pyulog's recovery itself keeps other rows when some topics are
    // filtered out, and a read that a `struct.error` ended early (`stopped_at`) reads on
    // when the row that raised it is filtered out (both checked against pyulog live:
    // `tests/fuzz_regressions/pyulog_compat/` and python/tests/test_compat.py), so only
    // an intact log read to its end is held to this.
    if let Some(first) = full
        .data
        .first()
        .filter(|_| !full.file_corrupt && full.stopped_at.is_none())
    {
        let kept = first.name.clone();
        let filtered = PyulogOptions {
            filter: NameFilter::Names(vec![kept.clone()]),
            ..Default::default()
        };
        let filtered = pyulog::read(data, &filtered).expect("a filter adds no failure");
        let expected: Vec<_> = full.data.iter().filter(|d| d.name == kept).collect();
        let got: Vec<_> = filtered.data.iter().collect();
        assert_eq!(got, expected, "the filtered read's datasets of `{kept}`");
    }
    if let Ok(log) = Log::from_slice(data) {
        let recovered = pyulog::recovered_datasets(&log, &full, &NameFilter::All);
        whole_rows(&pyulog::PyulogFile {
            data: recovered,
            ..Default::default()
        });
    }
}
