//! Inputs, errors and names of the generator; the generated code itself is checked by the
//! golden and corpus tests of `ulog-tests`.

use super::emit::{field_name, type_name};
use super::*;

fn toml_error(text: &str) -> String {
    input::parse_toml(Path::new("topics.toml"), text)
        .unwrap_err()
        .to_string()
}

#[test]
fn toml_errors_name_the_file_and_line() {
    assert_eq!(
        toml_error(
            "[[topic]]\nname = \"a\"\nfields = [\n  { name = \"x\", typ = \"float\" },\n]\n"
        ),
        "topics.toml:4: unknown field `typ`, expected one of `name`, `type`, `len`, `doc`"
    );
    assert_eq!(
        toml_error(
            "[[topic]]\nname = \"a\"\n\nfields = [ { name = \"x\", type = \"float\", len = \"4\" } ]\n"
        ),
        "topics.toml:4: invalid type: string \"4\", expected u32"
    );
    assert!(toml_error("[[topic]]\nname = \"a\"\nfields = [").starts_with("topics.toml:3: "));
    assert_eq!(
        toml_error("[[topic]]\nname = \"a\"\n"),
        "topics.toml:1: missing field `fields`"
    );
    assert_eq!(
        toml_error(
            "[[topic]]\nname = \"a\"\nfields = [\n { name = \"x\", type = \"float\", len = 0 },\n]"
        ),
        "topics.toml:4: field `x`: `len` must be 1..=65535, not 0"
    );
    assert_eq!(
        toml_error(
            "[[topic]]\nname = \"a\"\nfields = [\n { name = \"x\", type = \"float[4]\" },\n]"
        ),
        "topics.toml:4: field `x`: type `float[4]` must be a bare type name; give the array length as `len`"
    );
    assert_eq!(
        toml_error("\n[[topic]]\nname = \"a b\"\nfields = [ { name = \"x\", type = \"float\" } ]"),
        "topics.toml:3: `a b:float x;` is not a valid format: at byte 1: character ' ' is not allowed in a message name (allowed: a-z A-Z 0-9 _ - /)"
    );
}

#[test]
fn toml_topics_carry_docs_and_options() {
    let defs = input::parse_toml(
        Path::new("t.toml"),
        "[[topic]]\nname = \"gps\"\ndoc = \"Fix.\"\nderives = [\"Copy\"]\nexact = true\n\
         fields = [\n  { name = \"timestamp\", type = \"uint64_t\", doc = \"µs\" },\n  \
         { name = \"q\", type = \"float\", len = 4 },\n]\n",
    )
    .unwrap();
    assert_eq!(defs.len(), 1);
    assert_eq!(
        defs[0].format.to_string(),
        "gps:uint64_t timestamp;float[4] q;"
    );
    assert_eq!(defs[0].doc.as_deref(), Some("Fix."));
    assert_eq!(defs[0].field_docs["timestamp"], "µs");
    assert_eq!(defs[0].derives, ["Copy"]);
    assert!(defs[0].exact);
    assert_eq!(defs[0].place.to_string(), "t.toml:2");
}

#[test]
fn resolution_errors_name_every_place() {
    let err = Builder::new()
        .format("a:uint64_t timestamp;b x;")
        .format("b:float y;")
        .format("b:double y;")
        .render()
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "`b` is defined twice, differently: `b:float y;` (format string #2) and `b:double y;` (format string #3)"
    );
    let err = Builder::new()
        .format("a:uint64_t timestamp;c x;")
        .render()
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "`a` (format string #1): field `x` has type `c`, which no input defines"
    );
    let err = Builder::new()
        .format("a:b x;")
        .format("b:a y;")
        .render()
        .unwrap_err();
    assert!(
        matches!(&err, CodegenError::Cycle { cycle } if cycle.len() >= 2),
        "{err}"
    );
    assert!(err.to_string().contains("`a` (format string #1)"), "{err}");
    assert!(err.to_string().contains("`b` (format string #2)"), "{err}");
    // The same definition twice is fine.
    assert!(
        Builder::new()
            .format("b:float y;")
            .format("b:float y;")
            .render()
            .is_ok()
    );
    // A single `char` is a `Char` field.
    let code = Builder::new().format("a:char c;").render().unwrap();
    assert!(code.contains("pub c: ::ulog_runtime::Char,"), "{code}");
    // Nested padding is bytes of the nested type's size; a timestamp that is not an
    // unsigned integer makes a nested-only type.
    let code = Builder::new()
        .format("n:uint8_t a;uint8_t[3] _padding0;float b;")
        .format("t:uint64_t timestamp;n _padding0;n[2] _padding1;")
        .format("odd:float timestamp;")
        .render()
        .unwrap();
    assert!(code.contains("pub _padding0: [u8; 8],"), "{code}");
    assert!(code.contains("pub _padding1: [u8; 16],"), "{code}");
    assert!(
        code.contains("#[ulog(name = \"odd\", nested, crate"),
        "{code}"
    );
    let err = Builder::new()
        .format("a:float x;")
        .derive("not a path")
        .render()
        .unwrap_err();
    assert!(
        err.to_string().starts_with("invalid derive `not a path`"),
        "{err}"
    );
}

#[test]
fn rust_names() {
    assert_eq!(type_name("vehicle_attitude"), "VehicleAttitude");
    assert_eq!(type_name("actuator_controls_0"), "ActuatorControls0");
    assert_eq!(type_name("GPS-data/raw"), "GpsDataRaw");
    assert_eq!(type_name("3d"), "T3d");
    assert_eq!(type_name("self"), "Self_");
    assert_eq!(field_name("airspeedSp"), "airspeed_sp");
    assert_eq!(field_name("R_body"), "r_body");
    assert_eq!(field_name("hipower_5V_OC"), "hipower_5v_oc");
    assert_eq!(field_name("voltage3V3_v"), "voltage3v3_v");
    assert_eq!(field_name("type"), "type_");
    assert_eq!(field_name("self"), "self_");
    assert_eq!(field_name("5v"), "f_5v");
    assert_eq!(field_name("_"), "f__");
    assert_eq!(field_name("__"), "__");
    assert_eq!(field_name("q"), "q");
}

#[test]
fn the_output_is_rewritten_only_when_it_changes() {
    let dir = std::env::temp_dir().join(format!("ulog-codegen-{}", std::process::id()));
    let path = dir.join("out/topics.rs");
    let mut b = Builder::new();
    b.format("t:uint64_t timestamp;float x;");
    assert_eq!(b.generate(&path).unwrap(), path);
    let first = std::fs::read_to_string(&path).unwrap();
    assert!(first.starts_with("// @generated"));
    let modified = std::fs::metadata(&path).unwrap().modified().unwrap();
    std::thread::sleep(std::time::Duration::from_millis(20));
    b.generate(&path).unwrap();
    assert_eq!(
        std::fs::metadata(&path).unwrap().modified().unwrap(),
        modified
    );
    b.format("u:uint64_t timestamp;");
    b.generate(&path).unwrap();
    assert_ne!(std::fs::read_to_string(&path).unwrap(), first);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A folder of `.msg` files, written for one test.
fn msg_folder(name: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ulog-msg-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (file, text) in files {
        std::fs::write(dir.join(file), text).unwrap();
    }
    dir
}

#[test]
fn msg_errors_name_the_file_and_line() {
    let cases: &[(&[(&str, &str)], &str)] = &[
        (
            &[("A.msg", "uint64 timestamp\nfloat32[x] q\n")],
            "A.msg:2: bad array length in `float32[x]`: `x` is not a number",
        ),
        (
            &[("A.msg", "uint64 timestamp\n\nuint8 a\nuint16 a\n")],
            "A.msg:4: field `a` is defined twice",
        ),
        (
            &[("A.msg", "uint8 LIMIT = 300\nuint64 timestamp\n")],
            "A.msg:1: constant `LIMIT`: `300` does not fit uint8 (0..=255)",
        ),
        (
            &[("A.msg", "uint64 timestamp\nstring name\n")],
            "A.msg:2: unknown type `string`",
        ),
        (
            &[("A.msg", "uint64 timestamp\nMissing m # no such file\n")],
            "`a` (A.msg:2): field `m` has type `Missing`, which no input defines",
        ),
    ];
    for (i, (files, expected)) in cases.iter().enumerate() {
        let dir = msg_folder(&format!("err{i}"), files);
        let err = Builder::new()
            .msg_dir(&dir)
            .render()
            .unwrap_err()
            .to_string();
        let err = err.replace(&format!("{}/", dir.display()), "");
        assert!(err.contains(expected), "{err}\nwanted: {expected}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
    // A cycle between files names each file and line.
    let dir = msg_folder(
        "cycle",
        &[
            ("A.msg", "uint64 timestamp\nB b\n"),
            ("B.msg", "uint8 x\nC c\n"),
            ("C.msg", "uint8 y\n\nA a\n"),
        ],
    );
    let err = Builder::new()
        .msg_dir(&dir)
        .render()
        .unwrap_err()
        .to_string();
    let err = err.replace(&format!("{}/", dir.display()), "");
    assert_eq!(
        err,
        "nested types form a cycle: `a` (A.msg:2) -> `b` (B.msg:2) -> `c` (C.msg:3)"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn msg_folders_resolve_across_inputs_and_select_topics() {
    let dir = msg_folder(
        "select",
        &[
            (
                "Attitude.msg",
                "uint64 timestamp\nfloat32[4] q\n# TOPICS attitude estimator_attitude\n",
            ),
            (
                "Status.msg",
                "uint64 timestamp\nReport[2] reports\nExternal e\n",
            ),
            ("Report.msg", "uint32 rpm\n"),
            ("Unused.msg", "uint64 timestamp\n"),
        ],
    );
    // `generate` asks cargo to watch the folder, which cargo scans, as one path.
    let watched = Builder::new()
        .msg_dir(&dir)
        .format("x:uint8_t a;")
        .msg(dir.join("Report.msg"))
        .watched_files();
    assert_eq!(watched, [dir.clone(), dir.join("Report.msg")]);
    // A topic misspelled: the closest names of the folder are suggested.
    let err = Builder::new()
        .msg_dir_topics(&dir, &["statuss"])
        .types()
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        format!(
            "{}: no .msg file defines topic `statuss`; did you mean `status`?",
            dir.display()
        )
    );
    // A nested type from another input (a format string), used by the folder.
    let types = Builder::new()
        .msg_dir_topics(&dir, &["estimator_attitude", "status"])
        .format("external:uint16_t v;")
        .types()
        .unwrap();
    let names: Vec<(&str, &str, Vec<&str>)> = types
        .iter()
        .map(|t| {
            (
                t.format.as_str(),
                t.path.as_str(),
                t.topics.iter().map(String::as_str).collect(),
            )
        })
        .collect();
    assert_eq!(
        names,
        [
            (
                "attitude",
                "Attitude",
                vec!["attitude", "estimator_attitude"]
            ),
            ("report", "Report", vec!["report"]),
            ("status", "Status", vec!["status"]),
            ("external", "External", vec!["external"]),
        ]
    );
    let err = Builder::new()
        .msg_dir_topics(&dir, &["nothing"])
        .render()
        .unwrap_err()
        .to_string();
    assert!(
        err.ends_with("no .msg file defines topic `nothing`"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn merging_strictly_refuses_fields_without_a_common_type() {
    let mut b = Builder::new();
    b.format("t:uint64_t timestamp;int64_t x;")
        .format("t:uint64_t timestamp;uint64_t x;");
    assert!(matches!(
        b.render().unwrap_err(),
        CodegenError::Redefinition { .. }
    ));
    b.merge(Merge::Strict);
    assert_eq!(
        b.render().unwrap_err().to_string(),
        "`t`: field `x` has no type that holds every value of its types: `int64_t` in \
         `format string #1`; `uint64_t` in `format string #2`"
    );
    b.merge(Merge::Lossless);
    let code = b.render().unwrap();
    assert!(
        code.contains("Left out (no Rust type holds every value of its types): `x`"),
        "{code}"
    );
    assert!(!code.contains("pub x:"), "{code}");
    b.exact(true);
    assert!(
        b.render()
            .unwrap_err()
            .to_string()
            .contains("cannot be exact")
    );
}

#[test]
fn a_topic_a_log_lacks_suggests_the_closest_it_has() {
    let mut w = crate::Writer::new(Vec::new(), crate::WriterOptions::default()).unwrap();
    w.format("battery:uint64_t timestamp;float voltage_v;")
        .unwrap();
    w.subscribe("battery", 0).unwrap();
    let path = std::env::temp_dir().join(format!("ulog-codegen-topic-{}.ulg", std::process::id()));
    std::fs::write(&path, w.into_inner()).unwrap();
    let err = Builder::new()
        .ulog_topics(&path, &["batery"])
        .types()
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        format!(
            "{}: no format `batery` in this log; did you mean `battery`?",
            path.display()
        )
    );
    std::fs::remove_file(&path).unwrap();
}

/// A log cut short inside its definitions, after a format and before the format it nests:
/// the error says the log is damaged and where, not only that no input defines the nested
/// type. The damage is no error where another input defines the type, or where the topics
/// taken do not need it.
#[test]
fn a_log_cut_before_a_nested_format_says_it_is_damaged() {
    let mut w = crate::Writer::new(Vec::new(), crate::WriterOptions::default()).unwrap();
    w.format("other:uint64_t timestamp;").unwrap();
    w.format("fence:uint64_t timestamp;fence_vertex[2] vertices;")
        .unwrap();
    w.format("fence_vertex:float lat;float lon;").unwrap();
    let bytes = w.into_inner();
    // The last format message (3 header bytes and 33 of text) loses its last 10 bytes.
    let cut = bytes.len() - 10;
    let path = std::env::temp_dir().join(format!("ulog-codegen-cut-{}.ulg", std::process::id()));
    std::fs::write(&path, &bytes[..cut]).unwrap();
    let err = Builder::new().ulog(&path).types().unwrap_err();
    let start = cut - 26;
    assert_eq!(
        err.to_string(),
        format!(
            "{}: format `fence` nests `fence_vertex` (field `vertices`), which no input \
             defines: the log is damaged (1 problem(s), the first at byte {start}: message cut \
             short: 33 payload bytes declared, 23 available; dropped)",
            path.display()
        )
    );
    let types = Builder::new()
        .ulog(&path)
        .format("fence_vertex:float lat;float lon;")
        .types()
        .unwrap();
    assert_eq!(types.len(), 3);
    let types = Builder::new()
        .ulog_topics(&path, &["other"])
        .types()
        .unwrap();
    assert_eq!(types.len(), 1);
    std::fs::remove_file(&path).unwrap();
}
