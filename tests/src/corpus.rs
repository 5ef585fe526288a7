//! Finding the corpus, its oracles, and what pyulog cannot see in it. Also compiled into
//! `ulog-runtime`'s CLI test (by path, beside `files.rs` as `crate::files`), so it depends on
//! nothing but `ulog_runtime`, `serde_json` and std.

use std::ops::Range;
use std::path::{Path, PathBuf};

use ulog_runtime::read::SYNC_MAGIC;
use ulog_runtime::{DiagnosticKind, Log};

/// The corpus folder.
pub fn corpus_dir() -> PathBuf {
    match std::env::var_os("ULOG_CORPUS") {
        Some(dir) => PathBuf::from(dir),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/testdata/ulog"),
    }
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
