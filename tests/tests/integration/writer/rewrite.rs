//! The rewriter on every corpus log: rewritten without rules, message for message; cut and
//! filtered, as pyulog finds the window of the original; anonymized, with no original
//! position or time left in the bytes and every track's distances kept.

use std::path::{Path, PathBuf};
use std::process::Command;

use ulog_runtime::columns::{Admit, Window};
use ulog_runtime::rewrite::{Anonymize, Rewrite};
use ulog_runtime::{Log, StreamReader};
use ulog_tests::{check_file, corpus_files, pyulog_view, short_name, under_ci};

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ulog-rewrite-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs a script of `tests/py`: its JSON summary, or its error text; `None` when pyulog is
/// not installed (a failure under CI).
fn script(name: &str, args: &[&str]) -> Option<Result<serde_json::Value, String>> {
    let has = Command::new("python3")
        .args(["-c", "import pyulog"])
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(has || !under_ci(), "under CI pyulog must be installed");
    if !has {
        return None;
    }
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("py").join(name);
    let out = Command::new("python3")
        .arg(path)
        .args(args)
        .output()
        .unwrap();
    Some(if out.status.success() {
        Ok(serde_json::from_slice(&out.stdout).unwrap())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).into_owned())
    })
}

/// Every message as the framer finds it (type, payload), flag bits aside.
fn messages(bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
    let mut reader = StreamReader::new(bytes).unwrap();
    let mut out = Vec::new();
    while reader.next_event().unwrap().is_some() {
        if let Some(m) = reader.message()
            && m.ty != b'B'
        {
            out.push((m.ty, m.payload.to_vec()));
        }
    }
    out
}

#[test]
fn without_rules_every_corpus_log_keeps_every_message() {
    let (mut same_bytes, mut logs) = (0, 0);
    for path in corpus_files() {
        let input = std::fs::read(&path).unwrap();
        let mut out = Vec::new();
        let report = Rewrite::new().run(&input[..], &mut out).unwrap();
        let name = short_name(&path);
        assert_eq!(
            messages(&out),
            messages(&input),
            "{name}: message for message"
        );
        let (a, b) = (
            Log::from_slice(&input).unwrap(),
            Log::from_slice(&out).unwrap(),
        );
        assert!(b.diagnostics().is_empty(), "{name}: the output is clean");
        assert_eq!(a.row_count(), b.row_count(), "{name}");
        assert_eq!(
            report.skipped.is_empty(),
            a.diagnostics().is_empty(),
            "{name}"
        );
        let appended = a.flag_bits().is_some_and(|f| f.has_data_appended());
        if a.diagnostics().is_empty() && !appended && a.header().version == 1 {
            assert!(out == input, "{name}: a clean log comes out byte for byte");
            same_bytes += 1;
        }
        logs += 1;
    }
    eprintln!("{logs} logs rewritten message for message, {same_bytes} of them byte for byte");
}

/// The rows of each topic instance of the window, as the rewriter must keep them.
fn window_rows(
    log: &Log<'_>,
    window: Window,
    kept: impl Fn(&str) -> bool,
) -> Vec<(String, u8, Vec<Vec<u8>>)> {
    let mut out = Vec::new();
    for t in log.topics() {
        if !kept(&t.name) {
            continue;
        }
        let subs: Vec<_> = log
            .subscriptions()
            .iter()
            .filter(|s| s.name == t.name && s.multi_id == t.multi_id)
            .collect();
        let mut rows = Vec::new();
        let mut started = false;
        for row in log.instance_rows(&subs) {
            match window.admit(row.timestamp, started) {
                Admit::Skip => {}
                Admit::Stop => break,
                Admit::Take => {
                    started = true;
                    rows.push(row.data.to_vec());
                }
            }
        }
        if !rows.is_empty() {
            out.push((t.name.clone(), t.multi_id, rows));
        }
    }
    out.sort();
    out
}

#[test]
fn every_corpus_log_cut_and_filtered_holds_exactly_the_window() {
    let dir = temp("cut");
    let mut checked = 0;
    for path in corpus_files() {
        let name = short_name(&path);
        let log = Log::open(&path).unwrap();
        let times: Vec<u64> = log.data().map(|r| r.timestamp).collect();
        let (Some(&first), Some(&last)) = (times.iter().min(), times.iter().max()) else {
            continue;
        };
        let span = (last - first) as f64;
        let window = Window {
            start_us: Some(first as f64 + 0.3 * span),
            end_us: Some(first as f64 + 0.7 * span),
        };
        // The topic with most rows left out; then only three topics kept.
        let mut topics = log.topics();
        topics.sort_by_key(|t| std::cmp::Reverse(t.rows));
        let biggest = topics[0].name.clone();
        let few: Vec<String> = topics
            .iter()
            .skip(1)
            .take(3)
            .map(|t| t.name.clone())
            .collect();
        let damaged = !log.diagnostics().is_empty();
        for (k, (keep, exclude)) in [(vec![], vec![biggest.clone()]), (few.clone(), vec![])]
            .into_iter()
            .enumerate()
        {
            let out = dir.join(format!("{}_{k}.ulg", name.replace('/', "_")));
            let report = Rewrite::new()
                .window(window)
                .topics(&keep)
                .exclude(&exclude)
                .run_file(&path, &out)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            let cut = Log::open(&out).unwrap();
            assert!(
                cut.diagnostics().is_empty(),
                "{name}: {:?}",
                cut.diagnostics()
            );
            let kept = |t: &str| {
                (keep.is_empty() || keep.iter().any(|x| x == t)) && !exclude.contains(&t.to_owned())
            };
            // Every kept row of the window, byte for byte; nothing else.
            assert_eq!(
                window_rows(&cut, Window::default(), |_| true),
                window_rows(&log, window, kept),
                "{name} #{k}: the rows of the window"
            );
            assert_eq!(report.skipped.is_empty(), !damaged, "{name}");
            // pyulog reads the cut as this reader does.
            if let Some(o) = pyulog_view(&out) {
                let diffs = check_file(&out, &o);
                assert!(diffs.is_empty(), "{name} #{k}: {diffs:?}");
            }
            // pyulog on the original and on the cut (damaged logs: pyulog cannot see all of
            // what this reader recovers, so only the cut itself is compared above).
            if !damaged {
                let us =
                    |x: Option<f64>| x.map_or("-".to_owned(), |v| format!("{}", v.ceil() as u64));
                let list = |v: &[String]| {
                    if v.is_empty() {
                        "-".to_owned()
                    } else {
                        v.join(",")
                    }
                };
                let args = [
                    path.to_str().unwrap(),
                    out.to_str().unwrap(),
                    &us(window.start_us),
                    &us(window.end_us),
                    &list(&keep),
                    &list(&exclude),
                ];
                if let Some(result) = script("cut_check.py", &args) {
                    result.unwrap_or_else(|e| panic!("{name} #{k}: {e}"));
                }
            }
            std::fs::remove_file(&out).unwrap();
            checked += 1;
        }
    }
    assert!(checked > 0 || !under_ci());
    eprintln!("{checked} cuts checked");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn anonymized_corpus_logs_keep_no_original_position_or_time() {
    let dir = temp("anon");
    let mut checked = 0;
    for (k, path) in corpus_files().into_iter().enumerate() {
        let name = short_name(&path);
        let out = dir.join(format!("{}.ulg", name.replace('/', "_")));
        let report = Rewrite::new()
            .anonymize(Anonymize::seed(k as u64 + 1))
            .run_file(&path, &out)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let a = report.anonymized.unwrap();
        let back = Log::open(&out).unwrap();
        assert!(back.diagnostics().is_empty(), "{name}");
        if let Some(o) = pyulog_view(&out) {
            let diffs = check_file(&out, &o);
            assert!(diffs.is_empty(), "{name}: {diffs:?}");
        }
        // The track of `ulog kml` has as many points as the original's.
        let original = Log::open(&path).unwrap();
        let options = ulog_runtime::tools::KmlOptions::default();
        // The coordinate tuples of every `<coordinates>` element.
        let points = |log: &Log<'_>| {
            ulog_runtime::tools::kml(log, &options).ok().map(|k| {
                k.split("<coordinates>")
                    .skip(1)
                    .map(|c| {
                        c.split("</coordinates>")
                            .next()
                            .unwrap_or("")
                            .split_whitespace()
                            .count()
                    })
                    .sum::<usize>()
            })
        };
        assert_eq!(points(&original), points(&back), "{name}: kml track points");
        if !original.diagnostics().is_empty() {
            // pyulog cannot see all of a damaged original: the checks below need its view.
            continue;
        }
        if let Some(result) = script(
            "anon_check.py",
            &[path.to_str().unwrap(), out.to_str().unwrap()],
        ) {
            let summary = result.unwrap_or_else(|e| panic!("{name}: {e}"));
            eprintln!("{name}: {summary} {:?}", a.target);
        }
        checked += 1;
    }
    assert!(checked > 0 || !under_ci());
    std::fs::remove_dir_all(&dir).unwrap();
}
