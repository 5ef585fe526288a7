//! The Parquet converter (`to_parquet`) and the `ulog` command-line tool (`cli_main`).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use ulog_runtime::columns::Window;
use ulog_runtime::columns::parquet::{Converter, Layout, ParquetOptions};

/// Converts logs to Parquet with the Rust `Converter` (what `ulog parquet` does); one dict
/// per log, in order (only the rows from `start` to `end` seconds, as `ulog parquet --start
/// --end`): `log`, `ok`, and either `files` (dicts of `path`, `topic`,
/// `multi_id`, `rows`), `metadata`, `log_dir`, `notes`, `skipped` (what reading left out:
/// `unreadable_topics` as (topic, msg_id, why), `misfit_rows` as (topic, multi_id, rows),
/// `orphan_rows`, `unusable_messages`, `damaged_bytes`, `ignored_appended_offsets`), `said` (what `ulog parquet` says of
/// the log on stderr, a line each), or `error`. A log that fails does
/// not stop the others. The GIL is released while converting; called from the main thread,
/// a signal whose handler raises (Ctrl-C) stops it after the logs under way, and the
/// exception propagates.
#[pyfunction]
#[pyo3(signature = (paths, out_dir, layout="per-log", topics=None, threads=None, analysis=true, start=None, end=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn to_parquet<'py>(
    py: Python<'py>,
    paths: Vec<PathBuf>,
    out_dir: PathBuf,
    layout: &str,
    topics: Option<Vec<String>>,
    threads: Option<usize>,
    analysis: bool,
    start: Option<f64>,
    end: Option<f64>,
) -> PyResult<Bound<'py, PyList>> {
    let window = Window::seconds(start, end)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    let layout = match layout {
        "per-log" => Layout::PerLog,
        "hive" => Layout::Hive,
        other => {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "layout `{other}`: `per-log` or `hive`"
            )));
        }
    };
    let options = ParquetOptions {
        layout,
        topics: topics.unwrap_or_default(),
        analysis,
        window,
        ..ParquetOptions::default()
    };
    let threads = threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, std::num::NonZero::get));
    let (wanted, window) = (options.topics.clone(), options.window);
    // As `ulog parquet -m`: a topic no log defines fails before any log is converted; one
    // that some logs lack is said of each of them.
    let check = py.detach(|| ulog_runtime::read::check_topics(&paths, &wanted));
    if let Some((missing, text)) = check.refusal(paths.len()) {
        let hint = if missing.suggestions.is_empty() {
            " (no topic the logs define has a close name)"
        } else {
            ""
        };
        let message = match paths.as_slice() {
            [path] => format!("{}: {text}{hint}", path.display()),
            _ => format!("{text}{hint}"),
        };
        return Err(pyo3::exceptions::PyKeyError::new_err(message));
    }
    let converter = Converter::new(out_dir, options);
    let stop = AtomicBool::new(false);
    let results = until_signal(py, &stop, || {
        converter.convert_files_until(&paths, threads, &stop)
    })?;
    let out = PyList::empty(py);
    for (path, result) in paths.iter().zip(results) {
        let d = PyDict::new(py);
        d.set_item("log", path.display().to_string())?;
        match result {
            Ok(c) => {
                d.set_item("ok", true)?;
                let files = PyList::empty(py);
                for f in &c.files {
                    let fd = PyDict::new(py);
                    fd.set_item("path", f.path.display().to_string())?;
                    fd.set_item("topic", &f.topic)?;
                    fd.set_item("multi_id", f.multi_id)?;
                    fd.set_item("rows", f.rows)?;
                    files.append(fd)?;
                }
                d.set_item("files", files)?;
                d.set_item("metadata", c.metadata.display().to_string())?;
                d.set_item("log_dir", &c.log_dir)?;
                d.set_item("notes", &c.notes)?;
                let s = &c.skipped;
                let skipped = PyDict::new(py);
                skipped.set_item("unreadable_topics", s.unreadable_topics.clone())?;
                skipped.set_item("misfit_rows", s.misfit_rows.clone())?;
                skipped.set_item("orphan_rows", s.orphan_rows)?;
                skipped.set_item("unusable_messages", s.unusable_messages)?;
                skipped.set_item("damaged_bytes", s.damaged_bytes)?;
                skipped.set_item(
                    "ignored_appended_offsets",
                    s.ignored_appended_offsets.clone(),
                )?;
                d.set_item("skipped", skipped)?;
                let mut said: Vec<String> = check
                    .missing
                    .iter()
                    .filter(|m| m.lacking.contains(path))
                    .map(|m| format!("no topic `{}` in this log", m.topic))
                    .collect();
                said.extend(c.lines(&wanted, &window));
                d.set_item("said", said)?;
            }
            Err(e) => {
                d.set_item("ok", false)?;
                d.set_item("error", e.to_string())?;
            }
        }
        out.append(d)?;
    }
    Ok(out)
}

/// Runs the `ulog` tool with `argv` (the program name first); its exit code. The GIL is
/// released while it runs. `as_process`: the process is the tool (the package's `ulog`
/// command), and Ctrl-C or SIGTERM stop it as they stop the Rust binary
/// (`ulog_runtime::cli::handle_signals`: handlers set for the rest of the process's life).
#[pyfunction]
#[pyo3(signature = (argv, as_process=false))]
pub(crate) fn cli_main(py: Python<'_>, argv: Vec<std::ffi::OsString>, as_process: bool) -> u8 {
    if as_process {
        ulog_runtime::cli::handle_signals();
    }
    py.detach(|| ulog_runtime::cli::main(argv))
}

/// The names `ulog parquet --layout hive` gives the logs of `paths` converted together, in
/// order: each one's stem, made safe for a folder, `~2`, `~3`... after the first of a stem
/// (without regard to case).
#[pyfunction]
pub(crate) fn log_names(paths: Vec<PathBuf>) -> Vec<String> {
    let mut seen: std::collections::HashMap<String, u32> = std::collections::HashMap::new();
    paths
        .iter()
        .map(|p| {
            let stem = ulog_runtime::file_names::log_stem(p);
            let n = seen.entry(stem.to_lowercase()).or_insert(0);
            *n += 1;
            ulog_runtime::file_names::numbered("", &stem, "", *n)
        })
        .collect()
}

/// ` in the window from 1 s to 2 s` for the window of `start`/`end` seconds, `""` for none:
/// what `ulog parquet` adds to a message about missing rows. ValueError for a window
/// `Window::seconds` refuses.
#[pyfunction]
#[pyo3(signature = (start=None, end=None))]
pub(crate) fn window_words(start: Option<f64>, end: Option<f64>) -> PyResult<String> {
    Window::seconds(start, end)
        .map(|w| w.in_words())
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))
}

/// How often a long call looks for a signal Python's handlers have to run.
const SIGNAL_CHECK: Duration = Duration::from_millis(100);

/// Runs `work` on a thread of its own while this one, the GIL released, looks every
/// [`SIGNAL_CHECK`] for a signal whose Python handler raises (Ctrl-C's `KeyboardInterrupt`;
/// Python runs handlers on its main thread only, so from another thread nothing stops
/// `work`). Then `stop` is set for `work` to see, `work` is waited for (a second signal does
/// not cut the wait short), and the exception is returned; otherwise `work`'s result.
fn until_signal<T: Send>(
    py: Python<'_>,
    stop: &AtomicBool,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    std::thread::scope(|scope| {
        let (tx, mut rx) = mpsc::sync_channel(1);
        let worker = scope.spawn(move || {
            // The receiver waits for it while this thread lives.
            let _ = tx.send(work());
        });
        let mut raised = None;
        loop {
            // The receiver goes into the closure and back: the closure must be `Send`, and
            // a `Receiver` is not `Sync` (a reference to it is not `Send`). Once an exception
            // is taken there is nothing more to look for: the wait blocks.
            let wait = if raised.is_some() {
                Duration::MAX
            } else {
                SIGNAL_CHECK
            };
            let (got, back) = py.detach(move || (rx.recv_timeout(wait), rx));
            rx = back;
            match got {
                Ok(done) => return raised.map_or(Ok(done), Err),
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if raised.is_none()
                        && let Err(e) = py.check_signals()
                    {
                        stop.store(true, Ordering::Relaxed);
                        raised = Some(e);
                    }
                }
                // `work` panicked (PyO3 makes the panic an exception).
                Err(mpsc::RecvTimeoutError::Disconnected) => match worker.join() {
                    Err(panic) => std::panic::resume_unwind(panic),
                    Ok(()) => unreachable!("a worker that returned sent its result"),
                },
            }
        }
    })
}
