//! `Log`: a log over the Rust reader (memory-mapped for a path), its metadata as Python
//! objects, its topics as [`Table`]s: Arrow record batches handed over through the Arrow
//! PyCapsule interface (`__arrow_c_stream__`), so pyarrow, Polars and DuckDB take them
//! without a copy.

use std::sync::Arc;

use arrow_array::{RecordBatch, RecordBatchIterator};
use arrow_schema::SchemaRef;
use arrow_schema::ffi::FFI_ArrowSchema;
use numpy::IntoPyArray;
use pyo3::exceptions::{PyKeyError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyCapsule, PyDict, PyList, PyString};

use crate::errors::{ULogError, read_error};
use crate::values::{param, value};

/// A log read by the Rust reader: everything it recovers, nothing pyulog-shaped.
#[pyclass(frozen, module = "ulog._ulog", name = "Log")]
pub(crate) struct Log {
    log: Arc<ulog_runtime::Log<'static>>,
    name: String,
}

#[pymethods]
impl Log {
    /// Opens a log: a path (memory-mapped) or the file's bytes.
    #[staticmethod]
    fn open(py: Python<'_>, source: &Bound<'_, PyAny>) -> PyResult<Log> {
        if let Ok(bytes) = source.cast::<PyBytes>() {
            let data = bytes.as_bytes().to_vec();
            let log = py
                .detach(|| ulog_runtime::Log::from_vec(data))
                .map_err(|e| read_error("", &e))?;
            return Ok(Log {
                log: Arc::new(log),
                name: String::new(),
            });
        }
        let path: std::path::PathBuf = source.extract()?;
        let label = path.display().to_string();
        let log = py
            .detach(|| ulog_runtime::Log::open(&path))
            .map_err(|e| read_error(&label, &e))?;
        Ok(Log {
            log: Arc::new(log),
            name: path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
        })
    }

    /// The file's name (empty for bytes).
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// The header: version, start timestamp (µs), start as UTC text when it holds a date.
    #[getter]
    fn header<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let h = self.log.header();
        let d = PyDict::new(py);
        d.set_item("version", h.version)?;
        d.set_item("start_timestamp", h.start_timestamp)?;
        d.set_item("start_utc", h.start_utc().map(|t| t.to_string()))?;
        Ok(d)
    }

    /// The log's start as UTC text: the header's date when it holds one, else from the first
    /// GPS fix (as `metadata.json`'s `start_utc` and the Parquet files' `ulog.start_utc`),
    /// else None.
    /// The GIL is released while the GPS rows are read.
    #[getter]
    fn start_utc(&self, py: Python<'_>) -> Option<String> {
        let log = self.log.clone();
        py.detach(move || log.start_utc().map(|t| t.to_string()))
    }

    /// Info values by key (the whole key, spaces included).
    #[getter]
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for i in self.log.metadata().info() {
            d.set_item(&i.key, value(py, &i.value)?)?;
        }
        Ok(d)
    }

    /// Multi info values by key: a list of values, each the list of its parts.
    #[getter]
    fn multi_info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for m in self.log.metadata().multi_info() {
            let outer = PyList::empty(py);
            for parts in &m.values {
                let inner: Vec<Bound<'py, PyAny>> = parts
                    .iter()
                    .map(|v| value(py, v))
                    .collect::<PyResult<_>>()?;
                outer.append(PyList::new(py, inner)?)?;
            }
            d.set_item(&m.key, outer)?;
        }
        Ok(d)
    }

    /// Parameters as logging started.
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for p in self.log.metadata().initial_parameters() {
            d.set_item(&p.name, param(py, p.value)?)?;
        }
        Ok(d)
    }

    /// Parameter changes after the start: `(timestamp µs, name, value)`.
    #[getter]
    fn parameter_changes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let out = PyList::empty(py);
        for c in self.log.parameter_changes() {
            out.append((c.timestamp, &c.name, param(py, c.value)?))?;
        }
        Ok(out)
    }

    /// Default parameters: `(default_types bits, name, value)` in file order.
    #[getter]
    fn default_parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let out = PyList::empty(py);
        for p in self.log.metadata().default_parameters() {
            out.append((p.default_types, &p.name, param(py, p.value)?))?;
        }
        Ok(out)
    }

    /// Logged strings: `(timestamp µs, level byte, tag or None, text)`.
    #[getter]
    fn logged_messages<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let out = PyList::empty(py);
        for m in self.log.logged_messages() {
            out.append((m.timestamp, m.level_byte, m.tag, &m.text))?;
        }
        Ok(out)
    }

    /// Dropouts: `(timestamp µs, duration ms)`.
    #[getter]
    fn dropouts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let out = PyList::empty(py);
        for d in self.log.dropouts() {
            out.append((d.timestamp, d.duration_ms))?;
        }
        Ok(out)
    }

    /// What recovery skipped or found odd: `(byte offset, what)`.
    #[getter]
    fn diagnostics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let out = PyList::empty(py);
        for d in self.log.diagnostics() {
            out.append((d.offset, d.kind.to_string()))?;
        }
        Ok(out)
    }

    /// The logged messages and PX4 events as `ulog messages` lists them:
    /// `(timestamp µs, level, text)`; with `tagged`, also the tagged strings (`C`
    /// messages, which `ulog_messages` leaves out), their text as `[tag N] text`.
    #[pyo3(signature = (tagged = false))]
    fn messages<'py>(&self, py: Python<'py>, tagged: bool) -> PyResult<Bound<'py, PyList>> {
        let m = if tagged {
            ulog_runtime::events::all_messages(&self.log)
        } else {
            ulog_runtime::events::messages(&self.log)
        };
        let out = PyList::empty(py);
        for l in &m.lines {
            match l.kind {
                ulog_runtime::events::MessageKind::Tagged(t) => {
                    out.append((l.timestamp, l.level, format!("[tag {t}] {}", l.text)))?
                }
                _ => out.append((l.timestamp, l.level, &l.text))?,
            }
        }
        Ok(out)
    }

    /// PX4 events, decoded with the metadata the log embeds: dicts of `timestamp`, `id`,
    /// `name` and `message` (None when the log has no metadata or the id is unknown),
    /// `log_level` (external), `arguments` (name to the text its placeholder shows).
    fn events<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let events = self.log.events();
        let out = PyList::empty(py);
        for row in &events.rows {
            let d = PyDict::new(py);
            d.set_item("timestamp", row.timestamp)?;
            d.set_item("id", row.id)?;
            d.set_item("log_level", row.log_levels & 0x0F)?;
            let decoded = events
                .metadata
                .as_ref()
                .ok()
                .and_then(|m| ulog_runtime::events::decode(row, &m.definitions).ok());
            match decoded {
                Some(e) => {
                    d.set_item("name", format!("{}/{}", e.namespace, e.name))?;
                    d.set_item("message", e.message.ok())?;
                    let args = PyDict::new(py);
                    for (name, _, shown) in &e.arguments {
                        args.set_item(name, shown.as_ref().ok())?;
                    }
                    d.set_item("arguments", args)?;
                }
                None => {
                    d.set_item("name", py.None())?;
                    d.set_item("message", py.None())?;
                    d.set_item("arguments", PyDict::new(py))?;
                }
            }
            out.append(d)?;
        }
        Ok(out)
    }

    /// Every topic instance with rows: dicts of `name`, `multi_id`, `rows`,
    /// `first_timestamp`, `last_timestamp` (µs), sorted by name and instance.
    fn topics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let out = PyList::empty(py);
        for t in self.log.topics() {
            let d = PyDict::new(py);
            d.set_item("name", &t.name)?;
            d.set_item("multi_id", t.multi_id)?;
            d.set_item("rows", t.rows)?;
            d.set_item("first_timestamp", t.first_timestamp)?;
            d.set_item("last_timestamp", t.last_timestamp)?;
            out.append(d)?;
        }
        Ok(out)
    }

    /// One topic instance's columns as a [`Table`]: only `columns` if given, in that order;
    /// only the rows of the window from `start` to `end` (seconds, as `ulog csv --start
    /// --end` takes them). The GIL is released while the columns are made (on several
    /// cores for an instance of 65,536 rows or more: `Log::columns` in Rust).
    #[pyo3(signature = (topic, multi_id=0, columns=None, start=None, end=None))]
    fn table(
        &self,
        py: Python<'_>,
        topic: &str,
        multi_id: u8,
        columns: Option<Vec<String>>,
        start: Option<f64>,
        end: Option<f64>,
    ) -> PyResult<Table> {
        let window = ulog_runtime::columns::Window::seconds(start, end)
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
        let log = self.log.clone();
        let topic_name = topic.to_owned();
        let made = py.detach(move || make_table(&log, &topic_name, multi_id, columns, window));
        made.map_err(|e| match e {
            TableError::Columns(e) => PyKeyError::new_err(e.to_string()),
            TableError::NoColumn(m) => PyKeyError::new_err(m),
            TableError::Arrow(m) => ULogError::new_err(m),
        })
    }

    /// Every topic instance's columns as [`Table`]s, made in one pass over the file on
    /// every core (faster than a `table()` call per instance); a table's record batches are
    /// the parts the cores made.
    fn tables(&self, py: Python<'_>) -> PyResult<Vec<Table>> {
        let log = self.log.clone();
        let made = py.detach(move || {
            log.all_column_parts()
                .into_iter()
                .map(|(topic, multi_id, parts)| {
                    // Each part a record batch: the table's chunks, not copied together.
                    let schema = ulog_runtime::columns::arrow::schema(parts[0].spec(), &topic);
                    let rows = parts.iter().map(|p| p.rows()).sum();
                    let batches = parts
                        .into_iter()
                        .map(|p| ulog_runtime::columns::arrow::record_batch(&schema, p))
                        .collect::<Result<Vec<_>, _>>()?;
                    Ok::<_, arrow_schema::ArrowError>(Table {
                        schema: batches[0].schema(),
                        batches,
                        rows,
                        topic,
                        multi_id,
                    })
                })
                .collect::<Result<Vec<_>, _>>()
        });
        made.map_err(|e| ULogError::new_err(e.to_string()))
    }

    /// The flight analysis as JSON text (`ulog analyze --json`).
    fn analysis_json(&self, py: Python<'_>) -> PyResult<String> {
        let log = self.log.clone();
        let a = py.detach(move || ulog_runtime::analysis::Analysis::of_log(&log));
        serde_json::to_string(&a).map_err(|e| ULogError::new_err(e.to_string()))
    }

    fn __repr__(&self) -> String {
        let (instances, rows) = (self.log.topics().len(), self.log.row_count());
        format!(
            "<ulog.Log {} ({instances} topic instance{}, {rows} row{})>",
            if self.name.is_empty() {
                "(bytes)"
            } else {
                &self.name
            },
            if instances == 1 { "" } else { "s" },
            if rows == 1 { "" } else { "s" },
        )
    }
}

enum TableError {
    Columns(ulog_runtime::columns::ColumnsError),
    NoColumn(String),
    Arrow(String),
}

fn make_table(
    log: &ulog_runtime::Log<'_>,
    topic: &str,
    multi_id: u8,
    columns: Option<Vec<String>>,
    window: ulog_runtime::columns::Window,
) -> Result<Table, TableError> {
    let cols = log.columns(topic, multi_id).map_err(TableError::Columns)?;
    let names: Vec<String> = cols.names().map(str::to_owned).collect();
    let indices: Vec<usize> = match &columns {
        None => (0..names.len()).collect(),
        Some(wanted) => wanted
            .iter()
            .map(|w| {
                names.iter().position(|n| n == w).ok_or_else(|| {
                    TableError::NoColumn(format!(
                        "`{topic}` #{multi_id} has no column `{w}`{}",
                        ulog_runtime::schema::did_you_mean(&ulog_runtime::schema::closest_names(
                            w,
                            names.iter().map(String::as_str)
                        ))
                    ))
                })
            })
            .collect::<Result<_, _>>()?,
    };
    let cols = if window.is_bounded() {
        cols.window(&window)
    } else {
        cols
    };
    let schema = ulog_runtime::columns::arrow::schema(cols.spec(), topic);
    let rows = cols.rows();
    let batch = ulog_runtime::columns::arrow::record_batch(&schema, cols)
        .and_then(|b| b.project(&indices))
        .map_err(|e| TableError::Arrow(e.to_string()))?;
    Ok(Table {
        schema: batch.schema(),
        batches: vec![batch],
        rows,
        topic: topic.to_owned(),
        multi_id,
    })
}

/// A topic instance's columns as Arrow record batches (`__arrow_c_stream__`).
#[pyclass(frozen, module = "ulog._ulog", name = "Table")]
pub(crate) struct Table {
    schema: SchemaRef,
    batches: Vec<RecordBatch>,
    rows: usize,
    topic: String,
    multi_id: u8,
}

#[pymethods]
impl Table {
    /// The Arrow PyCapsule stream of the table's record batches (`requested_schema` is
    /// not used: the table has one schema).
    #[pyo3(signature = (requested_schema=None))]
    fn __arrow_c_stream__<'py>(
        &self,
        py: Python<'py>,
        requested_schema: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyCapsule>> {
        let _ = requested_schema;
        let reader = RecordBatchIterator::new(
            self.batches.clone().into_iter().map(Ok),
            self.schema.clone(),
        );
        let stream = arrow_array::ffi_stream::FFI_ArrowArrayStream::new(Box::new(reader));
        PyCapsule::new_with_value(py, stream, c"arrow_array_stream")
    }

    /// The Arrow PyCapsule of the table's schema.
    fn __arrow_c_schema__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyCapsule>> {
        let schema = FFI_ArrowSchema::try_from(self.schema.as_ref())
            .map_err(|e| ULogError::new_err(e.to_string()))?;
        PyCapsule::new_with_value(py, schema, c"arrow_schema")
    }

    /// Rows.
    #[getter]
    fn num_rows(&self) -> usize {
        self.rows
    }

    /// The column names, in order.
    #[getter]
    fn column_names(&self) -> Vec<String> {
        self.schema
            .fields()
            .iter()
            .map(|f| f.name().clone())
            .collect()
    }

    /// The topic.
    #[getter]
    fn topic(&self) -> &str {
        &self.topic
    }

    /// The instance.
    #[getter]
    fn multi_id(&self) -> u8 {
        self.multi_id
    }

    /// The columns as a dict of numpy arrays (text columns as lists of str).
    fn numpy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        use arrow_array::{Array, cast::AsArray, types::*};
        use arrow_schema::DataType as D;
        let d = PyDict::new(py);
        for (i, field) in self.schema.fields().iter().enumerate() {
            let mut parts: Vec<Bound<'py, PyAny>> = Vec::new();
            for b in &self.batches {
                let a = b.column(i);
                macro_rules! prim {
                    ($t:ty) => {
                        a.as_primitive::<$t>()
                            .values()
                            .to_vec()
                            .into_pyarray(py)
                            .into_any()
                    };
                }
                let part = match field.data_type() {
                    D::Int8 => prim!(Int8Type),
                    D::UInt8 => prim!(UInt8Type),
                    D::Int16 => prim!(Int16Type),
                    D::UInt16 => prim!(UInt16Type),
                    D::Int32 => prim!(Int32Type),
                    D::UInt32 => prim!(UInt32Type),
                    D::Int64 => prim!(Int64Type),
                    D::UInt64 => prim!(UInt64Type),
                    D::Float32 => prim!(Float32Type),
                    D::Float64 => prim!(Float64Type),
                    D::Boolean => {
                        let v: Vec<bool> = a.as_boolean().iter().map(|x| x == Some(true)).collect();
                        v.into_pyarray(py).into_any()
                    }
                    D::Utf8 => {
                        let s = a.as_string::<i32>();
                        let v: Vec<&str> = (0..s.len()).map(|k| s.value(k)).collect();
                        PyList::new(py, v)?.into_any()
                    }
                    other => {
                        return Err(PyValueError::new_err(format!(
                            "column `{}`: no numpy form for {other}",
                            field.name()
                        )));
                    }
                };
                parts.push(part);
            }
            let value = match parts.len() {
                1 => parts.pop().expect("one"),
                _ => {
                    let np = py.import("numpy")?;
                    np.call_method1("concatenate", (PyList::new(py, parts)?,))?
                }
            };
            d.set_item(PyString::new(py, field.name()), value)?;
        }
        Ok(d)
    }

    fn __len__(&self) -> usize {
        self.rows
    }

    fn __repr__(&self) -> String {
        let (rows, columns) = (self.rows, self.schema.fields().len());
        format!(
            "<ulog.Table {} #{}: {rows} row{}, {columns} column{}>",
            self.topic,
            self.multi_id,
            if rows == 1 { "" } else { "s" },
            if columns == 1 { "" } else { "s" },
        )
    }
}
