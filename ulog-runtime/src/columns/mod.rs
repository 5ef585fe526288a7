//! One topic instance as typed columns, in pyulog's names and order: the answer to "give me
//! `voltage_v` as a vector". No dependencies; [`csv`] writes them as pyulog's `ulog2csv`
//! does, [`arrow`] (feature `arrow`) makes record batches of them and [`parquet`] (feature
//! `parquet`) Parquet files.
//!
//! The columns of a format ([`ColumnSpec`]): `timestamp` first (the row's timestamp in µs as
//! `u64`, unwrapped for version-0 logs), then every leaf in format order, named as pyulog
//! names them (`q[0]`, `esc[3].esc_rpm`), padding hidden, each `char[N]` array one text
//! column (the bytes up to the first zero, each as one character, as pyulog's `ulog2csv`
//! shows them). [`ColumnBuilder`] takes rows in one pass (a copy of each row's bytes,
//! made columns every few kilobytes, one loop a column) and hands them over as columns in
//! batches of any size; [`RowBatch`] holds rows to be made columns later. `gather` makes a
//! large instance's columns ([`Log::columns`]) on every core.
//!
//! ```
//! use ulog_runtime::{Log, ULog, Writer, WriterOptions};
//!
//! #[derive(ULog)]
//! struct Battery { timestamp: u64, voltage_v: f32, cells: [u16; 2] }
//!
//! let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
//! let sub = w.topic::<Battery>(0)?;
//! for t in 1..=3 {
//!     w.write(&sub, &Battery { timestamp: t, voltage_v: 15.0 + t as f32, cells: [3, 4] })?;
//! }
//! let log = Log::from_vec(w.into_inner())?;
//! let columns = log.columns("battery", 0).unwrap();
//! assert_eq!(columns.names().collect::<Vec<_>>(), ["timestamp", "voltage_v", "cells[0]", "cells[1]"]);
//! assert_eq!(columns.get("voltage_v").unwrap().as_float(), Some(&[16.0, 17.0, 18.0][..]));
//! assert_eq!(columns.get("timestamp").unwrap().as_uint64(), Some(&[1, 2, 3][..]));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#[cfg(feature = "arrow")]
pub mod arrow;
pub mod csv;
mod fields;
mod gather;
#[cfg(feature = "parquet")]
pub mod parquet;

use std::sync::Arc;

pub(crate) use fields::{FieldIndex, Leaf};

use crate::read::{Log, Subscription};
use crate::schema::{FieldKind, FormatId, Primitive, Schema};
use crate::value::{PlanError, RowPlan};

/// What one column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColumnKind {
    /// Values of a basic type (`char` scalars as their byte).
    Value(Primitive),
    /// A `char[N]` array as text.
    Text {
        /// `N`.
        len: usize,
    },
}

/// One column of a format: its name, kind and place in the row.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ColumnDef {
    /// pyulog's name: `timestamp`, `q[0]`, `esc[3].esc_rpm`, `name` (a `char` array).
    pub name: String,
    /// What it holds.
    pub kind: ColumnKind,
    /// The ULog type of the field it comes from, as a format spells it (`float`,
    /// `char[10]`, `uint32_t`; the timestamp column's file type even when it is unwrapped to
    /// `u64`).
    pub ulog_type: String,
    /// Where its values come from.
    pub source: Source,
    /// The byte offset of the field in the row (the timestamp's too).
    pub offset: usize,
}

/// Where a column's values come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// The row's timestamp, µs (the `timestamp` field, unwrapped for version-0 logs).
    Timestamp,
    /// Bytes of the row at this offset.
    Offset(usize),
}

/// The columns of one format ([module docs](self)).
#[derive(Debug, Clone)]
pub struct ColumnSpec {
    format: String,
    columns: Vec<ColumnDef>,
    /// Bytes of a row the columns read.
    row_len: usize,
    /// Bytes a row takes once in columns.
    stored_row_size: usize,
}

impl ColumnSpec {
    /// The columns of format `id` of `schema` (its layout resolved if needed), padding hidden.
    pub fn new(schema: &mut Schema, id: FormatId) -> Result<ColumnSpec, PlanError> {
        RowPlan::check(schema, id)?;
        Ok(ColumnSpec::from_checked(schema, id, false))
    }

    /// As pyulog's `ulog2csv` writes them: padding inside nested types shown (as bytes of
    /// value 0 when written by PX4), only top-level padding hidden.
    pub fn like_ulog2csv(schema: &mut Schema, id: FormatId) -> Result<ColumnSpec, PlanError> {
        RowPlan::check(schema, id)?;
        Ok(ColumnSpec::from_checked(schema, id, true))
    }

    /// The columns of a format of `schema` whose layout is resolved (every format a log
    /// subscribes and can decode); `None` otherwise.
    pub fn of(schema: &Schema, id: FormatId) -> Option<ColumnSpec> {
        schema.resolved(id)?;
        Some(ColumnSpec::from_checked(schema, id, false))
    }

    /// [`ColumnSpec::of`] as pyulog's `ulog2csv` writes them (see
    /// [`ColumnSpec::like_ulog2csv`]).
    pub fn of_ulog2csv(schema: &Schema, id: FormatId) -> Option<ColumnSpec> {
        schema.resolved(id)?;
        Some(ColumnSpec::from_checked(schema, id, true))
    }

    /// The columns of a format whose layout is resolved.
    pub(crate) fn from_checked(schema: &Schema, id: FormatId, nested_padding: bool) -> ColumnSpec {
        let mut leaves: Vec<(String, ColumnKind, String, usize)> = Vec::new();
        flatten(schema, id, 0, "", true, nested_padding, &mut leaves);
        let timestamp = leaves.iter().position(|(name, kind, _, _)| {
            name == "timestamp" && matches!(kind, ColumnKind::Value(p) if p.is_unsigned_integer())
        });
        let mut spec = ColumnSpec {
            format: schema.format(id).to_string(),
            columns: Vec::with_capacity(leaves.len()),
            row_len: 0,
            stored_row_size: 8,
        };
        // `timestamp` first, as ulog2csv writes it: the row's (unwrapped) timestamp.
        let order = timestamp
            .into_iter()
            .chain((0..leaves.len()).filter(|&i| Some(i) != timestamp));
        for i in order {
            let (name, kind, ulog_type, offset) = leaves[i].clone();
            let (kind, source) = if Some(i) == timestamp {
                (ColumnKind::Value(Primitive::UInt64), Source::Timestamp)
            } else {
                (kind, Source::Offset(offset))
            };
            if let Source::Offset(at) = source {
                let (len, stored) = match kind {
                    ColumnKind::Value(p) => (p.size(), p.size()),
                    // A `String`, and its bytes.
                    ColumnKind::Text { len } => (len, len + 24),
                };
                spec.row_len = spec.row_len.max(at + len);
                spec.stored_row_size += stored;
            }
            spec.columns.push(ColumnDef {
                name,
                kind,
                ulog_type,
                source,
                offset,
            });
        }
        spec
    }

    /// The columns, in output order.
    pub fn columns(&self) -> &[ColumnDef] {
        &self.columns
    }

    /// The format's definition, as its `F` message has it.
    pub fn format(&self) -> &str {
        &self.format
    }

    /// Bytes a row takes once in columns: the timestamp's 8, each value's size, a text's
    /// length and its `String` (24).
    pub fn stored_row_size(&self) -> usize {
        self.stored_row_size
    }

    /// Bytes of a row the columns read: rows shorter than this are not taken.
    pub fn row_len(&self) -> usize {
        self.row_len
    }
}

/// How many columns [`ColumnSpec::of`] makes of a format (padding left out, a `char`
/// array one column), counted without making them: what a budget of columns checks before
/// a spec is built. Saturates rather than overflows.
pub(crate) fn column_count(schema: &Schema, id: FormatId) -> usize {
    let Some(layout) = schema.resolved(id) else {
        return 0;
    };
    layout
        .fields
        .iter()
        .filter(|f| !f.padding)
        .map(|f| match (f.kind, f.array_len) {
            (FieldKind::Primitive(Primitive::Char), Some(_)) => 1,
            (FieldKind::Primitive(_), _) => f.count(),
            (FieldKind::Nested(nested), _) => {
                f.count().saturating_mul(column_count(schema, nested))
            }
        })
        .fold(0, usize::saturating_add)
}

/// A budget of columns for the topic instances a reader takes in (the Parquet converter's
/// open tables, the analysis's field statistics), counted with [`column_count`] before any
/// column is made, and the instances it left out, each named once however often it is
/// subscribed again.
#[derive(Debug, Clone, Default)]
pub(crate) struct ColumnBudget {
    used: usize,
    /// The instances left out (topic, `multi_id`), each once.
    rejected: std::collections::HashSet<(String, u8)>,
    /// Those instances with their columns, in the order they were left out.
    left_out: Vec<(String, u8, usize)>,
}

impl ColumnBudget {
    /// Whether an instance of `columns` columns fits within `limit` with those taken so far:
    /// if so it is taken, if not it is named.
    pub(crate) fn admit(
        &mut self,
        limit: usize,
        topic: &str,
        multi_id: u8,
        columns: usize,
    ) -> bool {
        if self.used.saturating_add(columns) <= limit {
            self.used += columns;
            return true;
        }
        self.left_out_once(topic.to_owned(), multi_id, columns);
        false
    }

    fn left_out_once(&mut self, topic: String, multi_id: u8, columns: usize) {
        if self.rejected.insert((topic.clone(), multi_id)) {
            self.left_out.push((topic, multi_id, columns));
        }
    }

    /// The instances another part of a walk left out, after these (one both left out is
    /// named once).
    pub(crate) fn append(&mut self, other: ColumnBudget) {
        for (topic, multi_id, columns) in other.left_out {
            self.left_out_once(topic, multi_id, columns);
        }
    }

    /// What was left out, if anything: "2 topic instances left out, their columns past the
    /// limit of {limit}: `a` #0 (9 columns), `a` #1 (9 columns)", the first five named.
    pub(crate) fn said(&self, limit: &str) -> Option<String> {
        let n = self.left_out.len();
        let shown = n.min(5);
        let more = match n - shown {
            0 => String::new(),
            rest => format!(" and {rest} more"),
        };
        (n > 0).then(|| {
            format!(
                "{n} topic instance{} left out, their columns past the limit of {limit}: {}{more}",
                if n == 1 { "" } else { "s" },
                self.left_out[..shown]
                    .iter()
                    .map(|(t, m, c)| format!("`{t}` #{m} ({c} columns)"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
    }
}

#[cfg(test)]
#[test]
fn a_budget_names_each_instance_it_left_out_once() {
    let mut a = ColumnBudget::default();
    assert!(a.admit(10, "t", 0, 6));
    assert!(!a.admit(10, "t", 1, 6));
    assert!(!a.admit(10, "t", 1, 6), "resubscribed");
    let mut b = ColumnBudget::default();
    assert!(!b.admit(4, "t", 1, 6));
    assert!(!b.admit(4, "u", 0, 5));
    a.append(b);
    assert_eq!(
        a.said("10").unwrap(),
        "2 topic instances left out, their columns past the limit of 10: `t` #1 (6 columns), \
         `u` #0 (5 columns)"
    );
    assert_eq!(ColumnBudget::default().said("10"), None);
}

/// Every leaf of a format: (name, kind, ULog type, offset), depth first; `char` arrays as
/// one text leaf; padding left out (only at the top with `nested_padding`).
fn flatten(
    schema: &Schema,
    id: FormatId,
    base: usize,
    prefix: &str,
    top: bool,
    nested_padding: bool,
    out: &mut Vec<(String, ColumnKind, String, usize)>,
) {
    let Some(layout) = schema.resolved(id) else {
        return;
    };
    for f in &layout.fields {
        if f.padding && (top || !nested_padding) {
            continue;
        }
        let start = base + f.offset;
        match (f.kind, f.array_len) {
            (FieldKind::Primitive(Primitive::Char), Some(n)) => out.push((
                format!("{prefix}{}", f.name),
                ColumnKind::Text {
                    len: usize::from(n),
                },
                format!("char[{n}]"),
                start,
            )),
            (kind, len) => {
                for i in 0..len.map_or(1, usize::from) {
                    let name = match len {
                        Some(_) => format!("{prefix}{}[{i}]", f.name),
                        None => format!("{prefix}{}", f.name),
                    };
                    let offset = start + i * f.elem_size;
                    match kind {
                        FieldKind::Primitive(p) => {
                            out.push((name, ColumnKind::Value(p), p.c_name().to_owned(), offset));
                        }
                        FieldKind::Nested(nested) => {
                            let prefix = format!("{name}.");
                            flatten(schema, nested, offset, &prefix, false, nested_padding, out);
                        }
                    }
                }
            }
        }
    }
}

/// The values of one column.
#[derive(Debug, Clone, PartialEq)]
pub enum ColumnValues {
    /// `int8_t`
    Int8(Vec<i8>),
    /// `uint8_t`
    UInt8(Vec<u8>),
    /// `int16_t`
    Int16(Vec<i16>),
    /// `uint16_t`
    UInt16(Vec<u16>),
    /// `int32_t`
    Int32(Vec<i32>),
    /// `uint32_t`
    UInt32(Vec<u32>),
    /// `int64_t`
    Int64(Vec<i64>),
    /// `uint64_t` (and the timestamp column)
    UInt64(Vec<u64>),
    /// `float`
    Float(Vec<f32>),
    /// `double`
    Double(Vec<f64>),
    /// `bool` (any non-zero byte is true)
    Bool(Vec<bool>),
    /// `char` (one byte; pyulog shows it as a signed byte)
    Char(Vec<u8>),
    /// `char[N]` as text
    Text(Vec<String>),
}

macro_rules! accessors {
    ($($name:ident: $variant:ident($ty:ty, $ulog:literal)),* $(,)?) => {
        impl ColumnValues {
            $(
                #[doc = concat!(
                    "The values as stored, if the column is `", $ulog, "` (`", stringify!($ty),
                    "`); `None` for any other type, as nothing is converted here: ",
                    "[`ColumnValues::to_f64`] converts every numeric column."
                )]
                pub fn $name(&self) -> Option<&[$ty]> {
                    match self {
                        ColumnValues::$variant(v) => Some(v),
                        _ => None,
                    }
                }
            )*
        }
    };
}

// Named after the ULog types (`as_float` holds `float`s), so that no name promises a
// conversion: `to_f64` is the one that converts.
accessors! {
    as_int8: Int8(i8, "int8_t"), as_uint8: UInt8(u8, "uint8_t"),
    as_int16: Int16(i16, "int16_t"), as_uint16: UInt16(u16, "uint16_t"),
    as_int32: Int32(i32, "int32_t"), as_uint32: UInt32(u32, "uint32_t"),
    as_int64: Int64(i64, "int64_t"), as_uint64: UInt64(u64, "uint64_t"),
    as_float: Float(f32, "float"), as_double: Double(f64, "double"),
    as_bool: Bool(bool, "bool"), as_char: Char(u8, "char"), as_text: Text(String, "char[N]"),
}

impl ColumnValues {
    /// The number of values.
    pub fn len(&self) -> usize {
        match self {
            ColumnValues::Int8(v) => v.len(),
            ColumnValues::UInt8(v) | ColumnValues::Char(v) => v.len(),
            ColumnValues::Int16(v) => v.len(),
            ColumnValues::UInt16(v) => v.len(),
            ColumnValues::Int32(v) => v.len(),
            ColumnValues::UInt32(v) => v.len(),
            ColumnValues::Int64(v) => v.len(),
            ColumnValues::UInt64(v) => v.len(),
            ColumnValues::Float(v) => v.len(),
            ColumnValues::Double(v) => v.len(),
            ColumnValues::Bool(v) => v.len(),
            ColumnValues::Text(v) => v.len(),
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The ULog type of the values (`char[N]` for text).
    #[cfg(feature = "parquet")]
    pub(crate) fn type_name(&self) -> &'static str {
        match self {
            ColumnValues::Int8(_) => "int8_t",
            ColumnValues::UInt8(_) => "uint8_t",
            ColumnValues::Int16(_) => "int16_t",
            ColumnValues::UInt16(_) => "uint16_t",
            ColumnValues::Int32(_) => "int32_t",
            ColumnValues::UInt32(_) => "uint32_t",
            ColumnValues::Int64(_) => "int64_t",
            ColumnValues::UInt64(_) => "uint64_t",
            ColumnValues::Float(_) => "float",
            ColumnValues::Double(_) => "double",
            ColumnValues::Bool(_) => "bool",
            ColumnValues::Char(_) => "char",
            ColumnValues::Text(_) => "char[N]",
        }
    }

    /// Bytes of memory the values hold (a text's `String` and its bytes).
    #[cfg(feature = "parquet")]
    pub(crate) fn memory(&self) -> usize {
        fn held<T>(v: &Vec<T>) -> usize {
            v.capacity() * size_of::<T>()
        }
        match self {
            ColumnValues::Int8(v) => held(v),
            ColumnValues::UInt8(v) | ColumnValues::Char(v) => held(v),
            ColumnValues::Int16(v) => held(v),
            ColumnValues::UInt16(v) => held(v),
            ColumnValues::Int32(v) => held(v),
            ColumnValues::UInt32(v) => held(v),
            ColumnValues::Int64(v) => held(v),
            ColumnValues::UInt64(v) => held(v),
            ColumnValues::Float(v) => held(v),
            ColumnValues::Double(v) => held(v),
            ColumnValues::Bool(v) => held(v),
            ColumnValues::Text(v) => held(v) + v.iter().map(String::capacity).sum::<usize>(),
        }
    }

    /// Every value converted to `f64`, whatever the column's type (`bool` as 0/1, `char` as a
    /// signed byte, 64-bit integers beyond 2^53 rounded); `None` for text. The `as_*`
    /// accessors give the stored values without converting.
    pub fn to_f64(&self) -> Option<Vec<f64>> {
        Some(match self {
            ColumnValues::Int8(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ColumnValues::UInt8(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ColumnValues::Int16(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ColumnValues::UInt16(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ColumnValues::Int32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ColumnValues::UInt32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ColumnValues::Int64(v) => v.iter().map(|&x| x as f64).collect(),
            ColumnValues::UInt64(v) => v.iter().map(|&x| x as f64).collect(),
            ColumnValues::Float(v) => v.iter().map(|&x| f64::from(x)).collect(),
            ColumnValues::Double(v) => v.clone(),
            ColumnValues::Bool(v) => v.iter().map(|&x| f64::from(u8::from(x))).collect(),
            ColumnValues::Char(v) => v.iter().map(|&x| f64::from(x as i8)).collect(),
            ColumnValues::Text(_) => return None,
        })
    }
}

/// The values of a table's columns, in the order of its [`ColumnSpec`].
#[derive(Debug, Clone)]
pub struct Columns {
    spec: Arc<ColumnSpec>,
    values: Vec<ColumnValues>,
    rows: usize,
}

impl PartialEq for Columns {
    fn eq(&self, other: &Columns) -> bool {
        self.defs() == other.defs() && self.values == other.values
    }
}

impl Columns {
    /// The number of rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The column names, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.defs().iter().map(|d| d.name.as_str())
    }

    /// The columns' definitions, in order.
    pub fn defs(&self) -> &[ColumnDef] {
        self.spec.columns()
    }

    /// The spec the columns were built by.
    pub fn spec(&self) -> &Arc<ColumnSpec> {
        &self.spec
    }

    /// The values of the column of this name.
    pub fn get(&self, name: &str) -> Option<&ColumnValues> {
        let i = self.defs().iter().position(|d| d.name == name)?;
        Some(&self.values[i])
    }

    /// Every column: its definition and values.
    pub fn iter(&self) -> impl Iterator<Item = (&ColumnDef, &ColumnValues)> {
        self.defs().iter().zip(&self.values)
    }

    /// The rows of a time window, as [`Window::admit`] takes them (pyulog's `ulog2csv`
    /// rule: from the first row at or after the start, to the last before the first row
    /// at or after the end).
    pub fn window(self, window: &Window) -> Columns {
        let Some(t) = self.get("timestamp").and_then(ColumnValues::as_uint64) else {
            return self;
        };
        let mut started = false;
        let mut keep = Vec::with_capacity(t.len());
        for &t in t {
            let k = match window.admit(t, started) {
                Admit::Skip => false,
                Admit::Take => {
                    started = true;
                    true
                }
                Admit::Stop => break,
            };
            keep.push(k);
        }
        keep.resize(t.len(), false);
        fn pick<T: Clone>(v: Vec<T>, keep: &[bool]) -> Vec<T> {
            v.into_iter()
                .zip(keep)
                .filter(|(_, k)| **k)
                .map(|(x, _)| x)
                .collect()
        }
        let rows = keep.iter().filter(|k| **k).count();
        let values = self
            .values
            .into_iter()
            .map(|v| match v {
                ColumnValues::Int8(v) => ColumnValues::Int8(pick(v, &keep)),
                ColumnValues::UInt8(v) => ColumnValues::UInt8(pick(v, &keep)),
                ColumnValues::Int16(v) => ColumnValues::Int16(pick(v, &keep)),
                ColumnValues::UInt16(v) => ColumnValues::UInt16(pick(v, &keep)),
                ColumnValues::Int32(v) => ColumnValues::Int32(pick(v, &keep)),
                ColumnValues::UInt32(v) => ColumnValues::UInt32(pick(v, &keep)),
                ColumnValues::Int64(v) => ColumnValues::Int64(pick(v, &keep)),
                ColumnValues::UInt64(v) => ColumnValues::UInt64(pick(v, &keep)),
                ColumnValues::Float(v) => ColumnValues::Float(pick(v, &keep)),
                ColumnValues::Double(v) => ColumnValues::Double(pick(v, &keep)),
                ColumnValues::Bool(v) => ColumnValues::Bool(pick(v, &keep)),
                ColumnValues::Char(v) => ColumnValues::Char(pick(v, &keep)),
                ColumnValues::Text(v) => ColumnValues::Text(pick(v, &keep)),
            })
            .collect();
        Columns {
            spec: self.spec,
            values,
            rows,
        }
    }

    /// Adds the rows of `other` (columns of the same spec) after these.
    ///
    /// # Panics
    /// If `other`'s columns are not of the same types.
    pub(crate) fn append(&mut self, other: Columns) {
        for (a, b) in self.values.iter_mut().zip(other.values) {
            match (a, b) {
                (ColumnValues::Int8(a), ColumnValues::Int8(b)) => a.extend(b),
                (ColumnValues::UInt8(a), ColumnValues::UInt8(b)) => a.extend(b),
                (ColumnValues::Int16(a), ColumnValues::Int16(b)) => a.extend(b),
                (ColumnValues::UInt16(a), ColumnValues::UInt16(b)) => a.extend(b),
                (ColumnValues::Int32(a), ColumnValues::Int32(b)) => a.extend(b),
                (ColumnValues::UInt32(a), ColumnValues::UInt32(b)) => a.extend(b),
                (ColumnValues::Int64(a), ColumnValues::Int64(b)) => a.extend(b),
                (ColumnValues::UInt64(a), ColumnValues::UInt64(b)) => a.extend(b),
                (ColumnValues::Float(a), ColumnValues::Float(b)) => a.extend(b),
                (ColumnValues::Double(a), ColumnValues::Double(b)) => a.extend(b),
                (ColumnValues::Bool(a), ColumnValues::Bool(b)) => a.extend(b),
                (ColumnValues::Char(a), ColumnValues::Char(b)) => a.extend(b),
                (ColumnValues::Text(a), ColumnValues::Text(b)) => a.extend(b),
                _ => panic!("columns of other types appended"),
            }
        }
        self.rows += other.rows;
    }

    /// Bytes of memory the values hold.
    #[cfg(feature = "parquet")]
    pub(crate) fn memory(&self) -> usize {
        self.values.iter().map(ColumnValues::memory).sum()
    }

    /// The values, in column order.
    pub fn values(&self) -> &[ColumnValues] {
        &self.values
    }

    /// The values, in column order, taken out.
    pub fn into_values(self) -> Vec<ColumnValues> {
        self.values
    }
}

/// Fills the columns of a [`ColumnSpec`] row by row, in one pass ([module docs](self)):
/// rows are copied as they are into a small [`RowBatch`] (no dispatch a leaf), which is
/// turned into columns each time it fills, one column at a time over rows still in cache.
#[derive(Debug, Clone)]
pub struct ColumnBuilder {
    spec: Arc<ColumnSpec>,
    staged: RowBatch,
    /// Rows a staged batch holds before it is made columns.
    stage_rows: usize,
    columns: Vec<ColumnValues>,
    /// Rows in `columns`.
    rows: usize,
    /// Rows room is kept for after a [`ColumnBuilder::take`].
    capacity: usize,
}

/// Bytes of rows staged before they are made columns: well within a core's L2 cache.
const STAGE_BYTES: usize = 32 << 10;

impl ColumnBuilder {
    /// An empty builder.
    pub fn new(spec: impl Into<Arc<ColumnSpec>>) -> ColumnBuilder {
        ColumnBuilder::with_capacity(spec, 0)
    }

    /// An empty builder with room for `rows` rows in every column (and after each
    /// [`ColumnBuilder::take`]).
    pub fn with_capacity(spec: impl Into<Arc<ColumnSpec>>, rows: usize) -> ColumnBuilder {
        let spec = spec.into();
        let stage_rows = (STAGE_BYTES / spec.row_len.max(1)).clamp(1, 4096);
        ColumnBuilder {
            staged: RowBatch::with_capacity(spec.clone(), stage_rows),
            stage_rows,
            columns: empty_columns(&spec, rows),
            rows: 0,
            capacity: rows,
            spec,
        }
    }

    /// Rows taken since the last [`ColumnBuilder::take`].
    pub fn rows(&self) -> usize {
        self.rows + self.staged.rows()
    }

    /// The spec it builds by.
    pub fn spec(&self) -> &Arc<ColumnSpec> {
        &self.spec
    }

    /// Adds one row: its packed bytes (as a [`Row`](crate::Row)'s `data`) and its timestamp.
    /// Returns `false`, adding nothing, if `data` is shorter than the columns need.
    #[inline]
    pub fn push(&mut self, data: &[u8], timestamp: u64) -> bool {
        if !self.staged.push(data, timestamp) {
            return false;
        }
        if self.staged.rows() >= self.stage_rows {
            self.unstage();
        }
        true
    }

    /// Makes the staged rows columns.
    fn unstage(&mut self) {
        self.rows += self.staged.rows();
        self.staged.append_to(&mut self.columns);
    }

    /// The columns of the rows taken so far; the builder starts again empty (for batches of
    /// a bounded size).
    pub fn take(&mut self) -> Columns {
        self.unstage();
        let values = std::mem::replace(&mut self.columns, empty_columns(&self.spec, self.capacity));
        Columns {
            spec: self.spec.clone(),
            values,
            rows: std::mem::take(&mut self.rows),
        }
    }
}

/// Rows of one [`ColumnSpec`] as they came, not yet columns: each row's first
/// [`ColumnSpec::row_len`] bytes back to back, and the rows' timestamps. Collecting rows
/// costs a copy of their bytes; [`RowBatch::columns`] makes the columns later (on another
/// thread, say).
#[derive(Debug, Clone)]
pub struct RowBatch {
    spec: Arc<ColumnSpec>,
    /// The spec's `row_len`, at hand.
    row_len: usize,
    bytes: Vec<u8>,
    timestamps: Vec<u64>,
}

impl RowBatch {
    /// An empty batch with room for `rows` rows.
    pub fn with_capacity(spec: Arc<ColumnSpec>, rows: usize) -> RowBatch {
        RowBatch {
            row_len: spec.row_len,
            bytes: Vec::with_capacity(rows * spec.row_len),
            timestamps: Vec::with_capacity(rows),
            spec,
        }
    }

    /// Adds one row (as [`ColumnBuilder::push`]); `false`, adding nothing, if `data` is
    /// shorter than the columns need.
    #[inline]
    pub fn push(&mut self, data: &[u8], timestamp: u64) -> bool {
        let Some(data) = data.get(..self.row_len) else {
            return false;
        };
        self.bytes.extend_from_slice(data);
        self.timestamps.push(timestamp);
        true
    }

    /// The number of rows.
    pub fn rows(&self) -> usize {
        self.timestamps.len()
    }

    /// Bytes the batch holds.
    pub fn memory(&self) -> usize {
        self.bytes.capacity() + self.timestamps.capacity() * 8
    }

    /// The spec of the rows.
    pub fn spec(&self) -> &Arc<ColumnSpec> {
        &self.spec
    }

    /// The rows' columns, in the spec's order.
    pub fn columns(self) -> Columns {
        let rows = self.rows();
        let mut values = empty_columns(&self.spec, rows);
        // A block of rows at a time, in place, so that each column's loop reads rows the
        // one before brought into cache.
        let stage_rows = (STAGE_BYTES / self.spec.row_len.max(1)).max(1);
        // A spec without value columns reads no bytes: its rows are empty.
        let stride = self.spec.row_len;
        for (i, timestamps) in self.timestamps.chunks(stage_rows).enumerate() {
            let start = i * stage_rows * stride;
            let bytes = &self.bytes[start..start + timestamps.len() * stride];
            append(&self.spec, bytes, timestamps, &mut values);
        }
        Columns {
            spec: self.spec,
            values,
            rows,
        }
    }

    /// Appends the rows to `columns` (one vector per column of the spec), leaving the batch
    /// empty.
    fn append_to(&mut self, columns: &mut [ColumnValues]) {
        append(&self.spec, &self.bytes, &self.timestamps, columns);
        self.bytes.clear();
        self.timestamps.clear();
    }
}

impl Columns {
    /// The columns of `rows` (with their timestamps; rows shorter than
    /// [`ColumnSpec::row_len`] left out), `capacity` rows expected.
    pub(crate) fn from_rows<'r>(
        spec: Arc<ColumnSpec>,
        rows: impl Iterator<Item = (&'r [u8], u64)>,
        capacity: usize,
    ) -> Columns {
        let mut b = ColumnBuilder::with_capacity(spec, capacity);
        for (data, timestamp) in rows {
            b.push(data, timestamp);
        }
        b.take()
    }
}

/// Appends `rows` (`timestamps.len()` rows of the spec's `row_len` bytes each, back to
/// back; none when the spec reads no bytes) and their `timestamps` to `columns`, one vector
/// per column of `spec`.
fn append(spec: &ColumnSpec, rows: &[u8], timestamps: &[u64], columns: &mut [ColumnValues]) {
    let stride = spec.row_len;
    debug_assert_eq!(rows.len(), timestamps.len() * stride, "whole rows");
    for (c, values) in spec.columns.iter().zip(columns.iter_mut()) {
        match (c.source, c.kind) {
            (Source::Timestamp, _) => {
                if let ColumnValues::UInt64(v) = values {
                    v.extend_from_slice(timestamps);
                }
            }
            (Source::Offset(at), ColumnKind::Value(_)) => gather(rows, stride, at, values),
            (Source::Offset(at), ColumnKind::Text { len }) => {
                if let ColumnValues::Text(v) = values {
                    // By index, not by chunks of `stride`: a text of no length can be a
                    // format's only field (a format built in code), with rows of no bytes.
                    v.extend((0..timestamps.len()).map(|i| text(&rows[i * stride + at..][..len])));
                }
            }
        }
    }
}

/// Empty vectors for the columns of `spec`, with room for `rows` values each.
fn empty_columns(spec: &ColumnSpec, rows: usize) -> Vec<ColumnValues> {
    spec.columns
        .iter()
        .map(|c| match c.kind {
            ColumnKind::Value(p) => match p {
                Primitive::Int8 => ColumnValues::Int8(Vec::with_capacity(rows)),
                Primitive::UInt8 => ColumnValues::UInt8(Vec::with_capacity(rows)),
                Primitive::Int16 => ColumnValues::Int16(Vec::with_capacity(rows)),
                Primitive::UInt16 => ColumnValues::UInt16(Vec::with_capacity(rows)),
                Primitive::Int32 => ColumnValues::Int32(Vec::with_capacity(rows)),
                Primitive::UInt32 => ColumnValues::UInt32(Vec::with_capacity(rows)),
                Primitive::Int64 => ColumnValues::Int64(Vec::with_capacity(rows)),
                Primitive::UInt64 => ColumnValues::UInt64(Vec::with_capacity(rows)),
                Primitive::Float => ColumnValues::Float(Vec::with_capacity(rows)),
                Primitive::Double => ColumnValues::Double(Vec::with_capacity(rows)),
                Primitive::Bool => ColumnValues::Bool(Vec::with_capacity(rows)),
                Primitive::Char => ColumnValues::Char(Vec::with_capacity(rows)),
            },
            ColumnKind::Text { .. } => ColumnValues::Text(Vec::with_capacity(rows)),
        })
        .collect()
}

/// Appends to one column the value at `at` of each row of `rows` (`stride` bytes a row,
/// back to back; the value within the row).
#[inline]
fn gather(rows: &[u8], stride: usize, at: usize, values: &mut ColumnValues) {
    // Whole rows only (a spec that reads no bytes has no values to take).
    let n = rows.len().checked_div(stride).unwrap_or(0);
    if n == 0 {
        return;
    }
    macro_rules! extend {
        ($v:expr, $ty:ty, |$x:ident| $out:expr) => {{
            const SIZE: usize = size_of::<$ty>();
            assert!(at + SIZE <= stride, "a value within its row");
            // Every value read below lies in `rows`: the last ends at
            // `(n - 1) * stride + at + SIZE <= n * stride <= rows.len()`.
            let first = rows[at..].as_ptr();
            $v.extend((0..n).map(|i| {
                // SAFETY: `i < n`, so the `SIZE` bytes at `i * stride` from the first
                // value are in `rows` (the bound above); an unaligned read of bytes.
                #[allow(unsafe_code)]
                let bytes = unsafe { first.add(i * stride).cast::<[u8; SIZE]>().read_unaligned() };
                let $x = <$ty>::from_le_bytes(bytes);
                $out
            }));
        }};
    }
    match values {
        ColumnValues::Int8(v) => extend!(v, i8, |x| x),
        ColumnValues::UInt8(v) => extend!(v, u8, |x| x),
        ColumnValues::Int16(v) => extend!(v, i16, |x| x),
        ColumnValues::UInt16(v) => extend!(v, u16, |x| x),
        ColumnValues::Int32(v) => extend!(v, i32, |x| x),
        ColumnValues::UInt32(v) => extend!(v, u32, |x| x),
        ColumnValues::Int64(v) => extend!(v, i64, |x| x),
        ColumnValues::UInt64(v) => extend!(v, u64, |x| x),
        ColumnValues::Float(v) => extend!(v, f32, |x| x),
        ColumnValues::Double(v) => extend!(v, f64, |x| x),
        ColumnValues::Bool(v) => extend!(v, u8, |x| x != 0),
        ColumnValues::Char(v) => extend!(v, u8, |x| x),
        ColumnValues::Text(_) => {}
    }
}

/// The rows of a time window, as pyulog's `ulog2csv` takes them: from the first row at or
/// after `start` to the last before the first row at or after `end` (times in µs).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Window {
    /// Rows from this time on (µs).
    pub start_us: Option<f64>,
    /// Rows before this time (µs).
    pub end_us: Option<f64>,
}

/// `from 10 s to 20 s`, `from 10 s`, `before 20 s`, or `unbounded`: the window as a
/// message names it.
impl std::fmt::Display for Window {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (self.start_us, self.end_us) {
            (Some(s), Some(e)) => write!(f, "from {} s to {} s", s / 1e6, e / 1e6),
            (Some(s), None) => write!(f, "from {} s", s / 1e6),
            (None, Some(e)) => write!(f, "before {} s", e / 1e6),
            (None, None) => f.write_str("unbounded"),
        }
    }
}

/// What to do with one row of a [`Window`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Admit {
    /// Before the window: leave it out.
    Skip,
    /// In the window.
    Take,
    /// The window has ended: leave out this row and the rest.
    Stop,
}

/// Why [`Window::seconds`] refuses a window.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum WindowError {
    /// A bound is not a finite number (NaN or infinite).
    #[error("the window's {bound} ({value}) is not a finite number of seconds")]
    NotFinite {
        /// `start` or `end`.
        bound: &'static str,
        /// The value given.
        value: f64,
    },
    /// A bound beyond any time a log can hold (µs in 64 bits: about 584,542 years).
    #[error("the window's {bound} ({value:e} s) is beyond any time a log can hold")]
    OutOfRange {
        /// `start` or `end`.
        bound: &'static str,
        /// The value given, seconds.
        value: f64,
    },
    /// The end is not after the start: no row could lie in the window.
    #[error("the window ends ({end} s) at or before its start ({start} s), so no row lies in it")]
    Empty {
        /// The start given, seconds.
        start: f64,
        /// The end given, seconds.
        end: f64,
    },
}

/// ` (their rows run from 0 s to 1194.367328 s)`: what a message about a window no row lay in
/// adds, so that the user sees which window would have rows (timestamps in µs).
#[cfg(feature = "parquet")]
pub(crate) fn span_in_words(first_us: u64, last_us: u64) -> String {
    format!(
        " (their rows run from {} s to {} s)",
        first_us as f64 / 1e6,
        last_us as f64 / 1e6
    )
}

impl Window {
    /// A window from `start` to `end` seconds of log time (µs timestamps / 1e6), either
    /// bound absent for none; an error for a bound that is NaN, infinite or beyond what a
    /// `u64` of µs holds, and for an end at or before the start.
    pub fn seconds(start: Option<f64>, end: Option<f64>) -> Result<Window, WindowError> {
        for (bound, value) in [("start", start), ("end", end)] {
            if let Some(value) = value.filter(|v| !v.is_finite()) {
                return Err(WindowError::NotFinite { bound, value });
            }
            if let Some(value) = value.filter(|v| v.abs() * 1e6 > u64::MAX as f64) {
                return Err(WindowError::OutOfRange { bound, value });
            }
        }
        if let (Some(start), Some(end)) = (start, end)
            && end <= start
        {
            return Err(WindowError::Empty { start, end });
        }
        Ok(Window {
            start_us: start.map(|s| s * 1e6),
            end_us: end.map(|s| s * 1e6),
        })
    }

    /// Whether the window has a bound (a default window takes every row).
    pub fn is_bounded(&self) -> bool {
        self.start_us.is_some() || self.end_us.is_some()
    }

    /// `no CSV file written: the topics asked for have no rows that can be read in the
    /// window from 10 s to 20 s`: what an export says when it wrote no `what` (`topics`
    /// empty: `no topic has rows ...`), as `ulog csv`, `ulog parquet`, `ulog json` and
    /// Python's `to_parquet` say it.
    pub fn nothing_written(&self, what: &str, topics: &[String]) -> String {
        format!(
            "no {what} written: {} rows that can be read{}",
            if topics.is_empty() {
                "no topic has"
            } else {
                "the topics asked for have no"
            },
            self.in_words()
        )
    }

    /// ` in the window from 10 s to 20 s` for a bounded window, else nothing: what a
    /// message about missing rows adds, since rows outside the window were not asked for.
    pub fn in_words(&self) -> String {
        if self.is_bounded() {
            format!(" in the window {self}")
        } else {
            String::new()
        }
    }

    /// Whether to take the next row of one topic instance, given whether an earlier row of
    /// it was taken (`started`).
    pub fn admit(&self, timestamp: u64, started: bool) -> Admit {
        let t = timestamp as f64;
        if !started && self.start_us.is_some_and(|s| t < s) {
            return Admit::Skip;
        }
        if self.end_us.is_some_and(|e| t >= e) {
            return Admit::Stop;
        }
        Admit::Take
    }
}

/// A `char[N]` value as pyulog's `ulog2csv` shows it: the bytes up to the first zero, each
/// as one character (`chr(byte)`).
pub fn text(bytes: &[u8]) -> String {
    bytes
        .iter()
        .take_while(|&&b| b != 0)
        .map(|&b| char::from(b))
        .collect()
}

/// Why a log has no columns of a topic instance ([`Log::columns`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ColumnsError {
    /// The log never subscribes a topic of this name.
    #[error("the log has no topic `{topic}`{}", crate::schema::did_you_mean(.suggestions))]
    NoSuchTopic {
        /// The topic asked for.
        topic: String,
        /// The log's topics closest to it (at most 3, closest first).
        suggestions: Vec<String>,
    },
    /// The topic has no subscription with this instance number.
    #[error("`{topic}` has no instance {multi_id} (instances: {available:?})")]
    NoInstance {
        /// The topic.
        topic: String,
        /// The instance asked for.
        multi_id: u8,
        /// The instances the log has.
        available: Vec<u8>,
    },
    /// The instance's format cannot be laid out (a nested type the log does not define...):
    /// its rows cannot be decoded.
    #[error("`{topic}` #{multi_id}: its format cannot be read, so neither can its rows")]
    Unreadable {
        /// The topic.
        topic: String,
        /// The instance.
        multi_id: u8,
    },
}

impl Log<'_> {
    /// The columns of one topic instance (every subscription of that name and `multi_id`,
    /// rows in file order), or why there are none: no such topic (with the closest names
    /// the log has), no such instance, or a format that cannot be read.
    ///
    /// An instance's rows are scattered through the file, so gathering them waits on memory
    /// more than it computes: an instance of 65,536 rows or more is gathered on several
    /// threads (one per 32,768 rows, as many as the machine has cores, at most 8), each
    /// writing a run of consecutive rows in place.
    ///
    /// ```
    /// # use ulog_runtime::{Log, ULog, Writer, WriterOptions};
    /// # #[derive(ULog)] struct Battery { timestamp: u64, voltage_v: f32 }
    /// # let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
    /// # let sub = w.topic::<Battery>(0)?;
    /// # w.write(&sub, &Battery { timestamp: 1, voltage_v: 16.0 })?;
    /// # let log = Log::from_vec(w.into_inner())?;
    /// let err = log.columns("batery", 0).unwrap_err();
    /// assert_eq!(err.to_string(), "the log has no topic `batery`; did you mean `battery`?");
    /// let battery = log.columns("battery", 0)?;
    /// // `as_float` gives a `float` column's values as stored; `to_f64` converts any type.
    /// assert_eq!(battery.get("voltage_v").unwrap().as_float(), Some(&[16.0f32][..]));
    /// assert_eq!(battery.get("voltage_v").unwrap().to_f64(), Some(vec![16.0]));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn columns(&self, topic: &str, multi_id: u8) -> Result<Columns, ColumnsError> {
        self.columns_on(
            crate::read::all_cores(),
            gather::RUN_MIN_ROWS,
            topic,
            multi_id,
        )
    }

    /// [`Log::columns`] on at most `threads` threads, each taking `min_rows` rows or more.
    pub(crate) fn columns_on(
        &self,
        threads: usize,
        min_rows: usize,
        topic: &str,
        multi_id: u8,
    ) -> Result<Columns, ColumnsError> {
        let (subs, spec) = self.instance_spec(topic, multi_id)?;
        let rows: usize = subs.iter().map(|s| self.rows(s).len()).sum();
        let runs = (rows / min_rows.max(1)).clamp(1, threads.max(1));
        let gathered = (runs > 1)
            .then(|| gather::columns(&spec, self.instance_rows(&subs).split(runs)))
            .flatten();
        Ok(gathered.unwrap_or_else(|| {
            Columns::from_rows(
                spec,
                self.instance_rows(&subs).map(|r| (r.data, r.timestamp)),
                rows,
            )
        }))
    }

    /// The readable subscriptions of one topic instance and the spec of its columns, or
    /// why there are none ([`Log::columns`]' errors).
    pub(crate) fn instance_spec(
        &self,
        topic: &str,
        multi_id: u8,
    ) -> Result<(Vec<&Subscription>, Arc<ColumnSpec>), ColumnsError> {
        let subs = self.instance(topic, multi_id);
        let Some(first) = subs.first() else {
            let named: Vec<&Subscription> = self
                .subscriptions()
                .iter()
                .filter(|s| s.name == topic)
                .collect();
            if named.is_empty() {
                let names: std::collections::BTreeSet<&str> = self
                    .subscriptions()
                    .iter()
                    .map(|s| s.name.as_str())
                    .collect();
                return Err(ColumnsError::NoSuchTopic {
                    topic: topic.to_owned(),
                    suggestions: crate::schema::closest_names(topic, names.into_iter()),
                });
            }
            if named.iter().any(|s| s.multi_id == multi_id) {
                return Err(ColumnsError::Unreadable {
                    topic: topic.to_owned(),
                    multi_id,
                });
            }
            let mut available: Vec<u8> = named.iter().map(|s| s.multi_id).collect();
            available.sort_unstable();
            available.dedup();
            return Err(ColumnsError::NoInstance {
                topic: topic.to_owned(),
                multi_id,
                available,
            });
        };
        let unreadable = || ColumnsError::Unreadable {
            topic: topic.to_owned(),
            multi_id,
        };
        let id = first.format().ok_or_else(unreadable)?;
        let spec = ColumnSpec::of(self.metadata().schema(), id).ok_or_else(unreadable)?;
        Ok((subs, Arc::new(spec)))
    }

    /// The columns of every topic instance with rows (as [`Log::columns`] gives each), made
    /// in one pass over the file on every core (each core a part of the rows, the parts'
    /// columns joined in order): faster than a [`Log::columns`] call per instance, whose
    /// rows are scattered through the file. Instances in the order of
    /// [`Log::instances`].
    pub fn all_columns(&self) -> Vec<(String, u8, Columns)> {
        self.all_column_parts()
            .into_iter()
            .map(|(topic, multi_id, parts)| {
                let mut parts = parts.into_iter();
                let mut joined = parts.next().expect("an instance has a part");
                parts.for_each(|p| joined.append(p));
                (topic, multi_id, joined)
            })
            .collect()
    }

    /// [`Log::all_columns`] without joining: each instance's columns in parts (one per core
    /// that met its rows), which in order are its columns. For consumers that take chunks
    /// (an Arrow table of several record batches), this saves copying the parts together.
    pub fn all_column_parts(&self) -> Vec<(String, u8, Vec<Columns>)> {
        let groups = self.instances(&[]);
        // Per subscription: its instance's index.
        let mut by_sub = vec![usize::MAX; self.subscriptions().len()];
        let mut specs = Vec::with_capacity(groups.len());
        for (k, g) in groups.iter().enumerate() {
            let spec = g[0]
                .format()
                .and_then(|id| ColumnSpec::of(self.metadata().schema(), id))
                .map(Arc::new);
            for s in g {
                by_sub[s.index()] = k;
            }
            specs.push(spec);
        }
        let n = self.row_count();
        let threads = crate::read::all_cores().min(n.max(1));
        let part = |range: std::ops::Range<usize>| {
            let mut builders: Vec<Option<ColumnBuilder>> = specs
                .iter()
                .map(|s| s.as_ref().map(|s| ColumnBuilder::new(s.clone())))
                .collect();
            self.data_range(range).for_each(|row| {
                let k = by_sub[row.subscription.index()];
                if let Some(Some(b)) = builders.get_mut(k) {
                    b.push(row.data, row.timestamp);
                }
            });
            builders
        };
        let mut parts: Vec<Vec<Option<ColumnBuilder>>> = if threads == 1 {
            vec![part(0..n)]
        } else {
            std::thread::scope(|s| {
                let handles: Vec<_> = (0..threads)
                    .map(|t| t * n / threads..(t + 1) * n / threads)
                    .map(|r| s.spawn(move || part(r)))
                    .collect();
                handles
                    .into_iter()
                    .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
                    .collect()
            })
        };
        let mut out = Vec::with_capacity(groups.len());
        for (k, g) in groups.iter().enumerate() {
            let mut cols: Vec<Columns> = parts
                .iter_mut()
                .filter_map(|p| p[k].as_mut().map(ColumnBuilder::take))
                .collect();
            // The parts with rows (or one empty part, for an instance without a whole row).
            if cols.iter().any(|c| c.rows() > 0) {
                cols.retain(|c| c.rows() > 0);
            } else {
                cols.truncate(1);
            }
            if !cols.is_empty() {
                out.push((g[0].name.clone(), g[0].multi_id, cols));
            }
        }
        out
    }

    /// The subscriptions of one topic instance whose format can be read, in file order.
    pub(crate) fn instance(&self, topic: &str, multi_id: u8) -> Vec<&Subscription> {
        self.subscriptions()
            .iter()
            .filter(|s| s.name == topic && s.multi_id == multi_id && s.format().is_some())
            .collect()
    }
}

#[cfg(test)]
mod tests;
