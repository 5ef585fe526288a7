//! The `ulog` binary against pyulog: `ulog csv` equals `ulog2csv` value by value on every
//! corpus file, `ulog params`/`info`/`messages` carry the facts of pyulog's committed
//! `*_params.txt`, `*_info.txt` and `*_messages.txt`, snapshots of the human-readable output,
//! and one-line errors; `ulog parquet` read back by pyarrow and DuckDB ([`parquet`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[path = "../../tests/src/corpus.rs"]
#[allow(dead_code, unreachable_pub)]
mod corpus;
#[path = "../../tests/src/files.rs"]
#[allow(unreachable_pub)]
mod files;

#[path = "cli/analyze.rs"]
mod analyze;
#[path = "cli/parquet.rs"]
mod parquet;
#[path = "cli/pyulog_tools.rs"]
mod pyulog_tools;
#[path = "cli/report.rs"]
mod report;

use corpus::{corpus_files, fixture, pyulog_blind_ranges, short_name, under_ci};

fn ulog(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ulog"))
        .args(args)
        .output()
        .expect("the ulog binary runs")
}

fn stdout(args: &[&str]) -> String {
    let out = ulog(args);
    assert!(
        out.status.success(),
        "ulog {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ulog-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A log built by hand from the spec: the header (version 1, start 0), the flag bits, then
/// `messages` in order.
fn hand_built(messages: &[ulog_runtime::read::Message<'_>]) -> Vec<u8> {
    use ulog_runtime::read::{FileHeader, FlagBits, Message};
    let mut bytes = FileHeader {
        version: 1,
        start_timestamp: 0,
    }
    .to_bytes()
    .to_vec();
    Message::FlagBits(FlagBits::default())
        .encode(&mut bytes)
        .unwrap();
    for m in messages {
        m.encode(&mut bytes).unwrap();
    }
    bytes
}

/// Runs pyulog's `ulog2csv` if pyulog is installed (required under CI).
fn ulog2csv(file: &Path, dir: &Path) -> Option<String> {
    ulog2csv_with(file, dir, &[])
}

/// [`ulog2csv`] with more options: what it printed, if it ran.
fn ulog2csv_with(file: &Path, dir: &Path, options: &[&str]) -> Option<String> {
    let out = Command::new("python3")
        .args([
            "-c",
            "import sys; from pyulog.ulog2csv import main; sys.argv[0] = 'ulog2csv'; main()",
        ])
        .arg(file)
        .arg("-o")
        .arg(dir)
        .args(options)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8(o.stdout).unwrap());
    assert!(
        out.is_some() || !under_ci(),
        "under CI pyulog must be installed (.ci/run does it)"
    );
    out
}

fn csv_files(dir: &Path) -> BTreeMap<String, String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let path = e.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read_to_string(&path).unwrap())
        })
        .collect()
}

/// Two cells are the same value: equal numbers (NaN equal to NaN; `float` columns compared
/// as `f32`, whose shortest texts may differ in a last tied digit), or equal text.
fn same_cell(a: &str, b: &str, float32: bool) -> bool {
    if float32 && let (Ok(x), Ok(y)) = (a.parse::<f32>(), b.parse::<f32>()) {
        return x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan());
    }
    match (a.parse::<f64>(), b.parse::<f64>()) {
        (Ok(x), Ok(y)) => x == y || (x.is_nan() && y.is_nan()),
        _ => a == b,
    }
}

#[test]
fn csv_equals_ulog2csv_on_every_corpus_file() {
    let (mut files, mut identical, mut cells, mut compared) = (0, 0, 0usize, 0);
    for path in corpus_files() {
        let name = short_name(&path);
        let ours = temp_dir("ours");
        let theirs = temp_dir("theirs");
        let printed = stdout(&["csv", path.to_str().unwrap(), "-o", ours.to_str().unwrap()]);
        let Some(theirs_printed) = ulog2csv(&path, &theirs) else {
            eprintln!("pyulog not installed: nothing to compare ulog csv with");
            return;
        };
        let (ours_files, theirs_files) = (csv_files(&ours), csv_files(&theirs));
        assert_eq!(
            ours_files.keys().collect::<Vec<_>>(),
            theirs_files.keys().collect::<Vec<_>>(),
            "{name}: the CSV files"
        );
        // Rows pyulog cannot see (it resumes after damage only at a sync magic) are set aside.
        let log = ulog_runtime::Log::open(&path).unwrap();
        let blind = pyulog_blind_ranges(&log);
        // What it prints too (the folders differ), where pyulog sees every row.
        if blind.is_empty() {
            assert_eq!(
                printed.replace(ours.to_str().unwrap(), "DIR"),
                theirs_printed.replace(theirs.to_str().unwrap(), "DIR"),
                "{name}: what ulog2csv prints"
            );
        }
        let stem = path.file_stem().unwrap().to_string_lossy();
        for (file, text) in &ours_files {
            files += 1;
            let expected = &theirs_files[file];
            if text == expected {
                identical += 1;
            }
            let sub = log
                .subscriptions()
                .iter()
                .find(|s| {
                    *file == format!("{stem}_{}_{}.csv", s.name.replace('/', "_"), s.multi_id)
                        && log.rows(s).len() > 0
                })
                .unwrap();
            let hidden: Vec<bool> = log
                .subscriptions()
                .iter()
                .filter(|s| s.name == sub.name && s.multi_id == sub.multi_id)
                .flat_map(|s| log.rows(s))
                .map(|r| blind.iter().any(|b| b.contains(&r.offset)))
                .collect();
            let mut lines = text.lines();
            let header = lines.next().unwrap();
            let rows: Vec<&str> = lines
                .zip(&hidden)
                .filter(|(_, h)| !**h)
                .map(|(l, _)| l)
                .collect();
            let mut expected_lines = expected.lines();
            assert_eq!(
                header,
                expected_lines.next().unwrap(),
                "{name} {file}: header"
            );
            let schema = log.metadata().schema();
            let float_columns: Vec<String> = sub
                .plan(schema)
                .unwrap()
                .columns(schema)
                .into_iter()
                .filter(|c| c.primitive == ulog_runtime::schema::Primitive::Float)
                .map(|c| c.name)
                .collect();
            let float32: Vec<bool> = header
                .split(',')
                .map(|h| float_columns.iter().any(|c| c == h))
                .collect();
            let expected_rows: Vec<&str> = expected_lines.collect();
            assert_eq!(rows.len(), expected_rows.len(), "{name} {file}: rows");
            for (i, (a, b)) in rows.iter().zip(&expected_rows).enumerate() {
                let (a, b): (Vec<&str>, Vec<&str>) =
                    (a.split(',').collect(), b.split(',').collect());
                assert_eq!(a.len(), b.len(), "{name} {file} row {i}: cells");
                for (k, (x, y)) in a.iter().zip(&b).enumerate() {
                    cells += 1;
                    assert!(
                        same_cell(x, y, float32[k]),
                        "{name} {file} row {i} column {k}: ours {x:?}, ulog2csv {y:?}"
                    );
                }
            }
        }
        compared += 1;
        std::fs::remove_dir_all(&ours).unwrap();
        std::fs::remove_dir_all(&theirs).unwrap();
    }
    eprintln!(
        "{compared} logs, {files} CSV files, {cells} cells equal to ulog2csv's; \
         {identical} files byte for byte"
    );
}

#[test]
fn csv_options_select_topics_time_and_delimiter() {
    let Some(path) = fixture("pyulog/sample_log_small.ulg") else {
        return;
    };
    let dir = temp_dir("options");
    let log = ulog_runtime::Log::open(&path).unwrap();
    let first = log
        .rows(log.subscription("vehicle_attitude", 0).unwrap())
        .next()
        .unwrap()
        .timestamp;
    let start = (first / 1_000_000 + 2) as f64;
    let (start_text, end_text) = (start.to_string(), (start + 1.5).to_string());
    let listed = stdout(&[
        "csv",
        path.to_str().unwrap(),
        "-o",
        dir.to_str().unwrap(),
        "-m",
        "vehicle_attitude,sensor_combined",
        "-d",
        ";",
        "--start",
        &start_text,
        "--end",
        &end_text,
    ]);
    let files = csv_files(&dir);
    assert_eq!(
        files.keys().collect::<Vec<_>>(),
        [
            "sample_log_small_sensor_combined_0.csv",
            "sample_log_small_vehicle_attitude_0.csv"
        ]
    );
    assert_eq!(listed.lines().count(), 2);
    for text in files.values() {
        let mut lines = text.lines();
        assert!(lines.next().unwrap().starts_with("timestamp;"));
        let stamps: Vec<u64> = lines
            .map(|l| l.split(';').next().unwrap().parse().unwrap())
            .collect();
        assert!(!stamps.is_empty());
        let window = (start * 1e6) as u64..((start + 1.5) * 1e6) as u64;
        assert!(stamps.iter().all(|t| window.contains(t)), "{stamps:?}");
        // ulog2csv's rule: from the first row at or after the start.
        assert!(stamps[0] - window.start < 200_000, "{stamps:?}");
    }
    // Names of a `-m` list lose the spaces around them and empty ones are left out: as
    // for ulog2csv, `-m ""` names no topic, so every topic is written.
    let listed = |m: &str, to: &str| {
        let to = dir.join(to);
        stdout(&[
            "csv",
            path.to_str().unwrap(),
            "-o",
            to.to_str().unwrap(),
            "-m",
            m,
        ]);
        csv_files(&to).into_keys().collect::<Vec<_>>()
    };
    assert_eq!(
        listed(" vehicle_attitude , sensor_combined,", "spaced"),
        [
            "sample_log_small_sensor_combined_0.csv",
            "sample_log_small_vehicle_attitude_0.csv"
        ]
    );
    let every = listed("", "every");
    assert_eq!(every.len(), log.topics().len(), "{every:?}");
    if ulog2csv_with(&path, &dir.join("theirs"), &["-m", ""]).is_some() {
        let theirs = csv_files(&dir.join("theirs"))
            .into_keys()
            .collect::<Vec<_>>();
        assert_eq!(every, theirs);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn params_equal_ulog_params_output() {
    let (Some(expected), Some(log)) = (
        fixture("pyulog/sample_params.txt"),
        fixture("pyulog/sample.ulg"),
    ) else {
        return;
    };
    let ours = stdout(&["params", log.to_str().unwrap()]);
    assert_eq!(ours, std::fs::read_to_string(expected).unwrap());
}

/// The facts of a pyulog `*_info.txt`: start, duration, dropouts, info values, and per topic
/// instance the message size, row count and bytes.
#[test]
fn info_carries_the_facts_of_ulog_info() {
    let mut checked = 0;
    for stem in ["sample", "sample_appended_multiple"] {
        let (Some(expected), Some(log)) = (
            fixture(&format!("pyulog/{stem}_info.txt")),
            fixture(&format!("pyulog/{stem}.ulg")),
        ) else {
            continue;
        };
        let expected = std::fs::read_to_string(expected).unwrap();
        // pyulog shows perf_* info only with -v.
        let verbose = if expected.contains(" perf_") {
            "-v"
        } else {
            "--"
        };
        let ours = stdout(&["info", verbose, log.to_str().unwrap()]);
        let mut lines = expected.lines();
        let first = lines.next().unwrap(); // Logging start time: 0:01:52, duration: 0:01:08
        let (start, duration) = first
            .strip_prefix("Logging start time: ")
            .unwrap()
            .split_once(", duration: ")
            .unwrap();
        assert!(
            ours.contains(&format!("start {start} ("))
                && ours.contains(&format!("duration {duration} (")),
            "{stem}: {first}\n{ours}"
        );
        let mut section = "";
        for line in lines {
            if !line.starts_with(' ') {
                section = line;
            }
            if let Some(d) = line.strip_prefix("Dropouts: ") {
                assert!(ours.contains(&format!("Dropouts:   {d}")), "{stem}: {line}");
            } else if line == "No Dropouts" {
                assert!(ours.contains("Dropouts:   none"));
            } else if section == "Info Messages:" && line.starts_with(' ') {
                // An info value: ` key: value`.
                let (key, value) = line[1..].split_once(": ").unwrap();
                assert!(
                    ours.lines().any(|l| {
                        let mut w = l.split_whitespace();
                        w.next() == Some(key)
                            && w.collect::<Vec<_>>() == value.split_whitespace().collect::<Vec<_>>()
                    }),
                    "{stem}: info {key}"
                );
                checked += 1;
            } else if section == "Info Multiple Messages:" && line.starts_with(' ') {
                // ` key: [['part', ...], ...]`: ours names the key, then (with -v) lists
                // each value's parts, quoted.
                let (key, values) = line[1..].split_once(": ").unwrap();
                let at = ours
                    .find(&format!("\n  {key} ("))
                    .unwrap_or_else(|| panic!("{stem}: multi info {key}"));
                assert!(
                    ours[at..].contains("\n    0: \""),
                    "{stem}: multi info {key}"
                );
                // The first part's first line is shown as pyulog shows it.
                let first = values
                    .trim_start_matches("[['")
                    .split("\\n")
                    .next()
                    .unwrap();
                assert!(ours[at..].contains(first), "{stem}: {first}");
                checked += 1;
            } else if section.starts_with("Name (") && line.starts_with(' ') {
                // ` name (multi, size)   rows   bytes`
                let (name, rest) = line[1..].split_once(" (").unwrap();
                let (ids, counts) = rest.split_once(')').unwrap();
                let (multi, size) = ids.split_once(", ").unwrap();
                let counts: Vec<&str> = counts.split_whitespace().collect();
                let want = [name, multi, size, counts[0], counts[1]];
                assert!(
                    ours.lines()
                        .any(|l| l.split_whitespace().take(5).eq(want.iter().copied())),
                    "{stem}: no topic line {want:?} in\n{ours}"
                );
                checked += 1;
            }
        }
    }
    if !corpus_files().is_empty() {
        assert!(checked > 20, "{checked}");
    }
}

/// A small log written here, so the snapshot does not depend on the corpus.
fn snapshot_log(dir: &Path) -> PathBuf {
    use ulog_runtime::read::ParamValue;
    use ulog_runtime::{Value, Writer, WriterOptions};
    let path = dir.join("snapshot.ulg");
    let mut w = Writer::create(
        &path,
        WriterOptions {
            start_timestamp: 3_723_000_000,
            default_parameters: true,
        },
    )
    .unwrap();
    w.format("esc_report:int32_t esc_rpm;float esc_voltage;uint8_t[4] _padding0;")
        .unwrap();
    w.format("esc_status:uint64_t timestamp;uint8_t esc_count;uint8_t[7] _padding0;esc_report[2] esc;char[4] name;")
        .unwrap();
    w.info("sys_name", &Value::String("snap".into())).unwrap();
    w.info(
        "ver_sw_release",
        &Value::Scalar(ulog_runtime::Scalar::UInt32(0x010F_01C0)),
    )
    .unwrap();
    // Binary data in two continued parts, as PX4 writes its events metadata.
    let blob = |from: u8| {
        Value::Array(
            (from..from + 20)
                .map(|b| Value::Scalar(ulog_runtime::Scalar::UInt8(b)))
                .collect(),
        )
    };
    w.multi_info("blob", &blob(0), false).unwrap();
    w.multi_info("blob", &blob(20), true).unwrap();
    w.info("perf_top", &Value::String("hidden unless -v".into()))
        .unwrap();
    w.multi_info("boot", &Value::String("a".into()), false)
        .unwrap();
    w.parameter("MC_ROLL_P", ParamValue::Float(6.5)).unwrap();
    w.parameter("SYS_AUTOSTART", ParamValue::Int32(4001))
        .unwrap();
    w.default_parameter("MC_ROLL_P", ParamValue::Float(7.0), 1)
        .unwrap();
    let esc = [
        w.subscribe("esc_status", 0).unwrap(),
        w.subscribe("esc_status", 1).unwrap(),
    ];
    for i in 0..11u64 {
        for (k, id) in esc.iter().enumerate() {
            let mut row = (3_723_000_000 + i * 100_000 + k as u64)
                .to_le_bytes()
                .to_vec();
            row.extend_from_slice(&[2, 0, 0, 0, 0, 0, 0, 0]);
            for e in 0..2i32 {
                row.extend_from_slice(&(1000 * e + i as i32).to_le_bytes());
                row.extend_from_slice(&(0.1f32 * i as f32).to_le_bytes());
                row.extend_from_slice(&[0; 4]);
            }
            row.extend_from_slice(b"ab\0\0");
            w.data(*id, &row).unwrap();
        }
        if i == 5 {
            w.log(b'4', 3_723_500_000, "low battery").unwrap();
            w.log_tagged(b'6', 2, 3_723_500_123, "tagged").unwrap();
            w.parameter("MC_ROLL_P", ParamValue::Float(6.75)).unwrap();
            w.dropout(25).unwrap();
        }
    }
    w.flush().unwrap();
    path
}

#[test]
fn human_output_snapshots() {
    let dir = temp_dir("snapshot");
    let log = snapshot_log(&dir);
    let log = log.to_str().unwrap();
    let snapshots = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots");
    let refresh = std::env::var_os("ULOG_REFRESH").is_some();
    let mut stale = Vec::new();
    for (name, args) in [
        ("info.txt", vec!["info", log]),
        ("info_verbose.txt", vec!["info", "-v", log]),
        ("params.txt", vec!["params", log]),
        ("params_timestamps.txt", vec!["params", "-t", log]),
        ("params_defaults.txt", vec!["params", "-d", "system", log]),
        ("params_changed.txt", vec!["params", "--changed", log]),
        ("messages.txt", vec!["messages", log]),
        ("messages_tagged.txt", vec!["messages", "--tagged", log]),
    ] {
        // The file's path differs per run.
        let got = stdout(&args).replace(log, "snapshot.ulg");
        let path = snapshots.join(name);
        if refresh {
            std::fs::create_dir_all(&snapshots).unwrap();
            std::fs::write(&path, &got).unwrap();
        }
        if std::fs::read_to_string(&path).unwrap_or_default() != got {
            stale.push(format!("{name}:\n{got}"));
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(
        stale.is_empty(),
        "output changed (ULOG_REFRESH=1 to accept):\n{}",
        stale.join("\n")
    );
}

#[test]
fn json_and_codegen() {
    let dir = temp_dir("json");
    let path = snapshot_log(&dir);
    let file = path.to_str().unwrap();
    let lines = stdout(&["json", file]);
    let rows: Vec<serde_json::Value> = lines
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(rows.len(), 22);
    assert_eq!(rows[1]["multi_id"], 1);
    assert_eq!(rows[2]["data"]["esc"][1]["esc_rpm"], 1001);
    assert_eq!(rows[2]["data"]["name"], "ab");
    let doc: serde_json::Value =
        serde_json::from_str(&stdout(&["json", "--document", "-m", "esc_status", file])).unwrap();
    assert_eq!(doc["data"].as_array().unwrap().len(), 2);
    assert_eq!(doc["data"][0]["rows"].as_array().unwrap().len(), 11);
    assert_eq!(
        doc["topics"].as_array().unwrap().len(),
        2,
        "each instance with its row count"
    );
    assert_eq!(doc["topics"][0]["rows"], 11);
    assert_eq!(doc["info"]["sys_name"], "snap");
    // Integer parameters stay integers; floats keep their shortest text.
    assert!(
        doc["parameters"]["SYS_AUTOSTART"].is_i64(),
        "{}",
        doc["parameters"]
    );
    assert_eq!(doc["parameters"]["SYS_AUTOSTART"], 4001);
    assert_eq!(doc["parameters"]["MC_ROLL_P"].to_string(), "6.5");
    assert_eq!(doc["parameter_changes"][0]["name"], "MC_ROLL_P");
    assert_eq!(doc["parameter_changes"][0]["value"].to_string(), "6.75");
    assert_eq!(doc["default_parameters"][0]["default_types"], 1);
    assert_eq!(doc["multi_info"]["boot"], serde_json::json!([["a"]]));
    assert_eq!(doc["dropouts"][0]["duration_ms"], 25);
    assert_eq!(doc["logged_messages"][1]["tag"], 2);
    assert_eq!(
        doc["data"][0]["rows"][10]["data"]["esc"][0]["esc_voltage"].to_string(),
        "1.0"
    );
    let code = stdout(&["codegen", file, "-m", "esc_status"]);
    let expected = ulog_runtime::codegen::Builder::new()
        .ulog_topics(&path, &["esc_status"])
        .render()
        .unwrap();
    assert_eq!(code, expected);
    assert!(code.contains("pub struct EscStatus"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn errors_are_one_line_with_the_file_and_offset() {
    let dir = temp_dir("errors");
    let missing = dir.join("missing.ulg");
    let out = ulog(&["info", missing.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with(&format!("ulog: {}: ", missing.display())),
        "{err}"
    );
    let garbage = dir.join("garbage.ulg");
    std::fs::write(&garbage, b"not a ulog file at all").unwrap();
    let out = ulog(&["csv", garbage.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("garbage.ulg") && !err.contains("panicked"),
        "{err}"
    );
    let out = ulog(&["params", "--default", "nonsense", garbage.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "usage errors exit with 2");
    // Counts that would convert or buffer nothing are usage errors, before any log is read.
    for (option, value) in [("-j", "0"), ("--buffer-mb", "0")] {
        let pq = dir.join("pq0");
        let out = ulog(&[
            "parquet",
            garbage.to_str().unwrap(),
            "-o",
            pq.to_str().unwrap(),
            option,
            value,
        ]);
        assert_eq!(out.status.code(), Some(2), "{option} {value}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(err.contains("0 is not allowed: give 1 or more"), "{err}");
        assert!(!pq.exists(), "{option} {value}: nothing written");
    }
    // Plain messages, the path once.
    let err = |args: &[&str]| {
        let out = ulog(args);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        String::from_utf8(out.stderr).unwrap()
    };
    let d = dir.to_str().unwrap();
    assert_eq!(
        err(&["info", d]),
        format!("ulog: {d}: is a folder, not a log file\n")
    );
    let m = missing.to_str().unwrap();
    assert_eq!(err(&["messages", m]), format!("ulog: {m}: no such file\n"));
    // The same for every verb that takes paths: parquet per log, folders of `.msg` files.
    let o = dir.join("pq");
    assert_eq!(
        err(&["parquet", m, d, "-o", o.to_str().unwrap()]),
        format!(
            "ulog: {m}: no such file\nulog: {d}: is a folder, not a log file\n\
             ulog: 2 of 2 logs not converted\n"
        )
    );
    assert_eq!(
        err(&["check-msg", m, m]),
        format!("ulog: {m}: no such folder\n")
    );
    assert_eq!(
        err(&["codegen", "--msg-dir", m]),
        format!("ulog: {m}: no such folder\n")
    );
    // A topic the log lacks is an error for every verb that takes `-m`, with suggestions.
    let log = snapshot_log(&dir);
    let l = log.to_str().unwrap();
    for verb in ["csv", "json", "codegen"] {
        assert_eq!(
            err(&[verb, l, "-m", "esc_stat"]),
            format!("ulog: {l}: no topic `esc_stat` in this log; did you mean `esc_status`?\n"),
            "{verb}"
        );
    }
    // A name close to none says where the topics are listed.
    assert_eq!(
        err(&["csv", l, "-m", "zzzzzzzzzzzz"]),
        format!(
            "ulog: {l}: no topic `zzzzzzzzzzzz` in this log (`ulog info FILE` lists its topics)\n"
        )
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_verb_refuses_an_output_of_the_wrong_kind_alike_and_makes_missing_folders() {
    let dir = temp_dir("outputs");
    let log = snapshot_log(&dir);
    let l = log.to_str().unwrap();
    let d = dir.to_str().unwrap();
    let file = dir.join("a_file");
    std::fs::write(&file, b"x").unwrap();
    let f = file.to_str().unwrap();
    let under_file = file.join("out");
    let u = under_file.to_str().unwrap();
    let err = |args: &[&str]| {
        let out = ulog(args);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        String::from_utf8(out.stderr).unwrap()
    };
    // One output file: a folder in its place (or a path that names one, ending in `/`,
    // where none is yet), or a file in its folder's place.
    let slash = format!("{d}/not_yet/");
    for verb in ["cut", "anonymize", "kml", "report"] {
        for folder in [d, slash.as_str()] {
            assert_eq!(
                err(&[verb, l, "-o", folder]),
                format!("ulog: {folder}: a folder; the output is a file (give its path)\n"),
                "{verb}"
            );
        }
        assert_eq!(
            err(&[verb, l, "-o", u]),
            format!("ulog: {u}: `{f}` is a file, not a folder\n"),
            "{verb}"
        );
    }
    // A folder of outputs: a file in its place (before any log is converted).
    for verb in ["csv", "parquet", "gps-dump"] {
        assert_eq!(
            err(&[verb, l, "-o", f]),
            format!("ulog: {f}: a file; the output is a folder (give a folder's path)\n"),
            "{verb}"
        );
    }
    assert_eq!(
        std::fs::read(&file).unwrap(),
        b"x",
        "the file is left as it was"
    );
    // Missing folders are made, for one file as for a folder of them.
    for (verb, out) in [
        ("cut", "new/cut/out.ulg"),
        ("anonymize", "new/anonymize/out.ulg"),
        ("report", "new/report/report.html"),
        ("csv", "new/csv"),
        ("parquet", "new/parquet"),
        ("gps-dump", "new/gps-dump"),
    ] {
        let path = dir.join(out);
        stdout(&[verb, l, "-o", path.to_str().unwrap()]);
        assert!(path.exists(), "{verb}: {}", path.display());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn info_shows_the_version_as_pyulog_and_binary_data_as_a_digest() {
    use sha2::Digest;
    let dir = temp_dir("version");
    let log = snapshot_log(&dir);
    let text = stdout(&["info", log.to_str().unwrap()]);
    assert!(text.contains("\nSoftware:   v1.15.1 (RC)\n"), "{text}");
    let digest: String = sha2::Sha256::digest((0..40u8).collect::<Vec<_>>())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    assert!(
        text.contains(&format!(
            "\n  blob (uint8_t[20], 1 value)\n    0: binary, 40 bytes in 2 parts, sha256 {digest}\n"
        )),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
    // pyulog's `SW Version` line, on every corpus log.
    let (mut compared, mut developments) = (0, 0);
    for path in corpus_files() {
        let Some(theirs) = pyulog_info(&path) else {
            continue;
        };
        let theirs = theirs
            .lines()
            .find_map(|l| l.strip_prefix("SW Version: "))
            .map(str::to_owned);
        let text = stdout(&["info", path.to_str().unwrap()]);
        let software = text.lines().find_map(|l| l.strip_prefix("Software:   "));
        let ours = software.filter(|v| v.starts_with('v')).map(str::to_owned);
        assert_eq!(ours, theirs, "{}", short_name(&path));
        compared += 1;
        // Where pyulog gives no version (a development build), the numbers of the log's
        // `ver_sw_release` (0xMMmmpptt) are still shown.
        if let Some(dev) = software.and_then(|s| s.strip_prefix("a development build ")) {
            let release: u32 = text
                .lines()
                .find_map(|l| l.trim().strip_prefix("ver_sw_release"))
                .and_then(|v| v.trim().parse().ok())
                .expect("a development build is known from ver_sw_release");
            let [major, minor, patch, _] = release.to_be_bytes();
            assert_eq!(
                dev,
                format!("(ver_sw_release {major}.{minor}.{patch})"),
                "{}",
                short_name(&path)
            );
            developments += 1;
        }
    }
    eprintln!(
        "software versions compared with pyulog on {compared} logs \
         ({developments} development builds)"
    );
    assert!(
        compared == 0 || developments > 0,
        "the corpus has development builds"
    );
}

/// pyulog's `ulog_info` output, run live (required under CI).
fn pyulog_info(file: &Path) -> Option<String> {
    let out = Command::new("python3")
        .args([
            "-c",
            "import sys; from pyulog.info import main; sys.argv[0] = 'ulog_info'; main()",
        ])
        .arg(file)
        .output()
        .ok()
        .filter(|o| o.status.success());
    assert!(
        out.is_some() || !under_ci(),
        "under CI pyulog must be installed (.ci/run does it)"
    );
    out.map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
}

#[test]
fn pyulog_option_spellings_are_accepted() {
    let dir = temp_dir("aliases");
    let log = snapshot_log(&dir);
    let l = log.to_str().unwrap();
    let out = dir.join("out");
    let o = out.to_str().unwrap();
    // Made first: each run then prints the same (no "Creating output directory").
    std::fs::create_dir_all(&out).unwrap();
    // ulog2csv's -ts/-te (and --time_s/--time_e) are --start/--end.
    let short = stdout(&["csv", l, "-o", o, "-ts", "3723.3", "-te", "3723.6"]);
    let long = stdout(&[
        "csv", l, "-o", o, "--time_s", "3723.3", "--time_e", "3723.6",
    ]);
    let ours = stdout(&["csv", l, "-o", o, "--start", "3723.3", "--end", "3723.6"]);
    assert_eq!(short, ours);
    assert_eq!(long, ours);
    // The window's 3 rows in each instance's file (what is printed counts the whole log's,
    // as ulog2csv's lines do).
    let rows: Vec<usize> = csv_files(&out)
        .values()
        .map(|text| text.lines().count() - 1)
        .collect();
    assert_eq!(rows, [3, 3], "{ours}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// ulog2csv's `-te 0` is no bound (Python's truth test of the option): every row, as
/// without it, in the same files as ulog2csv writes.
#[test]
fn csv_end_of_zero_is_no_bound_as_in_ulog2csv() {
    let dir = temp_dir("end-zero");
    let log = snapshot_log(&dir);
    let l = log.to_str().unwrap();
    let (zero, none, theirs) = (dir.join("zero"), dir.join("none"), dir.join("theirs"));
    stdout(&["csv", l, "-o", zero.to_str().unwrap(), "-te", "0"]);
    stdout(&["csv", l, "-o", none.to_str().unwrap()]);
    assert_eq!(csv_files(&zero), csv_files(&none));
    assert!(csv_files(&zero).values().any(|t| t.lines().count() > 1));
    if ulog2csv_with(&log, &theirs, &["-te", "0"]).is_some() {
        assert_eq!(csv_files(&zero), csv_files(&theirs));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The PX4 `.msg` snapshots beside the corpus.
fn msg_root() -> PathBuf {
    match std::env::var_os("PX4_MSG_DIR") {
        Some(dir) => dir.into(),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/testdata/px4-msg"),
    }
}

#[test]
fn check_msg_says_whether_a_folder_makes_a_logs_formats() {
    let root = msg_root();
    let Some(quad) = fixture("px4-ulog-rs/quadrotor_local.ulg") else {
        return;
    };
    let (same, other) = (
        root.join("392e831c1f659429ca83902e66820d7094591410/msg"),
        root.join("6c5a8e74eb2d173c0decb3feacd7e1932b64095b/msg"),
    );
    if !same.exists() {
        assert!(!under_ci(), "the .msg snapshots are needed");
        return;
    }
    let (q, s, o) = (
        quad.to_str().unwrap(),
        same.to_str().unwrap(),
        other.to_str().unwrap(),
    );
    let out = ulog(&["check-msg", s, q]);
    assert!(out.status.success());
    assert_eq!(
        String::from_utf8(out.stdout).unwrap(),
        "117/117 formats identical\n"
    );
    // An older snapshot: every difference named, exit 1.
    let out = ulog(&["check-msg", o, q]);
    assert_eq!(out.status.code(), Some(1));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.ends_with("73/114 formats identical\n"), "{text}");
    assert!(
        text.contains(
            "vehicle_status: differs from VehicleStatus.msg\n  field `bool avoidance_system_required` \
             is in the .msg, not in the log\n"
        ),
        "{text}"
    );
    assert!(text.contains("  padding differs: uint8_t[6] after `pre_flight_checks_pass` in the log; uint8_t[4] after `pre_flight_checks_pass` in the .msg\n"), "{text}");
    assert_eq!(
        String::from_utf8(out.stderr).unwrap(),
        format!("ulog: {q}: 41 of 114 formats differ\n")
    );
    // A folder that defines none of the log's formats: M = 0 is not a success.
    let dir = temp_dir("checkmsg");
    std::fs::write(dir.join("Other.msg"), "uint64 timestamp\n").unwrap();
    let out = ulog(&["check-msg", dir.to_str().unwrap(), q]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        String::from_utf8(out.stdout).unwrap(),
        "0/0 formats identical\n"
    );
    // The folder is what lacks the formats: the error names it first.
    let d = dir.to_str().unwrap();
    assert_eq!(
        String::from_utf8(out.stderr).unwrap(),
        format!("ulog: {d}: defines none of the formats of {q}\n")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn codegen_from_several_logs_and_msg_folders() {
    let dir = temp_dir("codegen");
    let a = snapshot_log(&dir);
    // A second log where esc_count is wider and esc_status has one field more.
    let b = dir.join("wider.ulg");
    {
        use ulog_runtime::{Writer, WriterOptions};
        let mut w = Writer::create(&b, WriterOptions::default()).unwrap();
        w.format("esc_report:int32_t esc_rpm;float esc_voltage;uint8_t[4] _padding0;")
            .unwrap();
        w.format("esc_status:uint64_t timestamp;uint16_t esc_count;uint8_t[6] _padding0;esc_report[2] esc;char[4] name;float extra;").unwrap();
        let id = w.subscribe("esc_status", 0).unwrap();
        w.data(id, &[0u8; 8 + 8 + 24 + 4 + 4]).unwrap();
        w.flush().unwrap();
    }
    let (a, b) = (a.to_str().unwrap(), b.to_str().unwrap());
    let code = stdout(&["codegen", a, b, "-m", "esc_status"]);
    let expected = ulog_runtime::codegen::Builder::new()
        .ulog_topics(a, &["esc_status"])
        .ulog_topics(b, &["esc_status"])
        .merge(ulog_runtime::codegen::Merge::Lossless)
        .render()
        .unwrap();
    assert_eq!(code, expected);
    assert!(
        code.contains("#[ulog(widen)]\n    pub esc_count: u16,"),
        "{code}"
    );
    assert!(
        code.contains("pub extra: ::core::option::Option<f32>,"),
        "{code}"
    );
    let msg = dir.join("msg");
    std::fs::create_dir_all(&msg).unwrap();
    std::fs::write(
        msg.join("Rover.msg"),
        "uint64 timestamp\nfloat32 speed\n# TOPICS rover rover_backup\n",
    )
    .unwrap();
    let code = stdout(&[
        "codegen",
        "--msg-dir",
        msg.to_str().unwrap(),
        "-m",
        "rover_backup",
    ]);
    assert!(
        code.contains("topics(\"rover\", \"rover_backup\")"),
        "{code}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_closed_output_pipe_is_not_an_error() {
    use std::io::Read;
    // Megabytes of output: far more than a pipe buffers.
    let Some(path) = fixture("pyulog/sample_log_small.ulg") else {
        return;
    };
    let mut child = Command::new(env!("CARGO_BIN_EXE_ulog"))
        .args(["json", path.to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 16];
    child.stdout.take().unwrap().read_exact(&mut first).unwrap(); // then the pipe closes
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn csv_file_names_stay_in_the_folder_and_never_collide_silently() {
    use ulog_runtime::read::Message;
    let long = "x".repeat(300);
    let names = [
        "a/b",
        "a_b",
        "A_B",
        "..",
        "/etc/passwd",
        "name with space",
        long.as_str(),
    ];
    let mut bytes = hand_built(&[]);
    for name in names {
        let format = format!("{name}:uint64_t timestamp;");
        Message::Format(format.as_bytes())
            .encode(&mut bytes)
            .unwrap();
    }
    for (i, name) in names.iter().enumerate() {
        let msg_id = i as u16;
        Message::Subscribe {
            multi_id: 0,
            msg_id,
            name: name.as_bytes(),
        }
        .encode(&mut bytes)
        .unwrap();
        Message::Data {
            msg_id,
            data: &(i as u64).to_le_bytes(),
        }
        .encode(&mut bytes)
        .unwrap();
    }
    let dir = temp_dir("names");
    let log = dir.join("odd.ulg");
    std::fs::write(&log, &bytes).unwrap();
    let out_dir = dir.join("out");
    let out = ulog(&[
        "csv",
        log.to_str().unwrap(),
        "-o",
        out_dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut written: Vec<String> = std::fs::read_dir(&out_dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    written.sort();
    let shortened = written
        .iter()
        .find(|n| n.starts_with("odd_xxx"))
        .unwrap()
        .clone();
    assert_eq!(shortened.len(), 255);
    assert!(shortened.ends_with("_0.csv"), "{shortened}");
    let mut expected = vec![
        "odd_%2E%2E_0.csv".to_owned(),
        "odd_A_B_0~3.csv".to_owned(),
        "odd__etc_passwd_0.csv".to_owned(),
        "odd_a_b_0.csv".to_owned(),
        "odd_a_b_0~2.csv".to_owned(),
        "odd_name%20with%20space_0.csv".to_owned(),
        shortened,
    ];
    expected.sort();
    assert_eq!(written, expected);
    // Nothing outside the output folder, and every row is in its file.
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2);
    for name in &written {
        let text = std::fs::read_to_string(out_dir.join(name)).unwrap();
        assert_eq!(text.lines().count(), 2, "{name}");
    }
    let err = String::from_utf8(out.stderr).unwrap();
    let l = log.display();
    assert!(
        err.contains(&format!(
            "ulog: {l}: topics `a/b` and `a_b` map to one file name; `a_b` #0 goes to "
        )),
        "{err}"
    );
    assert!(
        err.contains("topics `a/b` and `A_B` map to one file name"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn csv_and_json_say_what_they_skip() {
    use ulog_runtime::read::Message;
    let bytes = hand_built(&[
        Message::Format(b"a:uint64_t timestamp;missing_type m;"),
        Message::Subscribe {
            multi_id: 0,
            msg_id: 0,
            name: b"a",
        },
        Message::Subscribe {
            multi_id: 0,
            msg_id: 1,
            name: b"undefined",
        },
        Message::Data {
            msg_id: 0,
            data: &[0; 9],
        },
        Message::Data {
            msg_id: 7,
            data: &[0; 8],
        },
    ]);
    let dir = temp_dir("skips");
    let log = dir.join("unreadable.ulg");
    std::fs::write(&log, &bytes).unwrap();
    let out = ulog(&[
        "csv",
        log.to_str().unwrap(),
        "-o",
        dir.join("out").to_str().unwrap(),
    ]);
    assert!(out.status.success());
    // As ulog2csv says it; no file.
    assert_eq!(
        String::from_utf8(out.stdout).unwrap(),
        format!("Creating output directory {}\n", dir.join("out").display())
    );
    let l = log.display();
    assert_eq!(
        String::from_utf8(out.stderr).unwrap(),
        format!(
            "ulog: {l}: skipped topic `a` (msg_id 0): a.m: type `missing_type` is not a basic type and no format defines it\n\
             ulog: {l}: skipped topic `undefined` (msg_id 1): no format named `undefined`\n\
             ulog: {l}: skipped 1 row of msg_ids no subscription declares\n\
             ulog: {l}: no CSV file written: no topic has rows that can be read\n"
        )
    );
    // `ulog json` says the same of what its rows lack, in both forms, and so does a file
    // cut short in a message (the 10 bytes left of its last 13-byte message are damage).
    let skips = format!(
        "ulog: {l}: skipped topic `a` (msg_id 0): a.m: type `missing_type` is not a basic type and no format defines it\n\
         ulog: {l}: skipped topic `undefined` (msg_id 1): no format named `undefined`\n\
         ulog: {l}: skipped 1 row of msg_ids no subscription declares\n"
    );
    for document in [false, true] {
        let mut args = vec!["json", log.to_str().unwrap()];
        if document {
            args.push("--document");
        }
        let out = ulog(&args);
        assert!(out.status.success());
        // JSON Lines with no line says why (it printed nothing at all before).
        let empty = if document {
            String::new()
        } else {
            format!("ulog: {l}: no row written: no topic has rows that can be read\n")
        };
        assert_eq!(
            String::from_utf8(out.stderr).unwrap(),
            format!("{skips}{empty}"),
            "{args:?}"
        );
    }
    // So does a header-only file, and a topic asked for whose instances have no row.
    let header_only = dir.join("header_only.ulg");
    std::fs::write(&header_only, &bytes[..16]).unwrap();
    let out = ulog(&["json", header_only.to_str().unwrap()]);
    assert!(out.status.success());
    assert!(out.stdout.is_empty());
    assert_eq!(
        String::from_utf8(out.stderr).unwrap(),
        format!(
            "ulog: {}: no row written: no topic has rows that can be read\n",
            header_only.display()
        )
    );
    let out = ulog(&["json", log.to_str().unwrap(), "-m", "a"]);
    assert!(
        String::from_utf8(out.stderr)
            .unwrap()
            .ends_with("no row written: the topics asked for have no rows that can be read\n")
    );
    let out = ulog(&[
        "csv",
        log.to_str().unwrap(),
        "-m",
        "a",
        "-o",
        dir.join("out_a").to_str().unwrap(),
    ]);
    assert!(
        String::from_utf8(out.stderr)
            .unwrap()
            .ends_with("no CSV file written: the topics asked for have no rows that can be read\n")
    );
    let cut = dir.join("cut.ulg");
    std::fs::write(&cut, &bytes[..bytes.len() - 3]).unwrap();
    let out = ulog(&["json", cut.to_str().unwrap()]);
    assert!(out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains(&format!(
            "ulog: {}: 10 damaged bytes skipped",
            cut.display()
        )),
        "{err}"
    );
    // The verbs that mirror a pyulog tool print their output and say the damage on stderr
    // (pyulog prints its `File corruption detected` among the output).
    for verb in [
        &["params"][..],
        &["messages"],
        &["info", "-m", "no_such_multi_info"],
    ] {
        let out = ulog(&[verb, &[cut.to_str().unwrap()][..]].concat());
        assert!(out.status.success(), "{verb:?}");
        assert_eq!(
            String::from_utf8(out.stderr).unwrap(),
            format!(
                "ulog: {}: 10 damaged bytes skipped (`ulog info -v` lists where)\n",
                cut.display()
            ),
            "{verb:?}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn info_lists_a_damaged_definition_in_printable_text() {
    use ulog_runtime::read::Message;
    let bytes = hand_built(&[
        // A type name zeroed in the middle, as a damaged file has it.
        Message::Format(b"t:uint64_t timestamp;f\0\0\0 x;"),
        Message::Subscribe {
            multi_id: 0,
            msg_id: 0,
            name: b"t",
        },
    ]);
    let dir = temp_dir("nul");
    let log = dir.join("nul.ulg");
    std::fs::write(&log, &bytes).unwrap();
    let text = stdout(&["info", "-v", log.to_str().unwrap()]);
    assert!(!text.contains('\0'), "{text:?}");
    let damage = text
        .lines()
        .skip_while(|l| !l.starts_with("Damage:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .collect::<Vec<_>>();
    assert!(
        damage.iter().any(|l| l.contains("f\\u{0}\\u{0}\\u{0}")),
        "{damage:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `info`'s rate column: a rate below 1 Hz to three significant digits (one decimal showed
/// 0.0 Hz below 0.05 Hz), in exponent form below 0.0001 Hz, and `-` for rows that span no
/// time (one row, or two at one time), where 0.0 Hz was shown.
#[test]
fn info_shows_a_sparse_topics_rate_and_none_for_rows_at_one_time() {
    use ulog_runtime::read::Message;
    // Rows at these seconds: 3 rows over 120 s (2 intervals: 1/60 Hz), one row, two rows at
    // one time, 11 rows over 1 s, 3 rows over 16 s (0.125 Hz), and 2 rows 1e9 s apart (a
    // row at time 0 beside a date).
    let topics: [(&str, &[u64]); 6] = [
        ("sparse", &[0, 60, 120]),
        ("once", &[5]),
        ("same", &[7, 7]),
        ("fast", &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10]),
        ("slow", &[0, 8, 16]),
        ("rare", &[0, 1_000_000_000]),
    ];
    let formats: Vec<String> = topics
        .iter()
        .map(|(name, _)| format!("{name}:uint64_t timestamp;"))
        .collect();
    // `fast` in tenths of a second, the others in seconds.
    let rows: Vec<(u16, [u8; 8])> = (0u16..)
        .zip(&topics)
        .flat_map(|(i, (name, times))| {
            let unit = if *name == "fast" { 100_000 } else { 1_000_000 };
            times.iter().map(move |t| (i, (t * unit).to_le_bytes()))
        })
        .collect();
    let mut messages = Vec::new();
    for ((i, (name, _)), format) in (0u16..).zip(&topics).zip(&formats) {
        messages.push(Message::Format(format.as_bytes()));
        messages.push(Message::Subscribe {
            multi_id: 0,
            msg_id: i,
            name: name.as_bytes(),
        });
    }
    messages.extend(rows.iter().map(|(msg_id, data)| Message::Data {
        msg_id: *msg_id,
        data,
    }));
    let bytes = hand_built(&messages);
    let dir = temp_dir("rates");
    let log = dir.join("rates.ulg");
    std::fs::write(&log, &bytes).unwrap();
    let text = stdout(&["info", log.to_str().unwrap()]);
    let cells = |topic: &str| -> Vec<String> {
        let line = text
            .lines()
            .find(|l| l.split_whitespace().next() == Some(topic))
            .unwrap_or_else(|| panic!("no line of `{topic}`:\n{text}"));
        line.split_whitespace().skip(6).map(str::to_owned).collect()
    };
    assert_eq!(cells("sparse"), ["0.0167", "120.0"], "{text}");
    assert_eq!(cells("once"), ["-", "0.0"], "{text}");
    assert_eq!(cells("same"), ["-", "0.0"], "{text}");
    assert_eq!(cells("fast"), ["10.0", "1.0"], "{text}");
    assert_eq!(cells("slow"), ["0.125", "16.0"], "{text}");
    assert_eq!(cells("rare"), ["1.00e-9", "1000000000.0"], "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn info_names_a_version_1_file_without_flag_bits_and_an_absolute_start() {
    use ulog_runtime::read::{FileHeader, Message};
    let mut bytes = FileHeader {
        version: 1,
        start_timestamp: 1_710_773_350_346_000,
    }
    .to_bytes()
    .to_vec();
    Message::Format(b"t:uint64_t timestamp;")
        .encode(&mut bytes)
        .unwrap();
    let dir = temp_dir("noflags");
    let log = dir.join("noflags.ulg");
    std::fs::write(&log, &bytes).unwrap();
    let text = stdout(&["info", log.to_str().unwrap()]);
    assert!(
        text.contains("\nFlag bits:  none: a version-1 file without its flag bits message\n"),
        "{text}"
    );
    assert!(
        // Its date, not 475214:49:10 (hours since 1970) as before.
        text.contains(
            "start 2024-03-18 14:49:10.346000 UTC (1710773350346000 µs, an absolute time),"
        ),
        "{text}"
    );
    // No row: nothing said of where the rows lie.
    assert!(!text.contains("later than every row"), "{text}");
    // A damaged start (past 2100) is no time at all, and a start later than every row says
    // where the rows lie (the duration, pyulog's, is 0 then).
    let mut bytes = FileHeader {
        version: 1,
        start_timestamp: u64::MAX,
    }
    .to_bytes()
    .to_vec();
    let mut put = |m: Message<'_>| m.encode(&mut bytes).unwrap();
    put(Message::Format(b"t:uint64_t timestamp;"));
    put(Message::Subscribe {
        multi_id: 0,
        msg_id: 0,
        name: b"t",
    });
    for t in [2_000_000u64, 5_500_000] {
        put(Message::Data {
            msg_id: 0,
            data: &t.to_le_bytes(),
        });
    }
    std::fs::write(&log, &bytes).unwrap();
    let text = stdout(&["info", log.to_str().unwrap()]);
    assert!(
        text.contains(
            "Logging:    start unknown (18446744073709551615 µs: neither a time since boot nor a \
             date), duration 0:00:00 (0.000 s)\n            the header's start is later than \
             every row: the rows run from 2 s to 5.5 s\n"
        ),
        "{text}"
    );
    // Rows out of time order (a clock stepped back): the rate and duration over their span,
    // earliest to latest (5 rows from 1 s to 5.5 s: 0.889 Hz over 4.5 s), not 0 as when the
    // first and the last row in the file (both at 2 s) were taken for the span.
    for t in [4_000_000u64, 1_000_000, 2_000_000] {
        Message::Data {
            msg_id: 0,
            data: &t.to_le_bytes(),
        }
        .encode(&mut bytes)
        .unwrap();
    }
    std::fs::write(&log, &bytes).unwrap();
    let text = stdout(&["info", log.to_str().unwrap()]);
    let line = text
        .lines()
        .find(|l| l.starts_with(" t "))
        .expect("the topic's line");
    let cells: Vec<&str> = line.split_whitespace().collect();
    assert_eq!(cells[3], "5", "{line}");
    assert_eq!(cells[6..], ["0.889", "4.5"], "{line}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn cut_and_anonymize_write_new_logs_and_say_what_they_changed() {
    let dir = temp_dir("rewrite");
    let log = snapshot_log(&dir);
    let input = std::fs::read(&log).unwrap();
    let out = dir.join("cut.ulg");
    let (l, o) = (log.to_str().unwrap(), out.to_str().unwrap());
    let text = stdout(&[
        "cut",
        l,
        "-o",
        o,
        "--start",
        "3723.3",
        "--end",
        "3723.7",
        "-m",
        "esc_status",
    ]);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], o);
    assert!(
        lines.contains(&"rows: 8 of 22 written, 2 topic instances"),
        "{text}"
    );
    assert!(lines.contains(&"  esc_status #0: 4 of 11 rows"), "{text}");
    assert!(
        lines.contains(
            &"parameter changes: 1 written, 0 moved into the initial parameters, 0 left out"
        ),
        "{text}"
    );
    let cut = ulog_runtime::Log::open(&out).unwrap();
    let times: Vec<u64> = cut.data().map(|r| r.timestamp).collect();
    assert_eq!(times.len(), 8);
    assert!(
        times
            .iter()
            .all(|&t| (3_723_300_000..3_723_700_000).contains(&t))
    );
    assert_eq!(cut.logged_messages().len(), 2, "the strings at 3723.5 s");
    // Never over the input; a topic the log lacks is named with the closest.
    let same = ulog(&["cut", l, "-o", l, "--start", "3723.3"]);
    assert_eq!(same.status.code(), Some(1));
    // The path once (it was printed twice before).
    assert_eq!(
        String::from_utf8_lossy(&same.stderr),
        format!("ulog: {l}: the output is the input file; write the rewritten log elsewhere\n")
    );
    assert_eq!(
        std::fs::read(&log).unwrap(),
        input,
        "the input is untouched"
    );
    let typo = ulog(&["cut", l, "-o", o, "-m", "esc_stat"]);
    assert_eq!(typo.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&typo.stderr).contains("did you mean `esc_status`?"));
    // Anonymize: what it changed, and the same seed the same bytes.
    let anon = dir.join("anon.ulg");
    let a = anon.to_str().unwrap();
    let text = stdout(&["anonymize", l, "-o", a, "--seed", "9"]);
    assert!(
        text.contains("anonymized: no position found (altitudes"),
        "{text}"
    );
    let first = std::fs::read(&anon).unwrap();
    stdout(&["anonymize", l, "-o", a, "--seed", "9"]);
    assert_eq!(std::fs::read(&anon).unwrap(), first);
    let meta = ulog_runtime::Log::open(&anon).unwrap();
    assert!(
        meta.metadata().multi_info().is_empty(),
        "multi info that is not kept by name goes"
    );
    let bad = ulog(&["anonymize", l, "-o", a, "--origin", "91,0"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--origin 91,0: expected LAT,LON"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_window_no_row_can_lie_in_is_refused_and_an_empty_one_is_named() {
    let dir = temp_dir("window");
    let log = snapshot_log(&dir);
    let l = log.to_str().unwrap();
    let o = dir.join("out");
    let o = o.to_str().unwrap();
    let cut = dir.join("cut.ulg");
    let c = cut.to_str().unwrap();
    // Refused before anything is read or written, by every verb that takes a window.
    for (verb, output) in [("csv", o), ("parquet", o), ("cut", c)] {
        for (bounds, says) in [
            (
                &["--start", "nan"][..],
                "the window's start (NaN) is not a finite number",
            ),
            (
                &["--end", "inf"][..],
                "the window's end (inf) is not a finite number",
            ),
            (
                &["--start", "3724", "--end", "3723"][..],
                "the window ends (3723 s) at or before its start (3724 s)",
            ),
        ] {
            let mut args = vec![verb, l, "-o", output];
            args.extend_from_slice(bounds);
            let out = ulog(&args);
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
            assert!(
                err.contains(&format!("--start/--end: {says}")),
                "{args:?}: {err}"
            );
        }
    }
    assert!(!Path::new(o).exists() && !cut.exists(), "nothing written");
    // A window before the log's rows (3723.0 s to 3724.0 s): each verb says so.
    let early = ["--start", "10", "--end", "20", "-m", "esc_status"];
    let window = "no row of the topics asked for lies in the window from 10 s to 20 s";
    let csv = ulog(&[&["csv", l, "-o", o][..], &early[..]].concat());
    let err = String::from_utf8_lossy(&csv.stderr);
    assert!(csv.status.success(), "{err}");
    assert!(
        err.contains(&format!(
            "{window} (their rows run from 3723 s to 3724.000001 s)"
        )),
        "{err}"
    );
    let cut_out = ulog(&[&["cut", l, "-o", c][..], &early[..]].concat());
    let err = String::from_utf8_lossy(&cut_out.stderr);
    assert!(cut_out.status.success(), "{err}");
    // `cut` says it in its report (stdout) and, as `csv` does, on stderr: its report runs to
    // a line per topic instance, where the one line could be missed.
    let text = String::from_utf8_lossy(&cut_out.stdout);
    assert!(
        text.contains(
            "  no row of the topics kept lies in the window from 10 s to 20 s: their rows run \
             from 3723 s to 3724.000001 s\n"
        ),
        "{text}"
    );
    assert!(
        err.contains(&format!(
            "{window} (their rows run from 3723 s to 3724.000001 s)"
        )),
        "{err}"
    );
    // Instances with no row written are counted in one line, not listed one by one.
    assert!(
        text.lines()
            .any(|l| l == "  2 topic instances left out whole (22 rows)"),
        "{text}"
    );
    assert!(!text.contains("0 of 11 rows"), "{text}");
    let pq = ulog(&[&["parquet", l, "-o", o][..], &early[..]].concat());
    let err = String::from_utf8_lossy(&pq.stderr);
    assert!(
        // `-m esc_status`: of the topics asked for.
        err.contains("no Parquet file written: the topics asked for have no rows that can be read in the window from 10 s to 20 s (their rows run from 3723 s to 3724.000001 s)"),
        "{err}"
    );
    assert!(
        err.contains("no log has rows of topic `esc_status` in the window from 10 s to 20 s"),
        "{err}"
    );
    // Negative bounds are numbers, not options.
    let neg = ulog(&["cut", l, "-o", c, "--start", "-1", "--end", "-0.5"]);
    let err = String::from_utf8_lossy(&neg.stderr);
    assert!(neg.status.success(), "{err}");
    let text = String::from_utf8_lossy(&neg.stdout);
    assert!(
        text.contains("no row of the topics kept lies in the window from -1 s to -0.5 s"),
        "{text}"
    );
    // Every topic excluded: no row asked for, so the window is not blamed.
    let none = ulog(&[
        "cut",
        l,
        "-o",
        c,
        "--start",
        "10",
        "--exclude",
        "esc_status",
    ]);
    assert!(none.status.success());
    assert!(
        !String::from_utf8_lossy(&none.stdout).contains("lies in the window"),
        "{none:?}"
    );
    // A topic both kept and excluded is left out, and said (it was silent before); the
    // names of the lists are compared without the spaces around them.
    for kept in ["esc_status", " esc_status ,"] {
        let both = ulog(&["cut", l, "-o", c, "-m", kept, "--exclude", "esc_status"]);
        assert!(both.status.success());
        assert_eq!(
            String::from_utf8_lossy(&both.stderr),
            format!("ulog: {l}: `esc_status` both kept (-m) and excluded (--exclude): left out\n")
        );
        assert_eq!(ulog_runtime::Log::open(c).unwrap().row_count(), 0);
    }
    // A window the rows lie in: no such note.
    let fine = ulog(&["cut", l, "-o", c, "--start", "3723.3", "-m", "esc_status"]);
    assert!(fine.status.success());
    assert!(
        !String::from_utf8_lossy(&fine.stdout).contains("lies in the window"),
        "{fine:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
