//! Generates Rust types with `ulog_runtime::codegen` for the `codegen` suite, and the list of
//! checks it runs on them (types -> typed decode of a log, compared with pyulog's oracle):
//! - one module per corpus log, from that log (`corpus_types.rs`);
//! - one module from every PX4 corpus log merged: one type per topic for the whole fleet
//!   (`fleet_types.rs`);
//! - one module per PX4 `.msg` snapshot of `../shared/testdata/px4-msg`, in exact mode, with
//!   the logs its PROVENANCE.md pairs it with (`msg_types.rs`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[path = "src/files.rs"]
#[allow(unreachable_pub)]
mod files;

/// `log_px4_ulog_rs_quadrotor_local`: a module name for a path.
fn module_name(prefix: &str, rel: &Path) -> String {
    format!("{prefix}_{}", rel.with_extension("").display())
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect()
}

fn module(out: &mut String, module: &str, doc: &str) {
    writeln!(
        out,
        "/// {doc}\n#[warn(clippy::pedantic)]\npub mod {module} {{\n    \
         include!(concat!(env!(\"OUT_DIR\"), \"/{module}.rs\"));\n}}"
    )
    .unwrap();
}

fn generate(
    builder: &ulog_runtime::codegen::Builder,
    target: &Path,
    what: &str,
) -> Vec<ulog_runtime::codegen::GeneratedType> {
    let types = builder
        .types()
        .unwrap_or_else(|e| panic!("codegen for {what}: {e}"));
    builder
        .generate(target)
        .unwrap_or_else(|e| panic!("codegen for {what}: {e}"));
    types
}

/// The pairs of PROVENANCE.md's table: a snapshot folder and the corpus logs (paths below
/// the corpus folder) whose formats it reproduces.
fn msg_pairs(msg_root: &Path) -> Vec<(String, Vec<String>)> {
    let Ok(text) = std::fs::read_to_string(msg_root.join("PROVENANCE.md")) else {
        return Vec::new();
    };
    text.lines()
        .filter(|l| l.starts_with("| `"))
        .filter_map(|l| {
            let ticked: Vec<&str> = l.split('`').skip(1).step_by(2).collect();
            let folder = ticked.first()?.to_string();
            let logs = ticked
                .iter()
                .filter_map(|t| t.strip_prefix("ulog/"))
                .filter(|t| t.ends_with(".ulg"))
                .map(str::to_owned)
                .collect();
            Some((folder, logs))
        })
        .collect()
}

fn main() {
    println!("cargo:rerun-if-env-changed=ULOG_CORPUS");
    println!("cargo:rerun-if-env-changed=PX4_MSG_DIR");
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap());
    let absolute = |p: PathBuf| {
        if p.is_absolute() {
            p
        } else {
            manifest.join("..").join(p)
        }
    };
    let corpus = absolute(
        std::env::var_os("ULOG_CORPUS")
            .map(PathBuf::from)
            .unwrap_or_else(|| manifest.join("../../shared/testdata/ulog")),
    );
    let project = manifest.join("../../shared/testdata/ulog");
    let msg_root = absolute(
        std::env::var_os("PX4_MSG_DIR")
            .map(PathBuf::from)
            .unwrap_or_else(|| manifest.join("../../shared/testdata/px4-msg")),
    );
    println!("cargo:rerun-if-changed={}", corpus.display());
    println!("cargo:rerun-if-changed={}", project.display());
    println!("cargo:rerun-if-changed={}", msg_root.display());
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap());
    let files = files::ulg_files(&corpus);

    // Per log.
    let mut modules = String::new();
    let mut checks = String::from("/// (log file name, topic, check) for every topic type.\n");
    checks.push_str("pub static CHECKS: &[(&str, &str, Checker)] = &[\n");
    let mut px4_logs = Vec::new();
    for file in &files {
        let rel = file.strip_prefix(&corpus).unwrap_or(file);
        let module_name = module_name("log", rel);
        let mut builder = ulog_runtime::codegen::Builder::new();
        builder.ulog(file);
        let types = generate(
            &builder,
            &out.join(format!("{module_name}.rs")),
            &file.display().to_string(),
        );
        module(
            &mut modules,
            &module_name,
            &format!("Types generated from `{}`.", rel.display()),
        );
        for ty in types.iter().filter(|t| t.topic) {
            writeln!(
                checks,
                "    ({:?}, {:?}, check::<{module_name}::{}>),",
                file.file_name().unwrap().to_string_lossy(),
                ty.format,
                ty.path
            )
            .unwrap();
        }
        let log = ulog_runtime::Log::read(file).ok();
        let px4 = log.is_some_and(|l| {
            l.metadata().info_value("sys_name").and_then(|v| v.as_str()) == Some("PX4")
        });
        if px4 {
            px4_logs.push(file.clone());
        }
    }
    checks.push_str("];\n");
    std::fs::write(out.join("corpus_types.rs"), modules + &checks).unwrap();

    // The PX4 fleet, merged.
    let mut fleet = String::new();
    let mut fleet_checks = String::from(
        "/// (topic, check) for every topic type of the merged fleet.\n\
         pub static FLEET_CHECKS: &[(&str, Checker)] = &[\n",
    );
    if !px4_logs.is_empty() {
        let mut builder = ulog_runtime::codegen::Builder::new();
        for log in &px4_logs {
            builder.ulog(log);
        }
        builder.merge(ulog_runtime::codegen::Merge::Lossless);
        let types = generate(&builder, &out.join("fleet.rs"), "the PX4 corpus logs");
        module(
            &mut fleet,
            "fleet",
            "One type per topic for every PX4 corpus log, merged.",
        );
        for ty in types.iter().filter(|t| t.topic) {
            writeln!(
                fleet_checks,
                "    ({:?}, check::<fleet::{}>),",
                ty.format, ty.path
            )
            .unwrap();
        }
    }
    fleet_checks.push_str("];\n");
    std::fs::write(out.join("fleet_types.rs"), fleet + &fleet_checks).unwrap();

    // The `.msg` snapshots, exact, with their paired logs.
    let mut msg = String::new();
    let mut msg_checks = String::from(
        "/// (snapshot, log path below the corpus, topic, check) for every topic of every type \
         generated from a snapshot, on every log paired with it.\n\
         pub static MSG_CHECKS: &[(&str, &str, &str, CheckerAs)] = &[\n",
    );
    let mut msg_pairs_list = String::from(
        "/// (snapshot folder, logs below the corpus) as PROVENANCE.md pairs them.\n\
         pub static MSG_PAIRS: &[(&str, &[&str])] = &[\n",
    );
    for (folder, logs) in msg_pairs(&msg_root) {
        let dir = msg_root.join(&folder).join("msg");
        let module_name = format!("msg_{}", &folder[..folder.len().min(8)]);
        let mut builder = ulog_runtime::codegen::Builder::new();
        builder.msg_dir(&dir).exact(true);
        let types = generate(
            &builder,
            &out.join(format!("{module_name}.rs")),
            &dir.display().to_string(),
        );
        module(
            &mut msg,
            &module_name,
            &format!("Types generated from the `.msg` files of `{folder}`."),
        );
        writeln!(msg_pairs_list, "    ({folder:?}, &{logs:?}),").unwrap();
        for log in &logs {
            // The paired logs are the project corpus's: from ULOG_CORPUS when it holds them
            // (as `ulog_tests::fixture` finds them), else from the project corpus.
            let Some(read) = [&corpus, &project]
                .into_iter()
                .find_map(|dir| ulog_runtime::Log::read(dir.join(log)).ok())
            else {
                continue; // the corpus test reports a missing paired log
            };
            let schema = read.metadata().schema();
            for ty in types.iter().filter(|t| t.topic) {
                for topic in ty.topics.iter().filter(|t| schema.get(t).is_some()) {
                    writeln!(
                        msg_checks,
                        "    ({folder:?}, {log:?}, {topic:?}, check_as::<{module_name}::{}>),",
                        ty.path
                    )
                    .unwrap();
                }
            }
        }
    }
    msg_checks.push_str("];\n");
    msg_pairs_list.push_str("];\n");
    std::fs::write(
        out.join("msg_types.rs"),
        msg + &msg_checks + &msg_pairs_list,
    )
    .unwrap();
}
