//! Finding the corpus, its oracles, and what pyulog cannot see in it. Also compiled into
//! `ulog-runtime`'s CLI test (by path, beside `files.rs` as `crate::files`), so it depends on
//! nothing but `ulog_runtime`, `serde_json` and std.

use std::ops::Range;
use std::path::{Path, PathBuf};

use ulog_runtime::read::SYNC_MAGIC;
use ulog_runtime::{DiagnosticKind, Log};

/// The corpus folder: `ULOG_CORPUS`, else the project's corpus ([`project_corpus_dir`]).
pub fn corpus_dir() -> PathBuf {
    match std::env::var_os("ULOG_CORPUS") {
        Some(dir) => PathBuf::from(dir),
        None => project_corpus_dir(),
    }
}

/// The project's corpus, `../shared/testdata/ulog` beside the checkout: real logs from
/// public projects with their pyulog oracles, `oracle.py`, and pyulog's expected tool
/// outputs for its own sample logs.
pub fn project_corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/testdata/ulog")
}

/// Whether the corpus is the project's (`ULOG_CORPUS` unset, or naming that folder). The
/// tests' counts of what the corpus holds (a topic in at least so many logs, so many rows
/// of one topic) are the project corpus's: another folder is checked log by log, without
/// them.
pub fn is_project_corpus() -> bool {
    let canonical = |p: PathBuf| std::fs::canonicalize(&p).unwrap_or(p);
    canonical(corpus_dir()) == canonical(project_corpus_dir())
}

/// A file of the project's corpus whose known facts a test checks (`pyulog/sample.ulg` and
/// pyulog's `sample_params.txt` for it, `oracle.py`): from `ULOG_CORPUS` when it holds the
/// file, else from the project's corpus, so that a folder of other logs named by
/// `ULOG_CORPUS` leaves these tests checking what they check. `None` when neither holds it,
/// with a note on stderr, outside CI only: under CI that panics, naming the file.
pub fn fixture(name: &str) -> Option<PathBuf> {
    let found = [corpus_dir(), project_corpus_dir()]
        .into_iter()
        .map(|dir| dir.join(name))
        .find(|p| p.exists());
    if found.is_none() {
        let msg = format!(
            "{name} is in neither {} nor {} (set ULOG_CORPUS)",
            corpus_dir().display(),
            project_corpus_dir().display()
        );
        assert!(!under_ci(), "{msg}");
        eprintln!("note: {msg}; the test that needs it has nothing to check");
    }
    found
}

/// Whether the tests run under CI, where nothing may be skipped.
pub fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true" || v == "1")
}

/// Every `.ulg` file of the corpus, sorted. Outside CI, an absent corpus yields an empty list
/// (and a note on stderr); under CI it panics.
pub fn corpus_files() -> Vec<PathBuf> {
    let dir = corpus_dir();
    let files = crate::files::ulg_files(&dir);
    if files.is_empty() {
        let msg = format!("no .ulg files under {} (set ULOG_CORPUS)", dir.display());
        assert!(!under_ci(), "{msg}");
        eprintln!("note: {msg}; corpus tests have nothing to check");
    }
    files
}

/// The pyulog oracle beside a corpus file (`FILE.ulg.oracle.json`), if there is one.
pub fn oracle(path: &Path) -> Option<serde_json::Value> {
    let mut name = path.as_os_str().to_owned();
    name.push(".oracle.json");
    let text = std::fs::read_to_string(PathBuf::from(name)).ok()?;
    Some(serde_json::from_str(&text).expect("oracle files are valid JSON"))
}

/// A short name for messages: the file name and its parent folder.
pub fn short_name(path: &Path) -> String {
    let parent = path
        .parent()
        .and_then(Path::file_name)
        .map(|p| p.to_string_lossy().into_owned());
    let file = path
        .file_name()
        .map(|p| p.to_string_lossy().into_owned())
        .unwrap_or_default();
    match parent {
        Some(p) => format!("{p}/{file}"),
        None => file,
    }
}

/// The byte ranges of a log that pyulog does not read: after damage, pyulog resumes only
/// after the next sync magic (or never, without one), where this reader resumes at the first
/// intact message. Each range runs from a damage this reader reported to the end of the first
/// sync magic after it (or the end of the file).
pub fn pyulog_blind_ranges(log: &Log<'_>) -> Vec<Range<u64>> {
    let bytes = log.bytes();
    log.diagnostics()
        .iter()
        .filter(|d| {
            matches!(
                d.kind,
                DiagnosticKind::Skipped { .. } | DiagnosticKind::Overlap { .. }
            )
        })
        .map(|d| {
            let from = d.offset as usize;
            let end = bytes[from + 1..]
                .windows(SYNC_MAGIC.len())
                .position(|w| w == SYNC_MAGIC)
                .map_or(bytes.len(), |i| from + 1 + i + SYNC_MAGIC.len());
            d.offset..end as u64
        })
        .collect()
}
