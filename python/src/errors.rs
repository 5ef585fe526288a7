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
                 set when known). Raised as the subclass that is also the `OSError` subclass \
                 of its errno, as Python's own `OSError` is: a missing log is a \
                 `ULogFileNotFoundError`, which `except FileNotFoundError` catches.",
            )?;
            let made = py
                .get_type::<PyType>()
                .call1(("ULogIOError", bases, namespace))?;
            let made = made.cast_into::<PyType>()?;
            pickled_whole(py, &made)?;
            Ok::<_, PyErr>(made.unbind())
        })
        .map(|t| t.bind(py))
}

/// Per `OSError` subclass Python raises for an errno (`FileNotFoundError`, `PermissionError`,
/// `IsADirectoryError`, ...), the `ULogIOError` subclass that is that one too
/// (`ULogFileNotFoundError`, ...): made on first use, once per interpreter.
static IO_ERROR_KINDS: PyOnceLock<Py<PyDict>> = PyOnceLock::new();

/// The type of a `ULogIOError` of `errno`: as Python's own `OSError(errno, ...)` is made as
/// the subclass of its errno, so that `except FileNotFoundError` catches a missing log, a
/// subclass of both `ULogIOError` and that one; `ULogIOError` itself for an errno Python
/// maps to no subclass, or none.
fn io_error_class(py: Python<'_>, errno: Option<i32>) -> PyResult<Bound<'_, PyType>> {
    let base = io_error_type(py)?;
    let Some(errno) = errno else {
        return Ok(base.clone());
    };
    let os_error = py.get_type::<PyOSError>();
    let builtin = os_error.call1((errno, ""))?.get_type();
    if builtin.is(&os_error) {
        return Ok(base.clone());
    }
    let kinds = IO_ERROR_KINDS
        .get_or_init(py, || PyDict::new(py).unbind())
        .bind(py);
    if let Some(made) = kinds.get_item(&builtin)? {
        return Ok(made.cast_into::<PyType>()?);
    }
    let name = format!("ULog{}", builtin.name()?);
    let namespace = PyDict::new(py);
    namespace.set_item("__module__", "ulog")?;
    namespace.set_item(
        "__doc__",
        format!(
            "A `ULogIOError` that is a `{}` too, as Python's own `OSError` of its errno is.",
            builtin.name()?
        ),
    )?;
    let bases = PyTuple::new(py, [base.as_any(), builtin.as_any()])?;
    let made = py
        .get_type::<PyType>()
        .call1((name, bases, namespace))?
        .cast_into::<PyType>()?;
    pickled_whole(py, &made)?;
    kinds.set_item(&builtin, &made)?;
    Ok(made)
}

/// Has `pickle` and `copy` keep an I/O error's message, `errno` and `filename` (through
/// `copyreg`: `BaseException`'s own reduction keeps the message only).
fn pickled_whole(py: Python<'_>, ty: &Bound<'_, PyType>) -> PyResult<()> {
    let reduce = wrap_pyfunction!(reduce_io_error, py)?;
    py.import("copyreg")?.call_method1("pickle", (ty, reduce))?;
    Ok(())
}

/// `copyreg`'s reduction of a `ULogIOError`: rebuilt by [`rebuild_io_error`].
#[pyfunction]
fn reduce_io_error<'py>(error: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyTuple>> {
    let py = error.py();
    // The module's function, which `pickle` finds by its module and name.
    let rebuild = py.import("ulog._ulog")?.getattr("_rebuild_io_error")?;
    let args = (
        error.str()?,
        error.getattr("errno")?,
        error.getattr("filename")?,
    );
    PyTuple::new(py, [rebuild.into_any(), args.into_pyobject(py)?.into_any()])
}

/// A `ULogIOError` as [`io_error`] makes it (the unpickling of one).
#[pyfunction]
#[pyo3(name = "_rebuild_io_error")]
fn rebuild_io_error(
    py: Python<'_>,
    message: String,
    errno: Option<i32>,
    filename: Option<String>,
) -> PyResult<Py<PyAny>> {
    Ok(io_error(message, errno, filename.as_deref())
        .into_value(py)
        .into_any())
}

/// Adds what unpickling an I/O error needs to the extension module.
pub(crate) fn add_to(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(rebuild_io_error, m)?)
}

/// A `ULogIOError` with `message`, and its `errno` and `filename` when given; of the
/// subclass for its errno ([`io_error_class`]).
pub(crate) fn io_error(message: String, errno: Option<i32>, filename: Option<&str>) -> PyErr {
    Python::attach(|py| {
        let ty = match io_error_class(py, errno) {
            Ok(ty) => ty,
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

/// The errno of an I/O error: the system's, else (a refusal of the reader's own, such as
/// a folder given for a log) the one Python's `errno` module gives its kind.
fn errno_of(io: &std::io::Error) -> Option<i32> {
    io.raw_os_error().or_else(|| {
        let name = match io.kind() {
            std::io::ErrorKind::NotFound => "ENOENT",
            std::io::ErrorKind::PermissionDenied => "EACCES",
            std::io::ErrorKind::IsADirectory => "EISDIR",
            std::io::ErrorKind::NotADirectory => "ENOTDIR",
            _ => return None,
        };
        Python::attach(|py| {
            let errno = py.import("errno").ok()?.getattr(name).ok()?;
            errno.extract().ok()
        })
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
        ReadError::Io(io) => io_error(message, errno_of(io), (!label.is_empty()).then_some(label)),
        _ => ULogError::new_err(message),
    }
}
