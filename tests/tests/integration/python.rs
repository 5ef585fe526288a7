//! The Python package's tests (`python/tests`, pytest) as part of `cargo test`: a virtual
//! environment made once under `target/` with the pins of `python/requirements-test.txt`
//! (or the Python given by `ULOG_PYTHON`, which `.ci/run` makes), the package's native
//! module `target/<profile>/lib_ulog.so` (made or brought up to date here with `cargo
//! build -p ulog-python`) beside its Python sources,
//! then pytest over every test file: pyulog side by side on the corpus, pyulog's own test
//! suite, the native API, bad input; and beside them, in a second pytest process, Spark
//! (when Java is there).
//!
//! Without python3 (or a working `venv`) the test says so and passes, except under CI.

use std::path::{Path, PathBuf};
use std::process::Command;

fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true" || v == "1")
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Gives up: a failure under CI, a note otherwise.
fn unavailable(why: &str) {
    assert!(!under_ci(), "under CI the Python tests must run: {why}");
    eprintln!("Python package tests not run: {why}");
}

/// The Python to run the tests with: `ULOG_PYTHON`, or a virtual environment under
/// `target/` with the pinned requirements (made again when they change).
fn python(target: &Path) -> Result<PathBuf, String> {
    if let Some(p) = std::env::var_os("ULOG_PYTHON") {
        return Ok(PathBuf::from(p));
    }
    let requirements = root().join("python/requirements-test.txt");
    let pins = std::fs::read_to_string(&requirements).map_err(|e| e.to_string())?;
    let venv = target.join("python-venv");
    let python = venv.join("bin/python");
    let stamp = venv.join("requirements-test.txt");
    if std::fs::read_to_string(&stamp).ok().as_deref() == Some(pins.as_str()) && python.exists() {
        return Ok(python);
    }
    let made = Command::new("python3")
        .args(["-m", "venv", "--clear"])
        .arg(&venv)
        .output()
        .map_err(|e| format!("python3: {e}"))?;
    if !made.status.success() {
        return Err(format!(
            "python3 -m venv failed: {}",
            String::from_utf8_lossy(&made.stderr)
        ));
    }
    let pip = Command::new(&python)
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "-r",
        ])
        .arg(&requirements)
        .output()
        .map_err(|e| e.to_string())?;
    if !pip.status.success() {
        return Err(format!(
            "pip install -r {}: {}",
            requirements.display(),
            String::from_utf8_lossy(&pip.stderr)
        ));
    }
    std::fs::write(&stamp, pins).map_err(|e| e.to_string())?;
    Ok(python)
}

/// The package laid out for import: its Python sources and the native module cargo built.
fn package(target: &Path, profile_dir: &Path) -> Result<PathBuf, String> {
    let lib = profile_dir.join("lib_ulog.so");
    // Built every time (nothing to do when it is up to date): `cargo test` builds the
    // crate's test harness, not its `cdylib`, so a module built before a change would
    // otherwise be tested in its place.
    let release = profile_dir.file_name().is_some_and(|p| p == "release");
    let built = Command::new(env!("CARGO"))
        .args(["build", "-p", "ulog-python"])
        .args(release.then_some("--release"))
        .current_dir(root())
        .status()
        .map_err(|e| e.to_string())?;
    if !built.success() || !lib.exists() {
        return Err(format!("no {} (cargo build -p ulog-python)", lib.display()));
    }
    let site = target.join("python-package");
    let pkg = site.join("ulog");
    std::fs::create_dir_all(&pkg).map_err(|e| e.to_string())?;
    let sources = root().join("python/python/ulog");
    for entry in std::fs::read_dir(&sources).map_err(|e| e.to_string())? {
        let entry = entry.map_err(|e| e.to_string())?;
        // Files only (a `__pycache__` of an import from the sources is no part of it).
        if !entry.file_type().map_err(|e| e.to_string())?.is_file() {
            continue;
        }
        std::fs::copy(entry.path(), pkg.join(entry.file_name())).map_err(|e| e.to_string())?;
    }
    std::fs::copy(&lib, pkg.join("_ulog.abi3.so")).map_err(|e| e.to_string())?;
    Ok(site)
}

#[test]
fn the_python_packages_tests_pass() {
    // target/<profile>/deps/python-<hash>: the profile's folder, and target/.
    let exe = std::env::current_exe().expect("the test's path");
    let profile_dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile>")
        .to_path_buf();
    let target = profile_dir.parent().expect("target").to_path_buf();
    let python = match python(&target) {
        Ok(p) => p,
        Err(why) => return unavailable(&why),
    };
    let site = match package(&target, &profile_dir) {
        Ok(s) => s,
        Err(why) => panic!("the package could not be laid out: {why}"),
    };
    // Two pytest processes at once: the Spark test (a JVM, mostly waiting on it) beside
    // all the others, so that the two cores are used.
    let groups: [&[&str]; 2] = [
        &["tests", "--ignore=tests/test_spark.py"],
        &["tests/test_spark.py"],
    ];
    let running: Vec<_> = groups
        .iter()
        .map(|args| {
            Command::new(&python)
                .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
                .args(*args)
                .current_dir(root().join("python"))
                .env("PYTHONPATH", &site)
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .expect("pytest runs")
        })
        .collect();
    let mut failed = Vec::new();
    for (args, child) in groups.iter().zip(running) {
        let out = child.wait_with_output().expect("pytest ends");
        let stdout = String::from_utf8_lossy(&out.stdout);
        let summary = stdout.lines().last().unwrap_or_default().to_owned();
        eprintln!("python/{}: {summary}", args[0]);
        if !out.status.success() {
            failed.push(format!(
                "{}\n{}",
                tail(&stdout, 8000),
                tail(&String::from_utf8_lossy(&out.stderr), 4000)
            ));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// The last `n` bytes of `text` or a little more, cut at a character boundary.
fn tail(text: &str, n: usize) -> &str {
    let mut start = text.len().saturating_sub(n);
    while !text.is_char_boundary(start) {
        start -= 1;
    }
    &text[start..]
}
