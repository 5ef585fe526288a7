//! `ulog parquet` against pyulog and independent Parquet readers: every corpus log's files
//! read back by pyarrow equal pyulog's columns, a hive-layout fleet answers DuckDB queries
//! as pyulog does, and the options, failures and damaged logs behave as documented.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use super::corpus::{corpus_files, pyulog_blind_ranges, short_name, under_ci};
use super::{stdout, temp_dir, ulog};

/// Whether python3 can import these modules (required under CI, where `.ci/run` installs
/// them).
fn python_has(modules: &str) -> bool {
    let ok = Command::new("python3")
        .args(["-c", &format!("import {modules}")])
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(
        ok || !under_ci(),
        "under CI python3 must have {modules} (.ci/run installs them)"
    );
    if !ok {
        eprintln!("python3 lacks {modules}: nothing to compare with");
    }
    ok
}

/// Runs a script of `tests/py`; its JSON summary, or its error text.
fn script(name: &str, args: &[&Path]) -> Result<serde_json::Value, String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/py")
        .join(name);
    let out = Command::new("python3")
        .arg(path)
        .args(args)
        .output()
        .expect("python3 runs");
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).into_owned());
    }
    serde_json::from_slice(&out.stdout).map_err(|e| format!("summary: {e}"))
}

/// Per topic instance, the indices (in file order) of our rows pyulog cannot see.
fn hidden_rows(path: &Path) -> BTreeMap<String, Vec<usize>> {
    let log = ulog_runtime::Log::open(path).unwrap();
    let blind = pyulog_blind_ranges(&log);
    let mut out = BTreeMap::new();
    if blind.is_empty() {
        return out;
    }
    for t in log.topics() {
        let mut offsets: Vec<u64> = log
            .subscriptions()
            .iter()
            .filter(|s| s.name == t.name && s.multi_id == t.multi_id)
            .flat_map(|s| log.rows(s).map(|r| r.offset))
            .collect();
        offsets.sort_unstable();
        let hidden: Vec<usize> = offsets
            .iter()
            .enumerate()
            .filter(|(_, o)| blind.iter().any(|b| b.contains(o)))
            .map(|(i, _)| i)
            .collect();
        if !hidden.is_empty() {
            out.insert(format!("{}/{}", t.name, t.multi_id), hidden);
        }
    }
    out
}

#[test]
fn parquet_equals_pyulog_on_every_corpus_file() {
    if !python_has("pyarrow, pyulog, numpy") {
        return;
    }
    let out = temp_dir("parquet");
    let (mut logs, mut files, mut rows, mut cells) = (0, 0, 0, 0);
    let mut failures = Vec::new();
    for path in corpus_files() {
        let name = short_name(&path);
        let dir = out.join(logs.to_string());
        let run = ulog(&[
            "parquet",
            path.to_str().unwrap(),
            "-o",
            dir.to_str().unwrap(),
        ]);
        if !run.status.success() {
            failures.push(format!(
                "{name}: ulog parquet failed: {}",
                String::from_utf8_lossy(&run.stderr)
            ));
            continue;
        }
        let hidden = dir.join("hidden.json");
        std::fs::write(&hidden, serde_json::to_vec(&hidden_rows(&path)).unwrap()).unwrap();
        let folder = dir.join(ulog_runtime::file_names::log_stem(&path));
        match script("parquet_check.py", &[&path, &folder, &hidden]) {
            Ok(summary) => {
                files += summary["files"].as_u64().unwrap();
                rows += summary["rows"].as_u64().unwrap();
                cells += summary["cells"].as_u64().unwrap();
            }
            Err(e) => failures.push(format!("{name}: {e}")),
        }
        logs += 1;
        std::fs::remove_dir_all(&dir).unwrap();
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    eprintln!(
        "{logs} logs, {files} Parquet files, {rows} rows, {cells} cells equal to pyulog's \
         (read by pyarrow); key-value metadata and metadata.json checked"
    );
    std::fs::remove_dir_all(&out).unwrap();
}

/// Corpus logs with distinct stems, PX4 ones with vehicle_attitude (the fleet query's topic).
fn fleet() -> Vec<PathBuf> {
    let mut seen = std::collections::HashSet::new();
    corpus_files()
        .into_iter()
        .filter(|p| {
            let Ok(log) = ulog_runtime::Log::open(p) else {
                return false;
            };
            log.diagnostics().iter().all(|d| !d.is_corruption())
                && log.topics().iter().any(|t| t.name == "vehicle_attitude")
                && seen.insert(ulog_runtime::file_names::log_stem(p).to_lowercase())
        })
        .collect()
}

#[test]
fn a_fleet_in_hive_layout_is_one_duckdb_table_per_topic() {
    if !python_has("duckdb, pyulog, numpy") {
        return;
    }
    let logs = fleet();
    assert!(logs.len() >= 2 || !under_ci(), "the corpus has PX4 logs");
    if logs.len() < 2 {
        return;
    }
    let dir = temp_dir("fleet");
    let mut args = vec!["parquet", "--layout", "hive", "-o", dir.to_str().unwrap()];
    args.extend(logs.iter().map(|p| p.to_str().unwrap()));
    stdout(&args);
    // The layout: a folder per topic, log and instance, and a metadata.json per log.
    let stem = ulog_runtime::file_names::log_stem(&logs[0]);
    assert!(
        dir.join("topic=vehicle_attitude")
            .join(format!("log={stem}"))
            .join("multi_id=0/data.parquet")
            .is_file()
    );
    assert!(
        dir.join("metadata")
            .join(format!("log={stem}"))
            .join("metadata.json")
            .is_file()
    );
    let mut script_args: Vec<&Path> = vec![&dir];
    script_args.extend(logs.iter().map(PathBuf::as_path));
    let summary = script("fleet_check.py", &script_args).unwrap_or_else(|e| panic!("{e}"));
    eprintln!("fleet of {} logs, duckdb vs pyulog: {summary}", logs.len());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A log made by the writer: two topics, one with two instances, over 10 s.
fn small_log(dir: &Path) -> PathBuf {
    small_log_of(dir, "small.ulg", 10)
}

/// [`small_log`] over `seconds`, written to `dir/name`.
fn small_log_of(dir: &Path, name: &str, seconds: u64) -> PathBuf {
    use ulog_runtime::{ULog, Writer, WriterOptions};
    #[derive(ULog)]
    struct Battery {
        timestamp: u64,
        voltage_v: f32,
    }
    #[derive(ULog)]
    struct Gps {
        timestamp: u64,
        alt: f64,
    }
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let battery = w.topic::<Battery>(0).unwrap();
    let battery1 = w.topic::<Battery>(1).unwrap();
    let gps = w.topic::<Gps>(0).unwrap();
    for s in 0..seconds {
        let t = s * 1_000_000;
        w.write(
            &battery,
            &Battery {
                timestamp: t,
                voltage_v: s as f32,
            },
        )
        .unwrap();
        w.write(
            &battery1,
            &Battery {
                timestamp: t,
                voltage_v: -(s as f32),
            },
        )
        .unwrap();
        w.write(
            &gps,
            &Gps {
                timestamp: t + 1,
                alt: 100.0 + s as f64,
            },
        )
        .unwrap();
    }
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, w.into_inner()).unwrap();
    path
}

/// The logs of `out` with a metadata.json (written last of a log's files).
#[cfg(unix)]
fn converted(out: &Path) -> Vec<String> {
    let Ok(dirs) = std::fs::read_dir(out) else {
        return Vec::new();
    };
    let mut done: Vec<String> = dirs
        .flatten()
        .filter(|d| d.path().join("metadata.json").is_file())
        .map(|d| d.file_name().to_string_lossy().into_owned())
        .collect();
    done.sort();
    done
}

/// A log of `rows` rows of one topic ([`hand_built`](super::hand_built)): 70 MB for 2.4 M
/// rows, whose conversion lasts long enough for signals 20 ms apart to arrive while it is
/// under way (`ulog parquet -j 1` of it on the 2-core machine this was written on: 0.26 s
/// optimized, its folder made at 0.06 s; 3.3 s in a debug build, its folder at 0.8 s).
#[cfg(unix)]
fn long_log(path: &Path, rows: u64) {
    use ulog_runtime::read::Message;
    let mut bytes = super::hand_built(&[
        Message::Format(b"t:uint64_t timestamp;float x;float y;double z;"),
        Message::Subscribe {
            multi_id: 0,
            msg_id: 0,
            name: b"t",
        },
    ]);
    let mut row = Vec::with_capacity(24);
    for i in 0..rows {
        row.clear();
        row.extend((1000 + i).to_le_bytes());
        row.extend((i as f32).to_le_bytes());
        row.extend((-(i as f32)).to_le_bytes());
        row.extend((i as f64 / 4.0).to_le_bytes());
        Message::Data {
            msg_id: 0,
            data: &row,
        }
        .encode(&mut bytes)
        .unwrap();
    }
    std::fs::write(path, bytes).unwrap();
}

/// `ulog parquet -j 1` of `logs` into `out`, sent `signals` SIGINTs (20 ms apart) once the
/// second log's folder is made (the first converted, the second under way: a signal between
/// the two would leave the second not started): its exit code, stdout and stderr.
#[cfg(unix)]
fn interrupted(logs: &[PathBuf], out: &Path, signals: usize) -> (Option<i32>, String, String) {
    let _ = std::fs::remove_dir_all(out);
    let mut child = Command::new(env!("CARGO_BIN_EXE_ulog"))
        .arg("parquet")
        .args(logs)
        .args(["-j", "1", "-o"])
        .arg(out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let second = out.join(logs[1].file_stem().unwrap());
    while !second.exists() && child.try_wait().unwrap().is_none() {
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    for k in 0..signals {
        if k > 0 {
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let kill = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status()
            .unwrap();
        assert!(kill.success());
    }
    let run = child.wait_with_output().unwrap();
    (
        run.status.code(),
        String::from_utf8_lossy(&run.stdout).into_owned(),
        String::from_utf8_lossy(&run.stderr).into_owned(),
    )
}

#[cfg(unix)]
#[test]
fn ctrl_c_stops_after_the_logs_under_way_and_twice_at_once() {
    let dir = temp_dir("parquet-ctrl-c");
    let n = 50;
    // The first log small, the second long (the one under way when the signals come), the
    // rest small; one at a time.
    let small = small_log_of(&dir.join("logs"), "log00.ulg", 10);
    let logs: Vec<PathBuf> = (0..n)
        .map(|i| {
            let p = dir.join(format!("logs/log{i:02}.ulg"));
            match i {
                0 => {}
                1 => long_log(&p, 2_400_000),
                _ => {
                    std::fs::copy(&small, &p).unwrap();
                }
            }
            p
        })
        .collect();
    let out = dir.join("out");

    // Once: the long log is finished, whole; no log is started after it.
    let (code, stdout, stderr) = interrupted(&logs, &out, 1);
    assert_eq!(code, Some(130), "{stderr}");
    assert_eq!(converted(&out), ["log00", "log01"]);
    assert!(
        stderr.contains(&format!(
            "stopped (signal 2): {} of {n} logs not converted",
            n - 2
        )),
        "{stderr}"
    );
    assert_eq!(
        stdout.lines().count(),
        2,
        "each converted log listed: {stdout}"
    );
    let mut files: Vec<String> = std::fs::read_dir(out.join("log01"))
        .unwrap()
        .flatten()
        .map(|f| f.file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    assert_eq!(
        files,
        ["metadata.json", "t_0.parquet"],
        "nothing half-written"
    );
    let folders = std::fs::read_dir(&out).unwrap().count();
    assert_eq!(folders, 2, "no folder of a log not converted");

    // Twice: the second ends it at once, in the long log (no summary: the tool was ended).
    let (code, _, stderr) = interrupted(&logs, &out, 2);
    assert_eq!(code, Some(130), "{stderr}");
    assert_eq!(converted(&out), ["log00"]);
    assert!(!stderr.contains("stopped"), "{stderr}");

    // Once, with every log started already: the one under way is finished, and the tool
    // still says it was stopped (none left unconverted).
    let (code, _, stderr) = interrupted(&logs[..2], &out, 1);
    assert_eq!(code, Some(130), "{stderr}");
    assert_eq!(converted(&out), ["log00", "log01"]);
    assert!(
        stderr.contains("stopped (signal 2): 0 of 2 logs not converted"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn two_logs_of_one_stem_converted_in_two_runs_keep_both() {
    use sha2::Digest;
    let dir = temp_dir("parquet-same-stem");
    let a = small_log_of(&dir.join("a"), "test.ulg", 4);
    let b = small_log_of(&dir.join("b"), "test.ulg", 7);
    let sha = |p: &Path| {
        let d = sha2::Sha256::digest(std::fs::read(p).unwrap());
        d.iter().map(|x| format!("{x:02x}")).collect::<String>()
    };
    let fleet = dir.join("fleet");
    // What each log folder holds: the digest its metadata.json names, and the battery
    // rows of its file.
    let held = |log_dir: &str| -> (String, u64) {
        let meta: serde_json::Value = serde_json::from_slice(
            &std::fs::read(fleet.join("metadata").join(log_dir).join("metadata.json")).unwrap(),
        )
        .unwrap();
        let file = meta["files"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["topic"] == "battery" && f["multi_id"] == 0)
            .unwrap();
        assert!(fleet.join(file["path"].as_str().unwrap()).is_file());
        (
            meta["log"]["sha256"].as_str().unwrap().to_owned(),
            file["rows"].as_u64().unwrap(),
        )
    };
    let run = |logs: &[&Path]| -> String {
        let mut args = vec!["parquet"];
        args.extend(logs.iter().map(|p| p.to_str().unwrap()));
        args.extend(["-o", fleet.to_str().unwrap(), "--layout", "hive"]);
        let out = ulog(&args);
        assert!(out.status.success(), "{out:?}");
        String::from_utf8(out.stderr).unwrap()
    };
    let first = run(&[&a, &b]);
    assert!(
        first.contains(&format!("{}: `log=test` holds another log", b.display()))
            && first.contains("`log=test~2`"),
        "the second log's new name is said: {first}"
    );
    // b again: its own folder is replaced, and it is said where that is.
    let second = run(&[&b]);
    assert!(second.contains("goes to `log=test~2`"), "{second}");
    assert_eq!(
        held("log=test"),
        (sha(&a), 4),
        "the first log's partition is kept"
    );
    assert_eq!(held("log=test~2"), (sha(&b), 7));
    // A third, different log of that stem takes the next free name.
    let c = small_log_of(&dir.join("c"), "test.ulg", 2);
    let third = run(&[&c]);
    assert!(third.contains("`log=test~3`"), "{third}");
    assert_eq!(held("log=test"), (sha(&a), 4));
    assert_eq!(held("log=test~2"), (sha(&b), 7));
    assert_eq!(held("log=test~3"), (sha(&c), 2));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn parquet_options_select_topics_and_time_and_say_what_they_wrote() {
    let dir = temp_dir("parquet-options");
    let log = small_log(&dir);
    let out = dir.join("out");
    let text = stdout(&[
        "parquet",
        log.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-m",
        "battery",
        "--start",
        "2",
        "--end",
        "5",
    ]);
    let folder = out.join("small");
    assert_eq!(
        text,
        format!(
            "{}: 2 files, 6 rows, {}\n",
            log.display(),
            folder.join("metadata.json").display()
        )
    );
    let mut names: Vec<String> = std::fs::read_dir(&folder)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["battery_0.parquet", "battery_1.parquet", "metadata.json"]
    );
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(folder.join("metadata.json")).unwrap()).unwrap();
    // The files list what was written; the topics describe the whole log.
    let files: Vec<(String, u64)> = meta["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            (
                f["path"].as_str().unwrap().to_owned(),
                f["rows"].as_u64().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        files,
        [
            ("small/battery_0.parquet".to_owned(), 3),
            ("small/battery_1.parquet".to_owned(), 3)
        ]
    );
    let topics: Vec<(&str, u64, u64)> = meta["topics"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| {
            (
                t["topic"].as_str().unwrap(),
                t["multi_id"].as_u64().unwrap(),
                t["rows"].as_u64().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        topics,
        [("battery", 0, 10), ("battery", 1, 10), ("gps", 0, 10)]
    );
    // The analysis is of the whole log, not of what the options kept: here the mean of
    // battery #1's voltage over its 10 rows (0, -1, ... -9), and gps's altitude.
    let stats: Vec<(&str, u64, &str, f64)> = meta["analysis"]["field_stats"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            (
                f["topic"].as_str().unwrap(),
                f["multi_id"].as_u64().unwrap(),
                f["field"].as_str().unwrap(),
                f["mean"].as_f64().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        stats,
        [
            ("battery", 0, "voltage_v", 4.5),
            ("battery", 1, "voltage_v", -4.5),
            ("gps", 0, "alt", 104.5)
        ]
    );
    let bare = dir.join("bare");
    stdout(&[
        "parquet",
        log.to_str().unwrap(),
        "-o",
        bare.to_str().unwrap(),
        "--no-analysis",
    ]);
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(bare.join("small/metadata.json")).unwrap()).unwrap();
    assert!(
        meta.get("analysis").is_none(),
        "--no-analysis leaves it out"
    );
    // A topic the log lacks is an error before anything is written, naming the closest.
    let fresh = dir.join("fresh");
    let only = |logs: &[&str], topic: &str| {
        let mut args = vec!["parquet"];
        args.extend(logs);
        args.extend(["-o", fresh.to_str().unwrap(), "-m", topic]);
        ulog(&args)
    };
    let run = only(&[log.to_str().unwrap()], "batery");
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("small.ulg: no topic `batery` in this log; did you mean `battery`?"),
        "{err}"
    );
    assert!(!fresh.exists(), "nothing is written");
    // Among several logs, one lacking a topic is said and the others convert; a topic no
    // log has is an error.
    let other = dir.join("only_battery.ulg");
    let mut w = ulog_runtime::Writer::new(Vec::new(), Default::default()).unwrap();
    w.format("battery:uint64_t timestamp;float voltage_v;")
        .unwrap();
    let id = w.subscribe("battery", 0).unwrap();
    w.data(id, &[5, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x48, 0x41])
        .unwrap();
    std::fs::write(&other, w.into_inner()).unwrap();
    let both = [log.to_str().unwrap(), other.to_str().unwrap()];
    let run = only(&both, "gps");
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{err}");
    assert!(
        err.contains("only_battery.ulg: no topic `gps` in this log"),
        "{err}"
    );
    assert!(!err.contains("small.ulg: no topic"), "{err}");
    assert!(fresh.join("small/gps_0.parquet").exists());
    // A topic the logs define but none has rows of (here: in the window) is said too.
    let run = ulog(&[
        "parquet",
        both[0],
        "-o",
        fresh.to_str().unwrap(),
        "-m",
        "gps",
        "--start",
        "100",
    ]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{err}");
    assert!(err.contains("no log has rows of topic `gps`"), "{err}");
    let run = only(&both, "gsp");
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("no topic `gsp` in any of the logs; did you mean `gps`?"),
        "{err}"
    );
    // One file, and one row, are said in the singular (gps's row at 0 s is its only one
    // before 0.5 s).
    let one = dir.join("one");
    for (window, says) in [
        (&[][..], "1 file, 10 rows"),
        (&["--end", "0.5"][..], "1 file, 1 row"),
    ] {
        let args = [
            &[
                "parquet",
                log.to_str().unwrap(),
                "-o",
                one.to_str().unwrap(),
            ][..],
            &["-m", "gps"],
            window,
        ]
        .concat();
        assert_eq!(
            stdout(&args),
            format!(
                "{}: {says}, {}\n",
                log.display(),
                one.join("small").join("metadata.json").display()
            )
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_log_that_cannot_be_read_is_reported_and_the_others_converted() {
    let dir = temp_dir("parquet-failures");
    let good = small_log(&dir);
    let bad = dir.join("notes.ulg");
    std::fs::write(&bad, b"these are not the bytes of a log").unwrap();
    let missing = dir.join("missing.ulg");
    let out = dir.join("out");
    let run = ulog(&[
        "parquet",
        bad.to_str().unwrap(),
        good.to_str().unwrap(),
        missing.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains(&format!("ulog: {}: not a ULog file", bad.display())),
        "{err}"
    );
    assert!(
        err.contains(&format!("ulog: {}: no such file\n", missing.display())),
        "{err}"
    );
    assert!(err.contains("ulog: 2 of 3 logs not converted"), "{err}");
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(
        text.starts_with(&format!("{}: 3 files, 30 rows", good.display())),
        "{text}"
    );
    assert!(out.join("small/gps_0.parquet").is_file());
    assert!(
        !out.join("notes").exists(),
        "nothing written for a log that cannot be read"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_damaged_log_converts_what_is_intact_and_says_what_was_skipped() {
    let dir = temp_dir("parquet-damaged");
    let log = small_log(&dir);
    let mut bytes = std::fs::read(&log).unwrap();
    // 40 bytes of garbage between two data messages: every row is intact.
    let at = ulog_runtime::Log::open(&log)
        .unwrap()
        .data()
        .nth(15)
        .unwrap()
        .offset as usize;
    bytes.splice(at..at, [0xAB; 40]);
    let damaged = dir.join("damaged.ulg");
    std::fs::write(&damaged, &bytes).unwrap();
    let out = dir.join("out");
    let run = ulog(&[
        "parquet",
        damaged.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("40 damaged bytes skipped"), "{err}");
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("damaged/metadata.json")).unwrap()).unwrap();
    assert_eq!(meta["skipped"]["damaged_bytes"], 40, "{meta}");
    assert!(
        meta["diagnostics"][0]
            .as_str()
            .unwrap()
            .contains(&at.to_string())
    );
    let written: Vec<u64> = meta["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["rows"].as_u64().unwrap())
        .collect();
    assert_eq!(written, [10, 10, 10], "all 30 rows the writer wrote");
    std::fs::remove_dir_all(&dir).unwrap();
}
