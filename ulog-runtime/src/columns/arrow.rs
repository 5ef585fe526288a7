//! A topic instance's columns as Arrow record batches (feature `arrow`, arrow-rs 60), with
//! exact types: `uint64_t` -> `UInt64`, `float` -> `Float32`, `double` -> `Float64`, `bool` ->
//! `Boolean`, `char[N]` -> `Utf8`, a single `char` -> `Int8` (its byte, as pyulog shows it),
//! and each integer type to the Arrow integer of the same size and sign. Every field's
//! metadata carries its ULog type (`ulog.type`); the schema's metadata the topic
//! (`ulog.topic`) and its format string (`ulog.format`).
//!
//! ```
//! use ulog_runtime::{Log, ULog, Writer, WriterOptions};
//! use ulog_runtime::columns::arrow::record_batches;
//!
//! #[derive(ULog)]
//! struct Gps { timestamp: u64, alt: f32, fix: bool }
//!
//! let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
//! let sub = w.topic::<Gps>(0)?;
//! for t in 0..5 {
//!     w.write(&sub, &Gps { timestamp: t, alt: 488.0, fix: t > 1 })?;
//! }
//! let log = Log::from_vec(w.into_inner())?;
//! let batches: Vec<_> = record_batches(&log, "gps", 0, 2).unwrap().collect::<Result<_, _>>()?;
//! assert_eq!(batches.iter().map(|b| b.num_rows()).collect::<Vec<_>>(), [2, 2, 1]);
//! let schema = batches[0].schema();
//! assert_eq!(schema.field(1).data_type(), &arrow_schema::DataType::Float32);
//! assert_eq!(schema.field(1).metadata()["ulog.type"], "float");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::collections::HashMap;
use std::sync::Arc;

/// The arrow-rs crates these batches are made of (60.x), for matching versions.
pub use {arrow_array, arrow_schema};

use arrow_array::builder::BooleanBufferBuilder;
use arrow_array::{
    ArrayRef, BooleanArray, Float32Array, Float64Array, Int8Array, Int16Array, Int32Array,
    Int64Array, RecordBatch, StringArray, UInt8Array, UInt16Array, UInt32Array, UInt64Array,
};
use arrow_schema::{ArrowError, DataType, Field, Schema, SchemaRef};

use super::{ColumnKind, ColumnSpec, ColumnValues, Columns, ColumnsError};
use crate::read::{InstanceRows, Log};
use crate::schema::Primitive;

/// The Arrow type of a column.
pub fn data_type(kind: ColumnKind) -> DataType {
    match kind {
        ColumnKind::Text { .. } => DataType::Utf8,
        ColumnKind::Value(p) => match p {
            Primitive::Int8 | Primitive::Char => DataType::Int8,
            Primitive::UInt8 => DataType::UInt8,
            Primitive::Int16 => DataType::Int16,
            Primitive::UInt16 => DataType::UInt16,
            Primitive::Int32 => DataType::Int32,
            Primitive::UInt32 => DataType::UInt32,
            Primitive::Int64 => DataType::Int64,
            Primitive::UInt64 => DataType::UInt64,
            Primitive::Float => DataType::Float32,
            Primitive::Double => DataType::Float64,
            Primitive::Bool => DataType::Boolean,
        },
    }
}

/// The Arrow schema of a topic's columns (no nulls: every row has every column).
pub fn schema(spec: &ColumnSpec, topic: &str) -> SchemaRef {
    let fields: Vec<Field> = spec
        .columns()
        .iter()
        .map(|c| {
            Field::new(&c.name, data_type(c.kind), false).with_metadata(HashMap::from([(
                "ulog.type".to_owned(),
                c.ulog_type.clone(),
            )]))
        })
        .collect();
    Arc::new(Schema::new_with_metadata(
        fields,
        HashMap::from([
            ("ulog.topic".to_owned(), topic.to_owned()),
            ("ulog.format".to_owned(), spec.format().to_owned()),
        ]),
    ))
}

/// Columns as a record batch of `schema` (made by [`schema`] from the same spec).
pub fn record_batch(schema: &SchemaRef, columns: Columns) -> Result<RecordBatch, ArrowError> {
    let rows = columns.rows();
    let arrays: Vec<ArrayRef> = columns.into_values().into_iter().map(array).collect();
    // The row count given, so that columns of no field (a format of padding only) still
    // make a batch of their rows.
    RecordBatch::try_new_with_options(
        schema.clone(),
        arrays,
        &arrow_array::RecordBatchOptions::new().with_row_count(Some(rows)),
    )
}

/// One column's values as an Arrow array, without copying the numbers.
fn array(values: ColumnValues) -> ArrayRef {
    match values {
        ColumnValues::Int8(v) => Arc::new(Int8Array::from(v)),
        ColumnValues::Char(v) => Arc::new(Int8Array::from(
            v.into_iter().map(|b| b as i8).collect::<Vec<_>>(),
        )),
        ColumnValues::UInt8(v) => Arc::new(UInt8Array::from(v)),
        ColumnValues::Int16(v) => Arc::new(Int16Array::from(v)),
        ColumnValues::UInt16(v) => Arc::new(UInt16Array::from(v)),
        ColumnValues::Int32(v) => Arc::new(Int32Array::from(v)),
        ColumnValues::UInt32(v) => Arc::new(UInt32Array::from(v)),
        ColumnValues::Int64(v) => Arc::new(Int64Array::from(v)),
        ColumnValues::UInt64(v) => Arc::new(UInt64Array::from(v)),
        ColumnValues::Float(v) => Arc::new(Float32Array::from(v)),
        ColumnValues::Double(v) => Arc::new(Float64Array::from(v)),
        ColumnValues::Bool(v) => {
            let mut bits = BooleanBufferBuilder::new(v.len());
            bits.append_slice(&v);
            Arc::new(BooleanArray::new(bits.finish(), None))
        }
        ColumnValues::Text(v) => Arc::new(StringArray::from(v)),
    }
}

/// The record batches of one topic instance of a log, each of at most `rows` rows
/// ([`record_batches`]); an Arrow [`RecordBatchReader`](arrow_array::RecordBatchReader).
pub struct RecordBatches<'a> {
    spec: Arc<ColumnSpec>,
    schema: SchemaRef,
    source: InstanceRows<'a>,
    rows: usize,
}

impl std::fmt::Debug for RecordBatches<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RecordBatches")
            .field("schema", &self.schema)
            .finish_non_exhaustive()
    }
}

/// The rows of one topic instance of `log` (every subscription of that name and `multi_id`,
/// rows in file order) as Arrow record batches of at most `rows` rows each; the errors of
/// [`Log::columns`] if the log has no such instance (the closest topic names suggested) or
/// cannot decode it.
///
/// ```
/// # use ulog_runtime::{Log, ULog, Writer, WriterOptions};
/// # #[derive(ULog)] struct Battery { timestamp: u64, voltage_v: f32 }
/// # let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
/// # let sub = w.topic::<Battery>(0)?;
/// # w.write(&sub, &Battery { timestamp: 1, voltage_v: 16.0 })?;
/// # let log = Log::from_vec(w.into_inner())?;
/// use ulog_runtime::columns::arrow::record_batches;
/// let err = record_batches(&log, "batery", 0, 1024).unwrap_err();
/// assert_eq!(err.to_string(), "the log has no topic `batery`; did you mean `battery`?");
/// assert_eq!(record_batches(&log, "battery", 0, 1024)?.count(), 1);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn record_batches<'a>(
    log: &'a Log<'a>,
    topic: &str,
    multi_id: u8,
    rows: usize,
) -> Result<RecordBatches<'a>, ColumnsError> {
    let (subs, spec) = log.instance_spec(topic, multi_id)?;
    let schema = schema(&spec, topic);
    Ok(RecordBatches {
        spec,
        schema,
        source: log.instance_rows(&subs),
        rows: rows.max(1),
    })
}

impl arrow_array::RecordBatchReader for RecordBatches<'_> {
    fn schema(&self) -> SchemaRef {
        self.schema.clone()
    }
}

impl Iterator for RecordBatches<'_> {
    type Item = Result<RecordBatch, ArrowError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let mut read = 0;
            // Room for this batch's rows: no more than the instance has left.
            let room = self.rows.min(self.source.size_hint().0).min(1 << 16);
            let rows = (&mut self.source)
                .take(self.rows)
                .inspect(|_| read += 1)
                .map(|r| (r.data, r.timestamp));
            let columns = Columns::from_rows(self.spec.clone(), rows, room);
            if columns.rows() > 0 {
                return Some(record_batch(&self.schema, columns));
            }
            // Rows too short for the format are left out; only the end ends the batches.
            if read == 0 {
                return None;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_ulog_type_has_its_arrow_type() {
        let mut schema = crate::schema::Schema::new();
        let id = schema
            .insert(
                "t:uint64_t timestamp;int8_t a;uint8_t b;int16_t c;uint16_t d;int32_t e;\
                 uint32_t f;int64_t g;uint64_t h;float i;double j;bool k;char l;char[3] m;"
                    .parse()
                    .unwrap(),
            )
            .unwrap();
        let spec = ColumnSpec::new(&mut schema, id).unwrap();
        let s = super::schema(&spec, "t");
        let types: Vec<String> = s
            .fields()
            .iter()
            .map(|f| f.data_type().to_string())
            .collect();
        assert_eq!(
            types,
            [
                "UInt64", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64",
                "Float32", "Float64", "Boolean", "Int8", "Utf8"
            ]
        );
        assert_eq!(s.metadata()["ulog.topic"], "t");
        assert_eq!(s.field(13).metadata()["ulog.type"], "char[3]");
        assert!(s.metadata()["ulog.format"].starts_with("t:uint64_t timestamp;"));
        let mut b = super::super::ColumnBuilder::new(spec);
        let mut row = 7u64.to_le_bytes().to_vec();
        row.extend_from_slice(&[0xFE, 2, 3, 0, 4, 0, 5, 0, 0, 0, 6, 0, 0, 0]);
        row.extend_from_slice(&(-7i64).to_le_bytes());
        row.extend_from_slice(&8u64.to_le_bytes());
        row.extend_from_slice(&9.5f32.to_le_bytes());
        row.extend_from_slice(&10.25f64.to_le_bytes());
        row.extend_from_slice(&[1, b'Z', b'h', b'i', 0]);
        assert!(b.push(&row, 7));
        let batch = record_batch(&s, b.take()).unwrap();
        assert_eq!(batch.num_rows(), 1);
        let text = batch
            .column(13)
            .as_any()
            .downcast_ref::<StringArray>()
            .unwrap();
        assert_eq!(text.value(0), "hi");
        let a = batch
            .column(1)
            .as_any()
            .downcast_ref::<Int8Array>()
            .unwrap();
        assert_eq!(a.value(0), -2);
        let l = batch
            .column(12)
            .as_any()
            .downcast_ref::<Int8Array>()
            .unwrap();
        assert_eq!(l.value(0), b'Z' as i8);
        let k = batch
            .column(11)
            .as_any()
            .downcast_ref::<BooleanArray>()
            .unwrap();
        assert!(k.value(0));
    }

    #[test]
    fn columns_of_no_field_make_a_batch_of_their_rows() {
        // A format of padding only: no column to show, and the rows still counted.
        let mut schema = crate::schema::Schema::new();
        let id = schema
            .insert("p:uint8_t[4] _padding0;".parse().unwrap())
            .unwrap();
        let spec = ColumnSpec::new(&mut schema, id).unwrap();
        assert!(spec.columns().is_empty());
        let s = super::schema(&spec, "p");
        let mut b = super::super::ColumnBuilder::new(spec);
        for _ in 0..3 {
            b.push(&[0; 4], 1);
        }
        let cols = b.take();
        let rows = cols.rows();
        let batch = record_batch(&s, cols).unwrap();
        assert_eq!((batch.num_columns(), batch.num_rows()), (0, 3));
        assert_eq!(rows, 3);
    }
}
