//! Finding `.ulg` files: std only, so `build.rs` and `ulog-runtime`'s CLI test include this
//! file by path too.

use std::path::{Path, PathBuf};

/// Every `.ulg` file under `dir` (recursively), sorted; empty if `dir` cannot be read.
pub fn ulg_files(dir: &Path) -> Vec<PathBuf> {
    fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                collect(&path, out);
            } else if path.extension().is_some_and(|e| e == "ulg") {
                out.push(path);
            }
        }
    }
    let mut files = Vec::new();
    collect(dir, &mut files);
    files.sort();
    files
}
