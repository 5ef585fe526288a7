//! Parquet files of topic instances (feature `parquet`, parquet-rs 60 with ZSTD): one file
//! per topic instance, its columns as [`columns::arrow`](super::arrow) types them, and the
//! log's identity in the file's key-value metadata.
//!
//! - [`write_topic`]: one topic instance of a whole-file [`Log`] to any writer.
//! - [`Converter`]: whole logs to a folder in one streaming pass each (memory bounded by
//!   [`ParquetOptions::buffer_bytes`], not by the log), with a `metadata.json` per log, in
//!   one of two [`Layout`]s; many logs in parallel ([`Converter::convert_files`]).
//!
//! Every file's key-value metadata (what DuckDB's `parquet_kv_metadata` and pyarrow's
//! `pyarrow.parquet.read_metadata(path).metadata` show; the stored Arrow schema's own
//! metadata, pyarrow's `schema.metadata`, holds only `ulog.topic` and `ulog.format`) holds,
//! each key only when the log has its value:
//!
//! | key | value |
//! |---|---|
//! | `ulog.file_name` | the log's file name |
//! | `ulog.sha256` | SHA-256 of the whole log file, hex |
//! | `ulog.sys_name`, `ulog.ver_sw`, `ulog.ver_hw` | those info values, when the log has them |
//! | `ulog.start_timestamp` | the header's start time, µs |
//! | `ulog.start_utc` | the start as a UTC date, from the header when it holds one, otherwise from the first GPS fix (`time_utc_usec` of `vehicle_gps_position` or `sensor_gps` from 2000 to 2100: [`GpsClock`]) |
//! | `ulog.topic`, `ulog.multi_id`, `ulog.format` | the table's topic, instance and format |
//!
//! The Arrow schema stored with the file also carries each column's ULog type
//! (`ulog.type`).
//!
//! Column chunks are ZSTD-compressed pages of at most 1 MiB of values (those of narrower
//! integers, booleans and text may pass it by a few KiB: parquet-rs's writer checks the
//! limit after each batch): PLAIN values, but DELTA_BINARY_PACKED for `INT64` columns
//! (timestamps and other 64-bit integers, whose deltas are small); every reader of Parquet
//! reads both (pyarrow, DuckDB, Polars, Spark). Padding fields are left out.

mod chunk;
mod convert;
mod encode;
mod fleet;
mod int64;
mod statistics;
#[cfg(test)]
mod tests;

use std::io::Write;

use parquet::arrow::ArrowWriter;
use parquet::basic::{Compression, ZstdLevel};
use parquet::errors::ParquetError;
use parquet::file::metadata::KeyValue;
use parquet::file::properties::{EnabledStatistics, WriterProperties};
use parquet::file::writer::SerializedFileWriter;

pub use convert::{Conversion, ConvertError, Converter, WrittenFile};

pub use fleet::Layout;

use super::{ColumnBuilder, ColumnSpec, Columns, Window};
pub use crate::read::GpsClock;
use crate::read::{Log, Metadata};

/// How Parquet files are written.
#[derive(Debug, Clone, PartialEq)]
pub struct ParquetOptions {
    /// ZSTD level (1, the parquet-rs default, to 22; negative levels are faster still).
    /// Default 1.
    pub zstd_level: i32,
    /// Most rows in one row group. Default 1,048,576 (2^20).
    pub row_group_rows: usize,
    /// Memory for the rows waiting for their row group, all tables of one log together
    /// (the bytes the rows take once columns): when they pass it, the table holding most
    /// bytes per column is encoded and written as a row group. Where row groups fall is
    /// decided from the rows as they are read, not from how far the encoding threads have
    /// got: the same log and options give the same files, byte for byte, on any number of
    /// threads. A conversion's memory is this, plus while a row group is encoded one
    /// column chunk's encoded pages at a time (row groups are encoded a column at a time)
    /// and a ZSTD context and a 1 MiB page buffer per thread that encodes, plus per table
    /// the batch being filled ([`ParquetOptions::batch_bytes`]) and the footer metadata of
    /// its row groups so far, plus what the log says besides its rows (formats, parameters,
    /// logged messages, parameter changes, dropouts: kept for `metadata.json`), plus the
    /// flight analysis's state when it is on. On the 400 MB benchmark log (70 tables) the whole process
    /// peaks at about 54 MiB with the default 16 MiB (on two cores, about 6 MiB of it
    /// copies of the file waiting to be hashed). Default 16 MiB.
    pub buffer_bytes: usize,
    /// Row data collected per topic instance before it is made an Arrow record batch (at
    /// least one row). Default 64 KiB.
    pub batch_bytes: usize,
    /// Dictionary encoding (off: flight data rarely repeats enough to gain from it, and
    /// dictionaries hold memory). With it on, parquet-rs holds a column chunk's
    /// dictionary-encoded pages until the chunk closes, before their compression: a chunk's
    /// encoded size on top of the memory [`ParquetOptions::buffer_bytes`] describes.
    /// Default off.
    pub dictionary: bool,
    /// Min/max statistics per page (the column index) as well as per row group. Default on.
    pub page_statistics: bool,
    /// Only these topics (all if empty, the default).
    pub topics: Vec<String>,
    /// Only the rows of this window. Default: the whole log.
    pub window: Window,
    /// Where the files of a conversion go. Default [`Layout::PerLog`].
    pub layout: Layout,
    /// The flight analysis ([`crate::analysis`]) in `metadata.json` (under `analysis`), as
    /// PX4's Flight Review converter writes its own. Default on.
    pub analysis: bool,
    /// Threads encoding one log's row groups beside the thread that reads it (0: none, the
    /// reading thread encodes). [`Converter::convert_file`] with the default (`None`)
    /// uses every core; [`Converter::convert_files`] of several logs at once, one thread a
    /// log.
    pub encoders: Option<usize>,
    /// Most columns of one log's tables open at once. Every column of a table open costs
    /// parquet-rs and Arrow about 1 to 4 KiB until the file closes (its schema, its writer,
    /// its footer's metadata), whatever its rows: a log whose formats define very wide
    /// topics (`uint8_t[65000]`, a 30-byte definition, is 65,000 columns) in many instances
    /// took gigabytes for a few megabytes of rows. A topic instance whose columns would pass
    /// the limit is left out with a note ([`Conversion::notes`]) saying so (its rows are in
    /// no file, and in no field statistics of the analysis); the other tables are written.
    /// PX4's logs hold a few thousand columns in all. Default 100,000.
    pub max_columns: usize,
}

impl Default for ParquetOptions {
    fn default() -> ParquetOptions {
        ParquetOptions {
            zstd_level: 1,
            row_group_rows: 1 << 20,
            buffer_bytes: 16 << 20,
            batch_bytes: 64 << 10,
            dictionary: false,
            page_statistics: true,
            topics: Vec::new(),
            window: Window::default(),
            layout: Layout::PerLog,
            analysis: true,
            encoders: None,
            max_columns: 100_000,
        }
    }
}

impl ParquetOptions {
    /// The writer properties, with `metadata` as the file's key-value metadata.
    pub fn properties(&self, metadata: Vec<KeyValue>) -> Result<WriterProperties, ParquetError> {
        Ok(self
            .builder(metadata)
            .set_compression(Compression::ZSTD(ZstdLevel::try_new(self.zstd_level)?))
            .build())
    }

    /// The properties without compression, for column writers whose pages are compressed
    /// by [`chunk`]; and whether `FLOAT`, `DOUBLE` and `INT64` columns are written by
    /// [`chunk`] itself (floats' statistics in the type-defined order, [`statistics`];
    /// 64-bit integers DELTA_BINARY_PACKED, [`int64`]), with a column index or not (unless
    /// a dictionary is asked for).
    fn chunk_properties(&self) -> chunk::ChunkProperties {
        let uncompressed = || {
            self.builder(Vec::new())
                .set_compression(Compression::UNCOMPRESSED)
        };
        chunk::ChunkProperties {
            parquet: std::sync::Arc::new(uncompressed().build()),
            int64: std::sync::Arc::new(
                uncompressed()
                    .set_encoding(parquet::basic::Encoding::DELTA_BINARY_PACKED)
                    .build(),
            ),
            own_pages: (!self.dictionary).then_some(self.page_statistics),
        }
    }

    fn builder(
        &self,
        metadata: Vec<KeyValue>,
    ) -> parquet::file::properties::WriterPropertiesBuilder {
        WriterProperties::builder()
            .set_dictionary_enabled(self.dictionary)
            // Pages of 1 MiB, however many values that is (parquet-rs also cuts pages at
            // 20,000 rows: 80 KB of `f32`, and each page its own ZSTD frame and tables; 1 MiB
            // pages took 3.6% fewer instructions to convert the benchmark log, its files 2%
            // smaller; the column index is coarser for it).
            .set_data_page_size_limit(1 << 20)
            .set_data_page_row_count_limit(usize::MAX)
            .set_statistics_enabled(if self.page_statistics {
                EnabledStatistics::Page
            } else {
                EnabledStatistics::Chunk
            })
            .set_created_by(format!(
                "ulog-runtime {} (parquet-rs)",
                env!("CARGO_PKG_VERSION")
            ))
            .set_key_value_metadata((!metadata.is_empty()).then_some(metadata))
    }

    /// Whether topic `name` is converted.
    pub fn wants(&self, name: &str) -> bool {
        self.topics.is_empty() || self.topics.iter().any(|t| t == name)
    }

    /// Rows per batch for rows of `row_size` bytes.
    fn batch_rows(&self, row_size: usize) -> usize {
        (self.batch_bytes / row_size.max(1)).clamp(1, 64 * 1024)
    }
}

/// Who a log is, as each of its Parquet files says (see the [module docs](self)).
#[derive(Debug, Clone, PartialEq, Eq, Default, serde::Serialize)]
pub struct LogIdentity {
    /// The log's file name.
    pub file_name: String,
    /// SHA-256 of the whole file, hex.
    pub sha256: String,
    /// Info `sys_name`.
    pub sys_name: Option<String>,
    /// Info `ver_sw`.
    pub ver_sw: Option<String>,
    /// Info `ver_hw`.
    pub ver_hw: Option<String>,
    /// The header's start time, µs.
    pub start_timestamp: u64,
    /// The start as a UTC date (see the [module docs](self)).
    pub start_utc: Option<String>,
}

impl LogIdentity {
    /// The identity of a log read from `meta`, with its file name and digest; `start_utc`
    /// from the header if it holds a date, else from `gps_utc_start` (see [`GpsClock`]).
    pub fn new(
        meta: &Metadata,
        file_name: &str,
        sha256: &[u8],
        gps_utc_start: Option<u64>,
    ) -> LogIdentity {
        let text = |key: &str| match meta.info_value(key) {
            Some(crate::Value::String(s)) => Some(s.clone()),
            _ => None,
        };
        let header = meta.header();
        let start_utc = GpsClock::date(header, gps_utc_start);
        LogIdentity {
            file_name: file_name.to_owned(),
            sha256: sha256.iter().map(|b| format!("{b:02x}")).collect(),
            sys_name: text("sys_name"),
            ver_sw: text("ver_sw"),
            ver_hw: text("ver_hw"),
            start_timestamp: header.start_timestamp,
            start_utc: start_utc.map(|t| t.to_string()),
        }
    }

    /// The identity of a whole-file log (its bytes hashed, its GPS rows read for the date).
    pub fn of_log(log: &Log<'_>, file_name: &str) -> LogIdentity {
        use sha2::Digest;
        let digest = sha2::Sha256::digest(log.bytes());
        LogIdentity::new(log.metadata(), file_name, &digest, GpsClock::of_log(log))
    }

    /// The key-value metadata that says which log a table comes from.
    pub fn key_values(&self) -> Vec<KeyValue> {
        let mut kv = vec![
            KeyValue::new("ulog.file_name".to_owned(), self.file_name.clone()),
            KeyValue::new("ulog.sha256".to_owned(), self.sha256.clone()),
        ];
        for (key, value) in [
            ("ulog.sys_name", &self.sys_name),
            ("ulog.ver_sw", &self.ver_sw),
            ("ulog.ver_hw", &self.ver_hw),
            ("ulog.start_utc", &self.start_utc),
        ] {
            if let Some(v) = value {
                kv.push(KeyValue::new(key.to_owned(), v.clone()));
            }
        }
        kv.push(KeyValue::new(
            "ulog.start_timestamp".to_owned(),
            self.start_timestamp.to_string(),
        ));
        kv
    }
}

/// The key-value metadata that says what a table holds: topic, instance and format.
fn table_key_values(topic: &str, multi_id: u8, format: &str) -> Vec<KeyValue> {
    vec![
        KeyValue::new("ulog.topic".to_owned(), topic.to_owned()),
        KeyValue::new("ulog.multi_id".to_owned(), multi_id.to_string()),
        KeyValue::new("ulog.format".to_owned(), format.to_owned()),
    ]
}

/// What was written of one table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TableWritten {
    /// Rows written.
    pub rows: usize,
    /// Row groups written.
    pub row_groups: usize,
}

/// Why [`write_topic`] wrote nothing.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TableError {
    /// The log has no such topic instance, or cannot decode its rows.
    #[error("no topic instance `{topic}` #{multi_id} with rows that can be read")]
    NoSuchInstance {
        /// The topic asked for.
        topic: String,
        /// The instance asked for.
        multi_id: u8,
    },
    /// Parquet refused the table, or writing failed.
    #[error(transparent)]
    Parquet(#[from] ParquetError),
}

/// Writes one topic instance of a whole-file log (every subscription of that name and
/// `multi_id`, rows in file order, of `options.window` only) as a Parquet file to `out`,
/// with `identity` in its key-value metadata. Row groups are written when the rows
/// waiting pass `options.buffer_bytes` or `options.row_group_rows`.
///
/// ```
/// use ulog_runtime::{Log, ULog, Writer, WriterOptions};
/// use ulog_runtime::columns::parquet::{LogIdentity, ParquetOptions, write_topic};
///
/// #[derive(ULog)]
/// struct Battery { timestamp: u64, voltage_v: f32 }
///
/// let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
/// let sub = w.topic::<Battery>(0)?;
/// w.write(&sub, &Battery { timestamp: 1, voltage_v: 16.2 })?;
/// let log = Log::from_vec(w.into_inner())?;
/// let identity = LogIdentity::of_log(&log, "flight.ulg");
/// let mut file = Vec::new();
/// let written = write_topic(&log, "battery", 0, &identity, &mut file, &ParquetOptions::default())?;
/// assert_eq!(written.rows, 1);
/// assert_eq!(&file[..4], b"PAR1");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_topic<W: Write + Send>(
    log: &Log<'_>,
    topic: &str,
    multi_id: u8,
    identity: &LogIdentity,
    out: W,
    options: &ParquetOptions,
) -> Result<TableWritten, TableError> {
    let subs = log.instance(topic, multi_id);
    let no_such = || TableError::NoSuchInstance {
        topic: topic.to_owned(),
        multi_id,
    };
    let id = subs.first().and_then(|s| s.format()).ok_or_else(no_such)?;
    let spec = ColumnSpec::of(log.metadata().schema(), id).ok_or_else(no_such)?;
    let mut table = Table::new(&spec, topic, multi_id, out, options);
    let batch_rows = options
        .batch_rows(spec.stored_row_size())
        .min(options.row_group_rows.max(1));
    let mut builder = ColumnBuilder::with_capacity(spec, batch_rows);
    let mut window = Admission::new(options.window);
    for row in log.instance_rows(&subs) {
        match window.admit(row.timestamp) {
            AdmitRow::Skip => continue,
            AdmitRow::Stop => break,
            AdmitRow::Take => {}
        }
        if builder.push(row.data, row.timestamp) && builder.rows() >= batch_rows {
            table.append(builder.take())?;
            if table.memory() > options.buffer_bytes {
                table.write_row_group()?;
            }
        }
    }
    table.append(builder.take())?;
    Ok(table.close(identity, true)?.1)
}

/// What to do with a row of a table.
enum AdmitRow {
    Skip,
    Take,
    Stop,
}

/// A [`Window`] applied to one topic instance's rows, in order.
struct Admission {
    window: Window,
    started: bool,
    stopped: bool,
}

impl Admission {
    fn new(window: Window) -> Admission {
        Admission {
            window,
            started: false,
            stopped: false,
        }
    }

    /// Whether to take the next row.
    #[inline]
    fn admit(&mut self, timestamp: u64) -> AdmitRow {
        if self.stopped {
            return AdmitRow::Stop;
        }
        match self.window.admit(timestamp, self.started) {
            super::Admit::Skip => AdmitRow::Skip,
            super::Admit::Take => {
                self.started = true;
                AdmitRow::Take
            }
            super::Admit::Stop => {
                self.stopped = true;
                AdmitRow::Stop
            }
        }
    }
}

/// One table being written: batches of columns held until they make a row group, each
/// row group encoded and written at once, the file begun only with the first row group.
///
/// A row group is encoded one column at a time ([`chunk::write_chunk`]): a column's chunk is
/// encoded from every batch, closed and written before the next column's is begun, so that
/// only one column's encoded pages are held at a time, whatever the number of columns.
struct Table<W: Write + Send> {
    schema: arrow_schema::SchemaRef,
    /// The writer, once the first row group is written; until then its output and
    /// properties. (Made by `ArrowWriter`, which stores the Arrow schema in the file.)
    writer: Option<SerializedFileWriter<statistics::Held<W>>>,
    out: Option<(W, WriterProperties)>,
    properties_error: Option<ParquetError>,
    /// The column writers' properties: as the file's, without compression.
    chunk_properties: std::sync::Arc<chunk::ChunkProperties>,
    zstd_level: i32,
    row_group_rows: usize,
    /// Batches of the next row group.
    pending: Vec<Columns>,
    pending_rows: usize,
    pending_bytes: usize,
    rows: usize,
}

impl<W: Write + Send> Table<W> {
    fn new(
        spec: &ColumnSpec,
        topic: &str,
        multi_id: u8,
        out: W,
        options: &ParquetOptions,
    ) -> Table<W> {
        let schema = super::arrow::schema(spec, topic);
        let kv = table_key_values(topic, multi_id, spec.format());
        let (out, properties_error) = match options.properties(kv) {
            Ok(p) => (Some((out, p)), None),
            Err(e) => (None, Some(e)),
        };
        Table {
            schema,
            writer: None,
            out,
            properties_error,
            chunk_properties: std::sync::Arc::new(options.chunk_properties()),
            zstd_level: options.zstd_level,
            row_group_rows: options.row_group_rows.max(1),
            pending: Vec::new(),
            pending_rows: 0,
            pending_bytes: 0,
            rows: 0,
        }
    }

    /// Adds a batch of columns; writes a row group first if the batch would make the
    /// pending one too long.
    fn append(&mut self, columns: Columns) -> Result<(), ParquetError> {
        let rows = columns.rows();
        if rows == 0 {
            return Ok(());
        }
        if self.pending_rows > 0 && self.pending_rows + rows > self.row_group_rows {
            self.write_row_group()?;
        }
        // Callers make batches of at most `row_group_rows` rows.
        debug_assert!(rows <= self.row_group_rows);
        self.pending_bytes += columns.memory();
        self.pending_rows += rows;
        self.rows += rows;
        self.pending.push(columns);
        Ok(())
    }

    /// Its columns: each row group holds a chunk of each.
    fn columns(&self) -> usize {
        self.schema.fields().len()
    }

    /// Memory the table holds: its batches waiting for their row group.
    fn memory(&self) -> usize {
        self.pending_bytes
    }

    /// The writer, made on first use (through `ArrowWriter`, which stores the Arrow
    /// schema in the file's metadata).
    fn writer(&mut self) -> Result<&mut SerializedFileWriter<statistics::Held<W>>, ParquetError> {
        if self.writer.is_none() {
            if let Some(e) = self.properties_error.take() {
                return Err(e);
            }
            let (out, props) = self.out.take().expect("an output until the writer is made");
            let out = statistics::Held::new(out);
            let writer = ArrowWriter::try_new(out, self.schema.clone(), Some(props))?;
            self.writer = Some(writer.into_serialized_writer()?.0);
        }
        Ok(self.writer.as_mut().expect("just made"))
    }

    /// Encodes and writes the pending batches as one row group, a column at a time, then
    /// flushes the output.
    fn write_row_group(&mut self) -> Result<(), ParquetError> {
        if self.pending.is_empty() {
            return Ok(());
        }
        let pending = std::mem::take(&mut self.pending);
        self.pending_rows = 0;
        self.pending_bytes = 0;
        let props = self.chunk_properties.clone();
        let level = self.zstd_level;
        let columns = self.columns();
        let file = self.writer()?;
        // Every column is a flat primitive or text one (`columns::arrow`): one Parquet leaf
        // each.
        let leaves = file.schema_descr().num_columns();
        if leaves != columns {
            return Err(ParquetError::General(format!(
                "{leaves} Parquet columns for {columns} columns"
            )));
        }
        let descrs: Vec<_> = (0..leaves).map(|i| file.schema_descr().column(i)).collect();
        let mut row_group = file.next_row_group()?;
        for (i, descr) in descrs.into_iter().enumerate() {
            let values = pending.iter().map(|batch| &batch.values()[i]);
            chunk::write_chunk(&mut row_group, descr, &props, level, values)?;
        }
        row_group.close()?;
        file.flush()?;
        Ok(())
    }

    /// Writes everything collected, as a row group.
    fn flush(&mut self) -> Result<(), ParquetError> {
        self.write_row_group()
    }

    /// The output, once the file is begun (to close a file handle between row groups:
    /// the writer is flushed after each).
    fn output(&mut self) -> Option<&mut W> {
        self.writer.as_mut().map(|w| &mut w.inner_mut().inner)
    }

    /// Writes what is left and the footer, with the log's identity; a table without rows
    /// is written only if `always`. Returns whether a file was written.
    fn close(
        mut self,
        identity: &LogIdentity,
        always: bool,
    ) -> Result<(bool, TableWritten), ParquetError> {
        self.flush()?;
        if self.writer.is_none() && !always {
            return Ok((
                false,
                TableWritten {
                    rows: 0,
                    row_groups: 0,
                },
            ));
        }
        let file = self.writer()?;
        for kv in identity.key_values() {
            file.append_key_value_metadata(kv);
        }
        // The footer held back, to give float columns the type-defined order their
        // statistics are taken in.
        file.inner_mut().hold();
        let meta = file.finish()?;
        let columns = file.schema_descr().num_columns();
        file.inner_mut()
            .write_held(|footer| statistics::type_defined_float_orders(footer, columns))?;
        Ok((
            true,
            TableWritten {
                rows: self.rows,
                row_groups: meta.num_row_groups(),
            },
        ))
    }
}
