//! Shared support for the integration suites: finding the ULog corpus and its pyulog oracles.
//!
//! The corpus is the folder named by `ULOG_CORPUS` (default `../shared/testdata/ulog`
//! relative to the workspace root), searched recursively for `.ulg` files. Under CI
//! (`CI=true`) a missing corpus fails the tests instead of skipping them.

pub mod corpus;
pub mod files;
pub mod typed_check;

pub use corpus::{
    corpus_dir, corpus_files, fixture, is_project_corpus, oracle, pyulog_blind_ranges, short_name,
    under_ci,
};

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use serde_json::Value as Json;
use sha2::{Digest, Sha256};
use ulog_runtime::read::ParamValue;
use ulog_runtime::{DiagnosticKind, Log, Row, Scalar, Value};

/// Collects every difference of one file instead of stopping at the first.
#[derive(Default)]
struct Diffs(Vec<String>);

impl Diffs {
    fn eq<T: PartialEq + std::fmt::Debug>(
        &mut self,
        what: impl std::fmt::Display,
        ours: T,
        pyulog: T,
    ) {
        if ours != pyulog {
            self.0
                .push(format!("{what}: ours {ours:?}, pyulog {pyulog:?}"));
        }
    }
    fn fail(&mut self, msg: String) {
        self.0.push(msg);
    }
}

/// Whether an oracle number (or "NaN"/"Infinity" string, or int8 for bool and char) is `v`.
pub fn scalar_matches(json: &Json, v: Scalar) -> bool {
    match v {
        Scalar::Float(_) | Scalar::Double(_) => {
            let ours = v.as_f64();
            match json {
                Json::String(s) if s == "NaN" => ours.is_nan(),
                Json::String(s) if s == "Infinity" => ours == f64::INFINITY,
                Json::String(s) if s == "-Infinity" => ours == f64::NEG_INFINITY,
                Json::Number(n) => n.as_f64() == Some(ours),
                _ => false,
            }
        }
        // pyulog shows bool as the raw byte (int8).
        Scalar::Bool(b) => json.as_i64().is_some_and(|x| (x != 0) == b),
        _ => {
            let ours = v.as_i128().expect("integer");
            json.as_i64()
                .map(i128::from)
                .or_else(|| json.as_u64().map(i128::from))
                == Some(ours)
        }
    }
}

fn value_matches(json: &Json, v: &Value) -> bool {
    match (json, v) {
        (Json::String(s), Value::String(ours)) => s == ours,
        (Json::Object(o), Value::Array(items)) => {
            let hex: String = items
                .iter()
                .map(|i| match i.as_scalar() {
                    Some(Scalar::UInt8(b)) => format!("{b:02x}"),
                    other => format!("<{other:?}>"),
                })
                .collect();
            o.get("hex").and_then(Json::as_str) == Some(hex.as_str())
        }
        (_, Value::Scalar(s)) => scalar_matches(json, *s),
        _ => false,
    }
}

fn param_matches(json: &Json, v: ParamValue) -> bool {
    match v {
        ParamValue::Int32(i) => json.as_i64() == Some(i64::from(i)),
        ParamValue::Float(f) => scalar_matches(json, Scalar::Float(f)),
    }
}

/// An oracle array of unsigned integers.
fn u64s(j: &Json) -> Vec<u64> {
    j.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect()
}

/// pyulog's view of `path` through the corpus's `oracle.py` (written beside it as
/// `PATH.oracle.json`), if pyulog and the script are here.
pub fn pyulog_view(path: &Path) -> Option<Json> {
    let script = fixture("oracle.py")?;
    let ok = std::process::Command::new("python3")
        .arg(&script)
        .arg(path)
        .output()
        .ok()?
        .status
        .success();
    if !ok {
        return None;
    }
    oracle(path)
}

/// Values by the key pyulog gives them: the key's part up to its first space, the last
/// value of a key winning (a Python dict).
fn by_pyulog_key<T>(
    items: &[T],
    key: impl Fn(&T) -> &String,
) -> std::collections::HashMap<&str, &T> {
    items
        .iter()
        .map(|i| (key(i).split(' ').next().unwrap_or_default(), i))
        .collect()
}

/// Everything an oracle (pyulog's view of a file, as `oracle.py` writes it) records, compared
/// with what this reader reads from the file; one line per difference.
pub fn check_file(path: &Path, o: &Json) -> Vec<String> {
    let mut d = Diffs::default();
    let log = Log::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let p = &o["pyulog"];

    // Header and flags (pyulog shows zeros when there is no `B` message).
    d.eq(
        "start_timestamp",
        log.header().start_timestamp,
        p["start_timestamp"].as_u64().unwrap(),
    );
    d.eq(
        "file_version",
        u64::from(log.header().version),
        p["file_version"].as_u64().unwrap(),
    );
    let bits = log.flag_bits().copied().unwrap_or_default();
    let json_bytes = |k: &str| -> Vec<u8> {
        p[k].as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_u64().unwrap() as u8)
            .collect()
    };
    d.eq(
        "compat_flags",
        bits.compat.to_vec(),
        json_bytes("compat_flags"),
    );
    d.eq(
        "incompat_flags",
        bits.incompat.to_vec(),
        json_bytes("incompat_flags"),
    );
    let mut offsets = bits.appended_offsets.to_vec();
    while offsets.last() == Some(&0) {
        offsets.pop();
    }
    let oracle_offsets = u64s(&p["appended_offsets"]);
    d.eq("appended_offsets", offsets, oracle_offsets);
    d.eq(
        "has_data_appended",
        bits.has_data_appended(),
        p["has_data_appended"].as_bool().unwrap(),
    );
    d.eq(
        "has_default_parameters",
        bits.has_default_parameters(),
        p["has_default_parameters_flag"].as_bool().unwrap(),
    );

    // Formats, exactly as declared.
    let schema = log.metadata().schema();
    let oracle_formats = p["message_formats"].as_object().unwrap();
    d.eq("number of formats", schema.len(), oracle_formats.len());
    for (name, fields) in oracle_formats {
        let Some(format) = schema.get(name) else {
            d.fail(format!("format {name} missing"));
            continue;
        };
        let ours: Vec<(String, u64, String)> = format
            .fields
            .iter()
            .map(|f| {
                (
                    f.ty.name().to_owned(),
                    f.array_len.map_or(0, u64::from),
                    f.name.clone(),
                )
            })
            .collect();
        let theirs: Vec<(String, u64, String)> = fields
            .as_array()
            .unwrap()
            .iter()
            .map(|f| {
                (
                    f[0].as_str().unwrap().to_owned(),
                    f[1].as_u64().unwrap(),
                    f[2].as_str().unwrap().to_owned(),
                )
            })
            .collect();
        d.eq(format!("format {name}"), ours, theirs);
    }

    // Info and multi info. pyulog names a key by its part up to the first space
    // (`char[11] Build Date` is `Build`), a later key of that name replacing an earlier
    // one; this reader keeps the whole name.
    let info = p["info"].as_object().unwrap();
    let ours_info = by_pyulog_key(log.metadata().info(), |i| &i.key);
    d.eq("number of info keys", ours_info.len(), info.len());
    for (key, entry) in info {
        match ours_info.get(key.as_str()) {
            None => d.fail(format!("info {key} missing")),
            Some(i) => {
                d.eq(
                    format!("info {key} type"),
                    i.type_name.as_str(),
                    entry["type"].as_str().unwrap(),
                );
                if !value_matches(&entry["value"], &i.value) {
                    d.fail(format!(
                        "info {key}: ours {}, pyulog {}",
                        i.value, entry["value"]
                    ));
                }
            }
        }
    }
    let multi = p["info_multiple"].as_object().unwrap();
    let ours_multi = by_pyulog_key(log.metadata().multi_info(), |m| &m.key);
    d.eq("number of multi info keys", ours_multi.len(), multi.len());
    for (key, entry) in multi {
        let Some(m) = ours_multi.get(key.as_str()) else {
            d.fail(format!("multi info {key} missing"));
            continue;
        };
        d.eq(
            format!("multi info {key} type"),
            m.type_name.as_str(),
            entry["type"].as_str().unwrap(),
        );
        let theirs = entry["value"].as_array().unwrap();
        d.eq(
            format!("multi info {key} count"),
            m.values.len(),
            theirs.len(),
        );
        for (ours, theirs) in m.values.iter().zip(theirs) {
            let theirs = theirs.as_array().unwrap();
            let same = ours.len() == theirs.len()
                && ours.iter().zip(theirs).all(|(v, j)| value_matches(j, v));
            if !same {
                d.fail(format!("multi info {key}: parts differ"));
            }
        }
    }

    // Parameters.
    let initial = p["initial_parameters"].as_object().unwrap();
    d.eq(
        "number of initial parameters",
        log.metadata().initial_parameters().len(),
        initial.len(),
    );
    for param in log.metadata().initial_parameters() {
        match initial.get(&param.name) {
            Some(j) if param_matches(j, param.value) => {}
            other => d.fail(format!(
                "initial parameter {}: ours {}, pyulog {other:?}",
                param.name, param.value
            )),
        }
    }
    let changed = p["changed_parameters"].as_array().unwrap();
    d.eq(
        "number of parameter changes",
        log.parameter_changes().len(),
        changed.len(),
    );
    for (c, j) in log.parameter_changes().iter().zip(changed) {
        let same = j[0].as_u64() == Some(c.timestamp)
            && j[1].as_str() == Some(c.name.as_str())
            && param_matches(&j[2], c.value);
        if !same {
            d.fail(format!("parameter change: ours {c:?}, pyulog {j}"));
        }
    }
    let mut defaults: BTreeMap<String, BTreeMap<String, ParamValue>> = BTreeMap::new();
    for q in log.metadata().default_parameters() {
        for bit in 0..8 {
            if q.default_types & (1 << bit) != 0 {
                defaults
                    .entry(bit.to_string())
                    .or_default()
                    .insert(q.name.clone(), q.value);
            }
        }
    }
    let oracle_defaults = p["default_parameters"].as_object().unwrap();
    d.eq(
        "default parameter types",
        defaults.keys().cloned().collect::<Vec<_>>(),
        oracle_defaults.keys().cloned().collect::<Vec<_>>(),
    );
    for (bit, params) in &defaults {
        let theirs = oracle_defaults[bit].as_object().unwrap();
        d.eq(
            format!("defaults bit {bit} count"),
            params.len(),
            theirs.len(),
        );
        for (name, v) in params {
            if !theirs.get(name).is_some_and(|j| param_matches(j, *v)) {
                d.fail(format!(
                    "default {name} (bit {bit}): ours {v}, pyulog {:?}",
                    theirs.get(name)
                ));
            }
        }
    }

    // Logged strings: untagged in file order; tagged grouped by tag in order of first appearance.
    let untagged: Vec<(u64, u64, String)> = log
        .logged_messages()
        .iter()
        .filter(|m| m.tag.is_none())
        .map(|m| (m.timestamp, u64::from(m.level_byte), m.text.clone()))
        .collect();
    let theirs: Vec<(u64, u64, String)> = p["logged_messages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            (
                m["timestamp"].as_u64().unwrap(),
                m["log_level"].as_u64().unwrap(),
                m["message"].as_str().unwrap().to_owned(),
            )
        })
        .collect();
    d.eq("logged messages", untagged, theirs);
    for m in log.logged_messages() {
        let named = m.level().map(|l| l.name()).unwrap_or("UNKNOWN");
        if let Some(j) = p["logged_messages"]
            .as_array()
            .unwrap()
            .iter()
            .find(|j| j["message"].as_str() == Some(&m.text))
        {
            d.eq(
                "log level name",
                named,
                j["log_level_str"].as_str().unwrap(),
            );
        }
    }
    let mut tags: Vec<u16> = Vec::new();
    for m in log.logged_messages() {
        if let Some(t) = m.tag.filter(|t| !tags.contains(t)) {
            tags.push(t);
        }
    }
    let tagged: Vec<(u64, u64, u64, String)> = tags
        .iter()
        .flat_map(|&t| {
            log.logged_messages()
                .iter()
                .filter(move |m| m.tag == Some(t))
        })
        .map(|m| {
            (
                m.timestamp,
                u64::from(m.level_byte),
                u64::from(m.tag.unwrap()),
                m.text.clone(),
            )
        })
        .collect();
    let theirs: Vec<(u64, u64, u64, String)> = p["logged_messages_tagged"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            (
                m["timestamp"].as_u64().unwrap(),
                m["log_level"].as_u64().unwrap(),
                m["tag"].as_u64().unwrap(),
                m["message"].as_str().unwrap().to_owned(),
            )
        })
        .collect();
    d.eq("tagged logged messages", tagged, theirs);

    let dropouts: Vec<(u64, u64)> = log
        .dropouts()
        .iter()
        .map(|x| (x.timestamp, u64::from(x.duration_ms)))
        .collect();
    let theirs: Vec<(u64, u64)> = p["dropouts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| {
            (
                x["timestamp"].as_u64().unwrap(),
                x["duration"].as_u64().unwrap(),
            )
        })
        .collect();
    d.eq("dropouts", dropouts, theirs);

    // Corruption as pyulog sees it: skipped bytes, rows that do not fit, unknown ids
    // (a file merely cut at the end is not corrupt to pyulog).
    let corrupt = log.diagnostics().iter().any(|x| {
        matches!(
            x.kind,
            DiagnosticKind::Skipped { .. }
                | DiagnosticKind::Overlap { .. }
                | DiagnosticKind::PayloadSize { .. }
                | DiagnosticKind::UnknownMsgId { .. }
        )
    });
    d.eq(
        "file_corruption",
        corrupt,
        p["file_corruption"].as_bool().unwrap(),
    );
    let mut missing: Vec<u64> = log
        .diagnostics()
        .iter()
        .filter_map(|x| match x.kind {
            DiagnosticKind::UnknownMsgId { msg_id } => Some(u64::from(msg_id)),
            _ => None,
        })
        .collect();
    missing.sort();
    missing.dedup();
    let theirs = u64s(&p["missing_message_ids"]);
    d.eq("missing_message_ids", missing, theirs);

    // Subscriptions with data, rows pyulog cannot see set aside.
    let blind = pyulog_blind_ranges(&log);
    let visible = |r: &Row<'_>| !blind.iter().any(|b| b.contains(&r.offset));
    let mut last_timestamp = log.header().start_timestamp;
    let mut ours: BTreeMap<(String, u8), Vec<Row<'_>>> = BTreeMap::new();
    for sub in log.subscriptions() {
        let rows: Vec<Row<'_>> = log.rows(sub).filter(visible).collect();
        last_timestamp = rows
            .iter()
            .map(|r| r.timestamp)
            .fold(last_timestamp, u64::max);
        if !rows.is_empty() {
            ours.insert((sub.name.clone(), sub.multi_id), rows);
        }
    }
    d.eq(
        "last_timestamp",
        last_timestamp,
        p["last_timestamp"].as_u64().unwrap(),
    );
    let subs = p["subscriptions"].as_array().unwrap();
    d.eq("subscriptions with data", ours.len(), subs.len());
    // `Log::topics`: pyulog's data_list, one entry per instance with data.
    let summaries = log.topics();
    d.eq("topics", summaries.len(), subs.len());
    for s in subs {
        let (name, multi_id) = (s["name"].as_str().unwrap(), s["multi_id"].as_u64().unwrap());
        let Some(t) = summaries
            .iter()
            .find(|t| t.name == name && u64::from(t.multi_id) == multi_id)
        else {
            d.fail(format!("topics: no {name}#{multi_id}"));
            continue;
        };
        let n = s["n_data"].as_u64().unwrap() as usize;
        if blind.is_empty() {
            d.eq(format!("topics {name}#{multi_id} rows"), t.rows, n);
            d.eq(
                format!("topics {name}#{multi_id} first"),
                t.first_timestamp,
                s["first_timestamp"].as_u64(),
            );
            d.eq(
                format!("topics {name}#{multi_id} last"),
                t.last_timestamp,
                s["last_timestamp"].as_u64(),
            );
        } else if t.rows < n {
            d.fail(format!(
                "topics {name}#{multi_id}: {} rows, pyulog {n}",
                t.rows
            ));
        }
    }
    for s in subs {
        let key = (
            s["name"].as_str().unwrap().to_owned(),
            s["multi_id"].as_u64().unwrap() as u8,
        );
        let topic = format!("{}#{}", key.0, key.1);
        let Some(rows) = ours.get(&key) else {
            d.fail(format!("{topic}: no rows"));
            continue;
        };
        let sub = rows[0].subscription;
        let plan = rows[0].plan().expect("rows have a plan");
        d.eq(
            format!("{topic} msg_id"),
            u64::from(sub.msg_id),
            s["msg_id"].as_u64().unwrap(),
        );
        d.eq(
            format!("{topic} n_data"),
            rows.len() as u64,
            s["n_data"].as_u64().unwrap(),
        );
        d.eq(
            format!("{topic} first_timestamp"),
            rows.first().map(|r| r.timestamp),
            s["first_timestamp"].as_u64(),
        );
        d.eq(
            format!("{topic} last_timestamp"),
            rows.last().map(|r| r.timestamp),
            s["last_timestamp"].as_u64(),
        );
        let columns = plan.columns(schema);
        let ours_cols: Vec<(String, &str)> = columns
            .iter()
            .map(|c| (c.name.clone(), c.primitive.c_name()))
            .collect();
        let theirs_cols: Vec<(String, &str)> = s["fields"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| (f[0].as_str().unwrap().to_owned(), f[1].as_str().unwrap()))
            .filter(|(n, _)| !n.split('.').any(|part| part.starts_with("_padding")))
            .collect();
        d.eq(format!("{topic} columns"), ours_cols, theirs_cols);
        let row_size = sub.payload_sizes().unwrap().0;
        d.eq(
            format!("{topic} row_size"),
            row_size as u64,
            s["row_size"].as_u64().unwrap(),
        );
        let mut sha = Sha256::new();
        for r in rows {
            sha.update(&r.data[..row_size]);
        }
        let digest: String = sha.finalize().iter().fold(String::new(), |mut acc, b| {
            let _ = write!(acc, "{b:02x}");
            acc
        });
        d.eq(
            format!("{topic} payload_sha256"),
            digest.as_str(),
            s["payload_sha256"].as_str().unwrap(),
        );
        let n = rows.len();
        let picks = (0..n.min(3)).map(|i| (&s["first_rows"], i, i)).chain(
            (n.saturating_sub(3)..n)
                .enumerate()
                .map(|(j, i)| (&s["last_rows"], j, i)),
        );
        for (list, j, i) in picks {
            let expected = &list[j];
            for c in &columns {
                let v = Scalar::decode(c.primitive, &rows[i].data[c.offset..]).unwrap();
                if !scalar_matches(&expected[&c.name], v) {
                    d.fail(format!(
                        "{topic} row {i} {}: ours {v}, pyulog {}",
                        c.name, expected[&c.name]
                    ));
                }
            }
        }
    }
    d.0
}
