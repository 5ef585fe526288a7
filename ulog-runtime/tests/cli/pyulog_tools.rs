//! The `ulog` verbs against pyulog 1.3.0's tools run live, byte for byte: `ulog_messages`
//! (PX4 events included), `ulog_params` in each format, `ulog_info -m`, `ulog2kml`,
//! `ulog_extract_gps_dump`.

use std::path::Path;
use std::process::{Command, Output};

use super::corpus::{corpus_files, short_name, under_ci};
use super::{stdout, temp_dir, ulog};

/// Runs pyulog's tool `module` (`messages`, `params`...) as its console script does, with
/// `args`, in `dir`; `None` when pyulog is not installed (a failure under CI).
pub(crate) fn pyulog_tool(module: &str, args: &[&str], dir: Option<&Path>) -> Option<Output> {
    let mut cmd = Command::new("python3");
    cmd.args([
        "-c",
        &format!("import sys; from pyulog.{module} import main; sys.argv[0] = '{module}'; main()"),
    ])
    .args(args);
    if let Some(d) = dir {
        cmd.current_dir(d);
    }
    let out = cmd.output().ok();
    let installed = Command::new("python3")
        .args(["-c", "import pyulog"])
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(
        installed || !under_ci(),
        "under CI pyulog must be installed (.ci/run does it)"
    );
    if !installed {
        eprintln!("pyulog not installed: nothing to compare with");
        return None;
    }
    out
}

#[test]
fn messages_equal_ulog_messages_on_every_corpus_log() {
    let (mut logs, mut lines, mut with_events) = (0, 0, 0);
    let mut failures = Vec::new();
    for path in corpus_files() {
        let file = path.to_str().unwrap();
        let Some(theirs) = pyulog_tool("messages", &[file], None) else {
            return;
        };
        assert!(theirs.status.success(), "ulog_messages {file} failed");
        let ours = stdout(&["messages", file]);
        let expected = String::from_utf8(theirs.stdout).unwrap();
        if ours != expected {
            failures.push(format!(
                "{}: ours\n{ours}\npyulog's\n{expected}",
                short_name(&path)
            ));
        }
        logs += 1;
        lines += expected.lines().count();
        if ulog_runtime::Log::open(&path)
            .is_ok_and(|l| l.topics().iter().any(|t| t.name == "event"))
        {
            with_events += 1;
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    eprintln!("{logs} logs ({with_events} with events), {lines} lines equal to ulog_messages'");
}

#[test]
fn messages_as_json_lines_carry_every_field() {
    let Some(path) = corpus_files()
        .into_iter()
        .find(|p| p.ends_with("pyulog/sample_px4_events.ulg"))
    else {
        assert!(!under_ci(), "the corpus has sample_px4_events.ulg");
        return;
    };
    let file = path.to_str().unwrap();
    let text_lines: Vec<String> = stdout(&["messages", file])
        .lines()
        .map(str::to_owned)
        .collect();
    let json: Vec<serde_json::Value> = stdout(&["messages", "--json", file])
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(json.len(), text_lines.len());
    for (j, line) in json.iter().zip(&text_lines) {
        assert!(line.ends_with(j["text"].as_str().unwrap()), "{line} vs {j}");
        assert!(line.contains(&format!(" {}: ", j["level"].as_str().unwrap())));
    }
    let armed = json
        .iter()
        .find(|j| j["text"] == "Armed by internal command")
        .expect("the log's arming event");
    assert_eq!(armed["kind"], "event");
    assert_eq!(armed["event"]["id"], 26_266_355);
    assert_eq!(armed["event"]["name"], "commander_armed_by");
    assert_eq!(armed["event"]["arguments"][0]["value"], "internal command");
    assert!(json.iter().any(|j| j["kind"] == "logged"));
}

#[test]
fn messages_without_ignore_refuse_text_that_is_not_utf8() {
    use ulog_runtime::read::{FileHeader, FlagBits, Message};
    let mut bytes = FileHeader {
        version: 1,
        start_timestamp: 0,
    }
    .to_bytes()
    .to_vec();
    let mut put = |m: Message<'_>| m.encode(&mut bytes).unwrap();
    put(Message::FlagBits(FlagBits::default()));
    put(Message::Logging {
        level: b'6',
        tag: None,
        timestamp: 2_000_000,
        text: b"caf\xe9 ok",
    });
    let dir = temp_dir("utf8");
    let log = dir.join("latin1.ulg");
    std::fs::write(&log, &bytes).unwrap();
    let file = log.to_str().unwrap();
    let refused = ulog(&["messages", file]);
    assert_eq!(refused.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("not valid UTF-8"));
    let ours = stdout(&["messages", "-i", file]);
    if let Some(theirs) = pyulog_tool("messages", &["-i", file], None) {
        assert_eq!(ours, String::from_utf8(theirs.stdout).unwrap());
        let strict = pyulog_tool("messages", &[file], None).unwrap();
        assert!(!strict.status.success(), "pyulog fails too without -i");
    }
    assert_eq!(ours, "0:00:02.000 INFO: caf ok\n");
    std::fs::remove_dir_all(&dir).unwrap();
}
