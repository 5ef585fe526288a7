//! `read_pyulog`: a log as pyulog reads it (`ulog_runtime::compat::pyulog`), as a dict of
//! the attributes `ulog.ULog` sets; each dataset's rows as one numpy `uint8` array that
//! owns the bytes the reader collected (no copy), which `ulog.ULog` views with its dtype.

use numpy::PyArray1;
use pyo3::exceptions::{PyRecursionError, PyUnicodeDecodeError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList, PyString, PyTuple};
use ulog_runtime::compat::pyulog::{self, NameFilter, PyulogError, PyulogFile, PyulogOptions};

use crate::errors::{NotAULogError, UnsupportedFlagError, read_error};
use crate::values::py_value;

/// Reads `source` (a path, or the file's bytes from its current position `base_offset`)
/// as pyulog 1.3.0 does; `filter` is None, a list of names or a str (pyulog's substring
/// test); `recover`: the datasets of every row the Rust reader recovers instead of
/// pyulog's. The GIL is released while the file is read.
#[pyfunction]
#[pyo3(signature = (source, filter=None, strict=false, header_only=false, base_offset=0, recover=false))]
pub(crate) fn read_pyulog<'py>(
    py: Python<'py>,
    source: &Bound<'py, PyAny>,
    filter: Option<&Bound<'py, PyAny>>,
    strict: bool,
    header_only: bool,
    base_offset: u64,
    recover: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let filter = match filter {
        None => NameFilter::All,
        Some(f) if f.is_instance_of::<PyString>() => NameFilter::Substring(f.extract()?),
        Some(f) => NameFilter::Names(f.extract()?),
    };
    let options = PyulogOptions {
        filter,
        strict_strings: strict,
        header_only,
        base_offset,
    };
    let recover = recover && !header_only;
    // With every recovered row, the whole-file reader's rows in pyulog's datasets.
    let recovered = |bytes: &[u8], mut f: PyulogFile| {
        if recover && let Ok(log) = ulog_runtime::Log::from_slice(bytes) {
            f.data = pyulog::recovered_datasets(&log, &f, &options.filter);
        }
        f
    };
    let path = source.cast::<PyString>().ok().map(|p| p.to_string());
    let read = if let Some(path) = &path {
        py.detach(|| {
            trimmed(|| {
                let file = ulog_runtime::read::MappedFile::open(path).map_err(Err)?;
                let f = pyulog::read_mapped(&file, &options).map_err(Ok)?;
                Ok(recovered(&file, f))
            })
        })
    } else {
        let bytes = source.cast::<PyBytes>()?.as_bytes();
        py.detach(|| trimmed(|| Ok(recovered(bytes, pyulog::read(bytes, &options).map_err(Ok)?))))
    };
    match read {
        Ok(f) => to_dict(py, f),
        Err(Err(e)) => Err(read_error(path.as_deref().unwrap_or_default(), &e)),
        Err(Ok(e)) => Err(raise(py, e)),
    }
}

/// Runs `read` between two [`trim_heap`]s: before reading and again before the Python
/// objects are made, so that a `ULog` peaks lower (the rows come on top of less).
fn trimmed<T>(read: impl FnOnce() -> T) -> T {
    trim_heap();
    let out = read();
    trim_heap();
    out
}

/// Gives the heap's free pages back to the system (the whole process's: what the
/// interpreter freed, after its imports, say, as well as what reading left). Called without
/// the GIL.
fn trim_heap() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[allow(unsafe_code)]
    // SAFETY: malloc_trim only returns free memory of the allocator to the system.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// pyulog's exception for what stopped it.
fn raise(py: Python<'_>, e: PyulogError) -> PyErr {
    match e {
        PyulogError::Header(m) => NotAULogError::new_err(m),
        PyulogError::IncompatibleFlag => UnsupportedFlagError::new_err(e.to_string()),
        PyulogError::Recursion(_) => PyRecursionError::new_err(e.to_string()),
        PyulogError::Unicode {
            bytes,
            start,
            end,
            reason,
        } => match PyUnicodeDecodeError::new(
            py,
            c"utf-8",
            &bytes,
            start..end,
            &std::ffi::CString::new(reason).unwrap_or_default(),
        ) {
            Ok(err) => PyErr::from_value(err.into_any()),
            Err(e) => e,
        },
        _ => crate::errors::ULogError::new_err(e.to_string()),
    }
}

fn to_dict(py: Python<'_>, f: PyulogFile) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("file_corrupt", f.file_corrupt)?;
    d.set_item("start_timestamp", f.start_timestamp)?;
    d.set_item("last_timestamp", f.last_timestamp)?;
    let info = PyList::empty(py);
    for (k, t, v) in &f.info {
        info.append((k, t, py_value(py, v)?))?;
    }
    d.set_item("info", info)?;
    let multi = PyList::empty(py);
    for (k, t, lists) in &f.info_multiple {
        let outer = PyList::empty(py);
        for l in lists {
            let inner: Vec<Bound<'_, PyAny>> =
                l.iter().map(|v| py_value(py, v)).collect::<PyResult<_>>()?;
            outer.append(PyList::new(py, inner)?)?;
        }
        multi.append((k, t, outer))?;
    }
    d.set_item("info_multiple", multi)?;
    let params = |list: &[(String, pyulog::PyValue)]| -> PyResult<Bound<'_, PyList>> {
        let out = PyList::empty(py);
        for (k, v) in list {
            out.append((k, py_value(py, v)?))?;
        }
        Ok(out)
    };
    d.set_item("initial_parameters", params(&f.initial_parameters)?)?;
    let defaults = PyList::empty(py);
    for (bit, list) in &f.default_parameters {
        defaults.append((bit, params(list)?))?;
    }
    d.set_item("default_parameters", defaults)?;
    let changed = PyList::empty(py);
    for (t, k, v) in &f.changed_parameters {
        changed.append(PyTuple::new(
            py,
            [
                t.into_pyobject(py)?.into_any(),
                k.into_pyobject(py)?.into_any(),
                py_value(py, v)?,
            ],
        )?)?;
    }
    d.set_item("changed_parameters", changed)?;
    let formats = PyList::empty(py);
    for fmt in &f.formats {
        let fields = PyList::empty(py);
        for (t, n, name) in &fmt.fields {
            fields.append((t, n, name))?;
        }
        formats.append((&fmt.name, fields))?;
    }
    d.set_item("formats", formats)?;
    let logged = PyList::empty(py);
    for m in &f.logged {
        logged.append((m.level, m.timestamp, &m.message))?;
    }
    d.set_item("logged", logged)?;
    let tagged = PyList::empty(py);
    for (tag, list) in &f.tagged {
        let msgs = PyList::empty(py);
        for m in list {
            msgs.append((m.level, m.tag, m.timestamp, &m.message))?;
        }
        tagged.append((tag, msgs))?;
    }
    d.set_item("tagged", tagged)?;
    d.set_item("dropouts", &f.dropouts)?;
    let data = PyList::empty(py);
    for ds in f.data {
        let fields = PyList::empty(py);
        for (name, ty) in &ds.fields {
            fields.append((name, ty))?;
        }
        let row_size = ds.row_size;
        let rows = PyArray1::from_vec(py, ds.rows);
        data.append((
            ds.name,
            ds.multi_id,
            ds.msg_id,
            fields,
            ds.timestamp_idx,
            rows,
            row_size,
        ))?;
    }
    d.set_item("data", data)?;
    d.set_item("filtered_ids", &f.filtered_ids)?;
    d.set_item("missing_ids", &f.missing_ids)?;
    d.set_item("file_version", f.file_version)?;
    // Lists of ints, as pyulog's (a `Vec<u8>` would become `bytes`).
    let ints = |b: &[u8; 8]| b.iter().map(|&x| u32::from(x)).collect::<Vec<u32>>();
    d.set_item("compat_flags", ints(&f.compat_flags))?;
    d.set_item("incompat_flags", ints(&f.incompat_flags))?;
    d.set_item("appended_offsets", &f.appended_offsets)?;
    d.set_item("has_sync", f.has_sync)?;
    d.set_item("sync_seq_cnt", f.sync_seq_cnt)?;
    d.set_item("printed", &f.printed)?;
    Ok(d)
}
