//! `ulog analyze --json` on every corpus log against the same statistics computed from
//! pyulog's arrays with numpy (`tests/py/analysis_check.py`): field statistics, motion,
//! battery, GPS quality, vibration and flight modes; and no diagnostic where the rules say
//! there can be none (outside armed time), none at all on the corpus's known flights.

use std::path::Path;
use std::process::Command;

use super::corpus::{corpus_files, short_name, under_ci};
use super::{stdout, temp_dir, ulog};

/// The corpus logs known to be flights without a fault (or no flight at all).
const CLEAN: [&str; 14] = [
    "yule_log/trig_stats.ulg",
    "yule_log/powers.ulg",
    "yule_log/short_list.ulg",
    "pyulog/sample_log_small.ulg",
    "pyulog/sample_2016.ulg",
    "pyulog/sample_unordered.ulg",
    "pyulog/sample_px4_events.ulg",
    "pyulog/sample.ulg",
    "pyulog/sample_appended_multiple.ulg",
    "px4-ulog-rs/quadrotor_local.ulg",
    "px4-ulog-rs/corrupt_unregistered_msg_id.ulg",
    "px4-ulog-rs/6ba1abc7-b433-4029-b8f5-3b2bb12d3b6c.ulg",
    "px4-ulog-rs/corrupt_actuator_armed_wrong_size.ulg",
    "px4-ulog-rs/corrupt_format_not_utf8.ulg",
];

fn numpy_and_pyulog() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import numpy, pyulog"])
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(
        ok || !under_ci(),
        "under CI python3 must have numpy and pyulog (.ci/run installs them)"
    );
    if !ok {
        eprintln!("python3 lacks numpy or pyulog: the analysis is not compared");
    }
    ok
}

#[test]
fn the_analysis_of_every_corpus_log_equals_numpy_on_pyulogs_arrays() {
    let dir = temp_dir("analyze");
    let compare = numpy_and_pyulog();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/py/analysis_check.py");
    let mut compared = 0u64;
    for log in corpus_files() {
        let name = short_name(&log);
        let json = stdout(&["analyze", "--json", log.to_str().unwrap()]);
        let analysis: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert_eq!(analysis["log"], log.to_str().unwrap(), "{name}: which log");
        // Every rule is about armed (or flying) time.
        let armed: Vec<(u64, u64)> = analysis["armed"]
            .as_array()
            .unwrap()
            .iter()
            .map(|i| {
                (
                    i["start_us"].as_u64().unwrap(),
                    i["end_us"].as_u64().unwrap(),
                )
            })
            .collect();
        for d in analysis["diagnostics"].as_array().unwrap() {
            let t = d["timestamp_us"].as_u64().unwrap();
            assert!(
                armed.iter().any(|(a, b)| (*a..=*b).contains(&t)),
                "{name}: a diagnostic outside armed time: {d}"
            );
        }
        if CLEAN.contains(&name.as_str()) {
            assert_eq!(
                analysis["diagnostics"].as_array().unwrap().len(),
                0,
                "{name}: a clean flight: {}",
                analysis["diagnostics"]
            );
        }
        if !compare {
            continue;
        }
        let path = dir.join("analysis.json");
        std::fs::write(&path, &json).unwrap();
        let out = Command::new("python3")
            .arg(&script)
            .arg(&log)
            .arg(&path)
            .output()
            .expect("python3 runs");
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(
            summary["mismatches"].as_array().unwrap().len(),
            0,
            "{name}: {}",
            summary["mismatches"]
        );
        let n = summary["compared"].as_u64().unwrap();
        assert!(n > 0, "{name}: nothing compared");
        compared += n;
    }
    eprintln!("{compared} facts compared with numpy");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn json_lines_name_their_logs_in_the_order_given() {
    // (An empty corpus fails under CI in `corpus_files`.)
    let logs: Vec<_> = corpus_files().into_iter().take(3).collect();
    if logs.len() < 2 {
        return;
    }
    let mut args = vec!["analyze", "--json"];
    args.extend(logs.iter().rev().map(|l| l.to_str().unwrap()));
    let out = stdout(&args);
    let named: Vec<String> = out
        .lines()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            assert!(v["flight_modes"].is_array(), "an analysis follows: {l}");
            v["log"].as_str().unwrap().to_owned()
        })
        .collect();
    let given: Vec<String> = logs
        .iter()
        .rev()
        .map(|l| l.to_str().unwrap().to_owned())
        .collect();
    assert_eq!(named, given);
}

#[test]
fn a_log_that_cannot_be_read_does_not_stop_the_analysis_of_the_others() {
    // (An empty corpus fails under CI in `corpus_files`.)
    let logs: Vec<_> = corpus_files().into_iter().take(2).collect();
    if logs.len() < 2 {
        return;
    }
    let dir = temp_dir("analyze-bad");
    std::fs::create_dir_all(&dir).unwrap();
    let empty = dir.join("empty.ulg");
    std::fs::write(&empty, b"").unwrap();
    let missing = dir.join("missing.ulg");
    let args = [
        "analyze",
        "--json",
        logs[0].to_str().unwrap(),
        missing.to_str().unwrap(),
        empty.to_str().unwrap(),
        logs[1].to_str().unwrap(),
    ];
    let out = ulog(&args);
    assert_eq!(out.status.code(), Some(1), "a failed log fails the run");
    let named: Vec<String> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            v["log"].as_str().unwrap().to_owned()
        })
        .collect();
    assert_eq!(named, [args[2], args[5]], "every readable log, in order");
    let err = String::from_utf8(out.stderr).unwrap();
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 3, "{err}");
    assert!(
        lines[0].starts_with(&format!("ulog: {}: ", args[3])),
        "{err}"
    );
    assert!(
        lines[1].starts_with(&format!("ulog: {}: ", args[4])),
        "{err}"
    );
    assert_eq!(lines[2], "ulog: 2 of 4 logs not analysed");
    // The text summaries of the readable logs, one blank line between them.
    let text_args: Vec<&str> = args.iter().copied().filter(|a| *a != "--json").collect();
    let text = String::from_utf8(ulog(&text_args).stdout).unwrap();
    let starts: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| *l == args[2] || *l == args[5])
        .map(|(i, _)| i)
        .collect();
    assert_eq!(starts.len(), 2, "{text}");
    assert_eq!(starts[0], 0, "{text}");
    assert_eq!(text.lines().nth(starts[1] - 1), Some(""), "{text}");
    assert_eq!(text.lines().filter(|l| l.is_empty()).count(), 1, "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}
