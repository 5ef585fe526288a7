//! The package's exceptions: one hierarchy under `ULogError`, each carrying the Rust
//! reader's message (the file, the byte offset).

use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyOSError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};
use ulog_runtime::ReadError;

create_exception!(
    ulog,
    ULogError,
    PyException,
    "A log could not be read, written or converted (pyulog's `ULogException`)."
);
create_exception!(
    ulog,
    NotAULogError,
    ULogError,
    "The input is not a ULog file (too short, or not the ULog magic)."
);
create_exception!(
    ulog,
    UnsupportedFlagError,
    ULogError,
    "The log sets an incompatible flag this reader does not know (pyulog's \
     `ULogIncompatibleFlagException`)."
);
/// `ulog.ULogIOError`: reading or writing a file failed. Both a [`ULogError`] and an
/// `OSError` (so `except OSError` catches it, as it catches pyulog's), which a type made by
/// `create_exception!` (one base) cannot be: made once per interpreter with Python's `type`.
static IO_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// The `ULogIOError` type.
pub(crate) fn io_error_type(py: Python<'_>) -> PyResult<&Bound<'_, PyType>> {
    IO_ERROR
        .get_or_try_init(py, || {
            let bases = PyTuple::new(py, [py.get_type::<ULogError>(), py.get_type::<PyOSError>()])?;
            let namespace = PyDict::new(py);
            namespace.set_item("__module__", "ulog")?;
            // The message as given: `OSError`'s own would be `[Errno 2] None: 'path'` once
            // `filename` is set.
            namespace.set_item(
                "__str__",
                py.get_type::<PyException>()
                    .getattr("__base__")?
                    .getattr("__str__")?,
            )?;
            namespace.set_item(
                "__doc__",
                "Reading or writing a file failed (an `OSError` too: `errno` and `filename` \
                 set when known).",
            )?;
            let made = py
                .get_type::<PyType>()
                .call1(("ULogIOError", bases, namespace))?;
            Ok::<_, PyErr>(made.cast_into::<PyType>()?.unbind())
        })
        .map(|t| t.bind(py))
}

/// A `ULogIOError` with `message`, and its `errno` and `filename` when given.
pub(crate) fn io_error(message: String, errno: Option<i32>, filename: Option<&str>) -> PyErr {
    Python::attach(|py| {
        let ty = match io_error_type(py) {
            Ok(ty) => ty.clone(),
            Err(e) => return e,
        };
        let err = PyErr::from_type(ty, (message,));
        let value = err.value(py);
        let set = value
            .setattr("errno", errno)
            .and_then(|()| value.setattr("filename", filename));
        match set {
            Ok(()) => err,
            Err(e) => e,
        }
    })
}

/// The Python exception of a read error, its message prefixed by `label` (the file).
pub(crate) fn read_error(label: &str, e: &ReadError) -> PyErr {
    let message = if label.is_empty() {
        e.to_string()
    } else {
        format!("{label}: {e}")
    };
    match e {
        ReadError::NotULog | ReadError::TooShort { .. } => NotAULogError::new_err(message),
        ReadError::IncompatibleFlags { .. } => UnsupportedFlagError::new_err(message),
        ReadError::Io(io) => io_error(
            message,
            io.raw_os_error(),
            (!label.is_empty()).then_some(label),
        ),
        _ => ULogError::new_err(message),
    }
}
