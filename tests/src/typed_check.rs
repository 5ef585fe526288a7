//! Typed reading checked against the oracle, shared by the typed and codegen suites.
//!
//! The generic part only gathers a topic's rows as bytes (encoded under the struct's own
//! format); the comparisons are not generic, so checking a thousand generated types stays
//! cheap to compile.

use std::collections::BTreeMap;
use std::path::Path;

use serde_json::Value as Json;
use ulog_runtime::schema::Schema;
use ulog_runtime::typed::{TypedFormat, TypedTopic};
use ulog_runtime::value::RowPlan;
use ulog_runtime::{Event, Log, Scalar, StreamReader, Topic, ULog};

use crate::{pyulog_blind_ranges, scalar_matches, short_name};

/// A row as named columns.
pub type Columns = BTreeMap<String, Scalar>;

/// A struct's own format, to read its encodings with the dynamic reader.
pub struct OwnPlan {
    schema: Schema,
    plan: RowPlan,
    names: Vec<String>,
}

impl OwnPlan {
    /// The plan of a typed format.
    pub fn new(format: &'static TypedFormat) -> OwnPlan {
        let mut schema = Schema::new();
        for f in format.formats() {
            schema.insert(f).unwrap();
        }
        let id = schema.id(format.name).unwrap();
        let plan = RowPlan::new(&mut schema, id).unwrap();
        let names = plan.columns(&schema).into_iter().map(|c| c.name).collect();
        OwnPlan {
            schema,
            plan,
            names,
        }
    }

    /// The leaves of an encoding, in column order.
    pub fn leaves(&self, bytes: &[u8]) -> Vec<Scalar> {
        let mut out = Vec::with_capacity(self.names.len());
        assert!(self.plan.for_each_leaf(bytes, |s| out.push(s)));
        out
    }

    /// An encoding as named columns.
    pub fn columns(&self, bytes: &[u8]) -> Columns {
        self.names.iter().cloned().zip(self.leaves(bytes)).collect()
    }

    /// The column names.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The struct's schema.
    pub fn schema(&self) -> &Schema {
        &self.schema
    }
}

/// Named columns of a typed value, made without its decoder: encoded under its own format,
/// then read by the dynamic reader.
pub fn columns<T: ULog>(value: &T) -> Columns {
    OwnPlan::new(&T::FORMAT).columns(&encode(value))
}

/// The full encoding of a value.
pub fn encode<T: ULog>(value: &T) -> Vec<u8> {
    let mut out = Vec::new();
    value.encode(&mut out);
    out
}

/// The oracle's instances (subscriptions with data) of a topic.
pub fn oracle_instances<'o>(o: &'o Json, topic: &str) -> Vec<&'o Json> {
    o["pyulog"]["subscriptions"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["name"] == topic)
        .collect()
}

/// What checking one topic of one file found.
#[derive(Debug, Default)]
pub struct FileCheck {
    /// Instances (`multi_id`s with data in the oracle) checked.
    pub instances: usize,
    /// Rows compared with pyulog's count.
    pub rows: usize,
    /// Values compared with pyulog's first and last rows.
    pub values: usize,
    /// Every difference.
    pub failures: Vec<String>,
}

/// A topic's rows as read by every typed path, encoded.
struct Gathered {
    /// Per subscription index: the rows decoded by `TypedDecoder::decode_row`.
    by_row: BTreeMap<usize, Vec<Vec<u8>>>,
    /// Per `multi_id`: the rows of `TypedTopic::instance`.
    by_instance: BTreeMap<u8, Vec<Vec<u8>>>,
    /// All instances through `TypedTopic::rows`.
    all: Vec<Vec<u8>>,
    /// All instances through the streaming reader.
    streamed: Vec<Vec<u8>>,
}

fn gather<T: Topic>(path: &Path, log: &Log<'_>, typed: &TypedTopic<'_, T>) -> Gathered {
    let decoder = typed.decoder();
    let mut by_row = BTreeMap::new();
    for sub in log
        .subscriptions()
        .iter()
        .filter(|s| s.name == typed.name())
    {
        let rows = log
            .rows(sub)
            .map(|row| encode(&decoder.decode_row(&row).expect("a row of the topic")))
            .collect();
        by_row.insert(sub.index(), rows);
    }
    let by_instance = typed
        .multi_ids()
        .into_iter()
        .map(|m| (m, typed.instance(m).unwrap().map(|v| encode(&v)).collect()))
        .collect();
    let all = typed.rows().map(|(_, v)| encode(&v)).collect();
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let mut reader = StreamReader::new(file).unwrap();
    let mut stream_decoder = None;
    let mut streamed = Vec::new();
    while let Some(event) = reader.next_event().unwrap() {
        match event {
            Event::Subscription(s) if s.name == typed.name() && stream_decoder.is_none() => {
                stream_decoder = Some(reader.typed_as::<T>(typed.name()).unwrap());
            }
            Event::Row(row) => {
                if let Some(v) = stream_decoder.as_ref().and_then(|d| d.decode_row(&row)) {
                    streamed.push(encode(&v));
                }
            }
            _ => {}
        }
    }
    Gathered {
        by_row,
        by_instance,
        all,
        streamed,
    }
}

/// Whether a column (`esc[2].esc_power`) lies in an optional field at some level.
fn optional_path(format: &TypedFormat, col: &str) -> bool {
    let (head, rest) = col.split_once('.').unwrap_or((col, ""));
    let name = head.split('[').next().unwrap_or(head);
    let Some(field) = format.fields.iter().find(|f| f.name == name) else {
        return false;
    };
    field.optional
        || match field.kind {
            ulog_runtime::typed::TypedKind::Nested(inner) => optional_path(inner, rest),
            ulog_runtime::typed::TypedKind::Primitive(_) => false,
        }
}

/// Checks the rows of `typed` (a topic read as `T` from the log at `path`) against the
/// oracle `o`: per
/// instance with data, the row count and the first and last 3 rows value by value (rows
/// pyulog cannot see set aside), every row against the dynamic reader, `Log::topic` against
/// `TypedDecoder::decode_row`, and the whole file against the streaming reader.
///
/// # Panics
/// On a disagreement between this project's own readers.
pub fn check_typed_file<T: Topic>(
    path: &Path,
    o: &Json,
    log: &Log<'_>,
    typed: &TypedTopic<'_, T>,
) -> FileCheck {
    let gathered = gather(path, log, typed);
    compare(path, o, log, &T::FORMAT, typed.name(), &gathered)
}

fn compare(
    path: &Path,
    o: &Json,
    log: &Log<'_>,
    format: &'static TypedFormat,
    topic: &str,
    g: &Gathered,
) -> FileCheck {
    let mut check = FileCheck::default();
    let name = short_name(path);
    let own = OwnPlan::new(format);
    let blind = pyulog_blind_ranges(log);
    assert!(
        g.streamed == g.all,
        "{name}: streaming and whole-file rows differ"
    );
    for s in oracle_instances(o, topic) {
        let multi_id = u8::try_from(s["multi_id"].as_u64().unwrap()).unwrap();
        check.instances += 1;
        let mut ours = Vec::new();
        for sub in log.subscriptions().iter().filter(|x| x.name == topic) {
            if sub.multi_id != multi_id {
                continue;
            }
            let decoded = &g.by_row[&sub.index()];
            let plan = sub.plan(log.metadata().schema()).unwrap();
            let file_names: Vec<String> = plan
                .columns(log.metadata().schema())
                .into_iter()
                .map(|c| c.name)
                .collect();
            // Where each of the struct's columns is among the file's.
            let map: Vec<Option<usize>> = own
                .names()
                .iter()
                .map(|n| file_names.iter().position(|f| f == n))
                .collect();
            for (row, bytes) in log.rows(sub).zip(decoded) {
                let mut dynamic = Vec::with_capacity(file_names.len());
                row.for_each_leaf(|l| dynamic.push(l));
                for (i, v) in own.leaves(bytes).into_iter().enumerate() {
                    if let Some(j) = map[i]
                        && dynamic[j].as_f64().to_bits() != v.as_f64().to_bits()
                    {
                        check.failures.push(format!(
                            "{name} {topic} {}: typed {v}, dynamic {}",
                            own.names()[i],
                            dynamic[j]
                        ));
                    }
                }
                ours.push((bytes, blind.iter().any(|r| r.contains(&row.offset))));
            }
        }
        let from_topic: Vec<&Vec<u8>> = g.by_instance[&multi_id].iter().collect();
        assert!(
            from_topic == ours.iter().map(|(b, _)| *b).collect::<Vec<_>>(),
            "{name}: Log::topic and TypedDecoder::decode_row disagree"
        );
        let seen: Vec<&Vec<u8>> = ours.iter().filter(|(_, b)| !b).map(|(v, _)| *v).collect();
        assert_eq!(
            seen.len() as u64,
            s["n_data"].as_u64().unwrap(),
            "{name} {topic}/{multi_id}: rows"
        );
        check.rows += seen.len();
        let n = seen.len();
        let picks = (0..n.min(3)).map(|i| (&s["first_rows"][i], i)).chain(
            (n.saturating_sub(3)..n)
                .enumerate()
                .map(|(j, i)| (&s["last_rows"][j], i)),
        );
        for (expected, i) in picks {
            for (col, v) in own.columns(seen[i]) {
                match expected.get(&col) {
                    Some(e) => {
                        check.values += 1;
                        if !scalar_matches(e, v) {
                            check.failures.push(format!(
                                "{name} {topic}/{multi_id} row {i} {col}: typed {v}, pyulog {e}"
                            ));
                        }
                    }
                    // A column only the struct has must be (in) an absent optional field.
                    None => assert!(
                        optional_path(format, &col),
                        "{name}: {col} is not in the file"
                    ),
                }
            }
        }
    }
    check
}
