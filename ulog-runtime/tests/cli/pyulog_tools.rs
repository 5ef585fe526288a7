//! The `ulog` verbs against pyulog 1.3.0's tools run live, byte for byte: `ulog_messages`
//! (PX4 events included), `ulog_params` in each format, `ulog_info -m`, `ulog2kml`,
//! `ulog_extract_gps_dump`.

use std::path::Path;
use std::process::{Command, Output};

use super::corpus::{corpus_files, fixture, short_name, under_ci};
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

/// One pyulog tool run of [`pyulog_batch`].
pub(crate) struct ToolRun {
    pub(crate) status: i64,
    pub(crate) stdout: String,
    pub(crate) stderr: String,
}

/// Runs many pyulog tool invocations `(module, args)` in one Python process
/// (`tests/py/tools.py`: each log parsed once); `None` when pyulog is not installed (a
/// failure under CI).
pub(crate) fn pyulog_batch(runs: &[(&str, Vec<String>)]) -> Option<Vec<ToolRun>> {
    use std::io::Write;
    pyulog_tool("core", &["--help"], None)?;
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/py/tools.py");
    let input = serde_json::to_vec(
        &runs
            .iter()
            .map(|(m, a)| serde_json::json!({"module": m, "args": a}))
            .collect::<Vec<_>>(),
    )
    .unwrap();
    let mut child = Command::new("python3")
        .arg(script)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("python3 runs");
    child.stdin.take().unwrap().write_all(&input).unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "tests/py/tools.py failed");
    let results: Vec<serde_json::Value> = serde_json::from_slice(&out.stdout).unwrap();
    Some(
        results
            .into_iter()
            .map(|r| ToolRun {
                status: r["status"].as_i64().unwrap(),
                stdout: r["stdout"].as_str().unwrap().to_owned(),
                stderr: r["stderr"].as_str().unwrap().to_owned(),
            })
            .collect(),
    )
}

#[test]
fn messages_equal_ulog_messages_on_every_corpus_log() {
    let files = corpus_files();
    let runs: Vec<(&str, Vec<String>)> = files
        .iter()
        .map(|p| ("messages", vec![p.display().to_string()]))
        .collect();
    let Some(theirs) = pyulog_batch(&runs) else {
        return;
    };
    let (mut lines, mut with_events, mut tagged_lines) = (0, 0, 0);
    let mut failures = Vec::new();
    for (path, t) in files.iter().zip(&theirs) {
        assert_eq!(
            t.status,
            0,
            "ulog_messages {}: {}",
            path.display(),
            t.stderr
        );
        let ours = stdout(&["messages", path.to_str().unwrap()]);
        // `--tagged` adds the tagged strings (`[tag N]`) and changes nothing else.
        let tagged = stdout(&["messages", "--tagged", path.to_str().unwrap()]);
        let untagged: String = tagged
            .split_inclusive('\n')
            .filter(|l| !is_tagged_line(l))
            .collect();
        assert_eq!(untagged, ours, "{}: --tagged", short_name(path));
        tagged_lines += tagged.lines().filter(|l| is_tagged_line(l)).count();
        if !same_messages(&ours, &t.stdout) {
            failures.push(format!(
                "{}: ours\n{ours}\npyulog's\n{}",
                short_name(path),
                t.stdout
            ));
        }
        lines += t.stdout.lines().count();
        if ulog_runtime::Log::open(path).is_ok_and(|l| l.topics().iter().any(|t| t.name == "event"))
        {
            with_events += 1;
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    eprintln!(
        "{} logs ({with_events} with events), {lines} lines equal to ulog_messages'; \
         {tagged_lines} tagged strings added by --tagged",
        files.len()
    );
}

/// Whether a line of `ulog messages --tagged` is a tagged string: `h:mm:ss.mmm LEVEL: [tag N] `.
fn is_tagged_line(line: &str) -> bool {
    line.split_once(": ")
        .and_then(|(_, rest)| rest.strip_prefix("[tag "))
        .and_then(|rest| rest.split_once("] "))
        .is_some_and(|(n, _)| n.parse::<u16>().is_ok())
}

/// `ulog messages` against `ulog_messages`, line for line, but for the reason after
/// `Failed to get event parser: `: for a PX4 log with events and no events metadata pyulog
/// would download PX4's definitions (`tests/py/tools.py` keeps it offline, so it prints
/// that it could not), where this reader says the log has none.
fn same_messages(ours: &str, theirs: &str) -> bool {
    const NO_PARSER: &str = "Failed to get event parser: ";
    ours.lines().count() == theirs.lines().count()
        && ours.ends_with('\n') == theirs.ends_with('\n')
        && ours
            .lines()
            .zip(theirs.lines())
            .all(|(a, b)| a == b || (a.starts_with(NO_PARSER) && b.starts_with(NO_PARSER)))
}

#[test]
fn messages_as_json_lines_carry_every_field() {
    let Some(path) = fixture("pyulog/sample_px4_events.ulg") else {
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
    let bytes = super::hand_built(&[ulog_runtime::read::Message::Logging {
        level: b'6',
        tag: None,
        timestamp: 2_000_000,
        text: b"caf\xe9 ok",
    }]);
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
    // Each verb's refusal names its own spelling of the option, and that spelling works
    // (`params -i` is `--initial`, `gps-dump -i` its instance).
    for (verb, flag) in [
        ("messages", "-i"),
        ("info", "-i"),
        ("params", "--ignore"),
        ("gps-dump", "-x"),
    ] {
        let refused = ulog(&[verb, file]);
        assert_eq!(refused.status.code(), Some(1), "{verb}");
        let err = String::from_utf8_lossy(&refused.stderr).into_owned();
        assert!(
            err.contains(&format!(
                "not valid UTF-8 ({flag} leaves out the invalid bytes, as pyulog's {flag} does)"
            )),
            "{verb}: {err}"
        );
        let allowed = ulog(&[verb, flag, file]);
        assert!(
            !String::from_utf8_lossy(&allowed.stderr).contains("UTF-8"),
            "{verb} {flag}: {}",
            String::from_utf8_lossy(&allowed.stderr)
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn params_equal_ulog_params_in_every_format_on_every_corpus_log() {
    let options: [&[&str]; 11] = [
        &["-f", "csv"],
        &["-f", "octave"],
        &["-f", "qgc"],
        &["-f", "octave", "-i"],
        &["-t"],
        &["-i"],
        // pyulog stamps the changes with the header's time here (it reads no row for -i)...
        &["-i", "-t"],
        // ...and not here (-d implies -i only after the log is read).
        &["-d", "system", "-t"],
        &["-l", ";"],
        &["-d", "system"],
        &["-d", "current_setup"],
    ];
    let dir = temp_dir("params-out");
    let mut runs = Vec::new();
    let mut ours = Vec::new();
    for (n, path) in corpus_files().iter().enumerate() {
        let file = path.to_str().unwrap().to_owned();
        for opts in options {
            let mut args = vec![file.clone()];
            args.extend(opts.iter().map(|o| o.to_string()));
            let mut mine = vec!["params".to_owned()];
            mine.extend(args.iter().cloned());
            ours.push((short_name(path), mine));
            runs.push(("params", args));
        }
        // The output file argument.
        let theirs = dir.join(format!("theirs{n}.txt")).display().to_string();
        let mine = dir.join(format!("ours{n}.txt")).display().to_string();
        runs.push((
            "params",
            vec![file.clone(), theirs, "-f".into(), "qgc".into()],
        ));
        ours.push((
            short_name(path),
            vec!["params".into(), file, mine, "-f".into(), "qgc".into()],
        ));
    }
    let Some(theirs) = pyulog_batch(&runs) else {
        return;
    };
    let mut failures = Vec::new();
    for ((name, args), t) in ours.iter().zip(&theirs) {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = ulog(&args);
        // pyulog fails on -d when the log has no default parameters; so must we.
        if (t.status == 0) != o.status.success() || t.stdout.as_bytes() != o.stdout {
            failures.push(format!("{name} {:?}: {}", &args[2..], t.stderr));
        }
    }
    for n in 0..corpus_files().len() {
        let (a, b) = (
            dir.join(format!("ours{n}.txt")),
            dir.join(format!("theirs{n}.txt")),
        );
        if std::fs::read(&a).ok() != std::fs::read(&b).ok() {
            failures.push(format!("log {n}: qgc to a file"));
        }
    }
    assert!(failures.is_empty(), "differ from ulog_params: {failures:?}");
    eprintln!("{} ulog_params runs equal byte for byte", theirs.len());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn info_m_equals_ulog_info_m_for_every_multi_info_of_every_log() {
    let mut runs = Vec::new();
    for path in corpus_files() {
        let file = path.to_str().unwrap().to_owned();
        let log = ulog_runtime::Log::open(&path).unwrap();
        let mut keys: Vec<String> = log
            .metadata()
            .multi_info()
            .iter()
            .map(|m| m.key.clone())
            .collect();
        keys.push("no_such_message".to_owned());
        for key in keys {
            for newline in [false, true] {
                let mut args = vec![file.clone(), "-m".to_owned(), key.clone()];
                if newline {
                    args.push("-n".to_owned());
                }
                runs.push(("info", args));
            }
        }
    }
    let Some(theirs) = pyulog_batch(&runs) else {
        return;
    };
    let mut failures = Vec::new();
    for ((_, args), t) in runs.iter().zip(&theirs) {
        let mut mine = vec!["info"];
        mine.extend(args.iter().map(String::as_str));
        let o = ulog(&mine);
        if !o.status.success() || t.stdout.as_bytes() != o.stdout {
            failures.push(format!("{args:?}"));
        }
    }
    assert!(
        failures.is_empty(),
        "differ from ulog_info -m: {failures:?}"
    );
    eprintln!("{} ulog_info -m runs equal byte for byte", theirs.len());
}

/// The coordinates of a KML document, line by line of its `<coordinates>`.
fn kml_points(text: &str) -> Vec<String> {
    text.split("<coordinates>")
        .skip(1)
        .flat_map(|c| {
            c.split("</coordinates>")
                .next()
                .unwrap()
                .split(' ')
                .map(str::to_owned)
        })
        .collect()
}

#[test]
fn kml_equals_ulog2kml_on_every_corpus_log() {
    let dir = temp_dir("kml");
    let files = corpus_files();
    let path_of = |who: &str, n: usize| dir.join(format!("{who}{n}.kml"));
    let runs: Vec<(&str, Vec<String>)> = files
        .iter()
        .enumerate()
        .map(|(n, p)| {
            let out = path_of("theirs", n).display().to_string();
            (
                "ulog2kml",
                vec![p.display().to_string(), "-o".to_owned(), out],
            )
        })
        .collect();
    let Some(theirs) = pyulog_batch(&runs) else {
        return;
    };
    let (mut same, mut failing) = (0, 0);
    let mut failures = Vec::new();
    for (n, (path, run)) in files.iter().zip(&theirs).enumerate() {
        let ours = path_of("ours", n);
        let mine = ulog(&["kml", path.to_str().unwrap(), "-o", ours.to_str().unwrap()]);
        if run.status != 0 {
            // pyulog finds no track (no GPS topic): neither do we, and we say which topics
            // we looked for.
            if mine.status.success() {
                failures.push(format!(
                    "{}: pyulog fails, we wrote a track",
                    short_name(path)
                ));
            } else if !String::from_utf8_lossy(&mine.stderr)
                .contains("vehicle_gnss or vehicle_gps_position not found in data")
            {
                failures.push(format!(
                    "{}: {}",
                    short_name(path),
                    String::from_utf8_lossy(&mine.stderr)
                ));
            }
            failing += 1;
            continue;
        }
        if run.stdout.as_bytes() != mine.stdout {
            failures.push(format!("{}: stdout", short_name(path)));
        }
        let (a, b) = (
            std::fs::read_to_string(&ours).unwrap(),
            std::fs::read_to_string(path_of("theirs", n)).unwrap(),
        );
        let log = ulog_runtime::Log::open(path).unwrap();
        if a == b {
            same += 1;
        } else if log.diagnostics().iter().any(|d| d.is_corruption()) {
            // A damaged log: we keep rows pyulog cannot see after the damage. Its points
            // must be ours, in order, with the same lines.
            let (ours, theirs) = (kml_points(&a), kml_points(&b));
            let mut rest = ours.iter();
            if !theirs.iter().all(|p| rest.any(|q| q == p))
                || a.matches("<Placemark").count() != b.matches("<Placemark").count()
            {
                failures.push(format!(
                    "{}: track differs beyond the damage",
                    short_name(path)
                ));
            }
        } else {
            failures.push(format!("{}: KML differs", short_name(path)));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
    eprintln!(
        "{same} tracks equal to ulog2kml's byte for byte; {failing} logs without a track for both"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A log with a `gps_dump` topic as PX4 logs it: two receivers, both directions.
fn gps_dump_log(dir: &Path, with_instance: bool, dropout: bool) -> std::path::PathBuf {
    use ulog_runtime::{Writer, WriterOptions};
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let format = if with_instance {
        "gps_dump:uint64_t timestamp;uint8_t instance;uint8_t len;uint8_t[79] data;uint8_t[5] _padding0;"
    } else {
        "gps_dump:uint64_t timestamp;uint8_t len;uint8_t[79] data;"
    };
    w.format(format).unwrap();
    let sub = w.subscribe("gps_dump", 0).unwrap();
    for i in 0..40u8 {
        let receiver = i % 2;
        let to_device = i % 3 == 0;
        let n = 1 + (u16::from(i) * 7 % 79) as u8;
        let mut row = (u64::from(i) * 1000).to_le_bytes().to_vec();
        if with_instance {
            row.push(receiver);
        }
        row.push(if to_device { n | 0x80 } else { n });
        row.extend((0..79u8).map(|k| k.wrapping_mul(i).wrapping_add(receiver)));
        w.data(sub, &row).unwrap();
        if dropout && i == 20 {
            w.dropout(30).unwrap();
        }
    }
    let name = format!("dump_{with_instance}_{dropout}.ulg");
    let path = dir.join(name);
    std::fs::write(&path, w.into_inner()).unwrap();
    path
}

#[test]
fn gps_dump_equals_ulog_extract_gps_dump_byte_for_byte() {
    let dir = temp_dir("gps-dump");
    let (ours, theirs) = (dir.join("ours"), dir.join("theirs"));
    std::fs::create_dir_all(&ours).unwrap();
    std::fs::create_dir_all(&theirs).unwrap();
    let mut compared = 0;
    for (with_instance, dropout) in [(true, false), (true, true), (false, false)] {
        let log = gps_dump_log(&dir, with_instance, dropout);
        let file = log.to_str().unwrap();
        for instance in ["0", "1"] {
            let Some(run) = pyulog_tool(
                "extract_gps_dump",
                &[file, "-o", theirs.to_str().unwrap(), "-i", instance],
                None,
            ) else {
                return;
            };
            assert!(run.status.success());
            let mine = stdout(&[
                "gps-dump",
                file,
                "-o",
                ours.to_str().unwrap(),
                "-i",
                instance,
            ]);
            let expected = String::from_utf8(run.stdout)
                .unwrap()
                .replace(theirs.to_str().unwrap(), ours.to_str().unwrap());
            assert_eq!(mine, expected);
            for entry in std::fs::read_dir(&theirs).unwrap() {
                let name = entry.unwrap().file_name();
                let (a, b) = (
                    std::fs::read(ours.join(&name)).unwrap(),
                    std::fs::read(theirs.join(&name)).unwrap(),
                );
                assert_eq!(a, b, "{name:?}");
                assert!(
                    !b.is_empty() || (!with_instance && instance == "1"),
                    "{name:?}"
                );
                compared += 1;
            }
        }
    }
    // A log without the topic: pyulog's message, exit 0.
    let plain = dir.join("plain.ulg");
    std::fs::write(&plain, gps_free_log()).unwrap();
    let text = stdout(&["gps-dump", plain.to_str().unwrap()]);
    if let Some(run) = pyulog_tool("extract_gps_dump", &[plain.to_str().unwrap()], Some(&dir)) {
        assert_eq!(text, String::from_utf8(run.stdout).unwrap());
    }
    assert!(
        text.ends_with("does not contain gps_dump messages!\n"),
        "{text}"
    );
    eprintln!("{compared} gps dump files equal to pyulog's");
    std::fs::remove_dir_all(&dir).unwrap();
}

fn gps_free_log() -> Vec<u8> {
    use ulog_runtime::{Writer, WriterOptions};
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    w.format("t:uint64_t timestamp;").unwrap();
    let sub = w.subscribe("t", 0).unwrap();
    w.data(sub, &1u64.to_le_bytes()).unwrap();
    w.into_inner()
}

/// A log with an older PX4's GPS topic (`int32_t` degrees × 1e7), flight modes and camera
/// triggers, written by the writer.
fn kml_log(dir: &Path) -> std::path::PathBuf {
    use ulog_runtime::{Writer, WriterOptions};
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    w.format("vehicle_gps_position:uint64_t timestamp;int32_t lat;int32_t lon;int32_t alt;uint8_t fix_type;uint8_t[3] _padding0;")
        .unwrap();
    w.format("vehicle_status:uint64_t timestamp;uint8_t nav_state;uint8_t[7] _padding0;")
        .unwrap();
    w.format("camera_capture:uint64_t timestamp;uint32_t seq;float alt;double lat;double lon;")
        .unwrap();
    let gps = w.subscribe("vehicle_gps_position", 0).unwrap();
    let status = w.subscribe("vehicle_status", 0).unwrap();
    let camera = w.subscribe("camera_capture", 0).unwrap();
    for i in 0..200u64 {
        let t = 1_000_000 + i * 50_000;
        if i % 60 == 0 {
            let mut row = t.to_le_bytes().to_vec();
            // Without the trailing padding, as PX4 logs rows (pyulog refuses longer ones).
            row.push([2u8, 4, 17, 5][(i / 60) as usize % 4]);
            w.data(status, &row).unwrap();
        }
        let mut row = t.to_le_bytes().to_vec();
        row.extend_from_slice(&(473_977_418 + i as i32 * 13).to_le_bytes());
        row.extend_from_slice(&(85_455_939 - i as i32 * 7).to_le_bytes());
        row.extend_from_slice(&(488_005 + i as i32 * 3).to_le_bytes());
        row.push(if i % 17 == 5 { 1 } else { 3 });
        w.data(gps, &row).unwrap();
        if i % 50 == 10 {
            let mut row = t.to_le_bytes().to_vec();
            row.extend_from_slice(&(i as u32 / 50).to_le_bytes());
            row.extend_from_slice(&(490.1f32 + i as f32).to_le_bytes());
            row.extend_from_slice(&(47.397 + i as f64 * 1e-6).to_le_bytes());
            row.extend_from_slice(&(8.545 - i as f64 * 1e-6).to_le_bytes());
            w.data(camera, &row).unwrap();
        }
    }
    let path = dir.join("track.ulg");
    std::fs::write(&path, w.into_inner()).unwrap();
    path
}

#[test]
fn kml_with_camera_triggers_and_flight_modes_equals_ulog2kml() {
    let dir = temp_dir("kml-camera");
    let log = kml_log(&dir);
    let (ours, theirs) = (dir.join("ours.kml"), dir.join("theirs.kml"));
    let file = log.to_str().unwrap();
    let args = |out: &Path| {
        vec![
            file.to_owned(),
            "-o".to_owned(),
            out.display().to_string(),
            "--camera-trigger".to_owned(),
            "camera_capture".to_owned(),
        ]
    };
    let Some(run) = pyulog_batch(&[("ulog2kml", args(&theirs))]) else {
        return;
    };
    assert_eq!(run[0].status, 0, "{}", run[0].stderr);
    let mut mine = vec!["kml".to_owned()];
    mine.extend(args(&ours));
    stdout(&mine.iter().map(String::as_str).collect::<Vec<_>>());
    let (a, b) = (
        std::fs::read_to_string(&ours).unwrap(),
        std::fs::read_to_string(&theirs).unwrap(),
    );
    assert_eq!(a, b);
    // A line per flight mode (2, 4, 17, 5; the last row, at the end of the log, is within
    // 0.1 s of the last point, so no line for the end); four camera triggers.
    assert_eq!(a.matches("<LineString").count(), 4);
    assert!(a.contains("<name>vehicle_gps_position:17</name>"));
    assert_eq!(a.matches("<name>Camera Trigger").count(), 4);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn messages_json_says_pyulogs_warnings_as_warnings_beside_the_json() {
    use ulog_runtime::{LogLevel, Value, Writer, WriterOptions};
    // A PX4 log with an event row and no events metadata: pyulog warns that it has no
    // event parser, then lists the logged strings.
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    w.info("sys_name", &Value::String("PX4".into())).unwrap();
    w.format("event:uint64_t timestamp;uint32_t id;uint16_t event_sequence;uint8_t[25] arguments;uint8_t log_levels;")
        .unwrap();
    let sub = w.subscribe("event", 0).unwrap();
    let mut row = 1_000u64.to_le_bytes().to_vec();
    row.extend_from_slice(&((1u32 << 24) | 5).to_le_bytes());
    row.extend_from_slice(&1u16.to_le_bytes());
    row.extend_from_slice(&[0; 25]);
    row.push(0x66);
    w.data(sub, &row).unwrap();
    w.log(LogLevel::Warning, 2_000, "low battery").unwrap();
    let dir = temp_dir("messages-warning");
    let path = dir.join("no_metadata.ulg");
    std::fs::write(&path, w.into_inner()).unwrap();
    let file = path.to_str().unwrap();

    let text = stdout(&["messages", file]);
    assert!(text.starts_with("Failed to get event parser: "), "{text}");
    assert!(
        text.ends_with("0:00:00.002 WARNING: low battery\n"),
        "{text}"
    );
    if let Some(theirs) = pyulog_tool("messages", &[file], None) {
        // The same lines; the reason differs by design (pyulog tried to download the
        // metadata, which an offline reader never does).
        let theirs = String::from_utf8_lossy(&theirs.stdout).into_owned();
        let (ours_first, ours_rest) = text.split_once('\n').unwrap();
        let (their_first, their_rest) = theirs.split_once('\n').unwrap();
        assert_eq!(ours_rest, their_rest, "as ulog_messages");
        assert!(their_first.starts_with("Failed to get event parser: "));
        assert!(ours_first.contains("no events metadata"), "{ours_first}");
    }
    let json = ulog(&["messages", "--json", file]);
    assert!(json.status.success(), "a warning, not an error");
    let out = String::from_utf8(json.stdout).unwrap();
    let lines: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 1, "only JSON on stdout: {out}");
    let err = String::from_utf8(json.stderr).unwrap();
    assert!(
        err.starts_with(&format!(
            "ulog: warning: {file}: Failed to get event parser: "
        )),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
