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
    let err = Builder::new().format("a:char c;").render().unwrap_err();
    assert!(err.to_string().contains("single `char`"), "{err}");
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
