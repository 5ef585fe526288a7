//! The native part of the Python package `ulog` (`ulog._ulog`): pyulog's data model read by
//! `ulog_runtime::compat::pyulog` (module `compat`), logs over the Rust reader with their topics
//! as Arrow streams (module `log`), the Parquet converter and the command-line tool (module `tools`).
//! The Python modules in `python/ulog/` build the public API on these.

use pyo3::prelude::*;

mod compat;
mod errors;
mod log;
mod tools;
mod values;

/// The extension module.
#[pymodule]
fn _ulog(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("ULogError", py.get_type::<errors::ULogError>())?;
    m.add("NotAULogError", py.get_type::<errors::NotAULogError>())?;
    m.add(
        "UnsupportedFlagError",
        py.get_type::<errors::UnsupportedFlagError>(),
    )?;
    m.add("ULogIOError", errors::io_error_type(py)?)?;
    errors::add_to(m)?;
    m.add_function(wrap_pyfunction!(compat::read_pyulog, m)?)?;
    m.add_class::<log::Log>()?;
    m.add_class::<log::Table>()?;
    m.add_function(wrap_pyfunction!(tools::to_parquet, m)?)?;
    m.add_function(wrap_pyfunction!(tools::window_words, m)?)?;
    m.add_function(wrap_pyfunction!(tools::cli_main, m)?)?;
    m.add_function(wrap_pyfunction!(tools::log_names, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    load_numpy_api(m.py())
}

/// Loads numpy's C API now rather than at the first array a read makes. Loading it runs
/// Python code (numpy's version check), and a signal handler that raises there (a load
/// timeout's `SIGALRM`, as Flight Review sets one) made the numpy crate panic in the middle
/// of the first `ULog(...)`: a `PanicException`, which `except Exception` does not catch,
/// instead of the handler's exception. Here such a failure is an `ImportError`.
fn load_numpy_api(py: Python<'_>) -> PyResult<()> {
    // The lightest call that loads it (no array: no more of numpy's code touched than a
    // read touches anyway).
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        numpy::npyffi::is_numpy_2(py);
    }))
    .map_err(|_| {
        pyo3::exceptions::PyImportError::new_err("ulog: numpy's C API could not be loaded")
    })
}
