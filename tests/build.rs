//! Generates Rust types for every corpus log with `ulog_runtime::codegen` (one module per
//! log, in `OUT_DIR/corpus_types.rs`), and the list of topic checks the `codegen` suite runs
//! on them: log -> types -> typed decode, compared with pyulog's oracle.

use std::fmt::Write as _;
use std::path::PathBuf;

#[path = "src/files.rs"]
#[allow(unreachable_pub)]
mod files;

fn main() {
    println!("cargo:rerun-if-env-changed=ULOG_CORPUS");
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap());
    let corpus = std::env::var_os("ULOG_CORPUS")
        .map(PathBuf::from)
        .unwrap_or_else(|| manifest.join("../../shared/testdata/ulog"));
    let corpus = if corpus.is_absolute() {
        corpus
    } else {
        // Relative to the workspace root, as the tests take it.
        manifest.join("..").join(corpus)
    };
    println!("cargo:rerun-if-changed={}", corpus.display());
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap());
    let files = files::ulg_files(&corpus);
    let mut modules = String::new();
    let mut checks = String::from("/// (log file name, topic, check) for every topic type.\n");
    checks.push_str("pub static CHECKS: &[(&str, &str, Checker)] = &[\n");
    for file in &files {
        let rel = file.strip_prefix(&corpus).unwrap_or(file);
        let module: String = format!("log_{}", rel.with_extension("").display())
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() {
                    c.to_ascii_lowercase()
                } else {
                    '_'
                }
            })
            .collect();
        let target = out.join(format!("{module}.rs"));
        let mut builder = ulog_runtime::codegen::Builder::new();
        builder.ulog(file);
        let types = builder
            .types()
            .unwrap_or_else(|e| panic!("codegen for {}: {e}", file.display()));
        builder
            .generate(&target)
            .unwrap_or_else(|e| panic!("codegen for {}: {e}", file.display()));
        writeln!(
            modules,
            "/// Types generated from `{}`.\n#[warn(clippy::pedantic)]\npub mod {module} {{\n    \
             include!(concat!(env!(\"OUT_DIR\"), \"/{module}.rs\"));\n}}",
            rel.display()
        )
        .unwrap();
        for ty in types.iter().filter(|t| t.topic) {
            writeln!(
                checks,
                "    ({:?}, {:?}, check::<{module}::{}>),",
                file.file_name().unwrap().to_string_lossy(),
                ty.format,
                ty.path
            )
            .unwrap();
        }
    }
    checks.push_str("];\n");
    std::fs::write(out.join("corpus_types.rs"), modules + &checks).unwrap();
}
