//! Dynamic values for rows of any format: a value tree ([`Value`]) for convenience, and a
//! flat, allocation-free leaf walk ([`RowPlan::for_each_leaf`]) for speed. Column names follow
//! pyulog (`q[0]`, `esc[3].esc_rpm`); padding is never shown.

use std::fmt;

use crate::schema::{FieldKind, FormatId, Layout, Primitive, Schema};

/// Deepest nesting of formats the dynamic decoder follows (PX4 uses 2 or 3 levels).
pub const MAX_NESTING_DEPTH: usize = 64;

/// One decoded basic value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scalar {
    /// `int8_t`
    Int8(i8),
    /// `uint8_t`
    UInt8(u8),
    /// `int16_t`
    Int16(i16),
    /// `uint16_t`
    UInt16(u16),
    /// `int32_t`
    Int32(i32),
    /// `uint32_t`
    UInt32(u32),
    /// `int64_t`
    Int64(i64),
    /// `uint64_t`
    UInt64(u64),
    /// `float`
    Float(f32),
    /// `double`
    Double(f64),
    /// `bool`: any non-zero byte is true.
    Bool(bool),
    /// `char`: the raw byte.
    Char(u8),
}

impl Scalar {
    /// Decodes a little-endian value of type `p` from the start of `b`; `None` if `b` is
    /// shorter than the type.
    #[inline]
    pub fn decode(p: Primitive, b: &[u8]) -> Option<Scalar> {
        Some(match p {
            Primitive::Int8 => Scalar::Int8(i8::from_le_bytes(array(b)?)),
            Primitive::UInt8 => Scalar::UInt8(u8::from_le_bytes(array(b)?)),
            Primitive::Int16 => Scalar::Int16(i16::from_le_bytes(array(b)?)),
            Primitive::UInt16 => Scalar::UInt16(u16::from_le_bytes(array(b)?)),
            Primitive::Int32 => Scalar::Int32(i32::from_le_bytes(array(b)?)),
            Primitive::UInt32 => Scalar::UInt32(u32::from_le_bytes(array(b)?)),
            Primitive::Int64 => Scalar::Int64(i64::from_le_bytes(array(b)?)),
            Primitive::UInt64 => Scalar::UInt64(u64::from_le_bytes(array(b)?)),
            Primitive::Float => Scalar::Float(f32::from_le_bytes(array(b)?)),
            Primitive::Double => Scalar::Double(f64::from_le_bytes(array(b)?)),
            Primitive::Bool => Scalar::Bool(*b.first()? != 0),
            Primitive::Char => Scalar::Char(*b.first()?),
        })
    }

    /// The value as `f64`: `bool` as 0 or 1, `char` as a signed byte (as pyulog shows it);
    /// 64-bit integers beyond 2^53 are rounded.
    #[inline]
    pub fn as_f64(self) -> f64 {
        match self {
            Scalar::Int8(v) => f64::from(v),
            Scalar::UInt8(v) => f64::from(v),
            Scalar::Int16(v) => f64::from(v),
            Scalar::UInt16(v) => f64::from(v),
            Scalar::Int32(v) => f64::from(v),
            Scalar::UInt32(v) => f64::from(v),
            Scalar::Int64(v) => v as f64,
            Scalar::UInt64(v) => v as f64,
            Scalar::Float(v) => f64::from(v),
            Scalar::Double(v) => v,
            Scalar::Bool(v) => f64::from(u8::from(v)),
            Scalar::Char(v) => f64::from(v as i8),
        }
    }

    /// The value as `i128` if it is an integer (`bool` and `char` included).
    pub fn as_i128(self) -> Option<i128> {
        Some(match self {
            Scalar::Int8(v) => v.into(),
            Scalar::UInt8(v) => v.into(),
            Scalar::Int16(v) => v.into(),
            Scalar::UInt16(v) => v.into(),
            Scalar::Int32(v) => v.into(),
            Scalar::UInt32(v) => v.into(),
            Scalar::Int64(v) => v.into(),
            Scalar::UInt64(v) => v.into(),
            Scalar::Bool(v) => u8::from(v).into(),
            Scalar::Char(v) => (v as i8).into(),
            Scalar::Float(_) | Scalar::Double(_) => return None,
        })
    }

    /// The basic type of this value.
    pub fn primitive(self) -> Primitive {
        match self {
            Scalar::Int8(_) => Primitive::Int8,
            Scalar::UInt8(_) => Primitive::UInt8,
            Scalar::Int16(_) => Primitive::Int16,
            Scalar::UInt16(_) => Primitive::UInt16,
            Scalar::Int32(_) => Primitive::Int32,
            Scalar::UInt32(_) => Primitive::UInt32,
            Scalar::Int64(_) => Primitive::Int64,
            Scalar::UInt64(_) => Primitive::UInt64,
            Scalar::Float(_) => Primitive::Float,
            Scalar::Double(_) => Primitive::Double,
            Scalar::Bool(_) => Primitive::Bool,
            Scalar::Char(_) => Primitive::Char,
        }
    }
}

#[inline]
fn array<const N: usize>(b: &[u8]) -> Option<[u8; N]> {
    b.get(..N)?.try_into().ok()
}

impl fmt::Display for Scalar {
    /// Integers exactly; floats in the shortest form that parses back to the same value.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Scalar::Int8(v) => write!(f, "{v}"),
            Scalar::UInt8(v) => write!(f, "{v}"),
            Scalar::Int16(v) => write!(f, "{v}"),
            Scalar::UInt16(v) => write!(f, "{v}"),
            Scalar::Int32(v) => write!(f, "{v}"),
            Scalar::UInt32(v) => write!(f, "{v}"),
            Scalar::Int64(v) => write!(f, "{v}"),
            Scalar::UInt64(v) => write!(f, "{v}"),
            Scalar::Float(v) => write!(f, "{v}"),
            Scalar::Double(v) => write!(f, "{v}"),
            Scalar::Bool(v) => write!(f, "{}", u8::from(v)),
            Scalar::Char(v) => write!(f, "{}", v as i8),
        }
    }
}

/// A decoded value of any type: what a row, a nested field, an array or an info value holds.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// A basic value.
    Scalar(Scalar),
    /// A `char` array, as text: lossy UTF-8, cut at the first NUL in data rows.
    String(String),
    /// A fixed array of anything but `char`.
    Array(Vec<Value>),
    /// A format's fields by name, in declaration order, padding left out.
    Struct(Vec<(String, Value)>),
    /// Bytes without a type: an info value of a type that is not basic, or too short for its
    /// type (a diagnostic says which).
    Bytes(Vec<u8>),
}

impl Value {
    /// The field with this name, for a struct.
    pub fn field(&self, name: &str) -> Option<&Value> {
        match self {
            Value::Struct(fields) => fields.iter().find(|(n, _)| n == name).map(|(_, v)| v),
            _ => None,
        }
    }

    /// The scalar, for a basic value.
    pub fn as_scalar(&self) -> Option<Scalar> {
        match self {
            Value::Scalar(s) => Some(*s),
            _ => None,
        }
    }

    /// The text, for a `char` array.
    pub fn as_str(&self) -> Option<&str> {
        match self {
            Value::String(s) => Some(s),
            _ => None,
        }
    }

    /// Decodes `count` elements of primitive `p` (`None`: a scalar) from `b`, as an info value
    /// or a row field: `char` arrays become text, other arrays become [`Value::Array`].
    /// `cut_at_nul` cuts text at the first NUL (data rows) or keeps every byte (info values).
    pub fn decode_primitive(
        p: Primitive,
        count: Option<usize>,
        b: &[u8],
        cut_at_nul: bool,
    ) -> Option<Value> {
        match count {
            None => Scalar::decode(p, b).map(Value::Scalar),
            Some(n) if p == Primitive::Char => {
                let bytes = b.get(..n)?;
                let bytes = if cut_at_nul {
                    bytes.split(|&c| c == 0).next().unwrap_or_default()
                } else {
                    bytes
                };
                Some(Value::String(String::from_utf8_lossy(bytes).into_owned()))
            }
            Some(n) => {
                let bytes = b.get(..n.checked_mul(p.size())?)?;
                Some(Value::Array(
                    bytes
                        .chunks_exact(p.size())
                        .map(|c| Scalar::decode(p, c).map(Value::Scalar))
                        .collect::<Option<_>>()?,
                ))
            }
        }
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Scalar(s) => write!(f, "{s}"),
            Value::String(s) => write!(f, "{s:?}"),
            Value::Array(items) => {
                f.write_str("[")?;
                for (i, v) in items.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{v}")?;
                }
                f.write_str("]")
            }
            Value::Struct(fields) => {
                f.write_str("{")?;
                for (i, (n, v)) in fields.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{n}: {v}")?;
                }
                f.write_str("}")
            }
            Value::Bytes(bytes) => {
                f.write_str("<")?;
                for (i, b) in bytes.iter().enumerate() {
                    if i > 0 {
                        f.write_str(" ")?;
                    }
                    write!(f, "{b:02x}")?;
                }
                f.write_str(">")
            }
        }
    }
}

#[cfg(feature = "serde")]
impl serde::Serialize for Scalar {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match *self {
            Scalar::Int8(v) => s.serialize_i8(v),
            Scalar::UInt8(v) => s.serialize_u8(v),
            Scalar::Int16(v) => s.serialize_i16(v),
            Scalar::UInt16(v) => s.serialize_u16(v),
            Scalar::Int32(v) => s.serialize_i32(v),
            Scalar::UInt32(v) => s.serialize_u32(v),
            Scalar::Int64(v) => s.serialize_i64(v),
            Scalar::UInt64(v) => s.serialize_u64(v),
            Scalar::Float(v) => s.serialize_f32(v),
            Scalar::Double(v) => s.serialize_f64(v),
            Scalar::Bool(v) => s.serialize_bool(v),
            Scalar::Char(v) => s.serialize_i8(v as i8),
        }
    }
}

#[cfg(feature = "serde")]
impl serde::Serialize for Value {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::{SerializeMap, SerializeSeq};
        match self {
            Value::Scalar(v) => v.serialize(s),
            Value::String(v) => s.serialize_str(v),
            Value::Array(items) => {
                let mut seq = s.serialize_seq(Some(items.len()))?;
                for v in items {
                    seq.serialize_element(v)?;
                }
                seq.end()
            }
            Value::Struct(fields) => {
                let mut map = s.serialize_map(Some(fields.len()))?;
                for (n, v) in fields {
                    map.serialize_entry(n, v)?;
                }
                map.end()
            }
            Value::Bytes(bytes) => {
                let mut seq = s.serialize_seq(Some(bytes.len()))?;
                for b in bytes {
                    seq.serialize_element(b)?;
                }
                seq.end()
            }
        }
    }
}

/// What [`RowPlan::visit_runs`] calls: one method per basic type, each given a run of
/// values of that type as their little-endian bytes (`f32::from_le_bytes(v[i])` is the
/// `i`-th `float`). Every method does nothing by default.
#[allow(unused_variables)]
pub trait VisitLeaves<'r> {
    /// `int8_t` values (each byte as `i8`).
    fn int8(&mut self, v: &'r [u8]) {}
    /// `uint8_t` values.
    fn uint8(&mut self, v: &'r [u8]) {}
    /// `int16_t` values.
    fn int16(&mut self, v: &'r [[u8; 2]]) {}
    /// `uint16_t` values.
    fn uint16(&mut self, v: &'r [[u8; 2]]) {}
    /// `int32_t` values.
    fn int32(&mut self, v: &'r [[u8; 4]]) {}
    /// `uint32_t` values.
    fn uint32(&mut self, v: &'r [[u8; 4]]) {}
    /// `int64_t` values.
    fn int64(&mut self, v: &'r [[u8; 8]]) {}
    /// `uint64_t` values.
    fn uint64(&mut self, v: &'r [[u8; 8]]) {}
    /// `float` values.
    fn float(&mut self, v: &'r [[u8; 4]]) {}
    /// `double` values.
    fn double(&mut self, v: &'r [[u8; 8]]) {}
    /// `bool` values (any non-zero byte is true).
    fn bool(&mut self, v: &'r [u8]) {}
    /// `char` values (bytes).
    fn char(&mut self, v: &'r [u8]) {}
}

/// The little-endian bytes of a run of same-typed leaves ([`RowPlan::for_each_run`]), one
/// array per value: `f32::from_le_bytes(values[i])` is the `i`-th `float`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Leaves<'a> {
    /// `int8_t` values (each byte as `i8`).
    Int8(&'a [u8]),
    /// `uint8_t` values.
    UInt8(&'a [u8]),
    /// `int16_t` values.
    Int16(&'a [[u8; 2]]),
    /// `uint16_t` values.
    UInt16(&'a [[u8; 2]]),
    /// `int32_t` values.
    Int32(&'a [[u8; 4]]),
    /// `uint32_t` values.
    UInt32(&'a [[u8; 4]]),
    /// `int64_t` values.
    Int64(&'a [[u8; 8]]),
    /// `uint64_t` values.
    UInt64(&'a [[u8; 8]]),
    /// `float` values.
    Float(&'a [[u8; 4]]),
    /// `double` values.
    Double(&'a [[u8; 8]]),
    /// `bool` values (any non-zero byte is true).
    Bool(&'a [u8]),
    /// `char` values (bytes).
    Char(&'a [u8]),
}

impl Leaves<'_> {
    /// The number of values.
    pub fn len(&self) -> usize {
        match self {
            Leaves::Int8(v) | Leaves::UInt8(v) | Leaves::Bool(v) | Leaves::Char(v) => v.len(),
            Leaves::Int16(v) | Leaves::UInt16(v) => v.len(),
            Leaves::Int32(v) | Leaves::UInt32(v) | Leaves::Float(v) => v.len(),
            Leaves::Int64(v) | Leaves::UInt64(v) | Leaves::Double(v) => v.len(),
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A run of `count` consecutive leaves of one basic type starting at `offset`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LeafRun {
    /// Byte offset in the row.
    pub offset: u32,
    /// Number of consecutive values.
    pub count: u32,
    /// Their type.
    pub primitive: Primitive,
}

/// One flattened column of a format: pyulog's name, type and byte offset.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Column {
    /// `timestamp`, `q[0]`, `esc[3].esc_rpm`...
    pub name: String,
    /// The basic type.
    pub primitive: Primitive,
    /// Byte offset in the row.
    pub offset: usize,
}

/// Why a format cannot be decoded dynamically.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// The format has no layout (unknown nested type, cycle, too large...).
    #[error(transparent)]
    Layout(#[from] crate::schema::LayoutError),
    /// The nesting is deeper than [`MAX_NESTING_DEPTH`].
    #[error("`{format}` nests {depth} levels deep; at most {MAX_NESTING_DEPTH} are supported")]
    TooDeep {
        /// The format.
        format: String,
        /// Its depth.
        depth: usize,
    },
}

/// How to decode rows of one format dynamically: its leaves as merged runs of one basic type,
/// so that a row is decoded with one type dispatch per run, not per value.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RowPlan {
    root: FormatId,
    runs: Vec<LeafRun>,
    leaves: usize,
    /// Bytes a row needs for all its leaves.
    need: usize,
}

impl RowPlan {
    /// The plan for a format of `schema` (resolving its layout if needed).
    pub fn new(schema: &mut Schema, root: FormatId) -> Result<RowPlan, PlanError> {
        RowPlan::check(schema, root)?;
        Ok(RowPlan::from_checked(schema, root))
    }

    /// The plan of a format [`RowPlan::check`] accepted (its layouts are resolved).
    pub(crate) fn from_checked(schema: &Schema, root: FormatId) -> RowPlan {
        let mut runs: Vec<LeafRun> = Vec::new();
        let mut leaves = 0;
        walk_leaves(schema, root, 0, &mut |offset, primitive, count| {
            leaves += count;
            if let Some(last) = runs.last_mut() {
                let end = last.offset as usize + last.count as usize * primitive.size();
                if last.primitive == primitive && end == offset {
                    last.count += count as u32;
                    return;
                }
            }
            runs.push(LeafRun {
                offset: offset as u32,
                count: count as u32,
                primitive,
            });
        });
        let need = runs.last().map_or(0, |r| {
            r.offset as usize + r.count as usize * r.primitive.size()
        });
        RowPlan {
            root,
            runs,
            leaves,
            need,
        }
    }

    /// Checks that a format can be decoded dynamically (it has a layout, not nested too
    /// deep), resolving its layout if needed, without building the plan.
    pub fn check(schema: &mut Schema, root: FormatId) -> Result<&Layout, PlanError> {
        let depth = schema.layout(root)?.depth;
        if depth > MAX_NESTING_DEPTH {
            return Err(PlanError::TooDeep {
                format: schema.format(root).name.clone(),
                depth,
            });
        }
        Ok(schema.layout(root)?)
    }

    /// The format decoded.
    pub fn format(&self) -> FormatId {
        self.root
    }

    /// The leaf runs, in column order.
    pub fn runs(&self) -> &[LeafRun] {
        &self.runs
    }

    /// Number of leaves (non-padding basic values, every array element counted) per row.
    pub fn leaf_count(&self) -> usize {
        self.leaves
    }

    /// Calls `f` with every run of same-typed leaves of a row, in column order, as a typed
    /// slice of the row's bytes: one type dispatch per run, the loop over a run's values
    /// left to the caller. Returns `false` (having visited nothing) if `row` is shorter than
    /// the leaves need. [`RowPlan::visit_runs`] is the same with one method per type, which
    /// saves the caller's own match on the type.
    ///
    /// ```
    /// # use ulog_runtime::schema::Schema;
    /// # use ulog_runtime::value::{Leaves, RowPlan};
    /// let mut schema = Schema::new();
    /// let id = schema.insert("t:uint64_t timestamp;float[2] q;".parse().unwrap()).unwrap();
    /// let plan = RowPlan::new(&mut schema, id).unwrap();
    /// let mut row = 5u64.to_le_bytes().to_vec();
    /// row.extend([1.5f32, -2.0].iter().flat_map(|x| x.to_le_bytes()));
    /// let mut sum = 0.0;
    /// plan.for_each_run(&row, |run| match run {
    ///     Leaves::Float(values) => sum += values.iter().map(|b| f64::from(f32::from_le_bytes(*b))).sum::<f64>(),
    ///     Leaves::UInt64(values) => sum += values.iter().map(|b| u64::from_le_bytes(*b) as f64).sum::<f64>(),
    ///     _ => {}
    /// });
    /// assert_eq!(sum, 4.5);
    /// ```
    #[inline]
    pub fn for_each_run<'r>(&self, row: &'r [u8], f: impl FnMut(Leaves<'r>)) -> bool {
        struct Each<F>(F);
        impl<'r, F: FnMut(Leaves<'r>)> VisitLeaves<'r> for Each<F> {
            fn int8(&mut self, v: &'r [u8]) {
                (self.0)(Leaves::Int8(v));
            }
            fn uint8(&mut self, v: &'r [u8]) {
                (self.0)(Leaves::UInt8(v));
            }
            fn int16(&mut self, v: &'r [[u8; 2]]) {
                (self.0)(Leaves::Int16(v));
            }
            fn uint16(&mut self, v: &'r [[u8; 2]]) {
                (self.0)(Leaves::UInt16(v));
            }
            fn int32(&mut self, v: &'r [[u8; 4]]) {
                (self.0)(Leaves::Int32(v));
            }
            fn uint32(&mut self, v: &'r [[u8; 4]]) {
                (self.0)(Leaves::UInt32(v));
            }
            fn int64(&mut self, v: &'r [[u8; 8]]) {
                (self.0)(Leaves::Int64(v));
            }
            fn uint64(&mut self, v: &'r [[u8; 8]]) {
                (self.0)(Leaves::UInt64(v));
            }
            fn float(&mut self, v: &'r [[u8; 4]]) {
                (self.0)(Leaves::Float(v));
            }
            fn double(&mut self, v: &'r [[u8; 8]]) {
                (self.0)(Leaves::Double(v));
            }
            fn bool(&mut self, v: &'r [u8]) {
                (self.0)(Leaves::Bool(v));
            }
            fn char(&mut self, v: &'r [u8]) {
                (self.0)(Leaves::Char(v));
            }
        }
        self.visit_runs(row, &mut Each(f))
    }

    /// Calls the method of `visitor` for the type of every run of same-typed leaves of a
    /// row, in column order, with the run's values as a typed slice of the row's bytes: the
    /// fastest way through every leaf (one dispatch per run). Returns `false` (having
    /// visited nothing) if `row` is shorter than the leaves need.
    #[inline]
    pub fn visit_runs<'r>(&self, row: &'r [u8], visitor: &mut impl VisitLeaves<'r>) -> bool {
        let Some(row) = row.get(..self.need) else {
            return false;
        };
        for run in &self.runs {
            let start = run.offset as usize;
            let n = run.count as usize;
            macro_rules! chunks {
                ($size:literal) => {
                    row[start..start + n * $size].as_chunks::<$size>().0
                };
            }
            match run.primitive {
                Primitive::Int8 => visitor.int8(&row[start..start + n]),
                Primitive::UInt8 => visitor.uint8(&row[start..start + n]),
                Primitive::Bool => visitor.bool(&row[start..start + n]),
                Primitive::Char => visitor.char(&row[start..start + n]),
                Primitive::Int16 => visitor.int16(chunks!(2)),
                Primitive::UInt16 => visitor.uint16(chunks!(2)),
                Primitive::Int32 => visitor.int32(chunks!(4)),
                Primitive::UInt32 => visitor.uint32(chunks!(4)),
                Primitive::Float => visitor.float(chunks!(4)),
                Primitive::Int64 => visitor.int64(chunks!(8)),
                Primitive::UInt64 => visitor.uint64(chunks!(8)),
                Primitive::Double => visitor.double(chunks!(8)),
            }
        }
        true
    }

    /// Calls `f` with every leaf of a row, in column order, without allocating. Returns
    /// `false` (having visited nothing) if `row` is shorter than the leaves need.
    #[inline]
    pub fn for_each_leaf(&self, row: &[u8], mut f: impl FnMut(Scalar)) -> bool {
        let Some(row) = row.get(..self.need) else {
            return false;
        };
        for run in &self.runs {
            let start = run.offset as usize;
            let n = run.count as usize;
            macro_rules! each {
                ($t:ty, $variant:ident) => {{
                    let bytes = &row[start..start + n * size_of::<$t>()];
                    let (chunks, _) = bytes.as_chunks::<{ size_of::<$t>() }>();
                    for c in chunks {
                        f(Scalar::$variant(<$t>::from_le_bytes(*c)));
                    }
                }};
            }
            match run.primitive {
                Primitive::Int8 => each!(i8, Int8),
                Primitive::UInt8 => each!(u8, UInt8),
                Primitive::Int16 => each!(i16, Int16),
                Primitive::UInt16 => each!(u16, UInt16),
                Primitive::Int32 => each!(i32, Int32),
                Primitive::UInt32 => each!(u32, UInt32),
                Primitive::Int64 => each!(i64, Int64),
                Primitive::UInt64 => each!(u64, UInt64),
                Primitive::Float => each!(f32, Float),
                Primitive::Double => each!(f64, Double),
                Primitive::Bool => row[start..start + n]
                    .iter()
                    .for_each(|&b| f(Scalar::Bool(b != 0))),
                Primitive::Char => row[start..start + n]
                    .iter()
                    .for_each(|&b| f(Scalar::Char(b))),
            }
        }
        true
    }

    /// The flattened columns, named as pyulog names them, padding left out.
    pub fn columns(&self, schema: &Schema) -> Vec<Column> {
        let mut out = Vec::with_capacity(self.leaves);
        flatten(schema, self.root, "", 0, &mut out);
        out
    }

    /// Decodes a row into a value tree; `None` if `row` is shorter than the format's payload.
    pub fn value(&self, schema: &Schema, row: &[u8]) -> Option<Value> {
        let layout = schema.resolved(self.root)?;
        if row.len() < layout.payload_size {
            return None;
        }
        struct_value(schema, layout, row)
    }
}

/// Visits every non-padding leaf field (offset, type, element count), depth first.
fn walk_leaves(
    schema: &Schema,
    id: FormatId,
    base: usize,
    f: &mut impl FnMut(usize, Primitive, usize),
) {
    let Some(layout) = schema.resolved(id) else {
        return;
    };
    for field in layout.fields.iter().filter(|f| !f.padding) {
        match field.kind {
            FieldKind::Primitive(p) => f(base + field.offset, p, field.count()),
            FieldKind::Nested(dep) => {
                for i in 0..field.count() {
                    walk_leaves(schema, dep, base + field.offset + i * field.elem_size, f);
                }
            }
        }
    }
}

fn flatten(schema: &Schema, id: FormatId, prefix: &str, base: usize, out: &mut Vec<Column>) {
    let Some(layout) = schema.resolved(id) else {
        return;
    };
    for field in layout.fields.iter().filter(|f| !f.padding) {
        let offset = base + field.offset;
        match (field.kind, field.array_len) {
            (FieldKind::Primitive(primitive), None) => out.push(Column {
                name: format!("{prefix}{}", field.name),
                primitive,
                offset,
            }),
            (FieldKind::Primitive(primitive), Some(n)) => {
                for i in 0..usize::from(n) {
                    out.push(Column {
                        name: format!("{prefix}{}[{i}]", field.name),
                        primitive,
                        offset: offset + i * field.elem_size,
                    });
                }
            }
            (FieldKind::Nested(dep), None) => {
                flatten(
                    schema,
                    dep,
                    &format!("{prefix}{}.", field.name),
                    offset,
                    out,
                );
            }
            (FieldKind::Nested(dep), Some(n)) => {
                for i in 0..usize::from(n) {
                    let p = format!("{prefix}{}[{i}].", field.name);
                    flatten(schema, dep, &p, offset + i * field.elem_size, out);
                }
            }
        }
    }
}

fn struct_value(schema: &Schema, layout: &Layout, b: &[u8]) -> Option<Value> {
    let mut fields = Vec::with_capacity(layout.fields.len());
    for field in layout.fields.iter().filter(|f| !f.padding) {
        let at = b.get(field.offset..)?;
        let value = match field.kind {
            FieldKind::Primitive(p) => {
                Value::decode_primitive(p, field.array_len.map(usize::from), at, true)?
            }
            FieldKind::Nested(dep) => {
                let dep_layout = schema.resolved(dep)?;
                match field.array_len {
                    None => struct_value(schema, dep_layout, at)?,
                    Some(n) => Value::Array(
                        (0..usize::from(n))
                            .map(|i| {
                                struct_value(schema, dep_layout, at.get(i * field.elem_size..)?)
                            })
                            .collect::<Option<_>>()?,
                    ),
                }
            }
        };
        fields.push((field.name.clone(), value));
    }
    Some(Value::Struct(fields))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(defs: &[&str], root: &str) -> (Schema, RowPlan) {
        let mut s = Schema::new();
        for d in defs {
            s.insert(d.parse().unwrap()).unwrap();
        }
        let id = s.id(root).unwrap();
        let p = RowPlan::new(&mut s, id).unwrap();
        (s, p)
    }

    #[test]
    fn columns_runs_and_values_hide_padding() {
        let (s, p) = plan(
            &[
                "outer:uint64_t timestamp;float[2] q;inner[2] e;char[4] name;uint8_t[3] _padding0;",
                "inner:int16_t a;uint8_t[2] _padding0;float b;",
            ],
            "outer",
        );
        let names: Vec<String> = p.columns(&s).into_iter().map(|c| c.name).collect();
        assert_eq!(
            names,
            [
                "timestamp",
                "q[0]",
                "q[1]",
                "e[0].a",
                "e[0].b",
                "e[1].a",
                "e[1].b",
                "name[0]",
                "name[1]",
                "name[2]",
                "name[3]"
            ]
        );
        assert_eq!(p.leaf_count(), 11);
        // timestamp | q[0] q[1] | a | b | a | b | name: the two floats of q merge into one run.
        assert_eq!(p.runs().len(), 7);

        let mut row = Vec::new();
        row.extend_from_slice(&7u64.to_le_bytes());
        row.extend_from_slice(&1.5f32.to_le_bytes());
        row.extend_from_slice(&(-2.0f32).to_le_bytes());
        for (a, b) in [(-3i16, 0.25f32), (4, 8.0)] {
            row.extend_from_slice(&a.to_le_bytes());
            row.extend_from_slice(&[0xEE, 0xEE]);
            row.extend_from_slice(&b.to_le_bytes());
        }
        row.extend_from_slice(b"hi\0x");
        let mut leaves = Vec::new();
        assert!(p.for_each_leaf(&row, |v| leaves.push(v.as_f64())));
        assert_eq!(
            leaves,
            [
                7.0, 1.5, -2.0, -3.0, 0.25, 4.0, 8.0, 104.0, 105.0, 0.0, 120.0
            ]
        );

        let v = p.value(&s, &row).unwrap();
        assert_eq!(
            v.field("timestamp").unwrap().as_scalar(),
            Some(Scalar::UInt64(7))
        );
        assert_eq!(v.field("name").unwrap().as_str(), Some("hi"));
        assert_eq!(
            v.to_string(),
            "{timestamp: 7, q: [1.5, -2], e: [{a: -3, b: 0.25}, {a: 4, b: 8}], name: \"hi\"}"
        );
        assert!(p.value(&s, &row[..row.len() - 1]).is_none());
        assert!(!p.for_each_leaf(&row[..10], |_| panic!("nothing is visited")));
    }

    #[test]
    fn scalars_follow_pyulog_conventions() {
        assert_eq!(
            Scalar::decode(Primitive::Char, &[0xff]).unwrap().as_f64(),
            -1.0
        );
        assert_eq!(
            Scalar::decode(Primitive::Bool, &[0x41]).unwrap().as_f64(),
            1.0
        );
        assert_eq!(Scalar::decode(Primitive::UInt16, &[1]), None);
        assert_eq!(Scalar::UInt64(u64::MAX).as_i128(), Some(u64::MAX as i128));
    }

    #[test]
    fn too_deep_nesting_is_refused() {
        let mut s = Schema::new();
        for i in 0..70 {
            s.insert(format!("t{i}:t{} n;", i + 1).parse().unwrap())
                .unwrap();
        }
        s.insert("t70:uint8_t v;".parse().unwrap()).unwrap();
        let id = s.id("t0").unwrap();
        assert!(matches!(
            RowPlan::new(&mut s, id),
            Err(PlanError::TooDeep { depth: 71, .. })
        ));
        let ok = s.id("t10").unwrap();
        assert_eq!(RowPlan::new(&mut s, ok).unwrap().leaf_count(), 1);
    }

    #[cfg(feature = "serde")]
    #[test]
    fn values_serialize_as_json() {
        let v = Value::Struct(vec![
            ("a".into(), Value::Scalar(Scalar::Float(0.5))),
            ("s".into(), Value::String("x".into())),
            (
                "l".into(),
                Value::Array(vec![Value::Scalar(Scalar::Bool(true))]),
            ),
        ]);
        assert_eq!(
            serde_json::to_string(&v).unwrap(),
            r#"{"a":0.5,"s":"x","l":[true]}"#
        );
    }
}
