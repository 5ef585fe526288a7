//! Has the linker put the functions that common reads run first in the module's code
//! (`link/hot-symbols.txt`, written by `link/hot_symbols.py`, which says why: a process maps
//! an extension's code 64 to 128 KiB at a time around each page it runs, so those functions
//! spread over the whole module mapped 1.7 MiB of it, and packed map about 0.25 MiB).
//!
//! Only where the linker is known to be LLD, which takes `--symbol-ordering-file`: rustc's
//! default for `x86_64-unknown-linux-gnu` from Rust 1.90, when no linker or linker flavour
//! is chosen in the build's flags or configuration. Elsewhere (an older rustc, another
//! target or linker, a copy of the crate without the list) the module links as before.

use std::env;
use std::process::Command;

/// Whether `rustc` is 1.90 or later.
fn lld_by_default(rustc: &str) -> bool {
    let Ok(out) = Command::new(rustc).arg("--version").output() else {
        return false;
    };
    let version = String::from_utf8_lossy(&out.stdout);
    // "rustc 1.95.0 (59807616e 2026-04-14)"
    let mut parts = version
        .split_whitespace()
        .nth(1)
        .unwrap_or_default()
        .split(['.', '-'])
        .map(|p| p.parse::<u32>().ok());
    matches!((parts.next(), parts.next()), (Some(Some(1)), Some(Some(minor))) if minor >= 90)
}

fn main() {
    println!("cargo:rerun-if-changed=link/hot-symbols.txt");
    println!("cargo:rerun-if-env-changed=RUSTC_LINKER");
    let target = env::var("TARGET").unwrap_or_default();
    let flags = env::var("CARGO_ENCODED_RUSTFLAGS").unwrap_or_default();
    let chosen = env::var_os("RUSTC_LINKER").is_some()
        || flags.split('\x1f').any(|f| {
            ["linker", "link-self-contained", "fuse-ld"]
                .iter()
                .any(|k| f.contains(k))
        });
    let list = std::path::Path::new(&env::var("CARGO_MANIFEST_DIR").expect("set by cargo"))
        .join("link/hot-symbols.txt");
    let rustc = env::var("RUSTC").unwrap_or_else(|_| "rustc".to_owned());
    // `-Wl,` splits its argument at commas: a path with one cannot be passed this way.
    let passable = list.is_file() && !list.to_string_lossy().contains(',');
    if target != "x86_64-unknown-linux-gnu" || chosen || !passable || !lld_by_default(&rustc) {
        return;
    }
    println!(
        "cargo:rustc-link-arg-cdylib=-Wl,--symbol-ordering-file={}",
        list.display()
    );
    // Names the build no longer has (renamed, removed) are expected, not worth a warning.
    println!("cargo:rustc-link-arg-cdylib=-Wl,--no-warn-symbol-ordering");
}
