//! Has the linker put the functions that common reads run first in the module's code
//! (`link/hot-symbols.txt`, written by `link/hot_symbols.py`, which says why: a process maps
//! an extension's code 64 to 128 KiB at a time around each page it runs, so those functions
//! spread over the whole module mapped 1.7 MiB of it, and packed map about 0.25 MiB).
//!
//! Only where the linker takes LLD's `--symbol-ordering-file`, which a trial link of an
//! empty program here decides: with rustc's own LLD, its default for `x86_64-unknown-linux-gnu`
//! from Rust 1.90, it does; with GNU ld (a rustc built without that default, a linker chosen
//! in the build's flags or configuration) it does not, and the module links as before. So
//! does a copy of the crate without the list. The names in the list are those of the rustc
//! and dependency versions it was made with (its first lines): with others, nearly every
//! function keeps its place.
//!
//! Not seen here: linker flags given to the final rustc alone (`cargo rustc -- -C linker=..`).

use std::env;
use std::path::Path;
use std::process::Command;

/// Whether an empty program links with `args` added to the build's flags.
fn links_with(args: &[String]) -> bool {
    let (Ok(rustc), Ok(target), Ok(out)) =
        (env::var("RUSTC"), env::var("TARGET"), env::var("OUT_DIR"))
    else {
        return false;
    };
    let out = Path::new(&out);
    let probe = out.join("ordering_probe.rs");
    if std::fs::write(&probe, "fn main() {}\n").is_err() {
        return false;
    }
    let mut cmd = Command::new(rustc);
    cmd.arg("--target")
        .arg(&target)
        .arg("--crate-type=bin")
        .arg("-o")
        .arg(out.join("ordering_probe"))
        .arg(&probe);
    if let Ok(flags) = env::var("CARGO_ENCODED_RUSTFLAGS") {
        cmd.args(flags.split('\x1f').filter(|f| !f.is_empty()));
    }
    if let Ok(linker) = env::var("RUSTC_LINKER") {
        cmd.arg(format!("-Clinker={linker}"));
    }
    for a in args {
        cmd.arg(format!("-Clink-arg={a}"));
    }
    cmd.output().is_ok_and(|o| o.status.success())
}

fn main() {
    let target = env::var("TARGET").unwrap_or_default();
    // A linker chosen by environment (`linker` in a configuration file is not tracked).
    println!(
        "cargo:rerun-if-env-changed=CARGO_TARGET_{}_LINKER",
        target.to_uppercase().replace(['-', '.'], "_")
    );
    let manifest = env::var("CARGO_MANIFEST_DIR").expect("set by cargo");
    let list = Path::new(&manifest).join("link/hot-symbols.txt");
    if !list.is_file() || env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("linux") {
        return;
    }
    println!("cargo:rerun-if-changed=link/hot-symbols.txt");
    // `-Wl,` splits its argument at commas, and the path must pass unchanged.
    let Some(path) = list.to_str().filter(|p| !p.contains(',')) else {
        return;
    };
    let args = [
        format!("-Wl,--symbol-ordering-file={path}"),
        // Names the build no longer has (renamed, removed) are expected, not worth a warning.
        "-Wl,--no-warn-symbol-ordering".to_owned(),
    ];
    if links_with(&args) {
        for a in args {
            println!("cargo:rustc-link-arg-cdylib={a}");
        }
    }
}
