//! Values of the Rust reader as Python objects.

use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyList};
use ulog_runtime::Value;
use ulog_runtime::compat::pyulog::PyValue;
use ulog_runtime::read::ParamValue;
use ulog_runtime::value::Scalar;

/// A value as pyulog gives it: `int`, `float`, `bool`, `str` or `bytes`.
pub(crate) fn py_value<'py>(py: Python<'py>, v: &PyValue) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        PyValue::Int(i) => i.into_pyobject(py)?.into_any(),
        PyValue::UInt(u) => u.into_pyobject(py)?.into_any(),
        PyValue::Float(f) => f.into_pyobject(py)?.into_any(),
        PyValue::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        PyValue::Str(s) => s.into_pyobject(py)?.into_any(),
        PyValue::Bytes(b) => PyBytes::new(py, b).into_any(),
    })
}

/// A parameter's value: `int` or `float`.
pub(crate) fn param<'py>(py: Python<'py>, v: ParamValue) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        ParamValue::Int32(i) => i.into_pyobject(py)?.into_any(),
        ParamValue::Float(f) => f64::from(f).into_pyobject(py)?.into_any(),
    })
}

/// A scalar as the Python number (or `bool`) it holds.
pub(crate) fn scalar<'py>(py: Python<'py>, s: Scalar) -> PyResult<Bound<'py, PyAny>> {
    Ok(match s {
        Scalar::Int8(v) => v.into_pyobject(py)?.into_any(),
        Scalar::UInt8(v) => v.into_pyobject(py)?.into_any(),
        Scalar::Int16(v) => v.into_pyobject(py)?.into_any(),
        Scalar::UInt16(v) => v.into_pyobject(py)?.into_any(),
        Scalar::Int32(v) => v.into_pyobject(py)?.into_any(),
        Scalar::UInt32(v) => v.into_pyobject(py)?.into_any(),
        Scalar::Int64(v) => v.into_pyobject(py)?.into_any(),
        Scalar::UInt64(v) => v.into_pyobject(py)?.into_any(),
        Scalar::Float(v) => f64::from(v).into_pyobject(py)?.into_any(),
        Scalar::Double(v) => v.into_pyobject(py)?.into_any(),
        Scalar::Bool(v) => v.into_pyobject(py)?.to_owned().into_any(),
        Scalar::Char(v) => PyBytes::new(py, &[v]).into_any(),
    })
}

/// A value of the reader: a number, `str`, `bytes`, a list (arrays) or a dict (structs).
pub(crate) fn value<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Scalar(s) => scalar(py, *s)?,
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Bytes(b) => PyBytes::new(py, b).into_any(),
        Value::Array(items) => {
            let items: Vec<Bound<'py, PyAny>> = items
                .iter()
                .map(|i| value(py, i))
                .collect::<PyResult<_>>()?;
            PyList::new(py, items)?.into_any()
        }
        Value::Struct(fields) => {
            let d = pyo3::types::PyDict::new(py);
            for (k, f) in fields {
                d.set_item(k, value(py, f)?)?;
            }
            d.into_any()
        }
    })
}
