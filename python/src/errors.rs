//! The package's exceptions: one hierarchy under `ULogError`, each carrying the Rust
//! reader's message (the file, the byte offset).

use pyo3::PyErr;
use pyo3::create_exception;
use pyo3::exceptions::PyException;
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
create_exception!(
    ulog,
    ULogIOError,
    ULogError,
    "Reading or writing a file failed."
);

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
        ReadError::Io(_) => ULogIOError::new_err(message),
        _ => ULogError::new_err(message),
    }
}
